//! The engine as the CLI and the closing-the-loop step use it: hold-out evaluation from
//! an accumulator, scoring and refitting a candidate column after
//! `ModelStructure::add_parameter`, bad data, and the JSON form of a fit.

mod estimate_common;

use estimate_common::*;
use mrsysid::Axis;
use mrsysid::Workspace;
use mrsysid::internals::estimate::{FitOptions, evaluate, fit, score_addition};
use mrsysid::internals::model::{Column, ParamId, Parameter, Signal, term};
use mrsysid::internals::stats::{AccumulateError, Accumulator};

/// θ fitted on one data set, evaluated on an independent one through its accumulator:
/// the validation RMSE equals the noise sd per axis within 5 % (N = 5000: sampling sd of
/// an RMSE ~1 %, parameter error adds ~p/N).
#[test]
fn hold_out_evaluation_from_an_accumulator() {
    let v = quad_x();
    let s = structure(&v);
    let theta = true_theta(&s, &v);
    let l = noise_factor();
    let make = |seed| {
        let mut r = rng(seed);
        let mut samples = random_samples(&mut r, 5000, 4);
        let noise = correlated_noise(&mut r, 5000, &l);
        set_outputs(&s, &theta, &mut samples, Some(&noise));
        accumulate(&s, &chunks(&samples, 4, 1024))
    };
    let (train, valid) = (make(30), make(31));
    let f = fit(&s, &train, &FitOptions::default()).unwrap();
    let m = evaluate(&s, &f.mmr.theta, &valid).unwrap();
    for (i, a) in m.iter().enumerate() {
        let sd = l[i].iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((a.rmse / sd - 1.0).abs() < 0.05, "{a:?}");
    }
    assert!(evaluate(&s, &f.mmr.theta[1..], &valid).is_err());
}

/// Data with a cubic drag term c·u³ in F_x that Eq. 22 lacks. After adding it as a
/// candidate parameter, a fresh accumulator over the same samples scores it: partial F
/// enormous and PSE lower with it; a candidate not in the data (u·p) gets a P-value
/// above 1e-3 (probability 0.999 under its null). The refit recovers c within 3σ.
#[test]
fn candidate_column_is_scored_and_refitted() {
    let v = quad_x();
    let base = structure(&v);
    let theta = true_theta(&base, &v);
    let c_true = -0.004;
    let mut r = rng(32);
    let n = 4000;
    let mut samples = random_samples(&mut r, n, 4);
    let noise = correlated_noise(&mut r, n, &noise_factor());
    set_outputs(&base, &theta, &mut samples, Some(&noise));
    for smp in &mut samples {
        smp.wrench[0] += c_true * smp.velocity[0].powi(3);
    }
    let mut s = base.clone();
    let column = |label: &str, factors: &[Signal]| Column {
        axis: Axis::Fx,
        param: ParamId::default(),
        label: label.into(),
        terms: vec![term(1.0, factors)],
    };
    let unit = |name: &str| Parameter {
        name: name.into(),
        unit: "-".into(),
    };
    let cubic = s.add_parameter(
        unit("C_u3"),
        vec![column("u^3", &[Signal::U, Signal::U, Signal::U])],
    );
    let null = s.add_parameter(unit("C_up"), vec![column("u*p", &[Signal::U, Signal::P])]);
    let acc = accumulate(&s, &chunks(&samples, 4, 1024));
    let col_of = |p: ParamId| s.columns.iter().position(|c| c.param == p).unwrap();
    let fx_base: Vec<usize> = s
        .axis_columns(Axis::Fx)
        .filter(|&c| s.columns[c].param != cubic && s.columns[c].param != null)
        .collect();
    let add = score_addition(&acc, Axis::Fx, &fx_base, col_of(cubic)).unwrap();
    println!("{add:?}");
    assert!(add.partial_f > 1e3 && add.p_value < 1e-100);
    assert!(add.pse_after < add.pse_before && add.r2_after > add.r2_before);
    let add_null = score_addition(&acc, Axis::Fx, &fx_base, col_of(null)).unwrap();
    println!("{add_null:?}");
    assert!(add_null.p_value > 1e-3, "{add_null:?}");
    let f = fit(&s, &acc, &FitOptions::default()).unwrap();
    let e = f.mmr.parameters.iter().find(|e| e.name == "C_u3").unwrap();
    assert!(((e.estimate - c_true) / e.std_error).abs() < 3.0, "{e:?}");
}

/// A NaN in the data is an error naming the column and the sample, never a panic or a
/// silently poisoned factor; the accumulator is unchanged by the failed push.
#[test]
fn non_finite_data_is_reported_with_its_position() {
    let v = quad_x();
    let s = structure(&v);
    let theta = true_theta(&s, &v);
    let mut samples = random_samples(&mut rng(33), 100, 4);
    set_outputs(&s, &theta, &mut samples, None);
    samples[57].wrench[2] = f64::NAN;
    let cs = chunks(&samples, 4, 50);
    let mut acc = Accumulator::new(&s);
    let mut ws = Workspace::default();
    acc.push(&s, &cs[0], &mut ws).unwrap();
    let before = acc.clone();
    match acc.push(&s, &cs[1], &mut ws) {
        Err(AccumulateError::NonFinite { field, sample }) => {
            assert_eq!(field, "output Fz");
            assert_eq!(sample, 57);
        }
        other => panic!("expected NonFinite, got {other:?}"),
    }
    assert_eq!(acc, before);
}

/// The fit serialises to JSON with the tables the report embeds.
#[test]
fn fit_serialises_to_json() {
    let v = quad_x();
    let s = structure(&v);
    let theta = true_theta(&s, &v);
    let mut r = rng(34);
    let mut samples = random_samples(&mut r, 1000, 4);
    let noise = correlated_noise(&mut r, 1000, &noise_factor());
    set_outputs(&s, &theta, &mut samples, Some(&noise));
    let f = fit(
        &s,
        &accumulate(&s, &chunks(&samples, 4, 1024)),
        &FitOptions::default(),
    )
    .unwrap();
    let json: serde_json::Value = serde_json::to_value(&f).unwrap();
    assert_eq!(
        json["mmr"]["parameters"].as_array().unwrap().len(),
        s.params.len()
    );
    assert_eq!(json["axes"][2]["fsoa"]["axis"], "Fz");
    assert_eq!(json["mmr"]["dof"], (1000 - s.params.len()) as f64);
}

/// Threads each own an accumulator or a residual pass (compile-time check).
const _: fn() = || {
    fn send<T: Send>() {}
    send::<Accumulator>();
    send::<mrsysid::internals::estimate::ResidualPass>();
    send::<mrsysid::internals::estimate::Fit>();
};
