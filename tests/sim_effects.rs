//! Every undeclared effect changes the wrench (or the log) as its formula says, in sign
//! and size. Wrench effects are checked against the effect-free truth at the same state:
//! the formulas act on the per-rotor blade-element loads, so the differences are exact up
//! to round-off (tolerance 1e-9 relative to the quantity compared).

use std::path::Path;

use mrsysid::internals::sim::blade_element::{HubLoads, RotorKinematics};
use mrsysid::internals::sim::effects::{EffectError, ground_effect_ratio, vortex_ring_factor};
use mrsysid::internals::sim::flight::{FlightConfig, fly};
use mrsysid::internals::sim::inflow::InflowState;
use mrsysid::internals::sim::{Effect, Effects, RotorFile, TruthInput, TruthModel};
use mrsysid::internals::util::cross;
use mrsysid::vehicle::Vehicle;

fn vehicle() -> Vehicle {
    Vehicle::from_toml_file(Path::new("data/vehicles/quad_x.toml")).unwrap()
}

fn model(effects: &[&str]) -> TruthModel {
    let v = vehicle();
    let list = effects
        .iter()
        .map(|e| e.parse::<Effect>().unwrap())
        .collect();
    TruthModel::new(&v, &RotorFile::default(), Effects::new(list, &v).unwrap()).unwrap()
}

struct State {
    velocity: [f64; 3],
    omega: [f64; 4],
    height: Option<f64>,
}

fn wrench(m: &TruthModel, s: &State) -> [f64; 6] {
    m.wrench(
        &TruthInput {
            velocity: s.velocity,
            rates: [0.0; 3],
            omega: &s.omega,
            omega_dot: &[0.0; 4],
            height: s.height,
            down_row: None,
        },
        &mut m.inflow_states(),
    )
}

/// Blade-element loads of rotor `i` alone at zero body rates.
fn rotor(m: &TruthModel, s: &State, i: usize) -> HubLoads {
    let kin = RotorKinematics {
        omega: s.omega[i],
        spin: m.vehicle.rotors()[i].spin,
        hub_velocity: s.velocity,
        body_rates: [0.0; 3],
    };
    m.rotor.loads(&kin, &m.inflow, &mut InflowState::default())
}

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-9 * scale.abs().max(1e-12)
}

fn hover(m: &TruthModel) -> State {
    State {
        velocity: [0.0; 3],
        omega: [m.hover_omega; 4],
        height: None,
    }
}

#[test]
fn ground_effect_raises_thrust_by_cheeseman_bennett() {
    let base = model(&[]);
    let ge = model(&["ground_effect"]);
    let r = base.vehicle.props.rotor_radius;
    let h = base.vehicle.props.hub_height;
    // Hub one radius above ground: T/T∞ = 1/(1 − 1/16) = 1.0667.
    let s = State {
        height: Some(r - h),
        ..hover(&base)
    };
    let ratio = wrench(&ge, &s)[2] / wrench(&base, &s)[2];
    assert!(close(ratio, 16.0 / 15.0, 1.0), "{ratio}");
    // Far away the effect vanishes like (R/4z)²; below R/2 it is capped at 4/3.
    assert!((ground_effect_ratio(1.0, r, 100.0 * r) - 1.0).abs() < 1e-5);
    assert!(close(ground_effect_ratio(1.0, r, 0.01 * r), 4.0 / 3.0, 1.0));
    // Without a height the effect is off.
    let far = hover(&base);
    assert_eq!(wrench(&ge, &far), wrench(&base, &far));
}

#[test]
fn weak_rotor_scales_its_force_and_torque() {
    let base = model(&[]);
    let weak = model(&["weak_rotor=2,0.8,0.7"]);
    let s = State {
        velocity: [6.0, -3.0, 1.0],
        omega: [2100.0, 2200.0, 2300.0, 2000.0],
        height: None,
    };
    let (b, w) = (wrench(&base, &s), wrench(&weak, &s));
    let l = rotor(&base, &s, 1);
    let hub = base.vehicle.hub_position(1);
    let df = l.force.map(|f| -0.2 * f);
    let dm_arm = cross(hub, df);
    let dm = [-0.2 * l.moment[0], -0.2 * l.moment[1], -0.3 * l.moment[2]];
    for k in 0..3 {
        assert!(close(w[k] - b[k], df[k], l.force[2]), "F{k}");
        assert!(
            close(w[3 + k] - b[3 + k], dm[k] + dm_arm[k], l.force[2]),
            "M{k}"
        );
    }
    // Sign: rotor 2 is rear-right (x < 0, y > 0) and loses thrust (ΔT < 0): less lift
    // (ΔF_z > 0), the vehicle rolls towards it (ΔM_x = −y ΔT > 0) and the tail drops
    // (ΔM_y = x ΔT > 0).
    assert!(w[3] - b[3] > 0.0 && w[4] - b[4] > 0.0 && w[2] - b[2] > 0.0);
}

#[test]
fn cg_offset_moves_moments_by_minus_d_cross_f() {
    let base = model(&[]);
    let off = model(&["cg_offset=0.01,-0.02,0.03"]);
    let s = State {
        velocity: [8.0, 2.0, -1.0],
        omega: [2100.0, 2200.0, 2300.0, 2000.0],
        height: None,
    };
    let (b, o) = (wrench(&base, &s), wrench(&off, &s));
    let d = [0.01, -0.02, 0.03];
    let f = [b[0], b[1], b[2]];
    let dm = cross(d, f);
    for k in 0..3 {
        assert!(close(o[k], b[k], b[2]), "F{k}");
        assert!(
            close(o[3 + k] - b[3 + k], -dm[k], b[2]),
            "M{k}: {} vs {}",
            o[3 + k] - b[3 + k],
            -dm[k]
        );
    }
}

#[test]
fn wake_interaction_costs_rear_rotors_thrust() {
    let base = model(&[]);
    let wake = model(&["wake_interaction=0.3"]);
    let nu0 = base.vehicle.hover_induced_velocity();
    let s = State {
        velocity: [12.0, 0.0, 0.0],
        omega: [2200.0; 4],
        height: None,
    };
    let (b, w) = (wrench(&base, &s), wrench(&wake, &s));
    // Flying forward, rotors 2 and 3 (x < 0) sit straight behind 1 and 4: full overlap.
    let loss = 0.3 * 144.0 / (144.0 + nu0 * nu0);
    let t_rear = rotor(&base, &s, 1).force[2] + rotor(&base, &s, 2).force[2];
    assert!(close(w[2] - b[2], -loss * t_rear, t_rear));
    // Less thrust at the rear pitches the nose up: ΔM_y = x ΔT with x < 0, ΔT < 0.
    assert!(w[4] - b[4] > 0.0);
    // Flying diagonally towards rotor 1 (front right), only rotor 3 (rear left) is in a
    // wake (rotor 1's); rotors 2 and 4 miss by ℓ = 0.225 m > 2R.
    let diag = State {
        velocity: [12.0 / 2f64.sqrt(), 12.0 / 2f64.sqrt(), 0.0],
        ..s
    };
    let (b2, w2) = (wrench(&base, &diag), wrench(&wake, &diag));
    let t3 = rotor(&base, &diag, 2).force[2];
    assert!(close(w2[2] - b2[2], -loss * t3, t3));
}

#[test]
fn quadratic_drag_follows_half_rho_cda_v_abs_v() {
    let base = model(&[]);
    let drag = model(&["quadratic_drag=0.01,0.02,0.04"]);
    let s = State {
        velocity: [15.0, -10.0, 3.0],
        omega: [2200.0; 4],
        height: None,
    };
    let (b, d) = (wrench(&base, &s), wrench(&drag, &s));
    let rho = base.vehicle.props.air_density;
    for (k, cda) in [0.01, 0.02, 0.04].into_iter().enumerate() {
        let v = s.velocity[k];
        let expected = -0.5 * rho * cda * v * v.abs();
        assert!(close(d[k] - b[k], expected, expected), "axis {k}");
    }
}

#[test]
fn vortex_ring_loses_thrust_in_descent_near_nu0() {
    let base = model(&[]);
    let vrs = model(&["vortex_ring=0.4"]);
    let nu0 = base.vehicle.hover_induced_velocity();
    // Descending at w = ν0 with no forward speed: the full loss k.
    let s = State {
        velocity: [0.0, 0.0, nu0],
        ..hover(&base)
    };
    // The rotors' share of F_z (airframe drag −D_z w removed) drops by the factor 1 − k.
    let drag = -base.linear_drag[2] * nu0;
    let ratio = (wrench(&vrs, &s)[2] - drag) / (wrench(&base, &s)[2] - drag);
    assert!(close(ratio, 0.6, 1.0), "{ratio}");
    // Forward speed of 2ν0 or climbing removes nearly all of it.
    assert!(vortex_ring_factor(0.4, nu0, 2.0 * nu0, nu0) > 0.99);
    assert!(vortex_ring_factor(0.4, -nu0, 0.0, nu0) > 0.99);
}

#[test]
fn delay_shifts_logged_rotor_speed_and_wind_logs_ground_velocity() {
    let v = vehicle();
    let cfg = FlightConfig {
        duration: 2.0,
        ..Default::default()
    };
    let make = |e: Vec<Effect>| {
        TruthModel::new(&v, &RotorFile::default(), Effects::new(e, &v).unwrap()).unwrap()
    };
    let plain = fly(&make(vec![]), &cfg, 4).unwrap().samples;
    let delayed = fly(&make(vec!["delay=0.05".parse().unwrap()]), &cfg, 4)
        .unwrap()
        .samples;
    // 0.05 s at 100 Hz is 5 log samples; the dynamics are identical, so the delayed log is
    // the plain log shifted (exactly: same history, same quantisation).
    for k in 5..plain.len() {
        for i in 0..4 {
            assert_eq!(delayed.omega[i][k], plain.omega[i][k - 5]);
        }
    }
    assert!((0..4).any(|i| delayed.omega[i][150] != plain.omega[i][150]));
    // Wind: at t = 0 the vehicle is at rest over the ground; the log says u, v, w ≈ 0
    // (within 5 σ of the velocity noise) while the true wrench is that of a 6 m/s
    // headwind, i.e. the model's wrench at air velocity −wind.
    let wind_model = make(vec!["wind=6,0,0".parse().unwrap()]);
    let log = fly(&wind_model, &cfg, 4).unwrap().samples;
    for k in 0..3 {
        assert!(log.velocity[k][0].abs() < 5.0 * 0.03);
    }
    let hover = [wind_model.hover_omega; 4];
    let w = wind_model.wrench(
        &TruthInput {
            velocity: [-6.0, 0.0, 0.0],
            rates: [0.0; 3],
            omega: &hover,
            omega_dot: &[0.0; 4],
            height: None,
            down_row: None,
        },
        &mut wind_model.inflow_states(),
    );
    for k in 0..3 {
        assert!((log.wrench[k][0] - w[k]).abs() < 1e-9 * w[2].abs(), "F{k}");
    }
    assert!(
        w[0] > 0.1,
        "a headwind pushes the vehicle back (+x force on a −x air velocity)"
    );
}

#[test]
fn bad_effect_strings_are_refused_with_the_reason() {
    for (s, needle) in [
        ("warp_drive", "unknown effect"),
        ("weak_rotor=2", "takes"),
        ("weak_rotor=0,0.5", "rotor"),
        ("cg_offset=1,nan,0", "not a finite number"),
        ("ground_effect=9", "(0, 3]"),
        ("delay=-1", "[0, 1]"),
        ("trim_moment=0.01,0.01", "takes"),
        ("trim_moment=0.01,-0.01,0", "my = -0.01"),
        ("trim_moment=0.01,0.01,0.01,0.02", "(0.05, 10] Hz"),
        ("smoothed_loads=0", "must be > 0 Hz"),
        ("smoothed_loads=5,2.5", "whole number 1 to 8"),
        ("smoothed_loads=5,9", "whole number 1 to 8"),
        ("rotor_speed_lag=0", "(0, 1] s"),
        ("rotor_speed_lag", "takes"),
        ("inflow_lag=2", "(0, 1] s"),
    ] {
        let e = s.parse::<Effect>().unwrap_err().to_string();
        assert!(e.contains(needle), "{s}: {e}");
    }
    let v = vehicle();
    let e = Effects::new(vec!["weak_rotor=5,0.5".parse().unwrap()], &v).unwrap_err();
    assert_eq!(
        e,
        EffectError::NoSuchRotor {
            rotor: 5,
            rotors: 4
        }
    );
    assert!(e.to_string().contains("rotor 5 does not exist"), "{e}");
    let twice = vec!["delay=0.1".parse().unwrap(), "delay=0.2".parse().unwrap()];
    let e = Effects::new(twice, &v).unwrap_err();
    assert_eq!(e, EffectError::Repeated { effect: "delay" });
    assert!(e.to_string().contains("more than once"), "{e}");
}

/// Every effect prints in canonical form (all parameters, defaults filled in) and parses
/// back to itself; defaults are those of the module table.
#[test]
fn effects_round_trip_through_their_text() {
    for (text, canonical) in [
        ("ground_effect", "ground_effect=1"),
        ("weak_rotor=2,0.8", "weak_rotor=2,0.8,0.8"),
        ("cg_offset=0.01,-0.02,0.03", "cg_offset=0.01,-0.02,0.03"),
        ("wake_interaction=0.3", "wake_interaction=0.3"),
        ("wake_advance=0.5", "wake_advance=0.5"),
        (
            "quadratic_drag=0.01,0.02,0.04",
            "quadratic_drag=0.01,0.02,0.04",
        ),
        ("vortex_ring=0.4", "vortex_ring=0.4"),
        ("delay=0.02", "delay=0.02"),
        ("wind=3,-1,0.5", "wind=3,-1,0.5"),
        ("flapping=2e-5", "flapping=0.00002"),
        ("dynamic_inflow=1e-5", "dynamic_inflow=0.00001"),
        (
            "trim_moment=0.02,0.02,0.01",
            "trim_moment=0.02,0.02,0.01,0.5",
        ),
        (
            "trim_moment=0.02, 0.02, 0.01, 1.5",
            "trim_moment=0.02,0.02,0.01,1.5",
        ),
        ("smoothed_loads=28.85", "smoothed_loads=28.85,2"),
        ("smoothed_loads=5,4", "smoothed_loads=5,4"),
        ("rotor_speed_lag=0.015", "rotor_speed_lag=0.015"),
        ("inflow_lag=0.005", "inflow_lag=0.005"),
    ] {
        let e: Effect = text.parse().unwrap();
        assert_eq!(e.to_string(), canonical, "{text}");
        assert_eq!(canonical.parse::<Effect>().unwrap(), e, "{canonical}");
    }
    let e: Effect = "trim_moment=0.02,0.02,0.01".parse().unwrap();
    assert_eq!(
        e,
        Effect::TrimMoment {
            rms: [0.02, 0.02, 0.01],
            max_frequency: 0.5
        }
    );
    let e: Effect = "smoothed_loads=28.85".parse().unwrap();
    assert_eq!(
        e,
        Effect::SmoothedLoads {
            cutoff: 28.85,
            order: 2
        }
    );
}
