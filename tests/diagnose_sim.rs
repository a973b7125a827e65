//! Closing the loop on data the model did not generate: sweeps of the blade-element truth
//! simulator with one undeclared effect (the estimator is never told which). Each effect
//! must be the first undeclared effect added (completions of Eq. 22's own assumptions —
//! yaw-rate rotor drag, the in-plane force lever arm — may come before it), its parameter
//! recovered, and validation NRMSE on the affected axis cut by ≥ 30 %.

use std::path::Path;

use mrsysid::SampleChunk;
use mrsysid::internals::diagnose::{DiagnoseOptions, Diagnosis, EffectKind, diagnose_chunks};
use mrsysid::internals::estimate::FitOptions;
use mrsysid::internals::sim::test_matrix::{Design, Ranges, sweep};
use mrsysid::internals::sim::{Effect, Effects, RotorFile, TruthModel};
use mrsysid::vehicle::Vehicle;
use mrsysid::{ModelOptions, ModelStructure};

fn vehicle() -> Vehicle {
    Vehicle::from_toml_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("data/vehicles/quad_x.toml"),
    )
    .unwrap()
}

/// 3000-point Latin-hypercube sweep with `effects`; the first 2400 points fit, the last
/// 600 validate (independent points, so a contiguous split is a fair hold-out).
fn run(effects: &[&str], seed: u64) -> Diagnosis {
    run_with(effects, seed, &DiagnoseOptions::default())
}

/// As [`run`] with the procedure's `options`.
fn run_with(effects: &[&str], seed: u64, options: &DiagnoseOptions) -> Diagnosis {
    let v = vehicle();
    let list: Vec<Effect> = effects.iter().map(|e| e.parse().unwrap()).collect();
    let truth =
        TruthModel::new(&v, &RotorFile::default(), Effects::new(list, &v).unwrap()).unwrap();
    let all = sweep(
        &truth,
        &Ranges::scaled_to(&truth),
        Design::LatinHypercube,
        3000,
        seed,
    );
    let split = |r: std::ops::Range<usize>| {
        let mut c = SampleChunk::default();
        c.extend_from(&all, r);
        vec![c]
    };
    let base = ModelStructure::eq22(&v, ModelOptions::default());
    diagnose_chunks(
        &v,
        &base,
        &split(0..2400),
        &split(2400..3000),
        &FitOptions::default(),
        options,
    )
    .unwrap()
}

/// The first undeclared effect (not a model completion) added.
fn first_effect(d: &Diagnosis) -> &mrsysid::internals::diagnose::CandidateScore {
    d.effects_added
        .iter()
        .find(|e| !e.role.is_model_completion())
        .unwrap_or_else(|| panic!("no effect added: {:#?}", d.steps.last().map(|s| &s.ranking)))
}

fn estimate(e: &mrsysid::internals::diagnose::CandidateScore, name: &str) -> f64 {
    e.parameters
        .iter()
        .find(|p| p.name == name)
        .unwrap()
        .estimate
}

fn assert_nrmse_drop(d: &Diagnosis, axis: usize) {
    let (b, a) = (d.before[axis].nrmse, d.after[axis].nrmse);
    assert!(a <= 0.7 * b, "axis {axis}: validation NRMSE {b} -> {a}");
}

#[test]
fn weak_rotor_is_found_with_its_index_and_loss() {
    let d = run(&["weak_rotor=3,0.9"], 11);
    let e = first_effect(&d);
    assert_eq!(e.name, "weak rotor 3");
    // Thrust −10 % within 10 % of its size.
    let s = estimate(e, "thrust_scale_3");
    assert!((s + 0.10).abs() < 0.01, "{s}");
    // The simulator's damaged rotor loses 10 % of its in-plane force too; that force's
    // yaw moment is what a CG offset took after the weak rotor (at every seed) while the
    // candidate scaled thrust and torque only. The fraction comes out smaller (measured
    // −2.7 %): the candidate's rotor share of Eq. 22a–b is 1/N of the fitted in-plane
    // force, which also carries the airframe's own drag; only the sign is asserted.
    let h = estimate(e, "in_plane_scale_3");
    assert!((-0.15..0.0).contains(&h), "{h}");
    let names: Vec<&str> = d.effects_added.iter().map(|e| e.name.as_str()).collect();
    assert!(
        !names.iter().any(|n| n.starts_with("CG offset")),
        "{names:?}"
    );
    assert_nrmse_drop(&d, 3);
}

#[test]
fn cg_offset_is_found_and_recovered_within_10_percent() {
    let d = run(&["cg_offset=0.01,-0.008,0"], 12);
    let e = first_effect(&d);
    assert!(e.name.starts_with("CG offset"), "{}", e.name);
    let (dx, dy) = (estimate(e, "cg_dx"), estimate(e, "cg_dy"));
    assert!(
        (dx - 0.01).abs() < 0.001 && (dy + 0.008).abs() < 0.0008,
        "{dx} {dy}"
    );
    assert_nrmse_drop(&d, 3);
}

#[test]
fn quadratic_drag_is_found_and_recovered() {
    let d = run(&["quadratic_drag=0.02,0.02,0.04"], 13);
    let e = first_effect(&d);
    assert_eq!(e.name, "quadratic airframe drag");
    let ax = estimate(e, "drag_area_x");
    assert!((ax - 0.02).abs() < 0.002, "{ax}");
    assert_nrmse_drop(&d, 0);
}

#[test]
fn ground_effect_is_found() {
    let d = run(&["ground_effect=1"], 14);
    let e = first_effect(&d);
    assert_eq!(e.name, "ground effect");
    let k = estimate(e, "ground_effect_scale");
    assert!((k - 1.0).abs() < 0.1, "{k}");
    assert_nrmse_drop(&d, 2);
}

#[test]
fn wake_interaction_is_found() {
    let d = run(&["wake_interaction=0.3"], 15);
    let e = first_effect(&d);
    assert_eq!(e.name, "rotor-wake interaction");
    let k = estimate(e, "wake_thrust_loss");
    assert!((k - 0.3).abs() < 0.03, "{k}");
    assert_nrmse_drop(&d, 4);
}

#[test]
fn two_effects_at_once_are_both_found() {
    let d = run(&["weak_rotor=2,0.9", "quadratic_drag=0.02,0.02,0.04"], 16);
    let names: Vec<&str> = d
        .effects_added
        .iter()
        .filter(|e| !e.role.is_model_completion())
        .map(|e| e.name.as_str())
        .collect();
    assert!(
        names.contains(&"weak rotor 2") && names.contains(&"quadratic airframe drag"),
        "{names:?}"
    );
}

/// The named value of parameter `name` among the effects added.
fn added_estimate(d: &Diagnosis, name: &str) -> Option<f64> {
    d.effects_added
        .iter()
        .flat_map(|e| &e.parameters)
        .find(|p| p.name == name)
        .map(|p| p.estimate)
}

#[test]
fn clean_sweeps_get_no_undeclared_effect() {
    for seed in 100..110 {
        let d = run(&[], seed);
        let effects: Vec<&str> = d
            .effects_added
            .iter()
            .filter(|e| e.kind != EffectKind::Generic && !e.role.is_model_completion())
            .map(|e| e.name.as_str())
            .collect();
        assert!(effects.is_empty(), "seed {seed}: {effects:?}");
        // At most one term of any kind beyond the completions (generic-pool terms form
        // one family: at most `max_generic` = 1 of them).
        let beyond: Vec<&str> = d
            .effects_added
            .iter()
            .filter(|e| !e.role.is_model_completion())
            .map(|e| e.name.as_str())
            .collect();
        assert!(beyond.len() <= 1, "seed {seed}: {beyond:?}");
        assert!(!d.stopped_at_limit, "seed {seed}");
        // The simulator's hubs move with p h, q h and r × r_i, which Eq. 22 drops
        // (Assumption 4); both rate completions then estimate the same lumped H-force
        // coefficient, so they must agree (20 %: each is ~5 σ from zero on 2400 points).
        let (pq, r) = (
            added_estimate(&d, "C_H_mub_pq").expect("roll/pitch-rate completion"),
            added_estimate(&d, "C_H_mub_r").expect("yaw-rate completion"),
        );
        assert!((pq / r - 1.0).abs() < 0.2, "seed {seed}: {pq} vs {r}");
        // The same hubs' in-plane airspeed under yaw, in Eq. 22c's edgewise thrust: the
        // yaw-rate hub airspeed completion reads C_T_mu2, which is G of Eq. 8, the
        // coefficient the base model fits as C_H_mub_mu0 (its own C_T_mu2, from F_z's V_h²
        // alone, is confounded there). Within 15 % (measured: 5–9 % under, at all ten).
        let thrust = added_estimate(&d, "C_T_mu2_r").expect("hub airspeed completion");
        let g = d.theta[d.structure.param_id("C_H_mub_mu0").expect("G").index()];
        assert!(
            (thrust / g - 1.0).abs() < 0.15,
            "seed {seed}: {thrust} vs {g}"
        );
    }
}

#[test]
fn rotor_flapping_moment_is_explained() {
    // Hub moment a Ω_i (−v_i, u_i): at Ω ~ 1000 rad/s and hub speeds of several m/s,
    // a = 1e-6 N s²/rad is a few 0.01 N m. On a sweep its shape, v Σ Ω_i on M_x, is that
    // of the H-force acting above the hubs (Eq. 22's F_y ∝ v δt), so the in-plane force
    // lever arm, a completion tried before undeclared effects, takes it (measured:
    // cg_dz = 70 mm); the flapping candidate itself is found on closed-form data
    // (tests/diagnose_closed_form.rs). Here the roll moment must be explained by one of
    // the two.
    let d = run(&["flapping=1e-6"], 21);
    let names: Vec<&str> = d.effects_added.iter().map(|e| e.name.as_str()).collect();
    assert!(
        names
            .iter()
            .any(|n| *n == "rotor flapping moment" || *n == "in-plane force lever arm"),
        "{names:?}"
    );
    assert_nrmse_drop(&d, 3);
}

#[test]
fn thrust_from_rotor_acceleration_is_found_and_recovered() {
    // Thrust k Ω̇_i per rotor: k = 2e-5 N s²/rad gives ~0.1 N at the sweep's rotor
    // accelerations of a few 1000 rad/s².
    let d = run(&["dynamic_inflow=2e-5"], 22);
    let e = first_effect(&d);
    assert_eq!(
        e.name, "thrust from rotor acceleration",
        "{:#?}",
        d.effects_added
    );
    let k = estimate(e, "thrust_per_rotor_acceleration");
    assert!((k - 2e-5).abs() < 2e-6, "{k}");
    assert_nrmse_drop(&d, 3);
}

#[test]
fn the_effect_limit_is_reported_when_it_stops_the_search() {
    // A clean sweep adds four completions (the rate-induced hub velocities, rate
    // damping, the lever arm) and one generic term; a limit of two stops it early.
    let options = DiagnoseOptions {
        max_effects: 2,
        ..DiagnoseOptions::default()
    };
    let d = run_with(&[], 100, &options);
    assert_eq!(d.effects_added.len(), 2);
    assert!(d.stopped_at_limit);
    let report = mrsysid::report::summary::DiagnosisReport::from(&d);
    let text = mrsysid::report::tables::render_diagnosis(&report);
    assert!(
        text.contains("stopped at its limit of 2 effects with candidates left"),
        "{text}"
    );
    // Without the limit the search ends by itself.
    assert!(!run(&[], 100).stopped_at_limit);
}

#[test]
fn an_advance_ratio_wake_loss_is_named_by_the_wake_family() {
    // The truth's downstream rotors lose k overlap_i μ_i of their thrust (μ_i = V_h/(Ω_i
    // R), growing with speed), not the overlap-area form's saturating V_h²/(V_h² + ν0²).
    // Before the family had two forms, the one form fitted it poorly. Now the family is
    // the first undeclared effect, with either form: on a sweep the two forms predict
    // the held-out points within a few percent of each other (held-out likelihood
    // ratios 444 and 459 measured), so the form is reported, not claimed.
    let d = run(&["wake_advance=1"], 17);
    let e = first_effect(&d);
    assert_eq!(e.kind, EffectKind::WakeInteraction, "{:#?}", d.findings);
    // It explains the pitching moment of the rear rotors (16–20 % measured).
    assert!(e.validation_gain[4] > 0.1, "{:?}", e.validation_gain);
    // One form of the family in the model.
    let forms = d
        .effects_added
        .iter()
        .filter(|e| e.kind == EffectKind::WakeInteraction)
        .count();
    assert_eq!(forms, 1);
}

#[test]
fn the_advance_ratio_form_is_chosen_once_the_inflows_w_terms_are_in() {
    // The truth's wake loss grows with the advance ratio. At this seed the overlap-area
    // form won when the family was first tried while the model lacked a thrust change
    // with w that is part of the advance-ratio form's signature (held-out likelihood
    // ratio 480 against 471); the form was chosen again only after a later `generic Fz w`.
    // The second-order inflow completion (V_h w_i, w_i²) now enters first, and the
    // advance-ratio form is chosen when the family is first tried, with no re-choice.
    let d = run(&["wake_advance=1"], 6001);
    let forms: Vec<&str> = d
        .effects_added
        .iter()
        .filter(|e| e.kind == EffectKind::WakeInteraction)
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(
        forms,
        ["rotor-wake interaction, advance ratio"],
        "{:#?}",
        d.findings
    );
    let position = |kind| d.effects_added.iter().position(|e| e.kind == kind);
    assert!(
        position(EffectKind::SecondOrderInflow) < position(EffectKind::WakeInteraction),
        "{:#?}",
        d.findings
    );
    let rechosen = d
        .steps
        .iter()
        .flat_map(|s| &s.withdrawn)
        .any(|w| w.contains("fits the held-out data better now"));
    assert!(
        !rechosen,
        "{:#?}",
        d.steps.iter().map(|s| &s.withdrawn).collect::<Vec<_>>()
    );
}
