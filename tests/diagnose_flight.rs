//! Closing the loop on noisy simulated flights (sensor noise, coloured residuals, the
//! default cross-validation on contiguous blocks) through the library's one fit path: an effect that
//! acts in part of the envelope only, and what a clean flight gets.

use std::path::Path;

use mrsysid::internals::diagnose::{Diagnosis, EffectKind};
use mrsysid::internals::sim::flight::{FlightConfig, fly};
use mrsysid::internals::sim::{Effect, Effects, RotorFile, TruthModel};
use mrsysid::{Identification, MemoryLog, Vehicle};

fn vehicle() -> Vehicle {
    Vehicle::from_toml_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("data/vehicles/quad_x.toml"),
    )
    .unwrap()
}

/// Flies `duration` s (the first `near_ground` s low) with `effects` and diagnoses it.
fn diagnose_flight(effects: &[&str], duration: f64, near_ground: f64, seed: u64) -> Diagnosis {
    let v = vehicle();
    let list: Vec<Effect> = effects.iter().map(|e| e.parse().unwrap()).collect();
    let truth =
        TruthModel::new(&v, &RotorFile::default(), Effects::new(list, &v).unwrap()).unwrap();
    let cfg = FlightConfig {
        duration,
        near_ground,
        ..Default::default()
    };
    let log = fly(&truth, &cfg, seed).unwrap();
    let height = log
        .samples
        .height
        .as_ref()
        .expect("the simulator logs height");
    let low = height
        .iter()
        .filter(|&&z| z + v.props.hub_height < 8.0 * v.props.rotor_radius);
    println!(
        "share within 4 rotor diameters: {:.2}",
        low.count() as f64 / height.len() as f64
    );
    let memory = MemoryLog::from_chunks("flight", [log.samples]).unwrap();
    let results = Identification::new(v)
        .log(memory)
        .diagnose(true)
        .run()
        .unwrap();
    results.outcome().diagnosis.clone().unwrap()
}

/// The ground effect the diagnosis added, which must be a form with each rotor at its
/// own height: Cheeseman–Bennett per rotor (the truth's law), or the multirotor form
/// (every rotor's ground image, its own among them). On this quadrotor's spacing (five
/// radii between neighbours) the neighbours' images add little near the ground, so the
/// two forms are alike there and the data may choose either; when they are within noise
/// of each other the finding must say they are not separable.
fn per_rotor_ground_effect(d: &Diagnosis) -> &mrsysid::internals::diagnose::CandidateScore {
    let e = d
        .effects_added
        .iter()
        .find(|e| e.kind == EffectKind::GroundEffect)
        .unwrap_or_else(|| panic!("no ground effect: {:#?}", d.findings));
    assert!(
        e.name == "ground effect, per-rotor height" || e.name == "ground effect, multirotor",
        "{}",
        e.name
    );
    e
}

/// Estimate and σ of the added ground-effect form's scale in the final model.
fn final_ground_effect_scale(d: &Diagnosis) -> (f64, f64) {
    let e = per_rotor_ground_effect(d);
    let i = d
        .structure
        .param_id(&e.parameters[0].name)
        .expect("in the final model")
        .index();
    (d.theta[i], d.std[i])
}

/// The first 30 s of a 60 s flight swing the rotor plane between 1 and 4 diameters
/// above the ground (under half the log within 4 diameters: 34 % measured), then the
/// vehicle climbs away. Cheeseman–Bennett ground effect on each rotor at its own height
/// is a few percent of thrust down there and nothing above, and the aggressive
/// manoeuvre tilts the vehicle so the low rotors feel more of it (a roll and pitch
/// moment). Before this test, the one ground-effect form (every rotor at the CG's
/// height) was not even significant and nothing named the effect; now a form with each
/// rotor at its own height is chosen and judged on the held-out samples where it acts (9 %
/// of them here).
#[test]
fn ground_effect_in_a_partly_low_flight_is_found_in_its_per_rotor_form() {
    let d = diagnose_flight(&["ground_effect=1"], 60.0, 30.0, 14_000);
    println!("{:#?}", d.findings);
    let e = per_rotor_ground_effect(&d);
    assert!(e.active_share < 0.5, "acts on {}", e.active_share);
    let local = e.local_gain.expect("judged where it acts");
    // Where it acts the thrust and moments are much better predicted (51–86 % measured).
    assert!(local[2] > 0.3 && local[3] > 0.3, "{local:?}");
    // Cheeseman–Bennett is the truth's law: the scale in the final model (after the
    // completions that follow it) within 25 % of 1 (1.01 ± 0.07 measured; 0.61 when
    // added, before the in-plane force lever arm and rate damping).
    let (k, std) = final_ground_effect_scale(&d);
    println!(
        "scale {k} ± {std} (when added {})",
        e.parameters[0].estimate
    );
    assert!((k - 1.0).abs() < 0.25, "{k}");
}

/// A 60 s flight at usual altitudes (nothing flown low on purpose) where the per-rotor
/// ground effect acts on only a handful of held-out samples (5 % measured), all in one of
/// the five contiguous cross-validation blocks. Their output range is small, so a fold
/// with under [`mrsysid::internals::diagnose::local::MIN_ACTIVE_SAMPLES`] of them gives no NRMSE
/// (before that minimum the gain came out non-finite and the form, P ≈ 1e-147, was
/// rejected "−inf % below 5 %"); the folds where it does act judge it, the others are
/// left out of its local gain.
#[test]
fn ground_effect_with_few_active_held_out_samples_is_judged_where_it_acts() {
    let d = diagnose_flight(&["ground_effect=1"], 60.0, 0.0, 14_008);
    println!("{:#?}", d.findings);
    let e = per_rotor_ground_effect(&d);
    assert!(e.active_share < 0.1, "acts on {}", e.active_share);
    // Judged where it acts: roll and pitch much better predicted there (69 % and 79 %
    // measured), every gain finite.
    let local = e.local_gain.expect("judged in the block where it acts");
    assert!(local.iter().all(|g| g.is_finite()), "{local:?}");
    assert!(local[3] > 0.3 && local[4] > 0.3, "{local:?}");
    // Cheeseman–Bennett is the truth's law: scale in the final model within 0.15 of 1
    // (1.04 ± 0.04 measured).
    let (k, std) = final_ground_effect_scale(&d);
    assert!((k - 1.0).abs() < 0.15, "{k} ± {std}");
}

/// A clean 30 s flight at a seed where the in-plane force lever arm (a completion of
/// Eq. 22, so tried first) takes the evidence of the rotor flapping moment: the flapping
/// moment is accepted in the same step and explains about as much (within 10 %), but no
/// longer once the lever arm is in. The finding must say so. (Seed 12 000 of the delay
/// flight was this test's case until the delay's yaw column gained the reaction torque's
/// lead: the delay is now added there itself.)
#[test]
fn a_completion_that_takes_an_effects_evidence_names_it_as_a_look_alike() {
    let d = diagnose_flight(&[], 30.0, 0.0, 16_008);
    println!("{:#?}", d.findings);
    let (k, step) = d
        .steps
        .iter()
        .enumerate()
        .find(|(_, s)| {
            s.added
                .is_some_and(|i| s.ranking[i].name == "in-plane force lever arm")
        })
        .expect("the lever arm added");
    let added = &step.ranking[step.added.unwrap()];
    let flapping = |s: &mrsysid::internals::diagnose::DiagnosisStep| {
        s.ranking
            .iter()
            .find(|c| c.name == "rotor flapping moment")
            .cloned()
            .unwrap()
    };
    let with = flapping(step);
    assert!(with.rejected.is_none(), "{:?}", with.rejected);
    assert!(with.total_gain > 0.9 * added.total_gain);
    let after = flapping(&d.steps[k + 1]);
    assert!(after.rejected.is_some(), "flapping still accepted");
    assert!(
        d.findings.contains(
            &"in-plane force lever arm; explains about as much: rotor flapping moment".to_string()
        ),
        "{:#?}",
        d.findings
    );
}

/// A 30 s flight whose logged rotor speeds lag by 20 ms. The reaction torque J_z δ̇r of
/// Eq. 22f leads the log as the thrusts do, and with the simulator's 30 ms motor time
/// constant its rate J_z τ δ̈r is most of the delay's yaw moment. Without it in the
/// delay's yaw column, the delay made the held-out yaw moment 153 % worse at this seed
/// and was never reported ("rotor rate damping" and a generic term instead); with it
/// (δ̈r from Ω̈, which the pipeline derives from Ω̇) the delay improves the yaw moment by
/// 31 % when first scored and is added.
#[test]
fn the_delays_yaw_column_carries_the_lead_of_the_reaction_torque() {
    let d = diagnose_flight(&["delay=0.02"], 30.0, 0.0, 12_001);
    println!("{:#?}", d.findings);
    let first = d.steps[0]
        .ranking
        .iter()
        .find(|c| c.name == "rotor-speed delay")
        .unwrap();
    // Measured: 0.313 (−1.531 without the J_z δ̈r term).
    assert!(
        first.validation_gain[5] > 0.2,
        "{:?}",
        first.validation_gain
    );
    let delay = d
        .effects_added
        .iter()
        .find(|e| e.name == "rotor-speed delay")
        .unwrap_or_else(|| panic!("no delay: {:#?}", d.findings));
    // τ = 20 ms logged at 100 Hz: within one sample.
    let tau = delay.parameters[0].estimate;
    assert!((tau - 0.02).abs() < 0.01, "{tau}");
}

/// A 30 s flight whose logged rotor speeds lag by 20 ms, at a seed where thrust from
/// rotor acceleration (ΔT_i ∝ Ω̇_i) and the delay (ΔT_i ∝ Ω_i Ω̇_i, with the yaw torque
/// and the reaction torque's lead that follow), two forms of one effect, are both
/// accepted in the same step. Once the delay's yaw column carried the reaction torque's
/// lead J_z τ δ̈r, the delay explains the yaw moment too; judged on contiguous blocks it
/// leads on the summed gain (1.04 against 0.54 measured) and on the held-out likelihood
/// (4570 against 2535), far beyond noise, so the delay is named alone, not as "or" its
/// other form.
#[test]
fn between_forms_of_one_effect_the_delay_is_named_when_it_leads_beyond_noise() {
    let d = diagnose_flight(&["delay=0.02"], 30.0, 0.0, 12_004);
    println!("{:#?}", d.findings);
    let step = d
        .steps
        .iter()
        .find(|s| {
            s.added
                .is_some_and(|i| s.ranking[i].name == "rotor-speed delay")
        })
        .expect("the delay added");
    let delay = &step.ranking[step.added.unwrap()];
    let acceleration = step
        .ranking
        .iter()
        .find(|c| c.name == "thrust from rotor acceleration")
        .unwrap();
    assert!(
        acceleration.rejected.is_none(),
        "{:?}",
        acceleration.rejected
    );
    // Measured: yaw gain 0.582 (delay) and −0.028 (acceleration form, which has no
    // yaw column); likelihood ratios 967 and 459.
    assert!(
        delay.validation_gain[5] > 0.3,
        "{:?}",
        delay.validation_gain
    );
    assert!(delay.total_gain > acceleration.total_gain);
    assert!(delay.held_out_lr > acceleration.held_out_lr);
    assert!(delay.held_out_lr > 1.5 * acceleration.held_out_lr);
    assert!(
        d.findings
            .iter()
            .any(|f| f.starts_with("rotor-speed delay")
                && !f.contains("thrust from rotor acceleration")),
        "{:#?}",
        d.findings
    );
}

/// A rotor-speed sensor that lags as a first-order filter (τ = 20 ms, the simulator's
/// `rotor_speed_lag`: ESC telemetry averaged over its report period), not as the pure
/// delay the candidate assumes. For slow rotor-speed changes a first-order lag is a
/// delay of τ, for faster ones less (its phase lag is atan(ωτ)/ω), so the delay form
/// names it with a delay at or somewhat under τ; the clean flight of the same seed gets
/// no delay.
#[test]
fn a_first_order_rotor_speed_sensor_lag_is_named_as_the_rotor_speed_delay() {
    let lagged = diagnose_flight(&["rotor_speed_lag=0.02"], 30.0, 0.0, 12_001);
    let delay = lagged
        .effects_added
        .iter()
        .find(|e| e.name == "rotor-speed delay")
        .unwrap_or_else(|| panic!("no delay: {:#?}", lagged.findings));
    let tau = delay.parameters[0].estimate;
    assert!((0.005..=0.025).contains(&tau), "{tau}");
    let clean = diagnose_flight(&[], 30.0, 0.0, 12_001);
    assert!(
        clean
            .effects_added
            .iter()
            .all(|e| e.name != "rotor-speed delay"),
        "{:#?}",
        clean.findings
    );
}

/// Dynamic inflow (the simulator's `inflow_lag=0.05`: each rotor's induced velocity
/// lags its quasi-steady value with a 50 ms time constant). When a rotor speeds up, its
/// induced flow has not yet grown, the blades meet the air at a larger angle and the
/// thrust overshoots: to first order ΔT_i = c Ω̇_i with c > 0, the "thrust from rotor
/// acceleration" form (its physics sentence names dynamic inflow). Named here with
/// c = 4.6·10⁻⁵ N s²/rad (σ 0.4·10⁻⁵) measured; the clean flight of the same seed gets
/// neither form of the family. (At 20 ms the same form is named at 1 of 3 seeds: below
/// that the overshoot is within the flight's noise.)
#[test]
fn dynamic_inflow_is_named_as_thrust_from_rotor_acceleration() {
    let family = ["thrust from rotor acceleration", "rotor-speed delay"];
    let lagged = diagnose_flight(&["inflow_lag=0.05"], 30.0, 0.0, 12_002);
    let form = lagged
        .effects_added
        .iter()
        .find(|e| e.name == family[0])
        .unwrap_or_else(|| panic!("not named: {:#?}", lagged.findings));
    let c = &form.parameters[0];
    assert!(c.estimate > 3.0 * c.std, "{} ± {}", c.estimate, c.std);
    let clean = diagnose_flight(&[], 30.0, 0.0, 12_002);
    assert!(
        clean
            .effects_added
            .iter()
            .all(|e| !family.contains(&e.name.as_str())),
        "{:#?}",
        clean.findings
    );
}

/// A slow airframe moment (content below 0.5 Hz, 20 mN m RMS in roll and pitch) that the
/// attitude loop trims: the trim moment is named in its 0.5 Hz form, with roll and pitch
/// fractions near 1 (the rotors cancel the slow moment: the simulator's own check puts
/// the rotors' slope on it at −0.99 to −1.01); the clean flight of the same seed gets no
/// trim term.
#[test]
fn a_slow_moment_the_controller_trims_is_named_and_a_clean_flight_has_none() {
    let trimmed = diagnose_flight(&["trim_moment=0.02,0.02,0.01"], 60.0, 0.0, 1);
    let trim = trimmed
        .effects_added
        .iter()
        .find(|e| e.kind == EffectKind::TrimMoment)
        .unwrap_or_else(|| panic!("no trim moment: {:#?}", trimmed.findings));
    assert_eq!(trim.name, "trim moment, 0.5 Hz");
    // The fractions when the effect was added (σ ~0.09 on this 60 s flight): within
    // 0.3 of a full trim.
    for p in trim.parameters.iter().filter(|p| p.name != "trim_yaw") {
        assert!((p.estimate - 1.0).abs() < 0.3, "{}: {}", p.name, p.estimate);
    }
    let clean = diagnose_flight(&[], 60.0, 0.0, 1);
    assert!(
        clean
            .effects_added
            .iter()
            .all(|e| e.kind != EffectKind::TrimMoment),
        "{:#?}",
        clean.findings
    );
}
