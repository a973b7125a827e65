//! Plots render without system fonts and are written whole (SVG + PNG, no partial files).

mod scratch;
use mrsysid::Axis;
use mrsysid::report::plots::{
    AxisSeries, EffectResidual, FoldR2, NormalProbability, ResidualDensity, effect_residuals,
    fold_r2, normal_probability, residual_densities, time_histories,
};

fn out_dir(name: &str) -> std::path::PathBuf {
    scratch::dir(&format!("plots-{name}"))
}

fn assert_written(files: &[std::path::PathBuf]) {
    assert_eq!(files.len(), 2);
    for f in files {
        let len = std::fs::metadata(f).unwrap().len();
        // A 1500×1100 chart with labelled axes is tens of kB in either format; an empty
        // canvas or a failed font would be far smaller.
        assert!(len > 20_000, "{} is only {len} bytes", f.display());
    }
    let png = &files[1];
    let bytes = std::fs::read(png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let dir = png.parent().unwrap();
    let partial = std::fs::read_dir(dir)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .contains("partial")
        })
        .count();
    assert_eq!(partial, 0, "temporary files left behind");
}

#[test]
fn time_histories_render() {
    let t: Vec<f64> = (0..20_000).map(|i| i as f64 * 0.005).collect();
    let z: Vec<Vec<f64>> = (0..6)
        .map(|a| t.iter().map(|x| (x * (a + 1) as f64).sin()).collect())
        .collect();
    let y: Vec<Vec<f64>> = z
        .iter()
        .map(|s| s.iter().map(|v| 0.9 * v).collect())
        .collect();
    let series: Vec<AxisSeries> = Axis::ALL
        .iter()
        .map(|&axis| AxisSeries {
            axis,
            t: &t,
            measured: &z[axis as usize],
            predicted: &y[axis as usize],
            final_model: Some(&z[axis as usize]),
            final_is_eq22: axis == Axis::Mz,
        })
        .collect();
    let dir = out_dir("time");
    assert_written(&time_histories(&dir.join("fit_time"), "fit data", &series).unwrap());
}

#[test]
fn residual_plots_render() {
    let dens: Vec<ResidualDensity> = Axis::ALL
        .iter()
        .map(|&axis| {
            let edges: Vec<f64> = (0..=30).map(|i| -3.0 + 0.2 * i as f64).collect();
            let density = edges
                .windows(2)
                .map(|e| {
                    (-0.5 * ((e[0] + e[1]) / 2.0f64).powi(2)).exp()
                        / (2.0 * std::f64::consts::PI).sqrt()
                })
                .collect();
            ResidualDensity {
                axis,
                edges,
                density,
                mean: 0.0,
                std: 1.0,
            }
        })
        .collect();
    let dir = out_dir("resid");
    assert_written(&residual_densities(&dir.join("residual_density"), "residuals", &dens).unwrap());
    let np: Vec<NormalProbability> = Axis::ALL
        .iter()
        .map(|&axis| NormalProbability {
            axis,
            points: (0..200)
                .map(|i| {
                    let q = -2.5 + 5.0 * i as f64 / 199.0;
                    (q, 0.3 * q)
                })
                .collect(),
            correlation: 1.0,
        })
        .collect();
    assert_written(
        &normal_probability(&dir.join("normal_probability"), "normal probability", &np).unwrap(),
    );
}

#[test]
fn unwritable_directory_is_an_error_naming_the_file() {
    let series: Vec<AxisSeries> = Vec::new();
    let err = time_histories(std::path::Path::new("/nonexistent-dir/x"), "t", &series).unwrap_err();
    assert!(
        err.to_string()
            .starts_with("/nonexistent-dir/x.svg: cannot write plot"),
        "{err}"
    );
}

/// Held-out R² per fold: three logs, one Eq. 22 figure far below the floor (drawn to it,
/// its value written on the bar, as NeuroBEM's −1587 % pitch), names kept to their
/// first 22 characters.
#[test]
fn fold_r2_renders_with_a_clipped_bar() {
    let axes: Vec<FoldR2> = Axis::ALL
        .iter()
        .map(|&axis| FoldR2 {
            axis,
            folds: vec![
                "figure8_1_20210218170320seg2.csv.gz".into(),
                "melon".into(),
                "block 3/3 (12.1-18.1 s)".into(),
            ],
            before: vec![-1587.0, 26.8, 5.8],
            after: vec![57.6, 63.0, 80.0],
        })
        .collect();
    let dir = out_dir("folds");
    let files = fold_r2(&dir.join("cross_validation_r2"), "folds", &axes).unwrap();
    assert_written(&files);
    let svg = std::fs::read_to_string(&files[0]).unwrap();
    assert!(
        svg.contains("-1587") && svg.contains("figure8_1_20210218170") && svg.contains("block 3/3")
    );
    assert!(!svg.contains("12.1-18.1"));
}

/// Partial residuals of two added effects render (one panel each).
#[test]
fn effect_residuals_render() {
    let load: Vec<f64> = (0..2000).map(|i| (i as f64 * 0.01).sin()).collect();
    let after: Vec<f64> = (0..2000).map(|i| 0.05 * (i as f64 * 0.37).cos()).collect();
    let before: Vec<f64> = load.iter().zip(&after).map(|(l, a)| l + a).collect();
    let effects = [
        EffectResidual {
            name: "quadratic airframe drag, along the airflow",
            axis: Axis::Fx,
            load: &load,
            before: &before,
            after: &after,
        },
        EffectResidual {
            name: "trim moment, 2 Hz",
            axis: Axis::My,
            load: &load,
            before: &before,
            after: &after,
        },
    ];
    let dir = out_dir("effects");
    assert_written(&effect_residuals(&dir.join("added_effects"), "effects", &effects).unwrap());
}
