//! Model files: save → load round trip, predictions equal the structure's, bad files are
//! refused with the file named.

mod scratch;
use mrsysid::IdentifiedModel;
use mrsysid::internals::rotor::BladeConstants;
use mrsysid::vehicle::Vehicle;
use mrsysid::{Axis, Sample, SampleChunk};
use mrsysid::{ModelOptions, ModelStructure, Workspace};

fn quad() -> Vehicle {
    Vehicle::from_toml_file(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/vehicles/quad_x.toml"),
    )
    .unwrap()
}

fn model() -> IdentifiedModel {
    let v = quad();
    let s = ModelStructure::eq22(&v, ModelOptions::default());
    let blade = BladeConstants {
        blades: 2.0,
        chord: 0.012,
        lift_slope: 5.7,
        mean_drag: 0.012,
        theta0: 0.3,
        theta_tw: -0.1,
        c_nu_mu: -0.1,
        c_nu_w: 0.3,
    };
    let lumped = blade.lumped_parameters(v.props.rotor_radius);
    let theta: Vec<f64> = s
        .params
        .iter()
        .map(|p| lumped.value(&p.name).unwrap())
        .collect();
    let std: Vec<f64> = theta.iter().map(|t| t.abs() * 0.01).collect();
    IdentifiedModel::new(v, s, &theta, &std)
}

fn tmp(name: &str) -> std::path::PathBuf {
    scratch::dir("model").join(name)
}

#[test]
fn round_trip_preserves_predictions_exactly() {
    let m = model();
    let path = tmp("model.toml");
    m.save(&path).unwrap();
    let back = IdentifiedModel::load(&path).unwrap();
    assert_eq!(back.parameters, m.parameters);
    let s = state(
        [5.0, -1.0, 0.5],
        [0.3, -0.2, 0.1],
        &[900.0, 950.0, 1000.0, 1050.0],
    );
    let a = m.predict(&s).unwrap();
    let b = back.predict(&s).unwrap();
    // TOML stores f64 with round-trip precision, so predictions are bit-identical.
    assert_eq!(a, b);
    // Equal rotor speeds at rest give upward thrust (F_z < 0) and zero moments; at
    // 2000 rad/s (λ = ν0/ΩR ≈ 0.077) these blade constants lift.
    let y = back
        .predict(&state([0.0; 3], [0.0; 3], &[2000.0; 4]))
        .unwrap();
    assert!(y[2] < -1.0, "{y:?}");
    assert!(y[3..].iter().all(|x| x.abs() < 1e-9), "{y:?}");
}

/// A state with rotor accelerations 10 rad/s² (the J_z terms need them).
fn state(velocity: [f64; 3], rates: [f64; 3], omega: &[f64]) -> Sample {
    Sample {
        velocity,
        rates,
        omega: omega.to_vec(),
        omega_dot: vec![10.0; omega.len()],
        ..Sample::default()
    }
}

#[test]
fn covariance_round_trips_and_gives_prediction_sigma() {
    // A diagonal covariance: the predicted F_z's σ is then √(Σ_p x_p² σ_p²) over the
    // parameters with an F_z column, computed here from the model's own regressors.
    let m = model();
    let n = m.structure.params.len();
    let sigma: Vec<f64> = (0..n).map(|i| 1e-3 * (1.0 + i as f64)).collect();
    let m = m.with_covariance(nalgebra::DMatrix::from_fn(n, n, |i, j| {
        if i == j { sigma[i] * sigma[i] } else { 0.0 }
    }));
    let path = tmp("covariance.toml");
    m.save(&path).unwrap();
    let back = IdentifiedModel::load(&path).unwrap();
    assert_eq!(back.covariance, m.covariance, "TOML keeps f64 exactly");
    let s = state(
        [4.0, 1.0, -0.5],
        [0.2, -0.1, 0.3],
        &[900.0, 1000.0, 1100.0, 950.0],
    );
    let std = back.prediction_std(&s).unwrap().expect("a covariance");
    let mut chunk = SampleChunk::with_capacity(4, 1, true);
    chunk.push(&s);
    let mut ws = Workspace::default();
    m.structure.assemble(&chunk, &mut ws).unwrap();
    let mut x = vec![0.0; n];
    for j in m.structure.axis_columns(Axis::Fz) {
        x[m.structure.columns[j].param.index()] += ws.column(j)[0];
    }
    let expect = x
        .iter()
        .zip(&sigma)
        .map(|(x, s)| (x * s).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(expect > 0.0);
    assert!(
        (std[2] - expect).abs() <= 1e-12 * expect,
        "{} vs {expect}",
        std[2]
    );
    // Without a covariance there is no interval.
    assert_eq!(model().prediction_std(&s).unwrap(), None);
    let _ = std::fs::remove_file(&path);
}

#[test]
fn chunk_prediction_equals_single_sample_prediction() {
    let m = model();
    let s = Sample {
        velocity: [3.0, 2.0, -1.0],
        rates: [1.0, 0.5, -0.2],
        omega: vec![800.0, 1100.0, 900.0, 1000.0],
        omega_dot: vec![50.0, -20.0, 0.0, 5.0],
        ..Sample::default()
    };
    let mut chunk = SampleChunk::with_capacity(4, 1, true);
    chunk.push(&s);
    let y = m.predict_chunk(&chunk, &mut Workspace::default()).unwrap();
    let single = m.predict(&s).unwrap();
    for (a, v) in single.iter().enumerate() {
        assert!(
            (y[a][0] - v).abs() <= 1e-12 * v.abs().max(1e-9),
            "axis {a}: {} vs {v}",
            y[a][0]
        );
    }
}

#[test]
fn bad_model_files_name_the_file_and_problem() {
    let m = model();
    let path = tmp("bad.toml");
    m.save(&path).unwrap();
    let good = std::fs::read_to_string(&path).unwrap();
    let cases = [
        (
            good.replace("schema_version = 1", "schema_version = 9"),
            "schema_version 9 is not supported",
        ),
        (
            good.replacen("name = \"C_T0\"", "name = \"C_X\"", 1),
            "do not match the model's",
        ),
        (
            good.replacen("mass = 1.2", "mass = -1.2", 1),
            "[vehicle]: field `mass` = -1.2",
        ),
        ("not toml at all =".to_string(), "not a model file"),
    ];
    for (text, expected) in cases {
        std::fs::write(&path, text).unwrap();
        let e = IdentifiedModel::load(&path).unwrap_err().to_string();
        assert!(
            e.starts_with(&path.display().to_string()) && e.contains(expected),
            "{e}"
        );
    }
    let missing = IdentifiedModel::load(std::path::Path::new("/nonexistent/m.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        missing.contains("/nonexistent/m.toml: cannot read file"),
        "{missing}"
    );
}

#[test]
fn added_effect_columns_survive_the_model_file() {
    use mrsysid::Axis;
    use mrsysid::internals::model::{Column, ParamId, Parameter, Signal, term};
    let m = model();
    let mut s = m.structure.clone();
    s.add_parameter(
        Parameter {
            name: "drag_area_x".into(),
            unit: "m^2".into(),
        },
        vec![Column {
            axis: Axis::Fx,
            param: ParamId::default(),
            label: "-rho/2*u|u|".into(),
            terms: vec![term(-0.6125, &[Signal::U, Signal::AbsU])],
        }],
    );
    s.add_parameter(
        Parameter {
            name: "thrust_scale_2".into(),
            unit: "-".into(),
        },
        vec![Column {
            axis: Axis::Fz,
            param: ParamId::default(),
            label: "T_2".into(),
            terms: vec![term(-1e-6, &[Signal::RotorSpeedSquared(1)])],
        }],
    );
    let mut theta = m.theta();
    theta.extend([0.02, -0.08]);
    let std = vec![0.0; theta.len()];
    let aug = IdentifiedModel::new(m.vehicle.clone(), s, &theta, &std);
    let path = tmp("augmented.toml");
    aug.save(&path).unwrap();
    let back = IdentifiedModel::load(&path).unwrap();
    assert_eq!(back.parameters, aug.parameters);
    let args = Sample {
        velocity: [12.0, 1.0, 0.5],
        rates: [0.2, 0.1, 0.0],
        omega: vec![900.0, 1000.0, 1100.0, 1200.0],
        omega_dot: vec![0.0; 4],
        ..Sample::default()
    };
    let a = aug.predict(&args).unwrap();
    let b = back.predict(&args).unwrap();
    assert_eq!(a, b);
    // The extra terms act: F_x gains −ρ/2 CdA u|u| = −0.6125·0.02·144 N.
    let plain = m.predict(&args).unwrap();
    let expect = -0.6125 * 0.02 * 144.0;
    assert!(
        (a[0] - plain[0] - expect).abs() < 1e-9,
        "{} vs {}",
        a[0] - plain[0],
        expect
    );
}

/// A structure with some axes taken from another (the diagnosis's per-axis fallback to
/// Eq. 22) predicts those axes exactly as the other and every other axis as itself, and
/// its model file round-trips: the copies are extra parameters, the replaced columns
/// left-out terms.
#[test]
fn axes_taken_from_another_structure_predict_as_it_and_round_trip() {
    let m = model();
    let s = &m.structure;
    let other = m.theta();
    // The "own" model: every coefficient 10-40 % off, so the two differ on every axis.
    let own: Vec<f64> = (other.iter().enumerate())
        .map(|(i, t)| t * (1.1 + 0.1 * (i % 4) as f64))
        .collect();
    let axes = [Axis::Fz, Axis::Mz];
    let (c, origins) = s.with_axes_of(s, &axes, |n, a| format!("{n}@{a} (Eq. 22)"));
    let theta: Vec<f64> = origins.iter().map(|o| o.value(&own, &other)).collect();
    // Every parameter has a column; C_Q0 acts on M_z alone, so its own copy is gone.
    assert_eq!(theta.len(), c.params.len());
    assert!(c.param_id("C_Q0").is_none());
    assert!(c.param_id("C_Q0@Mz (Eq. 22)").is_some());
    assert!(c.param_id("C_T0").is_some() && c.param_id("C_T0@Fz (Eq. 22)").is_some());
    let samples = [
        state(
            [5.0, -1.0, 0.5],
            [0.3, -0.2, 0.1],
            &[900.0, 950.0, 1000.0, 1050.0],
        ),
        state(
            [-2.0, 3.0, -1.5],
            [-0.5, 0.4, 0.8],
            &[1200.0, 800.0, 1100.0, 700.0],
        ),
    ];
    for x in &samples {
        let (a, b, y) = (
            s.predict(&own, x).unwrap(),
            s.predict(&other, x).unwrap(),
            c.predict(&theta, x).unwrap(),
        );
        for axis in Axis::ALL {
            let i = axis as usize;
            let expect = if axes.contains(&axis) { b[i] } else { a[i] };
            // The same columns and values summed, perhaps in another order: 1e-12.
            assert!(
                (y[i] - expect).abs() <= 1e-12 * expect.abs().max(1e-9),
                "{axis}: {} vs {expect}",
                y[i]
            );
        }
    }
    let std: Vec<f64> = theta.iter().map(|t| t.abs() * 0.01).collect();
    let composite = IdentifiedModel::new(quad(), c, &theta, &std);
    let path = tmp("composite.toml");
    composite.save(&path).unwrap();
    let back = IdentifiedModel::load(&path).unwrap();
    assert_eq!(back.parameters, composite.parameters);
    for x in &samples {
        assert_eq!(back.predict(x).unwrap(), composite.predict(x).unwrap());
    }
    let _ = std::fs::remove_file(&path);
}
