//! The diagnosis on an independent simulator (`tests/independent/`: its own rotor
//! formula, airframe, controller, sensors and hidden-effect forms; the crate's truth
//! simulator is not used), at one seed: every hidden effect named, and what it leaves.
//! The whole table over many seeds:
//! `cargo run --release --example independent_truth -- 10`.

mod independent;

use independent::effects::Hidden;
use independent::flight::FlightConfig;
use independent::physics::{Airframe, GRAVITY, LoadState, RotorCoefficients, Scale};
use independent::score::{
    Case, DataKind, Naming, Score, data, data_flown, diagnose, effect_size, expected_kind, iris,
    score, vehicle,
};
use independent::surface::FORCE_NOISE;
use mrsysid::Vehicle;
use mrsysid::internals::diagnose::Diagnosis;
use nalgebra::{UnitQuaternion, Vector3};

/// The seed of the harness's first row.
const SEED: u64 = 42_000;

/// The hidden effect of `Hidden::all()` whose label starts with `label`.
fn hidden(label: &str) -> Hidden {
    Hidden::all()
        .into_iter()
        .find(|h| h.label().starts_with(label))
        .expect("a hidden effect")
}

fn run(data_kind: DataKind, effect: Option<Hidden>) -> Diagnosis {
    run_on(
        &vehicle(),
        data_kind,
        effect,
        SEED,
        &FlightConfig::default(),
    )
}

/// The diagnosis of the second airframe's response-surface set with `effect` at [`SEED`].
fn iris_surface(effect: Option<Hidden>) -> Diagnosis {
    run_on(
        &iris(),
        DataKind::Surface,
        effect,
        SEED,
        &FlightConfig::default(),
    )
}

/// The diagnosis of `vehicle`'s data of kind `data_kind` with `effect` at `seed`, a
/// flight flown as `flight` says.
fn run_on(
    vehicle: &Vehicle,
    data_kind: DataKind,
    effect: Option<Hidden>,
    seed: u64,
    flight: &FlightConfig,
) -> Diagnosis {
    let case = Case {
        data: data_kind,
        hidden: effect,
    };
    let d = diagnose(
        vehicle,
        &case.label(),
        data_flown(vehicle, &case, seed, flight),
    );
    println!("{}: {:?}", case.label(), d.findings);
    d
}

fn scored(data_kind: DataKind, label: &str, clean: &Diagnosis) -> (Diagnosis, Score) {
    let h = hidden(label);
    let d = run(data_kind, Some(h));
    let s = score(&d, clean, Some(expected_kind(&h)));
    (d, s)
}

/// Loads of the independent model itself: the rotors carry the weight at its hover
/// speed with no moment, the rear-rotor wake acts in forward flight only and on the rear
/// rotors only, and the ground effect is the stated exponential.
#[test]
fn the_independent_model_hovers_and_its_effects_act_where_stated() {
    let v = vehicle();
    let clean = Airframe::new(&v, None);
    let hover = clean.hover_omega();
    let omega = [hover; 4];
    let state = |u: f64, height: f64| LoadState {
        velocity: Vector3::new(u, 0.0, 0.0),
        rates: Vector3::zeros(),
        omega: &omega,
        omega_dot: &[0.0; 4],
        height,
        attitude: UnitQuaternion::identity(),
    };
    let w = clean.wrench(&state(0.0, 100.0));
    // Round-off only: the sum of four equal thrusts against m g.
    assert!((w[2] + clean.mass * GRAVITY).abs() < 1e-12, "{w:?}");
    for j in [0, 1, 3, 4, 5] {
        assert!(w[j].abs() < 1e-12, "axis {j}: {w:?}");
    }
    let wake = Airframe::new(&v, Some(hidden("rear-rotor wake")));
    // Backwards: exactly the clean loads. Forwards at 8 m/s: the rear rotors (2 and 3)
    // lose loss·μ_f of their thrust, so F_z rises by that and the nose pitches up by
    // that times the arm x = 0.159 m.
    assert_eq!(
        wake.wrench(&state(-8.0, 100.0)),
        clean.wrench(&state(-8.0, 100.0))
    );
    let (a, b) = (
        wake.wrench(&state(8.0, 100.0)),
        clean.wrench(&state(8.0, 100.0)),
    );
    let rear_thrust: f64 = [1, 2]
        .iter()
        .map(|&i| {
            let alone = Airframe {
                hubs: vec![clean.hubs[i]],
                nominal_hubs: vec![clean.nominal_hubs[i]],
                spins: vec![clean.spins[i]],
                ..clean.clone()
            };
            let one = [hover];
            -alone.wrench(&LoadState {
                omega: &one,
                omega_dot: &[0.0],
                ..state(8.0, 100.0)
            })[2]
        })
        .sum();
    let mu = 8.0 / (hover * clean.radius);
    let lost = mu * rear_thrust; // loss = 1
    assert!((a[2] - b[2] - lost).abs() < 1e-9 * lost, "{a:?} {b:?}");
    assert!(
        (a[4] - b[4] - 0.159 * lost).abs() < 1e-9 * lost,
        "{a:?} {b:?}"
    );
    assert!((a[3] - b[3]).abs() < 1e-12);
    // Ground effect with the hubs half a diameter up: thrust × (1 + 0.3 e⁻¹).
    let ground = Airframe::new(&v, Some(hidden("ground effect")));
    let diameter = 2.0 * clean.radius;
    let low = 0.5 * diameter - v.props.hub_height;
    let ratio = ground.wrench(&state(0.0, low))[2] / clean.wrench(&state(0.0, low))[2];
    assert!(
        (ratio - (1.0 + 0.3 * (-1.0f64).exp())).abs() < 1e-12,
        "{ratio}"
    );
}

/// The second airframe (the Gazebo iris: 1.5 kg, 10-inch rotors, a rectangular ×) is
/// the reference grown by similarity: the reference's scale is exactly 1 (so its data
/// are the same to the bit), the iris's rotor has the reference's dimensionless
/// coefficients, and, independently of how the coefficients were scaled, its hover tip
/// speed relates to the reference's as the hover induced velocities do (momentum
/// theory: T = C_T ρ A (ΩR)² and ν_h² = T / (2 ρ A), so (ΩR)_h² = 2 ν_h² / C_T).
#[test]
fn the_second_airframe_is_the_reference_grown_by_similarity() {
    let reference = Airframe::new(&vehicle(), None);
    assert_eq!(
        reference.scale,
        Scale {
            length: 1.0,
            density: 1.0,
            mass: 1.0,
            inertia: [1.0; 3],
            inertia_sum: 1.0,
            induced: 1.0,
        }
    );
    assert_eq!(reference.rotor, RotorCoefficients::default());
    let big = Airframe::new(&iris(), None);
    let pi = std::f64::consts::PI;
    let dimensionless = |a: &Airframe| {
        let (c, rho, r) = (&a.rotor, a.rho, a.radius);
        [
            c.k_t / (rho * pi * r.powi(4)),
            c.k_q / (rho * pi * r.powi(5)),
            c.k_h / (rho * pi * r.powi(3)),
            c.k_h2 / (rho * r.powi(2)),
            c.k_r / (rho * pi * r.powi(4)),
        ]
    };
    for (a, b) in dimensionless(&big).iter().zip(dimensionless(&reference)) {
        assert!((a / b - 1.0).abs() < 1e-12, "{a} against {b}");
    }
    let induced = |a: &Airframe| {
        let thrust = a.mass * GRAVITY / a.hubs.len() as f64;
        (thrust / (2.0 * a.rho * pi * a.radius * a.radius)).sqrt()
    };
    let tip = |a: &Airframe| a.hover_omega() * a.radius;
    // Round-off only.
    let ratio = (tip(&big) / tip(&reference)) / (induced(&big) / induced(&reference));
    assert!((ratio - 1.0).abs() < 1e-12, "{ratio}");
    assert!((big.scale.induced / (induced(&big) / induced(&reference)) - 1.0).abs() < 1e-12);
    // A larger, slower rotor: 128 mm at ~500 rad/s against 63.5 mm at ~1800 rad/s.
    assert!(
        (400.0..600.0).contains(&big.hover_omega()),
        "{}",
        big.hover_omega()
    );
}

/// The response-surface set (3000 points with balance noise) at one seed.
///
/// Named at 10 of 10 seeds (42000–42009) on the response-surface set: a CG offset and a
/// weak rotor (rotor 2 at 90 % thrust) with no term beyond what the clean set of the
/// same seed gets, the exponential ground effect and the rear-rotor wake in forward
/// flight only (as the wake family's forward-flight form) with none beyond it either, the
/// |V|-weighted quadratic drag acting 15 mm above the CG (as the drag's off-the-CG form,
/// its centre of pressure read 15 mm above, its moment with it) with none (a generic
/// `My v*r` at one seed before the yaw-rate hub airspeed completion; before that form its
/// moment went to the in-plane force lever arm and a freed H-force coefficient, two
/// beyond). One term more than measured
/// is allowed for each: a term more is not what this test guards; naming the effect, and
/// the held-out F_z the drag leaves, are.
#[test]
fn surface_set_names_every_hidden_effect() {
    let clean = run(DataKind::Surface, None);
    // (label, the finding's name, most terms beyond the clean set, most held-out F_z
    // RMSE over the clean set's: 1.5 where the named form fits the effect's F_z; the
    // product's ground effect is Cheeseman–Bennett, which leaves part of this
    // exponential one, 0.069 N against 0.031 N clean, measured).
    for (label, named_as, beyond, fz_ratio) in [
        ("CG offset", None, 1, 1.5),
        ("weak rotor", Some("weak rotor 2"), 1, 1.5),
        ("ground effect", None, 1, 2.5),
        (
            "rear-rotor wake",
            Some("rotor-wake interaction, forward flight"),
            1,
            1.5,
        ),
        (
            "quadratic airframe drag",
            Some("quadratic airframe drag, off the CG"),
            2,
            1.5,
        ),
    ] {
        let (d, s) = scored(DataKind::Surface, label, &clean);
        assert!(
            matches!(s.naming, Naming::Added(_)),
            "{label}: {:?}",
            s.added
        );
        if let Some(name) = named_as {
            assert_eq!(s.naming, Naming::Added(name.into()), "{label}");
        }
        assert!(
            s.beyond_clean.len() <= beyond,
            "{label}: {:?}",
            s.beyond_clean
        );
        if label == "quadratic airframe drag" {
            // The centre of pressure, 15 mm above the CG (z_cp = −0.015 m), from the
            // moment areas z_cp A_y and z_cp A_x over the areas: −15.4 and −15.5 mm
            // measured; within 2 mm (the areas and moment areas are ~3 % apart).
            let drag = d.effects_added.iter().find(|e| e.name == named_as.unwrap());
            let value = |name: &str| {
                let p = drag.unwrap().parameters.iter().find(|p| p.name == name);
                p.unwrap().estimate
            };
            for (moment, area) in [
                ("drag_moment_area_x", "drag_area_y"),
                ("drag_moment_area_y", "drag_area_x"),
            ] {
                let z_cp = value(moment) / value(area);
                assert!((z_cp + 0.015).abs() < 0.002, "{moment}: z_cp {z_cp}");
            }
        }
        // The effect's F_z is explained (the drag's F_z is ~0.6 N RMS against 0.03 N of
        // balance noise).
        let fz = |d: &Diagnosis| d.after[2].rmse;
        assert!(
            fz(&d) < fz_ratio * fz(&clean),
            "{label}: F_z RMSE {} against clean {}",
            fz(&d),
            fz(&clean)
        );
    }
    // The drag is there to see.
    let v = vehicle();
    let case = Case {
        data: DataKind::Surface,
        hidden: Some(hidden("quadratic airframe drag")),
    };
    let size = effect_size(&v, &case, &data(&v, &case, SEED));
    assert!(size[2] > 10.0 * FORCE_NOISE, "{size:?}");
}

/// The noisy closed-loop flight (60 s at 200 Hz) at one seed: a CG offset and a weak
/// rotor are named with nothing beyond what the clean flight gets (10 of 10 seeds, 0
/// terms beyond the clean flight, measured; one allowed as above).
#[test]
fn flight_names_cg_offset_and_weak_rotor() {
    let clean = run(DataKind::Flight, None);
    for label in ["CG offset", "weak rotor"] {
        let (_, s) = scored(DataKind::Flight, label, &clean);
        assert!(
            matches!(s.naming, Naming::Added(_)),
            "{label}: {:?}",
            s.added
        );
        assert!(s.beyond_clean.len() <= 1, "{label}: {:?}", s.beyond_clean);
    }
}

/// A ground effect that reaches higher than a single rotor's (the other-values set:
/// gain 0.2 decaying over 0.8 D) in the noisy flight, at a seed where it was missed
/// before the multirotor form: both Cheeseman–Bennett forms read a scale of 3.8–4.1
/// there, above their plausible 3, and nothing was added (held-out F_z RMSE 0.162 N
/// against 0.083 N clean). The multirotor form (every rotor's ground image) is named,
/// with nothing beyond the clean flight, and leaves F_z near the clean flight's (0.087 N,
/// measured; 1.5 times allowed, against 1.95 times before).
#[test]
fn flight_names_a_ground_effect_reaching_higher_than_cheeseman_bennett() {
    const MISSED_BEFORE: u64 = 42_004;
    let v = vehicle();
    let diagnosed = |hidden| {
        run_on(
            &v,
            DataKind::Flight,
            hidden,
            MISSED_BEFORE,
            &FlightConfig::default(),
        )
    };
    let clean = diagnosed(None);
    let ground = Hidden::others()
        .into_iter()
        .find(|h| h.label().starts_with("ground effect"))
        .expect("a ground effect");
    let d = diagnosed(Some(ground));
    println!("{:?}", d.findings);
    let s = score(&d, &clean, Some(expected_kind(&ground)));
    assert_eq!(s.naming, Naming::Added("ground effect, multirotor".into()));
    assert!(s.beyond_clean.len() <= 1, "{:?}", s.beyond_clean);
    let fz = |d: &Diagnosis| d.after[2].rmse;
    assert!(
        fz(&d) < 1.5 * fz(&clean),
        "F_z RMSE {} against clean {}",
        fz(&d),
        fz(&clean)
    );
}

/// The noisy flight on the second airframe (the Gazebo iris, 1.5 kg, 10-inch rotors at
/// ~500 rad/s, arms 0.13 m fore and aft and 0.20–0.22 m to the side) at one seed: the
/// rear-rotor wake, the drag off the CG and the exponential ground effect are named in
/// their forms with nothing beyond what the clean flight gets. Measured over ten seeds
/// (42000–42009) in both value sets: every effect named at 10 of 10 but the drag of the
/// harness's values (9: at 42001 it pays under the importance bar), never a term beyond
/// the clean flight; one allowed here as above.
#[test]
fn second_airframe_flight_names_wake_drag_and_ground_effect() {
    let v = iris();
    let diagnosed = |hidden| run_on(&v, DataKind::Flight, hidden, SEED, &FlightConfig::default());
    let clean = diagnosed(None);
    for (label, named_as) in [
        ("rear-rotor wake", "rotor-wake interaction, forward flight"),
        (
            "quadratic airframe drag",
            "quadratic airframe drag, off the CG",
        ),
        ("ground effect", ""),
    ] {
        let h = hidden(label);
        let d = diagnosed(Some(h));
        println!("{label}: {:?}", d.findings);
        let s = score(&d, &clean, Some(expected_kind(&h)));
        match &s.naming {
            Naming::Added(name) => assert!(name.starts_with(named_as), "{label}: {name}"),
            other => panic!("{label}: {other:?}, added {:?}", s.added),
        }
        assert!(s.beyond_clean.len() <= 1, "{label}: {:?}", s.beyond_clean);
    }
}

/// The CG offset on the second airframe's response-surface set, at one seed: named with
/// nothing beyond what the clean set gets. The offset moves every hub, so each rotor
/// climbs by q dx − p dy more than the model has it; on the iris's slower rotors that
/// changes F_z by ~0.02 N RMS against 0.04 N of balance noise, which the lever arms alone
/// left to a generic `Fz p*dt` at 10 of 10 seeds. With the climb inflow in the CG-offset
/// form: none beyond the clean set at 10 of 10 seeds in both value sets (measured).
#[test]
fn second_airframe_surface_cg_offset_leaves_no_inflow_term() {
    let clean = iris_surface(None);
    let h = hidden("CG offset");
    let d = iris_surface(Some(h));
    println!("{:?}", d.findings);
    let s = score(&d, &clean, Some(expected_kind(&h)));
    assert!(
        matches!(&s.naming, Naming::Added(n) if n.starts_with("CG offset")),
        "{:?}",
        s.naming
    );
    assert!(s.beyond_clean.is_empty(), "{:?}", s.beyond_clean);
}

/// The drag in the flight with every sensor's noise doubled, at a seed where it is not
/// added: the off-the-CG form is significant (P ~ 1e-247) and predictive (held-out
/// likelihood ratio 1592) but gains 4.5 % on F_z against the 5 % bar, since the noise
/// inflates the NRMSE the gain is relative to. Nothing is added, so the diagnosis
/// reports it as present below the bar rather than saying nothing; the clean flight of
/// the same seed and noise has nothing to report. Measured over ten seeds: the drag is
/// added at 6 and reported below the bar at the other 4; no clean flight reports one.
#[test]
fn a_drag_under_the_bar_in_a_noisy_flight_is_reported_below_it() {
    let v = vehicle();
    let noisy = FlightConfig {
        noise_scale: 2.0,
        ..FlightConfig::default()
    };
    let diagnosed = |hidden| run_on(&v, DataKind::Flight, hidden, SEED, &noisy);
    let clean = diagnosed(None);
    assert!(clean.below_bar.is_empty(), "{:?}", clean.below_bar);
    let h = hidden("quadratic airframe drag");
    let d = diagnosed(Some(h));
    println!("{:?}", d.below_bar);
    let s = score(&d, &clean, Some(expected_kind(&h)));
    assert!(s.added.is_empty(), "{:?}", s.added);
    assert_eq!(
        s.naming,
        Naming::BelowBar("quadratic airframe drag, off the CG".into())
    );
}

/// The second airframe's clean response-surface set, and its rear-rotor wake, at one
/// seed. The iris's hubs sit 0.20–0.22 m to the side on rotors turning at ~500 rad/s, so
/// a yaw rate changes each hub's in-plane speed by a sizeable part of its tip speed's
/// share of the flow: the truth's rotor takes its thrust at each hub's own velocity,
/// v + ω × r_i. Before the yaw-rate hub airspeed completion (Eq. 22's edgewise thrust at
/// that velocity), the clean set got a generic `Mx u*r` (the roll moment
/// 2 ρπR² C_T_mu2 Σy_i² u r) at 10 of 10 seeds, and the wake's set a generic `Mz u*u*r`
/// beyond it at 10 of 10. Now (measured over 42000–42009): no generic roll or pitch term
/// on the clean set, and the wake named in its forward-flight form with nothing beyond
/// the clean set (the `Mz u*u*r`, the yaw moment of the H-force's airspeed term at the
/// same hub velocity, is on both: see `docs/closing-the-loop.md`).
#[test]
fn second_airframe_surface_set_leaves_no_yaw_rate_thrust_term() {
    let clean = iris_surface(None);
    let roll_or_pitch: Vec<&str> = clean
        .effects_added
        .iter()
        .map(|e| e.name.as_str())
        .filter(|n| n.starts_with("generic Mx") || n.starts_with("generic My"))
        .collect();
    assert!(roll_or_pitch.is_empty(), "{roll_or_pitch:?}");
    let h = hidden("rear-rotor wake");
    let d = iris_surface(Some(h));
    let s = score(&d, &clean, Some(expected_kind(&h)));
    assert_eq!(
        s.naming,
        Naming::Added("rotor-wake interaction, forward flight".into())
    );
    assert!(s.beyond_clean.is_empty(), "{:?}", s.beyond_clean);
}
