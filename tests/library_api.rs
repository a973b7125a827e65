//! The library's public entry points on malformed input: every one returns a typed error
//! naming what is wrong (and the binary's exit code follows from the variant); none
//! panics. Plus the fit builder on samples in memory: validation logs, a bad sample
//! reported by `run`, and the results object's statistics checked against their
//! definitions.

mod scratch;
use std::path::{Path, PathBuf};

use mrsysid::Holdout;
use mrsysid::IdentifiedModel;
use mrsysid::error::RequestError;
use mrsysid::internals::estimate::{self, FitOptions};
use mrsysid::internals::stats::{AccumulateError, Accumulator};
use mrsysid::io::{Location, Mapping, ReadOptions};
use mrsysid::vehicle::VehicleSource;
use mrsysid::{Error, Identification, MemoryLog, Sample, SampleChunk, Vehicle};
use mrsysid::{ModelError, ModelOptions, ModelStructure, Workspace};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn quad() -> Vehicle {
    Vehicle::from_toml_file(&root().join("data/vehicles/quad_x.toml")).expect("vehicle")
}

/// `n` samples of the shipped flight (which carries Ω̇, height and attitude).
fn flight(n: usize) -> Vec<Sample> {
    let log = mrsysid::io::open_log(
        &root().join("data/quad_x_flight_quadratic_drag.csv"),
        &quad(),
        None,
        &ReadOptions::default(),
    )
    .expect("shipped flight");
    let mut out = Vec::new();
    for chunk in log {
        let chunk = chunk.expect("valid rows");
        out.extend((0..chunk.len()).map(|k| chunk.sample(k)));
    }
    out.truncate(n);
    out
}

/// Makes a sample malformed.
type Spoil = fn(&mut Sample);

#[test]
fn malformed_samples_are_refused_by_name_and_index() {
    let good = flight(600);
    // 3 of 4 rotor speeds in sample 17 (once a panic in the mixing).
    let mut bad = good.clone();
    bad[17].omega.pop();
    let e = Identification::new(quad())
        .samples("mine", bad)
        .run()
        .unwrap_err();
    assert_eq!(e.exit_code(), 2);
    let Error::Input(io) = &e else {
        panic!("{e:?}")
    };
    assert_eq!(io.location, Location::Sample(17));
    assert!(
        e.to_string()
            .starts_with("mine: sample 17, signal \"omega\""),
        "{e}"
    );
    // NaN, time going back, a missing optional signal, a negative rotor speed.
    let cases: [(usize, Spoil, &str); 4] = [
        (
            3,
            |s| s.wrench[4] = f64::NAN,
            "signal \"my\": not a finite number",
        ),
        (250, |s| s.t = 0.0, "goes backwards"),
        (9, |s| s.height = None, "signal \"height\": absent here"),
        (40, |s| s.omega[2] = -1.0, "signal \"omega3\": value -1"),
    ];
    for (k, spoil, expect) in cases {
        let mut bad = good.clone();
        spoil(&mut bad[k]);
        let e = MemoryLog::from_samples("mine", bad).unwrap_err();
        assert_eq!(e.location, Location::Sample(k as u64), "{e}");
        assert!(e.to_string().contains(expect), "{e}");
    }
    // Another rotor count than the vehicle's: the model says so.
    let hexa: Vec<Sample> = good
        .iter()
        .map(|s| Sample {
            omega: vec![s.omega[0]; 6],
            omega_dot: vec![0.0; 6],
            ..s.clone()
        })
        .collect();
    let e = Identification::new(quad())
        .samples("hexa", hexa)
        .run()
        .unwrap_err();
    assert!(
        matches!(
            &e,
            Error::Accumulate {
                log,
                source: AccumulateError::Model(ModelError::RotorCountMismatch { expected: 4, found: 6 })
            } if log == "hexa"
        ),
        "{e:?}"
    );
    assert_eq!(e.exit_code(), 2);
}

#[test]
fn malformed_chunks_are_refused_everywhere_they_enter() {
    let vehicle = quad();
    let structure = ModelStructure::eq22(&vehicle, ModelOptions::default());
    let mut chunk = SampleChunk::with_capacity(4, 8, true);
    for s in flight(8) {
        chunk.push(&s);
    }
    // A chunk whose yaw-moment series is one short, and one pushed a 3-rotor sample.
    let mut short = chunk.clone();
    short.wrench[5].pop();
    let mut ragged = chunk.clone();
    ragged.push(&Sample {
        omega: vec![1.0; 3],
        ..Sample::default()
    });
    for bad in [&short, &ragged] {
        let mut ws = Workspace::default();
        let e = structure.assemble(bad, &mut ws).unwrap_err();
        assert!(matches!(e, ModelError::ChunkShape { .. }), "{e:?}");
        let mut acc = Accumulator::new(&structure);
        assert!(acc.push(&structure, bad, &mut ws).is_err());
        assert!(MemoryLog::from_chunks("chunks", [bad.clone()]).is_err());
        let theta = vec![0.0; structure.params.len()];
        assert!(structure.predict_chunk(&theta, bad, &mut ws).is_err());
    }
    // θ of the wrong length.
    let e = structure
        .predict_chunk(&[1.0; 3], &chunk, &mut Workspace::default())
        .unwrap_err();
    assert_eq!(
        e,
        ModelError::ParameterCount {
            expected: structure.params.len(),
            found: 3
        }
    );
    // A saved model asked about a state with 3 rotor speeds.
    let model = IdentifiedModel::new(
        vehicle.clone(),
        structure.clone(),
        &vec![0.0; structure.params.len()],
        &vec![0.0; structure.params.len()],
    );
    let three = Sample {
        omega: vec![500.0; 3],
        omega_dot: vec![0.0; 3],
        ..Sample::default()
    };
    assert!(model.predict(&three).is_err());
    let n = structure.params.len();
    let with_cov = model
        .clone()
        .with_covariance(nalgebra::DMatrix::identity(n, n));
    assert!(matches!(
        with_cov.prediction_std(&three),
        Err(ModelError::RotorCountMismatch {
            expected: 4,
            found: 3
        })
    ));
    // State without the rotor accelerations the J_z terms need.
    let no_dot = Sample {
        omega: vec![500.0; 4],
        ..Sample::default()
    };
    assert_eq!(
        model.predict(&no_dot).unwrap_err(),
        ModelError::MissingRotorAcceleration
    );
}

#[test]
fn requests_that_cannot_be_carried_out_are_refused_before_reading() {
    let e = Identification::new(quad()).run().unwrap_err();
    assert!(matches!(e, Error::Request(RequestError::NoLogs)), "{e:?}");
    let holdout = Holdout {
        blocks: 5,
        guard_seconds: f64::NAN,
    };
    let e = Identification::new(quad())
        .samples("a", flight(300))
        .holdout(holdout)
        .run()
        .unwrap_err();
    assert!(
        matches!(e, Error::Request(RequestError::InvalidHoldout { .. })),
        "{e:?}"
    );
    let hexa = Vehicle::from_toml_file(&root().join("data/vehicles/hexa_x.toml")).unwrap();
    let e = Identification::new(quad())
        .structure(ModelStructure::eq22(&hexa, ModelOptions::default()))
        .samples("a", flight(300))
        .run()
        .unwrap_err();
    assert!(
        matches!(
            e,
            Error::Request(RequestError::StructureMismatch {
                structure: 6,
                vehicle: 4
            })
        ),
        "{e:?}"
    );
    // One log of 3 s: shorter than a guard per cross-validation block (5 blocks, 2 s).
    let e = Identification::new(quad())
        .samples("short", flight(300))
        .run()
        .unwrap_err();
    assert!(
        matches!(e, Error::Request(RequestError::HoldoutTooShort { .. })),
        "{e:?}"
    );
    // A missing file, named.
    let e = Identification::new(quad())
        .log(Path::new("/nonexistent/flight.csv"))
        .run()
        .unwrap_err();
    assert!(e.to_string().starts_with("flight.csv"), "{e}");
    assert_eq!(e.exit_code(), 2);
}

#[test]
fn data_that_cannot_support_a_fit_fail_with_exit_code_1() {
    // One repeated state: no excitation (once a 0/0 t-value inside statrs).
    let one = flight(1)[0].clone();
    let same: Vec<Sample> = (0..1200)
        .map(|k| Sample {
            t: k as f64 * 0.01,
            ..one.clone()
        })
        .collect();
    let e = Identification::new(quad())
        .samples("hover", same.clone())
        .diagnose(false)
        .run()
        .unwrap_err();
    assert!(matches!(e, Error::Estimate(_)), "{e:?}");
    assert_eq!(e.exit_code(), 1);
    // The estimator on its own, on the same statistics.
    let structure = ModelStructure::eq22(&quad(), ModelOptions::default());
    let mut acc = Accumulator::new(&structure);
    let log = MemoryLog::from_samples("hover", same).unwrap();
    for c in log.chunks() {
        acc.push(&structure, c, &mut Workspace::default()).unwrap();
    }
    assert!(estimate::fit(&structure, &acc, &FitOptions::default()).is_err());
}

#[test]
fn text_inputs_are_refused_with_their_name() {
    let e = Vehicle::from_toml_str("mass = [", VehicleSource::Code).unwrap_err();
    assert!(!e.to_string().is_empty());
    let e = Mapping::from_toml_str("[signals\nrates =", "m.toml").unwrap_err();
    assert!(e.to_string().starts_with("m.toml"), "{e}");
    let path = scratch::dir("api").join("model.toml");
    std::fs::write(&path, "schema_version = 1\nparameters = 3\n").unwrap();
    let e = IdentifiedModel::load(&path).unwrap_err();
    assert!(e.to_string().contains("not a model file"), "{e}");
    let _ = std::fs::remove_file(&path);
}

#[test]
fn results_from_memory_match_their_definitions() {
    // 30 s flight: the first 24 s fit (cross-validated on 5 contiguous blocks), the last 6 s
    // only reported on.
    let all = flight(3000);
    let results = Identification::new(quad())
        .samples("fit", all[..2400].to_vec())
        .validate_samples("report", all[2400..].to_vec())
        .diagnose(false)
        .threads(2)
        .run()
        .expect("fit");
    let o = results.outcome();
    assert_eq!(o.validation_samples, 600);
    assert_eq!(o.summaries[0].file, "fit");
    let params = results.parameters();
    let cov = results.covariance();
    let kappa = results.variance_inflation();
    assert!(kappa >= 1.0);
    for p in &params {
        let i = results
            .structure()
            .param_id(&p.name)
            .expect("a parameter of the structure")
            .index();
        // σ² is the covariance's diagonal; the white σ is κ^-½ of it; t = θ̂/σ; the
        // 95 % interval is symmetric about θ̂ (relative rounding 1e-12).
        assert!(
            (cov[(i, i)].sqrt() - p.std).abs() <= 1e-12 * p.std,
            "{}",
            p.name
        );
        assert!((p.std_white * kappa.sqrt() - p.std).abs() <= 1e-12 * p.std);
        assert!((p.t - p.estimate / p.std).abs() <= 1e-12 * p.t.abs());
        let mid = 0.5 * (p.ci95[0] + p.ci95[1]);
        assert!((mid - p.estimate).abs() <= 1e-9 * p.estimate.abs().max(p.std));
        assert!((0.0..=1.0).contains(&p.p_value));
    }
    // Residuals are measured − fitted, and fitted values reproduce the fit metrics'
    // RMSE on the fit data (the same model, the same samples).
    let log = MemoryLog::from_samples("x", all[..20].to_vec()).unwrap();
    let fitted = results.fitted(&log.chunks()[0]).unwrap();
    let residuals = results.residuals(&log.chunks()[0]).unwrap();
    for a in 0..6 {
        for k in 0..20 {
            let z = log.chunks()[0].wrench[a][k];
            assert!((fitted[a][k] + residuals[a][k] - z).abs() <= 1e-9 * z.abs().max(1.0));
        }
    }
    // AIC/BIC by their definitions from the fit metrics.
    let n = results.estimation().samples as f64;
    for (ic, m) in results
        .information_criteria()
        .iter()
        .zip(results.fit_metrics())
    {
        let base = n * (m.rmse * m.rmse).ln();
        assert!((ic.aic - base - 2.0 * ic.parameters as f64).abs() < 1e-6 * base.abs());
        assert!(ic.bic > ic.aic, "ln N > 2 for N > 7");
    }
    // The saved model predicts what the results fitted.
    let model = results.to_identified_model();
    let y = model.predict(&all[5]).unwrap();
    let one = MemoryLog::from_samples("one", [all[5].clone()]).unwrap();
    let f = results.fitted(&one.chunks()[0]).unwrap();
    for a in 0..6 {
        assert!((y[a] - f[a][0]).abs() <= 1e-12 * f[a][0].abs().max(1e-9));
    }
    assert!(results.equations().lines().count() == 6);
    assert!(results.summary().contains("Final model"));
}

/// R² of `predicted` against `measured`, %.
fn r2(measured: &[f64], predicted: &[f64]) -> f64 {
    let mean = measured.iter().sum::<f64>() / measured.len() as f64;
    let sst: f64 = measured.iter().map(|z| (z - mean).powi(2)).sum();
    let sse: f64 = measured
        .iter()
        .zip(predicted)
        .map(|(z, y)| (z - y).powi(2))
        .sum();
    100.0 * (1.0 - sse / sst)
}

/// The plot series carry the final (diagnosed) model's output at the samples kept,
/// beside the Eq. 22 model's: on the shipped flight, whose airframe drag Eq. 22 lacks,
/// the final model follows F_x and F_y where Eq. 22 does not (fit-series R² 97.5 / 96.8 %
/// → 100.0 / 100.0 % measured), and every axis is at least as good. Without the
/// diagnosis there is no final series.
#[test]
fn plot_series_carry_the_final_model_beside_eq22() {
    let log = root().join("data/quad_x_flight_quadratic_drag.csv");
    let job = Identification::new(quad()).threads(1).log(log);
    let results = job.clone().run().unwrap();
    let s = &results.outcome().fit_series;
    assert!(s.t.len() > 1000, "{}", s.t.len());
    for a in 0..6 {
        assert_eq!(s.final_predicted[a].len(), s.t.len());
        let (before, after) = (
            r2(&s.measured[a], &s.predicted[a]),
            r2(&s.measured[a], &s.final_predicted[a]),
        );
        println!("axis {a}: {before:.1} -> {after:.1}");
        assert!(after >= before - 0.1, "axis {a}: {before} -> {after}");
        if a < 2 {
            assert!(
                before < 98.0 && after > 99.5,
                "axis {a}: {before} -> {after}"
            );
        }
    }
    // Each added effect's partial residuals: the final residual is orthogonal to the
    // effect's load (least squares, on the kept samples to within their sampling), so
    // it has no slope against it. A load computed from the wrong parameters would leave
    // a slope. (The residual without the effect is the final one plus the load, so its
    // slope is one more by construction and is not asserted.)
    assert!(!s.effects.is_empty());
    for e in &s.effects {
        let slope = |y: &[f64]| {
            let sxy: f64 = e.load.iter().zip(y).map(|(x, y)| x * y).sum();
            sxy / e.load.iter().map(|x| x * x).sum::<f64>()
        };
        let after = slope(&e.after);
        println!("{} on {:?}: slope {after:.3}", e.name, e.axis);
        assert!(after.abs() < 0.1, "{}: {after}", e.name);
    }
    let plain = job.diagnose(false).run().unwrap();
    assert!(plain.outcome().fit_series.final_predicted[0].is_empty());
    assert!(plain.outcome().fit_series.effects.is_empty());
}
