//! Each candidate effect's columns reproduce its effect exactly in the closed-form world
//! (per-rotor Eq. 5 loads summed over the airframe), so a recovered parameter means what
//! its name says. Tolerance 1e-9 relative to the effect's own size: both sides are a few
//! dozen products; a wrong sign, lever arm or rotor shows at ≥ 1e-2.

mod closed_form_common;

use closed_form_common::{BLADE, vehicle};
use mrsysid::Sample;
use mrsysid::internals::airframe::closed_form_wrench;
use mrsysid::internals::diagnose::{Candidate, CandidateContext, EffectKind, library};
use mrsysid::internals::util::cross;
use mrsysid::internals::util::quat_to_matrix;
use mrsysid::vehicle::{Preset, Rotor, Vehicle};
use mrsysid::{ModelOptions, ModelStructure};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

fn samples(n_rotors: usize, n: usize) -> Vec<Sample> {
    let mut rng = StdRng::seed_from_u64(3);
    (0..n)
        .map(|_| Sample {
            velocity: [
                rng.random_range(-15.0..15.0),
                rng.random_range(-15.0..15.0),
                rng.random_range(-3.0..12.0),
            ],
            rates: [
                rng.random_range(-8.0..8.0),
                rng.random_range(-8.0..8.0),
                rng.random_range(-4.0..4.0),
            ],
            omega: (0..n_rotors)
                .map(|_| rng.random_range(1500.0..2500.0))
                .collect(),
            omega_dot: (0..n_rotors)
                .map(|_| rng.random_range(-3000.0..3000.0))
                .collect(),
            height: Some(rng.random_range(0.0..0.5)),
            attitude: Some({
                let q: [f64; 4] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
                let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
                q.map(|c| c / n)
            }),
            ..Sample::default()
        })
        .collect()
}

/// Thrust of each rotor (N) from the closed form at its Eq. 18 hub velocity.
fn rotor_thrusts(v: &Vehicle, s: &Sample) -> Vec<f64> {
    (0..v.rotor_count())
        .map(|i| -rotor_force(v, s, i, false)[2])
        .collect()
}

/// Truth wrench with each rotor's thrust changed by `dt[i]` (N).
fn with_thrust_change(v: &Vehicle, base: [f64; 6], dt: &[f64]) -> [f64; 6] {
    let mut w = base;
    for (r, d) in v.rotors().iter().zip(dt) {
        w[2] -= d;
        w[3] -= r.y * d;
        w[4] += r.x * d;
    }
    w
}

/// Largest |model − truth| relative to the largest |truth − base| over the samples, for
/// the structure extended by candidate `kind` with parameters `values`.
fn check(
    v: &Vehicle,
    kind: EffectKind,
    values: &[f64],
    truth: impl Fn(&Sample, [f64; 6]) -> [f64; 6],
) -> f64 {
    check_candidate(v, |c| c.kind == kind, values, truth)
}

/// As [`check`] for the first candidate `pick` accepts.
fn check_candidate(
    v: &Vehicle,
    pick: impl Fn(&Candidate) -> bool,
    values: &[f64],
    truth: impl Fn(&Sample, [f64; 6]) -> [f64; 6],
) -> f64 {
    let base = ModelStructure::eq22(v, ModelOptions::default());
    let lumped = BLADE.lumped_parameters(v.props.rotor_radius);
    let theta: Vec<f64> = base
        .params
        .iter()
        .map(|p| lumped.value(&p.name).unwrap())
        .collect();
    // The lever arm's force with the same exact values, column by column.
    let force_theta: Vec<f64> = base
        .columns
        .iter()
        .map(|c| theta[c.param.index()])
        .collect();
    let ctx = CandidateContext {
        vehicle: v,
        structure: &base,
        theta: &theta,
        force_theta: &force_theta,
        has_height: true,
        has_omega_dot: true,
        has_omega_ddot: false,
        has_attitude: true,
        has_slow_thrust: false,
        hover_thrust_coefficient: None,
    };
    let cand = library(&ctx)
        .into_iter()
        .find(|c| pick(c))
        .expect("candidate present");
    let mut extended = base.clone();
    let idx = cand.add_to(&mut extended);
    let mut full = theta.clone();
    full.resize(extended.params.len(), 0.0);
    for (&i, &x) in idx.iter().zip(values) {
        full[i.index()] = x;
    }
    let (mut err, mut size) = (0.0_f64, 0.0_f64);
    for s in samples(v.rotor_count(), 300) {
        let b = closed_form_wrench(v, &BLADE, s.velocity, s.rates, &s.omega, &s.omega_dot);
        let t = truth(&s, b);
        let y = extended.predict(&full, &s).unwrap();
        for a in 0..6 {
            err = err.max((y[a] - t[a]).abs());
            size = size.max((t[a] - b[a]).abs());
        }
    }
    assert!(size > 0.0, "{}: the effect changes nothing", cand.name);
    err / size
}

/// Rotor `i`'s force (N) in the closed form, body axes: (−H, S, −T), at its Eq. 18 hub
/// velocity, with the yaw rate's in-plane share (Eq. 17) when `yaw_rate`.
fn rotor_force(v: &Vehicle, s: &Sample, i: usize, yaw_rate: bool) -> [f64; 3] {
    let r = v.rotors()[i];
    let yaw = if yaw_rate { s.rates[2] } else { 0.0 };
    let hub = [
        s.velocity[0] - yaw * r.y,
        s.velocity[1] + yaw * r.x,
        s.velocity[2] + s.rates[0] * r.y - s.rates[1] * r.x,
    ];
    let l = BLADE.loads(
        v.props.air_density,
        v.props.rotor_radius,
        s.omega[i],
        hub,
        v.hover_induced_velocity(),
    );
    [-l.hub_force, l.side_force, -l.thrust]
}

#[test]
fn weak_rotor_force_columns_are_exact() {
    for preset in [Preset::QuadX, Preset::HexaPlus] {
        let v = vehicle(preset);
        // Rotor 1's candidate: thrust −8 %, in-plane force +5 % (at the hub's in-plane
        // velocity with the yaw rate's share), with their lever-arm moments, torque
        // unchanged.
        let e = check(
            &v,
            EffectKind::RotorAsymmetry,
            &[-0.08, 0.05, 0.0],
            |s, b| {
                let mut df = rotor_force(&v, s, 0, true).map(|f| 0.05 * f);
                df[2] = -0.08 * rotor_force(&v, s, 0, false)[2];
                let dm = cross(v.hub_position(0), df);
                std::array::from_fn(|k| b[k] + if k < 3 { df[k] } else { dm[k - 3] })
            },
        );
        // Not 1e-9: the C_H_mub_mu V_h term takes the body's in-plane speed, as Eq. 22
        // does, where the closed form has the hub's (first order in r x_i/V_h; measured
        // 8e-5). The yaw share with the wrong sign shows at 1e-3.
        assert!(e < 2e-4, "{preset:?}: {e:e}");
    }
}

#[test]
fn ground_effect_columns_are_exact() {
    let v = vehicle(Preset::QuadX);
    let (r, h) = (v.props.rotor_radius, v.props.hub_height);
    let e = check(&v, EffectKind::GroundEffect, &[1.0], |s, b| {
        let g = mrsysid::internals::model::ground_effect_factor(r, s.height.unwrap() + h);
        let d: Vec<f64> = rotor_thrusts(&v, s).iter().map(|t| g * t).collect();
        with_thrust_change(&v, b, &d)
    });
    assert!(e < 1e-9, "{e:e}");
}

/// Each hub's position relative to the CG under the sample's attitude, NED (m): north,
/// east, and its height above the ground (the CG height less the down component of the
/// hub's body offset (x_i, y_i, −h)).
fn hubs_over_ground(v: &Vehicle, s: &Sample) -> Vec<[f64; 3]> {
    let body_to_ned = quat_to_matrix(s.attitude.unwrap());
    let h = v.props.hub_height;
    v.rotors()
        .iter()
        .map(|rotor| {
            let hub = [rotor.x, rotor.y, -h];
            let ned: [f64; 3] =
                std::array::from_fn(|k| (0..3).map(|c| body_to_ned[k][c] * hub[c]).sum());
            [ned[0], ned[1], s.height.unwrap() - ned[2]]
        })
        .collect()
}

/// Asserts the ground-effect form `name` exact (1e-9) against each rotor's thrust
/// times `gain(R, hubs, i)` (the hubs as [`hubs_over_ground`] gives them), over random
/// tilts on a quad× and a hexa+.
fn assert_ground_effect_form_exact(name: &str, gain: impl Fn(f64, &[[f64; 3]], usize) -> f64) {
    for preset in [Preset::QuadX, Preset::HexaPlus] {
        let v = vehicle(preset);
        let r = v.props.rotor_radius;
        let e = check_candidate(
            &v,
            |c| c.name == name,
            &[1.0],
            |s, b| {
                let hubs = hubs_over_ground(&v, s);
                let d: Vec<f64> = rotor_thrusts(&v, s)
                    .iter()
                    .enumerate()
                    .map(|(i, t)| gain(r, &hubs, i) * t)
                    .collect();
                with_thrust_change(&v, b, &d)
            },
        );
        assert!(e < 1e-9, "{name}, {preset:?}: {e:e}");
    }
}

#[test]
fn per_rotor_ground_effect_columns_are_exact() {
    // Each rotor at its own height: the CG height less the down component (NED) of the
    // hub's body offset (x_i, y_i, −h) under the sample's attitude, for random tilts.
    assert_ground_effect_form_exact("ground effect, per-rotor height", |r, hubs, i| {
        mrsysid::internals::model::ground_effect_factor(r, hubs[i][2])
    });
}

#[test]
fn multirotor_ground_effect_columns_are_exact() {
    // Each rotor's wake as a point source of strength Q = πR²ν at its hub, mirrored
    // below the ground (the image method): the upwash of a source at distance ρ is
    // Q/(4πρ²) along the line from it, so its vertical part at hub i from the image of
    // hub j is (R²ν/4) Δz/ρ³. Summed over all images (rotor i's own gives
    // Cheeseman–Bennett's (R/4z)²) it is s_i ν, and thrust rises by s_i/(1 − s_i) of
    // itself. Computed here from the hubs' positions in NED space (hub heights held at
    // ≥ R/2 as the product does).
    assert_ground_effect_form_exact("ground effect, multirotor", |r, hubs, i| {
        let held = |[n, e, z]: [f64; 3]| [n, e, z.max(r / 2.0)];
        let hub = held(hubs[i]);
        let q = std::f64::consts::PI * r * r;
        let upwash: f64 = (hubs.iter())
            .map(|&other| {
                let [n, e, z] = held(other);
                let rel = [hub[0] - n, hub[1] - e, hub[2] + z];
                let rho = rel.iter().map(|c| c * c).sum::<f64>().sqrt();
                q / (4.0 * std::f64::consts::PI * rho * rho) * rel[2] / rho
            })
            .sum();
        upwash / (1.0 - upwash)
    });
}

#[test]
fn second_order_inflow_columns_are_exact() {
    // ΔT_i = ρπR² (c₁ V_h w_i + c₂ w_i²) at each rotor's Eq. 18 axial hub velocity
    // w_i = w + p y_i − q x_i, summed over the airframe with each rotor's lever arm (a
    // layout with rotors off the axes and one with rotors on them).
    for preset in [Preset::QuadX, Preset::HexaPlus] {
        let v = vehicle(preset);
        let k = v.props.air_density * std::f64::consts::PI * v.props.rotor_radius.powi(2);
        let (c1, c2) = (0.03, -0.02);
        let e = check(&v, EffectKind::SecondOrderInflow, &[c1, c2], |s, b| {
            let vh = s.velocity[0].hypot(s.velocity[1]);
            let d: Vec<f64> = v
                .rotors()
                .iter()
                .map(|r| {
                    let w_i = s.velocity[2] + s.rates[0] * r.y - s.rates[1] * r.x;
                    k * (c1 * vh * w_i + c2 * w_i * w_i)
                })
                .collect();
            with_thrust_change(&v, b, &d)
        });
        assert!(e < 1e-9, "{preset:?}: {e:e}");
    }
}

/// A quadrotor on a rectangle whose rotor centroid is off the CG (every layout sum Σy_i,
/// Σx_i y_i, Σx_i(x_i² + y_i²) non-zero), with the test vehicle's properties.
fn rectangle() -> Vehicle {
    Vehicle::from_rotors(
        "rectangle off the CG",
        vehicle(Preset::QuadX).props.clone(),
        [
            (0.16, 0.23, 1.0),
            (-0.11, -0.19, 1.0),
            (0.16, -0.19, -1.0),
            (-0.11, 0.23, -1.0),
        ]
        .map(|(x, y, spin)| Rotor { x, y, spin })
        .to_vec(),
    )
    .unwrap()
}

#[test]
fn yaw_rate_edgewise_thrust_columns_are_exact() {
    // ΔT_i = ρπR² C_T_mu2 (V_h,i² − V_h²), Eq. 22c's edgewise thrust term at each hub's
    // own in-plane velocity (u − r y_i, v + r x_i) (Eq. 17), computed rotor by rotor
    // and summed with each rotor's lever arm; the candidate's columns are sums over the
    // layout. Layouts: rotors off the axes, on them, and a rectangle whose rotor centroid
    // is off the CG (every sum Σy_i, Σx_i y_i, Σx_i(x_i² + y_i²) non-zero). A wrong lever
    // sign or a missing r² term shows at ≥ 1e-1.
    for v in [
        vehicle(Preset::QuadX),
        vehicle(Preset::HexaPlus),
        rectangle(),
    ] {
        let k = v.props.air_density * std::f64::consts::PI * v.props.rotor_radius.powi(2);
        let c = 0.4;
        let e = check(&v, EffectKind::YawRateHubAirspeed, &[c], |s, b| {
            let [u, w_v, _] = s.velocity;
            let r = s.rates[2];
            let d: Vec<f64> = v
                .rotors()
                .iter()
                .map(|p| {
                    let (ui, vi) = (u - r * p.y, w_v + r * p.x);
                    k * c * (ui * ui + vi * vi - u * u - w_v * w_v)
                })
                .collect();
            with_thrust_change(&v, b, &d)
        });
        assert!(e < 1e-9, "{}: {e:e}", v.name);
    }
}

#[test]
fn cg_offset_columns_are_first_order_exact() {
    // The truth: the same airframe with every hub at r_i − d from the CG, in the closed
    // form (moments about the CG, each rotor's inflow from its own hub's climb velocity
    // w + p y_i − q x_i, Eq. 18). The candidate is first order in d: the lever arms
    // F̂ × d, and the climb velocity change q dx − p dy through the model's gradient in
    // w. The forces are linear in the hub positions, so exact; the moments leave
    // (force change) × d, second order: 2.3e-3 of the effect here (measured, and a
    // sixteenth of the moments' error at a quarter of d). The lever arms alone leave
    // 0.29 (measured): F_z's inflow change, which the bound catches.
    let v = vehicle(Preset::QuadX);
    let d = [0.004, -0.008];
    let rotors = v
        .rotors()
        .iter()
        .map(|r| Rotor {
            x: r.x - d[0],
            y: r.y - d[1],
            ..*r
        })
        .collect();
    let shifted = Vehicle::from_rotors("CG off", v.props.clone(), rotors).unwrap();
    let e = check(&v, EffectKind::CgOffset, &d, |s, _| {
        closed_form_wrench(
            &shifted,
            &BLADE,
            s.velocity,
            s.rates,
            &s.omega,
            &s.omega_dot,
        )
    });
    assert!(e < 5e-3, "{e:e}");
}

#[test]
fn quadratic_drag_columns_are_exact() {
    let v = vehicle(Preset::QuadPlus);
    let cda = [0.01, 0.02, 0.03];
    let e = check(&v, EffectKind::QuadraticDrag, &cda, |s, b| {
        let mut w = b;
        for k in 0..3 {
            w[k] -= 0.5 * 1.225 * cda[k] * s.velocity[k] * s.velocity[k].abs();
        }
        w
    });
    assert!(e < 1e-9, "{e:e}");
}

#[test]
fn drag_off_the_cg_columns_are_exact() {
    // Drag along the airflow, F = −ρ/2 |V| (A_x u, A_y v, A_z w), acting at a centre of
    // pressure r = (0, 0, z_cp) (body axes, below the CG for z_cp > 0): the wrench gains
    // F and the moment r × F. The candidate's parameters are the three areas and the
    // moment areas z_cp A_y (roll) and z_cp A_x (pitch).
    let v = vehicle(Preset::QuadX);
    let (cda, z_cp) = ([0.01, 0.02, 0.03], -0.04);
    let values = [cda[0], cda[1], cda[2], z_cp * cda[1], z_cp * cda[0]];
    let e = check_candidate(
        &v,
        |c| c.name == "quadratic airframe drag, off the CG",
        &values,
        |s, b| {
            let speed = s.velocity.iter().map(|c| c * c).sum::<f64>().sqrt();
            let f: [f64; 3] =
                std::array::from_fn(|k| -0.5 * 1.225 * cda[k] * s.velocity[k] * speed);
            let m = cross([0.0, 0.0, z_cp], f);
            [
                b[0] + f[0],
                b[1] + f[1],
                b[2] + f[2],
                b[3] + m[0],
                b[4] + m[1],
                b[5] + m[2],
            ]
        },
    );
    assert!(e < 1e-9, "{e:e}");
}

#[test]
fn vertical_linear_drag_column_is_exact() {
    // An airframe drag −D_z w on F_z alone, at the CG: no moment, no rotor speed.
    let v = vehicle(Preset::QuadX);
    let d = 0.4;
    let e = check(&v, EffectKind::VerticalLinearDrag, &[d], |s, b| {
        let mut w = b;
        w[2] -= d * s.velocity[2];
        w
    });
    assert!(e < 1e-9, "{e:e}");
}

#[test]
fn delay_columns_are_first_order_exact() {
    // Loads follow Ω(t + τ) = Ω + τ Ω̇ + O(τ²): the candidate is the first-order term, so
    // its error relative to the effect is O(τ Ω̈/Ω̇), here ~τΩ̇/Ω ≈ 1e-3.
    let v = vehicle(Preset::QuadX);
    let tau = 0.001;
    let e = check(&v, EffectKind::RotorSpeedDelay, &[tau], |s, _| {
        let late: Vec<f64> = s
            .omega
            .iter()
            .zip(&s.omega_dot)
            .map(|(w, wd)| w + tau * wd)
            .collect();
        closed_form_wrench(&v, &BLADE, s.velocity, s.rates, &late, &s.omega_dot)
    });
    assert!(e < 5e-3, "{e:e}");
}

#[test]
fn steady_wind_columns_are_first_order_exact() {
    // The rotors feel the airspeed v − C W, C the NED→body rotation (Rᵀ); the
    // candidate is the first-order term −(∂F/∂v) C W. Its error relative to the effect
    // is O(|W|/|v|) (second-order term over first); with |W| ≈ 0.06 m/s and airspeeds of
    // metres per second, 2e-2 bounds it, while a wrong axis or sign would show as O(1).
    let v = vehicle(Preset::QuadX);
    let wind = [0.05, -0.03, 0.02];
    let e = check(&v, EffectKind::SteadyWind, &wind, |s, _| {
        let r = quat_to_matrix(s.attitude.unwrap());
        let air: [f64; 3] =
            std::array::from_fn(|k| s.velocity[k] - (0..3).map(|j| r[j][k] * wind[j]).sum::<f64>());
        closed_form_wrench(&v, &BLADE, air, s.rates, &s.omega, &s.omega_dot)
    });
    assert!(e < 2e-2, "{e:e}");
}

/// The local-region statistics gather a chunk's active rows from its assembled
/// regressors instead of assembling the active part again; that is exact only while every
/// column of the candidate set (named library and generic pool) is a function of its own
/// sample. Checked bit for bit on a chunk with every signal, over a scattered row subset.
#[test]
fn gathered_rows_equal_the_assembled_part() {
    use mrsysid::Workspace;
    use mrsysid::internals::diagnose::{DiagnoseOptions, candidate_set};
    use mrsysid::internals::sample::{Axis, SampleChunk};
    let v = vehicle(Preset::QuadX);
    let base = ModelStructure::eq22(&v, ModelOptions::default());
    let theta = vec![1e-6; base.params.len()];
    let force_theta = vec![1e-6; base.columns.len()];
    let ctx = CandidateContext {
        vehicle: &v,
        structure: &base,
        theta: &theta,
        force_theta: &force_theta,
        has_height: true,
        has_omega_dot: true,
        has_omega_ddot: false,
        has_attitude: true,
        has_slow_thrust: false,
        hover_thrust_coefficient: None,
    };
    let mut rng = StdRng::seed_from_u64(5);
    let data: Vec<Sample> = samples(v.rotor_count(), 400)
        .into_iter()
        .map(|mut s| {
            s.wrench = std::array::from_fn(|_| rng.random_range(-5.0..5.0));
            s
        })
        .collect();
    let chunk_of = |rows: &[usize]| {
        let mut c = SampleChunk::with_capacity(v.rotor_count(), rows.len(), true);
        rows.iter().for_each(|&i| c.push(&data[i]));
        c
    };
    let all: Vec<usize> = (0..data.len()).collect();
    let chunk = chunk_of(&all);
    let set = candidate_set(&ctx, Some(&chunk), &DiagnoseOptions::default()).unwrap();
    let extended = &set.extended;
    assert!(extended.columns.len() > base.columns.len() + 50);
    let rows: Vec<usize> = all
        .iter()
        .copied()
        .filter(|i| i % 7 < 3 || i % 11 == 0)
        .collect();
    let (mut ws, mut gathered, mut direct) = (
        Workspace::default(),
        Workspace::default(),
        Workspace::default(),
    );
    extended.assemble(&chunk, &mut ws).unwrap();
    let every = vec![true; extended.columns.len()];
    ws.gather(&chunk, &rows, &every, &mut gathered);
    extended.assemble(&chunk_of(&rows), &mut direct).unwrap();
    assert_eq!(gathered.len(), rows.len());
    for j in 0..extended.columns.len() {
        assert_eq!(
            gathered.column(j),
            direct.column(j),
            "{}",
            extended.columns[j].label
        );
    }
    for axis in Axis::ALL {
        assert_eq!(gathered.output(axis), direct.output(axis));
        assert_eq!(gathered.measured_range(axis), direct.measured_range(axis));
    }
    for k in 0..6 {
        assert_eq!(gathered.motion_range(k), direct.motion_range(k));
    }
}
