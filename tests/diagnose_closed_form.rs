//! The closing-the-loop procedure on closed-form truth (Eq. 22 exact) with one effect
//! and measurement noise: the effect is found, ranked first, and its parameter
//! recovered; structure no named effect explains is found by the generic pool; clean data
//! gets no effect.

mod closed_form_common;

use closed_form_common::{BLADE, vehicle};
use mrsysid::internals::airframe::closed_form_wrench;
use mrsysid::internals::diagnose::{
    CandidateContext, CandidateStatistics, DiagnoseOptions, SCREENING_SAMPLES, Thinned,
    candidate_set, diagnose,
};
use mrsysid::internals::estimate::{FitOptions, Folds, fit};
use mrsysid::internals::stats::Accumulator;
use mrsysid::internals::util::cross;
use mrsysid::vehicle::{Preset, Vehicle};
use mrsysid::{ModelOptions, ModelStructure, Workspace};
use mrsysid::{Sample, SampleChunk};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// `n` random states with truth wrench `truth(sample, closed-form wrench)` plus white
/// noise of 1 % of each axis' typical size.
fn data(
    v: &Vehicle,
    seed: u64,
    n: usize,
    truth: &dyn Fn(&Sample, [f64; 6]) -> [f64; 6],
) -> Vec<SampleChunk> {
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = [0.05, 0.05, 0.1, 0.002, 0.002, 0.0005].map(|s| Normal::new(0.0, s).unwrap());
    let mut chunks = Vec::new();
    let mut c = SampleChunk::with_capacity(4, 1024, true);
    for k in 0..n {
        let mut s = Sample {
            t: k as f64 * 0.01,
            velocity: [
                rng.random_range(-12.0..12.0),
                rng.random_range(-12.0..12.0),
                rng.random_range(-4.0..4.0),
            ],
            rates: [
                rng.random_range(-6.0..6.0),
                rng.random_range(-6.0..6.0),
                rng.random_range(-3.0..3.0),
            ],
            omega: (0..4).map(|_| rng.random_range(1500.0..2600.0)).collect(),
            omega_dot: (0..4).map(|_| rng.random_range(-2000.0..2000.0)).collect(),
            ..Sample::default()
        };
        let base = closed_form_wrench(v, &BLADE, s.velocity, s.rates, &s.omega, &s.omega_dot);
        let w = truth(&s, base);
        for (a, x) in w.iter().enumerate() {
            s.wrench[a] = x + noise[a].sample(&mut rng);
        }
        c.push(&s);
        if c.len() == 1024 {
            chunks.push(std::mem::replace(
                &mut c,
                SampleChunk::with_capacity(4, 1024, true),
            ));
        }
    }
    chunks.push(c);
    chunks
}

fn run(truth: &dyn Fn(&Sample, [f64; 6]) -> [f64; 6]) -> mrsysid::internals::diagnose::Diagnosis {
    let v = vehicle(Preset::QuadX);
    let base = ModelStructure::eq22(&v, ModelOptions::default());
    let (fit_data, val_data) = (data(&v, 1, 6000, truth), data(&v, 2, 2000, truth));
    let mut ws = Workspace::default();
    let mut acc = Accumulator::new(&base);
    for c in &fit_data {
        acc.push(&base, c, &mut ws).unwrap();
    }
    let f = fit(&base, &acc, &FitOptions::default()).unwrap();
    let force_theta = f.own_axis_estimates(base.columns.len());
    let ctx = CandidateContext {
        vehicle: &v,
        structure: &base,
        theta: &f.mmr.theta,
        force_theta: &force_theta,
        has_height: false,
        has_omega_dot: true,
        has_omega_ddot: false,
        has_attitude: false,
        has_slow_thrust: false,
        hover_thrust_coefficient: None,
    };
    let mut screening = Thinned::new(SCREENING_SAMPLES);
    fit_data.iter().for_each(|c| screening.push(c));
    let options = DiagnoseOptions::default();
    let set = candidate_set(&ctx, Some(screening.samples()), &options).unwrap();
    let extended = set.extended;
    let (mut fa, mut va) = (Accumulator::new(&extended), Accumulator::new(&extended));
    for c in &fit_data {
        fa.push(&extended, c, &mut ws).unwrap();
    }
    for c in &val_data {
        va.push(&extended, c, &mut ws).unwrap();
    }
    let folds = Folds::holdout("validation", fa.clone(), va);
    let stats = CandidateStatistics {
        extended: &extended,
        candidates: &set.candidates,
        candidate_params: &set.params,
        base_params: base.params.len(),
        fit: &fa,
        folds: &folds,
        report: None,
        local: &[],
    };
    diagnose(&stats, &FitOptions::default(), &options).unwrap()
}

#[test]
fn weak_rotor_is_found_and_its_loss_recovered() {
    let v = vehicle(Preset::QuadX);
    let nu0 = v.hover_induced_velocity();
    let d = run(&|s, b| {
        // Rotor 3 thrust −8 %.
        let r = v.rotors()[2];
        let hub = [
            s.velocity[0],
            s.velocity[1],
            s.velocity[2] + s.rates[0] * r.y - s.rates[1] * r.x,
        ];
        let t = BLADE.loads(1.225, 0.0635, s.omega[2], hub, nu0).thrust * -0.08;
        let mut w = b;
        w[2] -= t;
        w[3] -= r.y * t;
        w[4] += r.x * t;
        w
    });
    let first = &d.effects_added[0];
    assert_eq!(first.name, "weak rotor 3", "{:#?}", d.steps[0].ranking);
    let scale = first
        .parameters
        .iter()
        .find(|p| p.name == "thrust_scale_3")
        .unwrap();
    // Within 10 % of −8 %: the base-model thrust used by the candidate carries the base
    // fit's small bias.
    assert!((scale.estimate + 0.08).abs() < 0.008, "{scale:?}");
    assert!(
        d.after[2].nrmse < 0.7 * d.before[2].nrmse,
        "Fz NRMSE {} -> {}",
        d.before[2].nrmse,
        d.after[2].nrmse
    );
}

#[test]
fn cg_offset_is_found_and_recovered() {
    let dxy = [0.0, -0.008, 0.0];
    let d = run(&|_, b| {
        let m = cross([b[0], b[1], b[2]], dxy);
        [b[0], b[1], b[2], b[3] + m[0], b[4] + m[1], b[5] + m[2]]
    });
    let first = &d.effects_added[0];
    assert!(
        first.name.starts_with("CG offset"),
        "{:#?}",
        d.steps[0].ranking
    );
    let dy = first.parameters.iter().find(|p| p.name == "cg_dy").unwrap();
    assert!((dy.estimate - dxy[1]).abs() < 0.1 * dxy[1].abs(), "{dy:?}");
}

#[test]
fn clean_data_gets_no_effect() {
    let d = run(&|_, b| b);
    assert!(d.effects_added.is_empty(), "{:#?}", d.effects_added);
}

#[test]
fn unnamed_structure_is_found_by_the_generic_pool() {
    // F_x gains c u q, a product no named candidate holds.
    let c = 0.01;
    let d = run(&|s, b| {
        let mut w = b;
        w[0] += c * s.velocity[0] * s.rates[1];
        w
    });
    assert_eq!(d.effects_added.len(), 1, "{:#?}", d.effects_added);
    let e = &d.effects_added[0];
    assert_eq!(e.name, "generic Fx u*q");
    // The parameter is the load at one RMS of u q: u ~ U(−12, 12), q ~ U(−6, 6)
    // independent, so RMS(u q) = √(48 · 12) = 24 and the load 0.24 N; 5 % covers the
    // RMS of 6000 draws (~1.5 %) and the 0.05 N noise.
    let g = e.parameters[0].estimate;
    assert!((g - 24.0 * c).abs() < 0.05 * 24.0 * c, "{g}");
    assert!(d.after[0].nrmse < 0.3 * d.before[0].nrmse);
}

/// The first effect added that is not a completion of Eq. 22's own assumptions.
fn first_effect(
    d: &mrsysid::internals::diagnose::Diagnosis,
) -> &mrsysid::internals::diagnose::CandidateScore {
    d.effects_added
        .iter()
        .find(|e| !e.role.is_model_completion())
        .unwrap_or_else(|| panic!("no effect added: {:#?}", d.steps[0].ranking))
}

/// Hub in-plane velocity (u_i, v_i) of rotor `i` of `v` (Eq. 18, hub at z = −h).
fn hub_velocity(v: &Vehicle, s: &Sample, i: usize) -> [f64; 2] {
    let r = v.rotors()[i];
    let h = v.props.hub_height;
    let [p, q, rr] = s.rates;
    [
        s.velocity[0] - q * h - rr * r.y,
        s.velocity[1] + p * h + rr * r.x,
    ]
}

#[test]
fn rotor_flapping_moment_is_found_and_recovered() {
    let v = vehicle(Preset::QuadX);
    // M_x = −a Σ Ω_i v_i, M_y = a Σ Ω_i u_i: at |v| ~ 7 m/s and Σ Ω ~ 8000 rad/s about
    // 0.01 N m, five times the moment noise.
    let a = 2e-7;
    let d = run(&|s, b| {
        let mut w = b;
        for i in 0..4 {
            let [ui, vi] = hub_velocity(&v, s, i);
            w[3] -= a * s.omega[i] * vi;
            w[4] += a * s.omega[i] * ui;
        }
        w
    });
    // The in-plane force lever arm, a completion tried first, can take part of it.
    let first = first_effect(&d);
    assert_eq!(
        first.name, "rotor flapping moment",
        "{:#?}",
        d.effects_added
    );
    let est = first.parameters[0].estimate;
    // 5 %: the moment noise leaves σ ≈ 0.3 % of a; the rest covers the base terms'
    // correlation with the flapping columns.
    assert!((est - a).abs() < 0.05 * a, "{est}");
    assert!(d.after[3].nrmse < 0.7 * d.before[3].nrmse);
}

#[test]
fn rotor_rate_damping_is_found_and_recovered() {
    let v = vehicle(Preset::QuadX);
    // ΔT_i = c Ω_i w_i, w_i = p y_i − q x_i: at 3 rad/s (RMS), 0.16 m and 2000 rad/s,
    // c = 2e-5 gives 0.02 N per rotor and ~0.006 N m of moment, three times the noise.
    let c = 2e-5;
    let d = run(&|s, b| {
        let mut w = b;
        for (i, r) in v.rotors().iter().enumerate() {
            let dt = c * s.omega[i] * (s.rates[0] * r.y - s.rates[1] * r.x);
            w[3] -= r.y * dt;
            w[4] += r.x * dt;
        }
        w
    });
    // A completion (Eq. 22's rate damping with a coefficient of its own).
    let first = d
        .effects_added
        .iter()
        .find(|e| e.name == "rotor rate damping")
        .unwrap_or_else(|| panic!("{:#?}", d.effects_added));
    let est = first.parameters[0].estimate;
    assert!((est - c).abs() < 0.05 * c, "{est}");
}

#[test]
fn thrust_from_rotor_acceleration_is_found_and_recovered() {
    let v = vehicle(Preset::QuadX);
    // ΔT_i = k Ω̇_i: Ω̇ ~ U(−2000, 2000) rad/s² and k = 3e-5 N s²/rad give up to
    // 0.06 N per rotor, ~0.005 N m of moment on the 0.16 m arms.
    let k = 3e-5;
    let d = run(&|s, b| {
        let mut w = b;
        for (i, r) in v.rotors().iter().enumerate() {
            let dt = k * s.omega_dot[i];
            w[2] -= dt;
            w[3] -= r.y * dt;
            w[4] += r.x * dt;
        }
        w
    });
    let first = first_effect(&d);
    assert_eq!(
        first.name, "thrust from rotor acceleration",
        "{:#?}",
        d.effects_added
    );
    let est = first.parameters[0].estimate;
    assert!((est - k).abs() < 0.05 * k, "{est}");
}
