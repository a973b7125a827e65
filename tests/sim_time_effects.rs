//! The time-structure effects (`trim_moment`, `smoothed_loads`, `rotor_speed_lag`,
//! `inflow_lag`) are present in a simulated flight log with the size their definition
//! gives, checked against an independent computation or the same flight without them.
//! Flights of one seed share every random draw (the trim moment has a stream of its own,
//! the other three draw nothing), so "with" and "without" differ by the effect alone.

use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion};

use mrsysid::SampleChunk;
use mrsysid::internals::sim::blade_element::RotorKinematics;
use mrsysid::internals::sim::controller::Gains;
use mrsysid::internals::sim::disturbance::TrimMoment;
use mrsysid::internals::sim::filter::smooth;
use mrsysid::internals::sim::flight::{FlightConfig, FlightLog, fly};
use mrsysid::internals::sim::run::{Mode, SimulateOptions, VehicleChoice, simulate};
use mrsysid::internals::sim::sensors::{SensorConfig, lag_step};
use mrsysid::internals::sim::{Effect, Effects, RotorFile, TruthInput, TruthModel};
use mrsysid::vehicle::Vehicle;

fn model(effects: &[&str]) -> TruthModel {
    let v = Vehicle::from_toml_file(Path::new("data/vehicles/quad_x.toml")).unwrap();
    let e = effects
        .iter()
        .map(|s| s.parse::<Effect>().unwrap())
        .collect();
    TruthModel::new(&v, &RotorFile::default(), Effects::new(e, &v).unwrap()).unwrap()
}

/// Sensors that report the truth: no noise, no bias, eRPM steps of 1e-6 (1.5e-8 rad/s).
fn exact_sensors() -> SensorConfig {
    SensorConfig {
        accel_noise: 0.0,
        accel_bias: 0.0,
        gyro_noise: 0.0,
        gyro_bias: 0.0,
        velocity_noise: 0.0,
        erpm_resolution: 1e-6,
        ..SensorConfig::default()
    }
}

/// Hover inputs (still air, level, no rates) at rotor speeds `omega`.
fn at(omega: &[f64; 4]) -> TruthInput<'_> {
    TruthInput {
        velocity: [0.0; 3],
        rates: [0.0; 3],
        omega,
        omega_dot: &[0.0; 4],
        height: None,
        down_row: None,
    }
}

fn flight(effects: &[&str], config: &FlightConfig, seed: u64) -> FlightLog {
    fly(&model(effects), config, seed).unwrap()
}

fn rms(x: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for v in x {
        s += v * v;
        n += 1.0;
    }
    (s / n).sqrt()
}

/// Copies the logged rotor speeds and accelerations of sample `k` into `omega`, `omega_dot`.
fn input(log: &FlightLog, k: usize, omega: &mut [f64; 4], omega_dot: &mut [f64; 4]) {
    let s = &log.samples;
    let logged_dot = s.omega_dot.as_ref().expect("the simulator logs Ω̇");
    for i in 0..4 {
        omega[i] = s.omega[i][k];
        omega_dot[i] = logged_dot[i][k];
    }
}

/// `trim_moment=0.02,0.02,0.01` (f = 0.5 Hz) on a 30 s flight, against the same flight
/// without it. The attitude loop (k_att e + k_rate ė per axis, no integrator) sees the
/// trim M as I ë + k_rate I ė + k_att I e = M, so for a tone of angular frequency ω, with
/// D = k_att − ω² + i k_rate ω:
///
/// - the attitude moves by |M|/(I |D|): the controller holds it (about 1° RMS here);
/// - the rotors' moment (logged moment minus trim) changes by I ë − M = −M (1 + ω²/D),
///   whose part in phase with M is −(1 + ω² Re D/|D|²) ≈ −1.01 to −1.07 over the tones.
///
/// Checked per axis: the RMS attitude difference within a factor 2 of its prediction
/// (summed over the tones as √(Σ a²/2); the position loop also re-aims the thrust, which
/// the prediction leaves out), and the regression slope of the rotors' moment change on
/// the trim within 0.1 of its prediction and of −1 (both series low-passed at 2 Hz, which
/// keeps the tones, |H|² ≥ 0.996, and removes a 250 Hz yaw chatter both flights have near
/// t = 17 s). The logged moment contains the trim: its RMS over the flight is the
/// parameter within 35 % (8 tones with periods up to 20 s, in 30 s).
#[test]
fn trim_moment_is_trimmed_by_the_rotors_and_logged() {
    let cfg = FlightConfig {
        duration: 30.0,
        ..Default::default()
    };
    let rms_param = [0.02, 0.02, 0.01];
    let plain = flight(&[], &cfg, 1);
    let trimmed = flight(&["trim_moment=0.02,0.02,0.01"], &cfg, 1);
    let trim = TrimMoment::new(rms_param, 0.5, 1);
    let (a, b) = (&plain.samples, &trimmed.samples);
    let len = a.len();
    // Body-axis rotation vector of the trimmed attitude relative to the plain one.
    let quat = |s: &SampleChunk, k: usize| {
        let q = s
            .attitude
            .as_ref()
            .expect("the simulator logs the attitude");
        UnitQuaternion::from_quaternion(Quaternion::new(q[0][k], q[1][k], q[2][k], q[3][k]))
    };
    let turn: Vec<_> = (0..len)
        .map(|k| (quat(a, k).inverse() * quat(b, k)).scaled_axis())
        .collect();
    let gains = Gains::for_time_scale(1.0);
    let inertia = [0.011, 0.012, 0.021];
    let lp = |x: &[f64]| smooth(x, 2, 2.0, cfg.log_rate).unwrap();
    for axis in 0..3 {
        let (k_att, k_rate) = if axis < 2 {
            (gains.attitude, gains.rate)
        } else {
            (gains.yaw, gains.yaw_rate)
        };
        let tone = rms_param[axis] * (2.0f64 / 8.0).sqrt();
        let (mut want_turn, mut want_slope) = (0.0, 0.0);
        for f in trim.frequencies(axis) {
            let w = std::f64::consts::TAU * f;
            let re = k_att - w * w;
            let den2 = re * re + (k_rate * w).powi(2);
            want_turn += tone * tone / (inertia[axis] * inertia[axis] * den2) / 2.0;
            want_slope += (-1.0 - w * w * re / den2) / 8.0;
        }
        let want_turn = want_turn.sqrt();
        let got_turn = rms(turn.iter().map(|v| v[axis]));
        let m: Vec<f64> = a.t.iter().map(|t| trim.at(*t)[axis]).collect();
        let d_rotor: Vec<f64> = (0..len)
            .map(|k| b.wrench[3 + axis][k] - m[k] - a.wrench[3 + axis][k])
            .collect();
        let m_rms = rms(m.iter().copied());
        let (lp_d, lp_m) = (lp(&d_rotor), lp(&m));
        let slope = lp_d.iter().zip(&lp_m).map(|(d, m)| d * m).sum::<f64>()
            / lp_m.iter().map(|m| m * m).sum::<f64>();
        println!(
            "axis {axis}: trim RMS {m_rms:.4} N m (parameter {}); attitude change RMS {:.3} deg (predicted {:.3}); rotor moment change per unit trim {slope:.4} (predicted {want_slope:.4})",
            rms_param[axis],
            got_turn.to_degrees(),
            want_turn.to_degrees(),
        );
        assert!((m_rms / rms_param[axis] - 1.0).abs() < 0.35, "axis {axis}");
        assert!((0.5..2.0).contains(&(got_turn / want_turn)), "axis {axis}");
        assert!((slope - want_slope).abs() < 0.1 && (slope + 1.0).abs() < 0.1);
    }
}

/// `smoothed_loads=5` (order 2): the flight is the same, every column but the loads is
/// byte-identical, and the loads (`fx..mz`, `ax..az`) are the plain flight's through the
/// independent filtfilt of `sim::filter` (tolerance 1e-12 relative). The size of the
/// effect: the roll/pitch excitation (0.6–2.2 Hz) and the rotor loads above 5 Hz lose
/// a measurable share of the moments, printed and bounded below by 1 %.
#[test]
fn smoothed_loads_filter_the_logged_loads_only() {
    let cfg = FlightConfig {
        duration: 30.0,
        ..Default::default()
    };
    let plain = flight(&[], &cfg, 3);
    let smoothed = flight(&["smoothed_loads=5"], &cfg, 3);
    let (a, b) = (&plain.table, &smoothed.table);
    assert_eq!(a.columns.len(), b.columns.len());
    for ((name, x), (_, y)) in a.columns.iter().zip(&b.columns) {
        let is_load =
            ["fx", "fy", "fz", "mx", "my", "mz", "ax", "ay", "az"].contains(&name.as_str());
        if !is_load {
            assert_eq!(x, y, "{name}");
            continue;
        }
        let want = smooth(x, 2, 5.0, cfg.log_rate).unwrap();
        let scale = rms(x.iter().copied());
        for (u, v) in y.iter().zip(&want) {
            assert!((u - v).abs() <= 1e-12 * scale, "{name}");
        }
        let change = rms(x.iter().zip(y).map(|(u, v)| u - v)) / scale;
        println!("{name}: RMS change {change:.4} of its RMS");
        if name.starts_with('m') {
            assert!(change > 0.01, "{name}: {change}");
        }
    }
}

/// `rotor_speed_lag=0.02` with exact sensors: the dynamics are those of the plain flight
/// (same wrench), the logged speed y obeys y' = (Ω − y)/τ with y' the logged Ω̇ and Ω the
/// plain flight's logged speed (both are the state at the same step: exact but for the
/// 1e-6 eRPM quantisation q of the exact sensors, |error| ≤ q/τ = 7.5e-7 rad/s²), and
/// the logged Ω̇ is the derivative of the logged speed. A central difference at 100 Hz
/// and the plain log run through an independent first-order lag (input linear between
/// log samples, not steps) agree with the logged values within 2 % of the RMS of Ω̇ and
/// 1 % of the RMS lag (measured 0.3–0.5 % each: the O(h²) errors of the 10 ms grid).
#[test]
fn rotor_speed_lag_is_a_first_order_lag_of_the_logged_speed() {
    let tau = 0.02;
    let cfg = FlightConfig {
        duration: 20.0,
        sensors: exact_sensors(),
        ..Default::default()
    };
    let plain = flight(&[], &cfg, 5).samples;
    let lagged = flight(&["rotor_speed_lag=0.02"], &cfg, 5).samples;
    assert_eq!(plain.wrench, lagged.wrench);
    let h = 1.0 / cfg.log_rate;
    for i in 0..4 {
        let lagged_dot = lagged.omega_dot.as_ref().expect("the simulator logs Ω̇");
        let (x, y, yd) = (&plain.omega[i], &lagged.omega[i], &lagged_dot[i]);
        let len = x.len();
        let yd_rms = rms(yd.iter().copied());
        let ode = (0..len)
            .map(|k| ((x[k] - y[k]) / tau - yd[k]).abs())
            .fold(0.0, f64::max);
        let diff = rms((1..len - 1).map(|k| (y[k + 1] - y[k - 1]) / (2.0 * h) - yd[k]));
        let mut relagged = vec![x[0]];
        for k in 1..len {
            let next = lag_step(relagged[k - 1], x[k - 1], x[k], h, tau);
            relagged.push(next);
        }
        let relag = rms(relagged.iter().zip(y).map(|(a, b)| a - b));
        let lag_rms = rms(x.iter().zip(y).map(|(a, b)| a - b));
        println!(
            "rotor {}: RMS(Ω − y) {lag_rms:.3} rad/s, RMS y' {yd_rms:.1} rad/s²; largest ODE error {ode:.2e} rad/s²; RMS error of the central difference {diff:.2} rad/s², of the re-lagged speed {relag:.4} rad/s",
            i + 1,
        );
        let q = 1e-6 * std::f64::consts::TAU / 60.0 / 7.0;
        assert!(ode <= q / tau * (1.0 + 1e-9), "{ode}");
        assert!(diff < 0.02 * yd_rms);
        assert!(relag < 0.01 * lag_rms);
        assert!(lag_rms > 1.0, "the lag is visible: {lag_rms}");
    }
}

/// Thrust overshoot after a step in Ω with inflow lag τ = 20 ms, in hover: at 0+ the
/// inflow is still the hover value, so the thrust is the blade-element thrust at
/// (1.1 Ω_h, ν_h) (checked against `loads_at_inflow` directly, 1e-12); the inflow state
/// then relaxes as ν_qs + (ν_h − ν_qs) e^(−t/τ) (RK4 at τ/100 in this test, 1e-9 m/s),
/// the thrust excess falls to e^(−1) of its start at t = τ (within 3 %: T is nonlinear in
/// ν over the step), and the end value is the quasi-steady wrench (1e-9 relative).
#[test]
fn inflow_lag_overshoots_a_rotor_speed_step_with_its_time_constant() {
    let tau = 0.02;
    let m = model(&["inflow_lag=0.02"]);
    let w_h = m.hover_omega;
    let step = [1.1 * w_h; 4];
    let mut inflow = m.inflow_states();
    let mut nu_h = [0.0; 4];
    m.wrench_lagged_inflow(&at(&[w_h; 4]), &mut inflow, &[0.0; 4], &mut nu_h);
    let mut nu_qs = [0.0; 4];
    let t0 = -m.wrench_lagged_inflow(&at(&step), &mut inflow, &nu_h, &mut nu_qs)[2];
    let t_end = -m.wrench(&at(&step), &mut inflow)[2];
    let t_hover = -m.wrench(&at(&[w_h; 4]), &mut inflow)[2];
    // Independent: the four rotors' blade thrust at the new speed and the old inflow.
    let blade: f64 = (0..4)
        .map(|i| {
            let kin = RotorKinematics {
                omega: step[i],
                spin: m.vehicle.rotors()[i].spin,
                hub_velocity: [0.0; 3],
                body_rates: [0.0; 3],
            };
            -m.rotor.loads_at_inflow(&kin, nu_h[i], false).force[2]
        })
        .sum();
    assert!((t0 - blade).abs() < 1e-12 * t0);
    assert!(t0 > t_end && t_end > t_hover);
    // Integrate ν̇ = (ν_qs − ν)/τ to t = τ and on to 10 τ.
    let h = tau / 100.0;
    let mut nu = nu_h;
    let mut t_tau = 0.0;
    let mut scratch = [0.0; 4];
    for n in 1..=1000 {
        let mut f = |nu: &[f64; 4]| {
            m.wrench_lagged_inflow(&at(&step), &mut inflow, nu, &mut scratch);
            [0, 1, 2, 3].map(|i| (scratch[i] - nu[i]) / tau)
        };
        let k1 = f(&nu);
        let k2 = f(&[0, 1, 2, 3].map(|i| nu[i] + 0.5 * h * k1[i]));
        let k3 = f(&[0, 1, 2, 3].map(|i| nu[i] + 0.5 * h * k2[i]));
        let k4 = f(&[0, 1, 2, 3].map(|i| nu[i] + h * k3[i]));
        nu = [0, 1, 2, 3].map(|i| nu[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        let t = n as f64 * h;
        for i in 0..4 {
            let exact = nu_qs[i] + (nu_h[i] - nu_qs[i]) * (-t / tau).exp();
            assert!((nu[i] - exact).abs() < 1e-9, "t {t}: {} vs {exact}", nu[i]);
        }
        if n == 100 {
            t_tau = -m.wrench_lagged_inflow(&at(&step), &mut inflow, &nu, &mut scratch)[2];
        }
    }
    let t_last = -m.wrench_lagged_inflow(&at(&step), &mut inflow, &nu, &mut scratch)[2];
    let ratio = (t_tau - t_end) / (t0 - t_end);
    println!(
        "hover thrust {t_hover:.4} N, step: 0+ {t0:.4} N, at τ {t_tau:.4} N, steady {t_end:.4} N; excess ratio at τ {ratio:.4} (e^-1 = 0.3679); ν_h {:.3} → ν_qs {:.3} m/s",
        nu_h[0], nu_qs[0]
    );
    assert!((ratio / (-1f64).exp() - 1.0).abs() < 0.03);
    // After 10 τ the excess is e^(−10) = 4.5e-5 of its start.
    assert!((t_last - t_end).abs() < 1e-4 * (t0 - t_end));
}

/// With τ → 0 the lagged flight tends to the quasi-steady one: 4 s at a 0.5 ms step,
/// τ = 0.5 ms and 1 ms. The largest change of the logged wrench is small (F_z within
/// 0.1 % of the weight at τ = 0.5 ms) and halves with τ (ratio 1.6–2.4: first order in τ).
#[test]
fn inflow_lag_tends_to_quasi_steady_as_tau_shrinks() {
    let cfg = FlightConfig {
        duration: 4.0,
        step: 0.0005,
        ..Default::default()
    };
    let plain = flight(&[], &cfg, 7).samples;
    let weight = 1.2 * 9.80665;
    let change = |tau: &str| {
        let lagged = flight(&[&format!("inflow_lag={tau}")], &cfg, 7).samples;
        (0..plain.len())
            .map(|k| (lagged.wrench[2][k] - plain.wrench[2][k]).abs())
            .fold(0.0, f64::max)
    };
    let (small, large) = (change("0.0005"), change("0.001"));
    println!("largest ΔF_z: τ = 0.5 ms {small:.5} N, τ = 1 ms {large:.5} N (weight {weight:.3} N)");
    assert!(small < 0.001 * weight);
    assert!((1.6..2.4).contains(&(large / small)), "{}", large / small);
}

/// `inflow_lag=0.01` on a 30 s flight logged at 500 Hz with exact sensors: from each
/// logged state the test computes the rotors' quasi-steady inflow ν_qs, runs it through
/// its own first-order lag (exact for ν_qs linear between samples) and evaluates the
/// wrench at that inflow. That prediction matches the logged F_z and M_z to within 1 % of
/// the lag's own effect (logged minus quasi-steady; measured 0.07 % and 0.1 %: the
/// linear interpolation against the flight's RK4), which is printed with its size.
#[test]
fn inflow_lag_in_a_flight_matches_an_independent_lag_of_the_quasi_steady_inflow() {
    let tau = 0.01;
    let cfg = FlightConfig {
        duration: 30.0,
        log_rate: 500.0,
        sensors: exact_sensors(),
        ..Default::default()
    };
    let m = model(&["inflow_lag=0.01"]);
    let log = fly(&m, &cfg, 2).unwrap();
    let s = &log.samples;
    let h = 1.0 / cfg.log_rate;
    let mut inflow = m.inflow_states();
    let (mut omega, mut omega_dot) = ([0.0; 4], [0.0; 4]);
    let mut nu = [0.0; 4];
    let mut nu_qs_prev = [0.0; 4];
    let mut effect = [Vec::new(), Vec::new()];
    let mut miss = [Vec::new(), Vec::new()];
    for k in 0..s.len() {
        input(&log, k, &mut omega, &mut omega_dot);
        let x = TruthInput {
            velocity: [0, 1, 2].map(|j| s.velocity[j][k]),
            rates: [0, 1, 2].map(|j| s.rates[j][k]),
            omega: &omega,
            omega_dot: &omega_dot,
            height: None,
            down_row: None,
        };
        let mut nu_qs = [0.0; 4];
        m.wrench_lagged_inflow(&x, &mut inflow, &nu, &mut nu_qs);
        if k == 0 {
            nu = nu_qs;
        } else {
            for i in 0..4 {
                nu[i] = lag_step(nu[i], nu_qs_prev[i], nu_qs[i], h, tau);
            }
        }
        nu_qs_prev = nu_qs;
        let predicted = m.wrench_lagged_inflow(&x, &mut inflow, &nu, &mut nu_qs);
        let quasi_steady = m.wrench(&x, &mut inflow);
        for (j, c) in [2, 5].into_iter().enumerate() {
            effect[j].push(s.wrench[c][k] - quasi_steady[c]);
            miss[j].push(s.wrench[c][k] - predicted[c]);
        }
    }
    for (j, (name, c)) in [("Fz", 2), ("Mz", 5)].into_iter().enumerate() {
        let size = rms(effect[j].iter().copied());
        let left = rms(miss[j].iter().copied());
        let mean = s.wrench[c].iter().sum::<f64>() / s.len() as f64;
        let spread = rms(s.wrench[c].iter().map(|v| v - mean));
        println!(
            "{name}: RMS of the lag's effect {size:.5}, unexplained {left:.6} ({:.4} of it); the load's own RMS about its mean {spread:.4}",
            left / size
        );
        assert!(left < 0.01 * size, "{name}");
    }
}

/// The effects that need time are refused in sweeps, with the reason.
#[test]
fn time_effects_are_refused_in_sweeps() {
    for e in [
        "trim_moment=0.01,0.01,0.01",
        "smoothed_loads=5",
        "rotor_speed_lag=0.01",
        "inflow_lag=0.01",
    ] {
        let opts = SimulateOptions {
            vehicle: VehicleChoice::Example("quad_x".into()),
            rotor_file: None,
            mode: Mode::Sweep {
                design: mrsysid::internals::sim::test_matrix::Design::LatinHypercube,
                points: 5,
            },
            effects: vec![e.parse().unwrap()],
            seed: 1,
        };
        let err = simulate(&opts).unwrap_err().to_string();
        assert!(err.contains("needs `--mode flight`"), "{e}: {err}");
    }
    // A smoothing cut-off at or above half the log rate, and an inflow lag shorter than
    // the integration step, are refused before flying.
    let cfg = FlightConfig {
        duration: 1.0,
        ..Default::default()
    };
    let e = fly(&model(&["smoothed_loads=60"]), &cfg, 1)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("smoothed_loads") && e.contains("half the sample rate"),
        "{e}"
    );
    let e = fly(&model(&["inflow_lag=0.001"]), &cfg, 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("inflow_lag") && e.contains("step"), "{e}");
}
