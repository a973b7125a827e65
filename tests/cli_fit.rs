//! End-to-end tests of the `mrsysid` binary: fit on the shipped data with fit-quality
//! bounds, JSON report and model file, predict/validate consistency, and bad input.

mod scratch;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn mrsysid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("binary runs")
}

fn tmp(name: &str) -> PathBuf {
    scratch::dir("cli").join(name)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn axis_metric(v: &serde_json::Value, part: &str, axis: &str, key: &str) -> f64 {
    v[part]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["axis"] == axis)
        .unwrap()[key]
        .as_f64()
        .unwrap()
}

/// The first undeclared effect (not a completion of Eq. 22's own assumptions) in a
/// report's diagnosis.
fn first_effect(diagnosis: &serde_json::Value) -> &serde_json::Value {
    diagnosis["effects_added"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["model_completion"] == false)
        .expect("an undeclared effect was added")
}

/// Estimate of parameter `name` of an effect row.
fn effect_parameter(effect: &serde_json::Value, name: &str) -> f64 {
    parameter_row(effect, name)["estimate"].as_f64().unwrap()
}

/// The row of parameter `name` of an `effects_added` entry.
fn parameter_row<'a>(effect: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    effect["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("no parameter {name} in {effect}"))
}

/// Simulates a 30 s quad× flight logged at 100 Hz with `extra` simulate arguments, fits
/// it with the diagnosis, and returns the JSON report.
fn simulate_and_fit(name: &str, extra: &[&str]) -> serde_json::Value {
    let flight = ["--mode", "flight", "--duration", "30", "--log-rate", "100"];
    simulate_data_and_fit(name, &[&flight, extra].concat())
}

/// Simulates the shipped quad× with the simulate arguments `data` (mode and its
/// settings, effects, seed), fits it with the diagnosis, and returns the JSON report.
fn simulate_data_and_fit(name: &str, data: &[&str]) -> serde_json::Value {
    let log = tmp(&format!("{name}.csv"));
    let mut args = vec![
        "simulate",
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--out",
        log.to_str().unwrap(),
    ];
    args.extend_from_slice(data);
    let out = mrsysid(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = tmp(&format!("{name}.json"));
    let out = mrsysid(&[
        "fit",
        log.to_str().unwrap(),
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--json",
        report.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    json(&report)
}

/// `mrsysid fit LOG --vehicle data/vehicles/quad_x.toml --no-diagnose --quiet` with
/// `extra` arguments, its JSON report written to `<name>.json` (the fit must succeed).
fn fit_without_diagnosis(log: &Path, name: &str, extra: &[&str]) -> serde_json::Value {
    let report = tmp(&format!("{name}.json"));
    let mut args = vec![
        "fit",
        log.to_str().unwrap(),
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--no-diagnose",
        "--quiet",
        "--json",
        report.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = mrsysid(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    json(&report)
}

#[test]
fn fit_on_shipped_sweeps_meets_fit_quality_bounds() {
    // Sweeps of the blade-element truth (no undeclared effect) over the scaled Table 1
    // ranges: Eq. 22 explains the forces and roll/pitch to a few percent NRMSE (the seed's
    // Table 4 reports 3–11 % on wind-tunnel data); bounds leave 2× margin over what the
    // shipped files give (Fx,Fy ≈ 0.1 %, Fz ≈ 2 %, Mx,My ≈ 1.4 %, Mz ≈ 5 %).
    for (data, vehicle) in [
        ("data/quad_x_sweep.csv", "data/vehicles/quad_x.toml"),
        ("data/quad_plus_sweep.csv", "data/vehicles/quad_plus.toml"),
        ("data/hexa_x_sweep.csv", "data/vehicles/hexa_x.toml"),
    ] {
        let report = tmp(&format!("{}.json", vehicle.replace('/', "_")));
        let out = mrsysid(&[
            "fit",
            data,
            "--vehicle",
            vehicle,
            "--json",
            report.to_str().unwrap(),
            "--no-diagnose",
            "--quiet",
        ]);
        assert!(
            out.status.success(),
            "{data}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = json(&report);
        assert_eq!(v["schema_version"], 2);
        // Every point is fitted, and held out once by the contiguous blocks.
        assert_eq!(v["samples"].as_u64().unwrap(), 2000);
        assert_eq!(v["validation_samples"].as_u64().unwrap(), 2000);
        for (axis, bound) in [
            ("Fx", 0.01),
            ("Fy", 0.01),
            ("Fz", 0.05),
            ("Mx", 0.04),
            ("My", 0.04),
            ("Mz", 0.12),
        ] {
            let nrmse = axis_metric(&v, "validation", axis, "nrmse");
            assert!(nrmse < bound, "{data} {axis}: validation NRMSE {nrmse}");
        }
    }
}

#[test]
fn printed_tables_match_the_json() {
    let report = tmp("quadx.json");
    let out = mrsysid(&[
        "fit",
        "data/quad_x_sweep.csv",
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--json",
        report.to_str().unwrap(),
        "--no-diagnose",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for section in [
        "FSOA Fx",
        "FSOA Mz",
        "MMR fit per axis (Table 4)",
        "MMR parameter estimates (Table 5)",
        "Residual covariance",
        "Residual normality",
        "Identifiability",
    ] {
        assert!(text.contains(section), "missing {section}");
    }
    let v = json(&report);
    // The Fz NRMSE line shows the JSON value to two decimals in percent.
    let nrmse = 100.0 * axis_metric(&v, "axes", "Fz", "nrmse");
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("Fz ") && l.contains('|'))
        .unwrap();
    assert!(
        line.contains(&format!("{nrmse:.2}")),
        "{line} vs {nrmse:.2}"
    );
}

#[test]
fn diagnosis_finds_the_undeclared_drag_in_the_shipped_flight() {
    // data/quad_x_flight_quadratic_drag.csv was flown with quadratic_drag=0.012,0.012,0.03.
    let report = tmp("flight.json");
    let model = tmp("flight_model.toml");
    let out = mrsysid(&[
        "fit",
        "data/quad_x_flight_quadratic_drag.csv",
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--json",
        report.to_str().unwrap(),
        "--model-out",
        model.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&report);
    let d = &v["diagnosis"];
    // Completions of Eq. 22's own assumptions (e.g. yaw-rate rotor drag, which the
    // simulator has) may come first; the first undeclared effect must be the drag.
    let first = first_effect(d);
    assert_eq!(first["name"], "quadratic airframe drag");
    let area_x = first["parameters"][0]["estimate"].as_f64().unwrap();
    // Drag area along x recovered within 10 % of 0.012 m² (measured: 2 %).
    assert!((area_x - 0.012).abs() < 0.0012, "{area_x}");
    let before = axis_metric(d, "before", "Fx", "nrmse");
    let after = axis_metric(d, "after", "Fx", "nrmse");
    assert!(
        after < 0.7 * before,
        "Fx validation NRMSE {before} -> {after}"
    );
    // One verdict per column: the simulator's yaw-rate rotor drag (a named two-parameter
    // completion) is added, not the generic `Mz r*dt` that holds its leading column (the
    // smallest-P test of its correlated parameters once rejected it, P = 3.7e-3).
    let added: Vec<&str> = d["effects_added"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert!(added.contains(&"yaw-rate rotor drag"), "{added:?}");
    assert!(!added.contains(&"generic Mz r*dt"), "{added:?}");
    // The saved model is the augmented one.
    let text = std::fs::read_to_string(&model).unwrap();
    assert!(text.contains("drag_area_x"));
}

#[test]
fn predict_and_validate_agree_with_fit() {
    let model = tmp("sweep_model.toml");
    let out = mrsysid(&[
        "fit",
        "data/quad_plus_sweep.csv",
        "--vehicle",
        "data/vehicles/quad_plus.toml",
        "--model-out",
        model.to_str().unwrap(),
        "--no-diagnose",
        "--quiet",
    ]);
    assert!(out.status.success());
    let pred = tmp("pred.csv");
    let out = mrsysid(&[
        "predict",
        "--model",
        model.to_str().unwrap(),
        "data/quad_plus_sweep.csv",
        "--out",
        pred.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&pred).unwrap();
    assert_eq!(text.lines().count(), 2001);
    assert_eq!(text.lines().next().unwrap(), "t,fx,fy,fz,mx,my,mz");
    // Predicted F_z tracks the logged F_z: RMS difference within 5 % of the RMS F_z.
    let data = std::fs::read_to_string(root().join("data/quad_plus_sweep.csv")).unwrap();
    let header: Vec<&str> = data.lines().next().unwrap().split(',').collect();
    let fz_col = header.iter().position(|h| *h == "fz").unwrap();
    let (mut se, mut ss) = (0.0, 0.0);
    for (p, d) in text.lines().skip(1).zip(data.lines().skip(1)) {
        let yp: f64 = p.split(',').nth(3).unwrap().parse().unwrap();
        let z: f64 = d.split(',').nth(fz_col).unwrap().parse().unwrap();
        se += (yp - z).powi(2);
        ss += z * z;
    }
    assert!((se / ss).sqrt() < 0.05, "{}", (se / ss).sqrt());
    let vjson = tmp("validate.json");
    let out = mrsysid(&[
        "validate",
        "--model",
        model.to_str().unwrap(),
        "data/quad_plus_sweep.csv",
        "--json",
        vjson.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&vjson);
    assert_eq!(v["samples"], 2000);
    let r2 = axis_metric(&v, "axes", "Fz", "r2");
    assert!(r2 > 0.95, "{r2}");
}

#[test]
fn bad_input_exits_2_with_a_message_naming_the_file_and_no_output() {
    let bad_csv = tmp("bad.csv");
    std::fs::write(&bad_csv, "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz\n0,1,0,0,0,0,0,500,500,500,500,0,0,-10,0,0,0\n0.01,nan,0,0,0,0,0,500,500,500,500,0,0,-10,0,0,0\n").unwrap();
    let report = tmp("never.json");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "fit",
                bad_csv.to_str().unwrap(),
                "--vehicle",
                "data/vehicles/quad_x.toml",
                "--json",
                report.to_str().unwrap(),
            ],
            "bad.csv",
        ),
        (
            vec![
                "fit",
                "data/quad_x_sweep.csv",
                "--vehicle",
                "/nonexistent/v.toml",
            ],
            "/nonexistent/v.toml",
        ),
        (
            vec![
                "fit",
                "/nonexistent/log.csv",
                "--vehicle",
                "data/vehicles/quad_x.toml",
            ],
            "log.csv",
        ),
        (
            vec![
                "fit",
                "data/hexa_x_sweep.csv",
                "--vehicle",
                "data/vehicles/quad_x.toml",
            ],
            "rotor",
        ),
        (
            vec![
                "predict",
                "--model",
                "/nonexistent/m.toml",
                "data/quad_x_sweep.csv",
                "--out",
                "/tmp/x.csv",
            ],
            "/nonexistent/m.toml",
        ),
    ];
    for (args, needle) in cases {
        let out = mrsysid(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    assert!(!report.exists(), "a failed fit left a report");
    // Usage errors are exit code 2 too (clap).
    assert_eq!(mrsysid(&["fit"]).status.code(), Some(2));
}

/// Fits the shipped NeuroBEM segments `logs` (paths after `data/neurobem/`, or absolute
/// paths, with options such as `--validate` in between) through the shipped vehicle and
/// mapping; the JSON report.
fn fit_neurobem(name: &str, logs: &[&str]) -> serde_json::Value {
    let report = tmp(&format!("{name}.json"));
    let paths: Vec<String> = logs
        .iter()
        .map(|l| {
            if l.starts_with("--") || Path::new(l).is_absolute() {
                l.to_string()
            } else {
                format!("data/neurobem/{l}")
            }
        })
        .collect();
    let mut args = vec!["fit"];
    args.extend(paths.iter().map(String::as_str));
    args.extend([
        "--vehicle",
        "data/vehicles/neurobem.toml",
        "--mapping",
        "examples/neurobem.toml",
        "--json",
        report.to_str().unwrap(),
        "--quiet",
    ]);
    let out = mrsysid(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    json(&report)
}

const FIGURE8: &str = "figure8_1_20210218170320seg2.csv.gz";
const MELON: &str = "melon_1_20210223114138seg3.csv.gz";
const RACETRACK: &str = "racetrack_1_20210218171908seg2.csv.gz";

/// R² of `axis` in the before/after row named `name` of the diagnosis' fold table.
fn fold_r2(d: &serde_json::Value, name: &str, part: &str, axis: usize) -> f64 {
    let row = d["folds"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["name"] == name)
        .unwrap_or_else(|| panic!("no fold {name}"));
    row[part][axis]["r2"].as_f64().unwrap()
}

#[test]
fn real_neurobem_three_logs_are_cross_validated_log_by_log() {
    // Three real flights: every decision is scored by leaving one log out. Measured
    // (docs/real-data.md): pooled cross-validated R² Fz 0.56 -> 0.95, Mx 0.09 -> 0.77,
    // My -0.04 -> 0.70, Mz -0.11 -> 0.16 with Fx, Fy at 0.93-0.95 (the trim moment
    // carries most of the moments' gain). The bounds pin that behaviour with a margin of
    // 0.05 for rounding across platforms.
    let v = fit_neurobem("neurobem", &[FIGURE8, MELON, RACETRACK]);
    assert_eq!(v["samples"].as_u64().unwrap(), 14306 + 11431 + 12724);
    let cv = v["cross_validation"].as_array().unwrap();
    let names: Vec<&str> = cv.iter().map(|f| f["name"].as_str().unwrap()).collect();
    assert_eq!(names, [FIGURE8, MELON, RACETRACK, "pooled"]);
    let d = &v["diagnosis"];
    let pooled = |part: &str, axis: usize| fold_r2(d, "pooled", part, axis);
    for (axis, at_least) in [(0, 0.9), (1, 0.9), (2, 0.9), (3, 0.72), (4, 0.65)] {
        assert!(
            pooled("after", axis) >= at_least,
            "axis {axis}: {}",
            pooled("after", axis)
        );
        assert!(pooled("after", axis) >= pooled("before", axis) - 0.01);
    }
    assert!(pooled("after", 5) > 0.11, "Mz {}", pooled("after", 5));
    // Parameters the held-out data do not support are listed, and the final model is
    // smaller than the Eq. 22 model plus the effects added.
    assert!(!d["unsupported"].as_array().unwrap().is_empty());
}

#[test]
fn real_neurobem_validation_logs_are_for_reporting_only() {
    // Fit two flights and report on a third: decisions are cross-validated on the two
    // fit logs (two folds), and the third is scored only at the end. Measured on the
    // race track: Fz R² 0.13 -> 0.85, Mx 0.07 -> 0.77 and My 0.29 -> 0.72 (bounds 0.8,
    // 0.7 and 0.65).
    let model = tmp("neurobem_rotation_model.toml");
    let model_out = format!("--model-out={}", model.display());
    let v = fit_neurobem(
        "neurobem_rotation",
        &[FIGURE8, MELON, "--validate", RACETRACK, &model_out],
    );
    assert_eq!(v["validation_samples"].as_u64().unwrap(), 12724);
    let d = &v["diagnosis"];
    let folds: Vec<&str> = d["folds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        folds,
        [FIGURE8, MELON, "pooled"],
        "the validation log is no fold"
    );
    let val = |part: &str, axis: usize| d["validation"][part][axis]["r2"].as_f64().unwrap();
    // The "before" row is the Eq. 22 model on the validation log, as in the main table.
    let main = axis_metric(&v, "validation", "Fz", "r2");
    assert!(
        (val("before", 2) - main).abs() < 1e-12,
        "{} vs {main}",
        val("before", 2)
    );
    assert!(val("after", 2) >= 0.8, "Fz {}", val("after", 2));
    assert!(val("after", 3) >= 0.7, "Mx {}", val("after", 3));
    assert!(val("after", 4) >= 0.65, "My {}", val("after", 4));
    // The saved model is the final one, terms left out included: `validate` on the
    // race track reproduces the diagnosis' "after" figures (1e-9: the same statistics
    // accumulated in another order).
    assert!(!d["unsupported"].as_array().unwrap().is_empty());
    let saved = validated_r2(&model, &format!("data/neurobem/{RACETRACK}"), "rotation");
    for (axis, r2) in saved.iter().enumerate() {
        assert!((r2 - val("after", axis)).abs() < 1e-9, "axis {axis}: {r2}");
    }
}

/// R² per axis, Fx…Mz, of `mrsysid validate` with the saved `model` on the NeuroBEM
/// `log` (through the shipped mapping); `name` tells the scratch files apart.
fn validated_r2(model: &Path, log: &str, name: &str) -> Vec<f64> {
    let metrics = tmp(&format!("{name}_validate.json"));
    let out = mrsysid(&[
        "validate",
        "--model",
        model.to_str().unwrap(),
        log,
        "--mapping",
        "examples/neurobem.toml",
        "--json",
        metrics.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m = json(&metrics);
    (0..6)
        .map(|axis| m["axes"][axis]["r2"].as_f64().unwrap())
        .collect()
}

/// The shipped NeuroBEM segment `log` cut in two contract-free CSV files in the scratch
/// directory: its first `share` of samples and the rest, each with the header.
fn split_neurobem(log: &str, share: f64) -> (PathBuf, PathBuf) {
    use std::io::Read;
    let mut text = String::new();
    flate2::read::GzDecoder::new(std::fs::File::open(format!("data/neurobem/{log}")).unwrap())
        .read_to_string(&mut text)
        .unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.collect();
    let k = (rows.len() as f64 * share) as usize;
    let write = |name: &str, rows: &[&str]| {
        let path = tmp(name);
        std::fs::write(&path, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
        path
    };
    let stem = log.split('_').next().unwrap();
    (
        write(&format!("{stem}_first.csv"), &rows[..k]),
        write(&format!("{stem}_last.csv"), &rows[k..]),
    )
}

#[test]
fn an_axis_the_final_model_predicts_worse_is_predicted_by_eq22() {
    // The race track fitted on its first 80 % and validated on its last 20 %, with the
    // documented NeuroBEM options. Measured: the final model predicts the held-out
    // blocks' M_z worse than Eq. 22 (pooled R² 5.7 % -> 5.1 %), and the flight's future
    // too (20.9 % -> 10.0 %). The adopted model predicts M_z with the Eq. 22 model, so
    // there it equals Eq. 22 exactly (on the blocks and on the validation log), and the
    // saved model reproduces the adopted model on every axis (1e-9: the same
    // statistics accumulated in another order).
    let (first, last) = split_neurobem(RACETRACK, 0.8);
    let model = tmp("eq22_axes_model.toml");
    let model_out = format!("--model-out={}", model.display());
    let v = fit_neurobem(
        "eq22_axes",
        &[
            first.to_str().unwrap(),
            "--validate",
            last.to_str().unwrap(),
            "--rotor-inertia=estimated",
            &model_out,
        ],
    );
    let d = &v["diagnosis"];
    let eq22 = d["eq22_axes"]
        .as_array()
        .expect("an axis falls back to Eq. 22");
    let axes: Vec<&str> = eq22.iter().map(|e| e["axis"].as_str().unwrap()).collect();
    assert_eq!(axes, ["Mz"]);
    let held_out = |part: &str| axis_metric(d, part, "Mz", "rmse");
    assert_eq!(held_out("after"), held_out("before"));
    assert!(eq22[0]["final_held_out"]["rmse"].as_f64().unwrap() > held_out("before"));
    let val = |part: &str, axis: usize| d["validation"][part][axis]["r2"].as_f64().unwrap();
    assert_eq!(val("after", 5), val("before", 5));
    let final_val = eq22[0]["final_validation"]["r2"].as_f64().unwrap();
    assert!(final_val < val("before", 5), "{final_val}");
    let saved = validated_r2(&model, last.to_str().unwrap(), "eq22_axes");
    for (axis, r2) in saved.iter().enumerate() {
        let after = val("after", axis);
        assert!((r2 - after).abs() < 1e-9, "axis {axis}: {r2} vs {after}");
    }
}

#[test]
fn json_report_round_trips_through_the_schema_types() {
    let report = tmp("roundtrip.json");
    let out = mrsysid(&[
        "fit",
        "data/hexa_x_sweep.csv",
        "--vehicle",
        "data/vehicles/hexa_x.toml",
        "--json",
        report.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&report).unwrap();
    let parsed: mrsysid::report::summary::Report = serde_json::from_str(&text).unwrap();
    assert_eq!(serde_json::to_string_pretty(&parsed).unwrap(), text);
    assert_eq!(parsed.vehicle.class, "multirotor>=6");
    assert_eq!(parsed.fsoa.len(), 6);
}

#[test]
fn diagnosis_on_an_imu_only_flight_finds_a_cg_offset() {
    // A 30 s aggressive flight logged like a real vehicle (gyro and accelerometer noise
    // and bias, quantised eRPM, no force/moment columns: F = m a, M = I ω̇ + ω × Iω are
    // derived on read), with the true CG 10 mm forward and 8 mm left of the reference.
    let v = simulate_and_fit(
        "imu_cg",
        &[
            "--imu-only",
            "--effect",
            "cg_offset=0.01,-0.008,0",
            "--seed",
            "7",
        ],
    );
    let d = &v["diagnosis"];
    let first = first_effect(d);
    // Either form of the offset (the lever force from F_z's own fit or the joint one).
    assert!(
        first["name"].as_str().unwrap().starts_with("CG offset"),
        "{}",
        first["name"]
    );
    let final_estimate = |name: &str| {
        parameter_row(first, name)["final_estimate"]
            .as_f64()
            .unwrap()
    };
    let (dx, dy) = (final_estimate("cg_dx"), final_estimate("cg_dy"));
    // In the adopted model, within 10 % (measured 9.57 mm and −7.67 mm; 9.50 mm and
    // −7.56 mm when it was added, first, in the form with the forces' own fit; before
    // that form it entered after the in-plane force lever arm at 8.9 mm and −5.9 mm).
    assert!((dx - 0.010).abs() < 0.001, "{dx}");
    assert!((dy + 0.008).abs() < 0.0008, "{dy}");
    let (b, a) = (
        axis_metric(d, "before", "Mx", "nrmse"),
        axis_metric(d, "after", "Mx", "nrmse"),
    );
    assert!(a < 0.7 * b, "Mx validation NRMSE {b} -> {a}");
}

#[test]
fn diagnosis_on_a_flight_finds_an_unmeasured_steady_wind() {
    // A 30 s flight in a steady 3 m/s north, 2 m/s west wind whose log holds the
    // ground-relative velocity. The candidate is first order in the wind and built
    // from base estimates the wind has biased: measured 3.13, −2.48, 0.21 m/s, so each
    // component must come within 0.6 m/s (a sixth of the 3.6 m/s wind).
    let v = simulate_and_fit("wind", &["--effect", "wind=3,-2,0", "--seed", "9"]);
    let d = &v["diagnosis"];
    let first = first_effect(d);
    assert_eq!(first["name"], "steady wind");
    for (name, truth) in [("wind_north", 3.0), ("wind_east", -2.0), ("wind_down", 0.0)] {
        let w = effect_parameter(first, name);
        assert!((w - truth).abs() < 0.6, "{name} {w}");
    }
    let (b, a) = (
        axis_metric(d, "before", "Fx", "nrmse"),
        axis_metric(d, "after", "Fx", "nrmse"),
    );
    assert!(a < 0.7 * b, "Fx validation NRMSE {b} -> {a}");
}

#[test]
fn clean_flights_name_no_undeclared_effect() {
    // Ten 30 s flights without any declared effect, loads logged with noise. The truth's
    // airframe has a linear drag along every body axis (src/sim/truth.rs, 0.15 N s/m
    // along z), which Eq. 22 holds in-plane (C_H_mub_mu0 ν0 u) but on F_z only inside
    // the rotor-speed-scaled C_T_muw it shares with the moments: the completion "linear
    // vertical airframe drag" takes it. Before that completion, vertical quadratic drag
    // (a w|w| look-alike) was named at 3 of these seeds (41, 42, 48); with the truth's
    // vertical linear drag set to zero it was named at none. The truth's momentum-theory
    // inflow also changes thrust in descent near ν0, which every flight visits and
    // Eq. 22's linearised inflow lacks; at seed 45 the vortex-ring candidate takes that
    // shape (as before this completion). So: at most one of the ten seeds names an
    // effect, and the airframe drag is named at none. Model completions and unspecific
    // terms may be added: the simulator's inflow, airframe and hub kinematics hold
    // physics Eq. 22 lacks, and naming it as such is right.
    let mut named_seeds = Vec::new();
    for seed in 40..50 {
        let v = simulate_and_fit(&format!("clean_{seed}"), &["--seed", &seed.to_string()]);
        let named: Vec<String> = v["diagnosis"]["effects_added"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["model_completion"] == false && e["unspecific"] == false)
            .map(|e| e["name"].as_str().unwrap().to_string())
            .collect();
        assert!(
            !named.iter().any(|n| n.contains("airframe drag")),
            "seed {seed}: {named:?}"
        );
        if !named.is_empty() {
            named_seeds.push((seed, named));
        }
    }
    assert!(named_seeds.len() <= 1, "{named_seeds:?}");
}

#[test]
fn diagnosis_on_a_flight_finds_the_vortex_ring_state() {
    // A 30 s flight whose rotors lose up to 40 % of their thrust descending near ν0
    // (`vortex_ring=0.4`). The state is named first; its loss reads above the truth's 0.4
    // because the truth's momentum-theory inflow already takes thrust below Eq. 22's
    // linear inflow there (the clean flight of seed 45 names a loss of 0.14 for it, 0.27
    // in its final model):
    // measured 0.566, 0.584, 0.586 and 0.579 at seeds 61–64, so within 0.4–0.6 (the
    // candidate's plausible range ends at 0.6).
    let v = simulate_and_fit(
        "vortex_ring",
        &["--effect", "vortex_ring=0.4", "--seed", "62"],
    );
    let first = first_effect(&v["diagnosis"]);
    assert_eq!(first["name"], "vortex-ring state");
    let loss = effect_parameter(first, "vortex_ring_thrust_loss");
    assert!((0.4..=0.6).contains(&loss), "{loss}");
}

#[test]
fn a_vertical_airframe_drag_is_recovered_as_the_linear_drag_completion() {
    // A sweep whose airframe drags 0.6 N s/m along z (four times the simulator's
    // default): the completion's column −D_z w holds it, so the diagnosis adds it first
    // and reads D_z. Measured 0.607 at seeds 1–3: within 3 % (the truth's blade-element
    // thrust has Ω-free w structure of its own, which the estimate shares: 0.107 on the
    // default 0.15 N s/m).
    let rotor = tmp("vertical_drag_rotor.toml");
    std::fs::write(&rotor, "linear_drag = [0.0753, 0.0753, 0.6]\n").unwrap();
    let sweep = ["--mode", "sweep", "--points", "3000", "--seed", "2"];
    let v = simulate_data_and_fit(
        "vertical_drag",
        &[&sweep[..], &["--rotor", rotor.to_str().unwrap()]].concat(),
    );
    let first = &v["diagnosis"]["effects_added"][0];
    assert_eq!(first["name"], "linear vertical airframe drag");
    assert_eq!(first["model_completion"], true);
    let d = effect_parameter(first, "linear_drag_z");
    assert!((d - 0.6).abs() < 0.018, "{d}");
}

#[test]
fn diagnosis_on_a_flight_finds_a_rotor_speed_delay_within_one_sample() {
    // A 30 s flight whose logged rotor speeds lag the true ones by 20 ms (2 log samples
    // at 100 Hz); the delay must come out within one sample (10 ms).
    // Thrust responding to rotor acceleration (ΔT_i = k Ω̇_i) is the same model to
    // within the Ω-weighting of the delay's dT/dΩ (±20 % about hover here): the two are
    // forms of one effect. When that form is added, the step must name the delay as the
    // form (or look-alike) the data cannot tell apart, and the delay candidate scored in
    // that step must hold the delay.
    let v = simulate_and_fit("delay", &["--effect", "delay=0.02", "--seed", "8"]);
    let d = &v["diagnosis"];
    let first = first_effect(d);
    let step = d["steps"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["added"] == first["name"])
        .unwrap();
    if first["name"] != "rotor-speed delay" {
        assert_eq!(first["name"], "thrust from rotor acceleration");
        let alike = |key: &str| step[key].as_array().unwrap().clone();
        let named = [alike("look_alikes"), alike("not_separable")].concat();
        assert!(named.iter().any(|n| n == "rotor-speed delay"), "{named:?}");
    }
    let delay = step["ranking"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "rotor-speed delay")
        .unwrap();
    // Accepted, or held back only by a held-out bar the winner just cleared (measured:
    // held-out likelihood ratio 303 against 332 for the winner and a bar of 318).
    let rejected = delay["rejected"].as_str().unwrap();
    assert!(
        rejected.is_empty() || rejected.starts_with("held-out likelihood ratio"),
        "{delay}"
    );
    let tau = effect_parameter(delay, "rotor_speed_delay");
    assert!((tau - 0.02).abs() < 0.01, "{tau}");
}

/// The first 80 % and the last 20 % of the rows of the shipped log `path` (plain or
/// gzip CSV), each written with the header as `<name>_80.csv` and `<name>_20.csv`.
fn cut_80_20(path: &str, name: &str) -> (PathBuf, PathBuf) {
    use std::io::Read;
    let bytes = std::fs::read(root().join(path)).unwrap();
    let mut text = String::new();
    if path.ends_with(".gz") {
        flate2::read::MultiGzDecoder::new(&bytes[..])
            .read_to_string(&mut text)
            .unwrap();
    } else {
        text = String::from_utf8(bytes).unwrap();
    }
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.collect();
    let cut = rows.len() * 8 / 10;
    let write = |part: &[&str], share: &str| {
        let file = tmp(&format!("{name}_{share}.csv"));
        std::fs::write(&file, format!("{header}\n{}\n", part.join("\n"))).unwrap();
        file
    };
    (write(&rows[..cut], "80"), write(&rows[cut..], "20"))
}

/// Fits the first 80 % of the shipped log `path` (vehicle and mapping in `options`) and
/// scores the last 20 % with `--validate`: R² per axis (Fx … Mz) of the Eq. 22 model and
/// of the final model there, and the report.
fn fit_on_the_past(
    path: &str,
    name: &str,
    options: &[&str],
) -> ([f64; 6], [f64; 6], serde_json::Value) {
    let (past, future) = cut_80_20(path, name);
    let report = tmp(&format!("{name}_80_20.json"));
    let mut args = vec![
        "fit",
        past.to_str().unwrap(),
        "--validate",
        future.to_str().unwrap(),
    ];
    args.extend_from_slice(options);
    args.extend(["--json", report.to_str().unwrap(), "--quiet"]);
    let out = mrsysid(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&report);
    let r2 = |part: &str| -> [f64; 6] {
        std::array::from_fn(|a| {
            v["diagnosis"]["validation"][part][a]["r2"]
                .as_f64()
                .unwrap()
        })
    };
    (r2("before"), r2("after"), v)
}

#[test]
fn a_single_flight_fitted_on_its_first_80_percent_predicts_the_rest_no_worse_than_eq22() {
    // A single log is cross-validated on contiguous blocks, so the diagnosis's decisions
    // are scored on data beyond the fitted data. Fitted on the first 80 % of a flight,
    // the final model predicts the last 20 % (which no decision sees) no worse than the
    // Eq. 22 model on any axis. Measured, R² [%] Eq. 22 -> final on the last 20 %, with
    // the documented NeuroBEM command (the mapping's 25 Hz consistent filter, J_z
    // estimated): figure-8 Fx 55.68 -> 55.69, Fy -0.9 -> 4.0, Fz -2.8 -> 61.9,
    // Mx 7.4 -> 62.5, My 10.6 -> 71.3, Mz 23.7 -> 36.9 (without the filter and with J_z
    // known: Fx 55.7 -> 57.2, Mx 9.0 -> 45.9, My 11.9 -> 68.1, Mz -0.3 -> 15.7; with
    // every 5th 2 s segment held out instead of blocks: Fx 52.0, Fy -2.2 and Mz -2.9,
    // worse than Eq. 22); the shipped simulated flight Fz 91.0 -> 91.8, every other axis
    // 85.7-99.8 -> 99.5-100. "No worse" is held to 0.1 points of R²: an axis the
    // diagnosis leaves alone still moves by rounding-level amounts through the parameters
    // the MMR shares between axes (F_x: 55.71 -> 55.69 with J_z known); the gains where
    // the diagnosis pays are pinned 0.05 below the measured figures.
    let nb = [
        "--vehicle",
        "data/vehicles/neurobem.toml",
        "--mapping",
        "examples/neurobem.toml",
        "--rotor-inertia",
        "estimated",
    ];
    let (before, after, v) = fit_on_the_past(&format!("data/neurobem/{FIGURE8}"), "figure8", &nb);
    let folds = v["diagnosis"]["folds"].as_array().unwrap();
    assert_eq!(folds.len(), 5 + 1, "five contiguous blocks, then pooled");
    assert!(folds[4]["name"].as_str().unwrap().starts_with("block 5/5"));
    for a in 0..6 {
        assert!(
            after[a] >= before[a] - 0.001,
            "axis {a}: {} -> {}",
            before[a],
            after[a]
        );
    }
    assert!(
        after[2] >= 0.56 && after[3] >= 0.57 && after[4] >= 0.66 && after[5] >= 0.31,
        "Fz {}, Mx {}, My {}, Mz {}",
        after[2],
        after[3],
        after[4],
        after[5]
    );
    let quad = ["--vehicle", "data/vehicles/quad_x.toml"];
    let (before, after, _) = fit_on_the_past(
        "data/quad_x_flight_quadratic_drag.csv",
        "drag_flight",
        &quad,
    );
    for a in 0..6 {
        assert!(
            after[a] >= before[a] - 0.001,
            "axis {a}: {} -> {}",
            before[a],
            after[a]
        );
    }
    assert!(after[3] >= 0.94, "Mx {}", after[3]);
}

/// Cross-validated R² of axis `axis` (pooled over the blocks) in a report.
fn cross_validated_r2(v: &serde_json::Value, axis: &str) -> f64 {
    let pooled = v["cross_validation"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["name"] == "pooled")
        .unwrap();
    axis_metric(pooled, "axes", axis, "r2")
}

/// Consistent filtering, proven on the simulator. A 60 s flight whose logged loads were
/// smoothed when the log was made (zero-phase 2nd-order Butterworth at 5 Hz, the
/// truth's `smoothed_loads=5`) while its states and rotor speeds were not: declaring the
/// cut-off (`--loads-low-pass 5`) passes the regressor signals through the crate's own
/// zero-phase low-pass (another filter shape at the same −3 dB frequency) and the yaw
/// moment, whose J_z Ω̇ reaction torque is the fastest load, is predicted (cross-validated
/// R² 0.9 % → 98.8 % measured); the model file keeps the cut-off, so `validate` on the
/// same log filters alike. On the clean flight of the same seed the same declaration is
/// wrong, and the yaw moment is lost (99.7 % → 0.8 % measured): the cut-off must be
/// the log's, never a tuning knob. Estimated from the data instead, the cut-off is
/// found on the smoothed log and none is kept on the clean one.
#[test]
fn declared_load_smoothing_is_matched_by_the_regressors_and_hurts_where_absent() {
    let smoothed = tmp("smoothed_5hz.csv");
    let clean = tmp("clean_for_smoothing.csv");
    for (log, effect) in [(&smoothed, Some("smoothed_loads=5")), (&clean, None)] {
        let mut args = vec![
            "simulate",
            "--vehicle",
            "data/vehicles/quad_x.toml",
            "--mode",
            "flight",
            "--duration",
            "60",
            "--log-rate",
            "100",
            "--seed",
            "7",
            "--out",
            log.to_str().unwrap(),
        ];
        if let Some(e) = effect {
            args.extend(["--effect", e]);
        }
        let out = mrsysid(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let fit = |log: &Path, name: &str, low_pass: Option<&str>| {
        let model = tmp(&format!("{name}.toml"));
        let mut extra = vec!["--model-out", model.to_str().unwrap()];
        if let Some(hz) = low_pass {
            extra.extend(["--loads-low-pass", hz]);
        }
        (fit_without_diagnosis(log, name, &extra), model)
    };
    let (raw, _) = fit(&smoothed, "smoothed_raw", None);
    let (matched, model) = fit(&smoothed, "smoothed_matched", Some("5"));
    let (r_raw, r_matched) = (
        cross_validated_r2(&raw, "Mz"),
        cross_validated_r2(&matched, "Mz"),
    );
    assert!(r_raw < 0.2 && r_matched > 0.9, "Mz {r_raw} -> {r_matched}");
    assert_eq!(matched["loads_low_pass_hz"], 5.0);
    // Roll and pitch no worse (97.0/97.1 % -> 97.1/97.2 % measured).
    for axis in ["Mx", "My"] {
        let (a, b) = (
            cross_validated_r2(&raw, axis),
            cross_validated_r2(&matched, axis),
        );
        assert!(b > a - 0.005, "{axis} {a} -> {b}");
    }
    // The model file keeps the cut-off; validate filters alike (98.8 % on the fit log).
    assert!(
        std::fs::read_to_string(&model)
            .unwrap()
            .contains("loads_low_pass_hz = 5.0")
    );
    let out = mrsysid(&[
        "validate",
        "--model",
        model.to_str().unwrap(),
        smoothed.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    let mz: f64 = text
        .lines()
        .find(|l| l.trim_start().starts_with("Mz"))
        .and_then(|l| l.split_whitespace().nth(3))
        .and_then(|r| r.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(mz > 90.0, "validate Mz R2 {mz} %");
    let (clean_raw, _) = fit(&clean, "clean_raw", None);
    let (clean_declared, _) = fit(&clean, "clean_declared", Some("5"));
    let (a, b) = (
        cross_validated_r2(&clean_raw, "Mz"),
        cross_validated_r2(&clean_declared, "Mz"),
    );
    assert!(a > 0.9 && b < 0.5, "clean flight Mz {a} -> {b}");

    // Not declared but estimated (`--loads-low-pass estimate`): the scan keeps a cut-off
    // near the log's (5.7 Hz measured: the crate's sinc³ filter at 5.7 Hz matches a
    // 2nd-order Butterworth at 5 Hz run forwards and backwards; 4 Hz scores within 0.6 %
    // of it) and on the clean flight keeps none (every filter from 11 Hz down loses the
    // yaw moment; above 16 Hz a 100 Hz log's filter window holds one sample and does
    // nothing, so those tie with unfiltered and unfiltered is kept).
    let (estimated, model) = fit(&smoothed, "smoothed_estimated", Some("estimate"));
    let chosen = estimated["loads_low_pass_hz"].as_f64();
    assert!(
        matches!(chosen, Some(hz) if (4.0..=5.7).contains(&hz)),
        "{chosen:?}"
    );
    assert!(cross_validated_r2(&estimated, "Mz") > 0.9);
    // The fit kept is the scan's trial at that cut-off, not fitted again: the report is
    // the one of the cut-off declared, bit for bit, but for the scan itself.
    let hz = format!("{}", chosen.unwrap());
    let (declared, _) = fit(&smoothed, "smoothed_declared_as_estimated", Some(&hz));
    let strip = |v: &serde_json::Value| {
        let mut v = v.clone();
        let o = v.as_object_mut().unwrap();
        o.remove("loads_low_pass_scan");
        o.remove("tool_version");
        v
    };
    assert_eq!(strip(&estimated), strip(&declared));
    let points = estimated["loads_low_pass_scan"]["points"]
        .as_array()
        .unwrap();
    assert!(
        points[0]["cutoff_hz"].is_null() && points.len() >= 5,
        "{points:?}"
    );
    assert!(
        std::fs::read_to_string(&model)
            .unwrap()
            .contains(&format!("loads_low_pass_hz = {:?}", chosen.unwrap()))
    );
    let (clean_estimated, _) = fit(&clean, "clean_estimated", Some("estimate"));
    assert!(clean_estimated["loads_low_pass_hz"].is_null());
    assert!(clean_estimated["loads_low_pass_scan"]["chosen_hz"].is_null());
    assert_eq!(cross_validated_r2(&clean_estimated, "Mz"), a);
}

/// A loads cut-off that is not a positive number of Hz is refused, on the command line
/// (exit 2) and in a mapping file (naming the key).
#[test]
fn a_loads_cut_off_must_be_a_positive_frequency() {
    let out = mrsysid(&[
        "fit",
        "data/quad_x_sweep.csv",
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--loads-low-pass=-3",
        "--quiet",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("low-pass cut-off") && err.contains("-3"),
        "{err}"
    );
    let mapping = tmp("bad_loads.toml");
    std::fs::write(&mapping, "[loads]\nlow_pass_hz = 0\n").unwrap();
    let e = mrsysid::io::Mapping::from_toml_file(&mapping).unwrap_err();
    assert!(e.to_string().contains("loads.low_pass_hz"), "{e}");
}

/// A declared loads cut-off above half the log's sample rate (the shipped flight logs at
/// 100 Hz) is refused, exit 2, naming the log, its half rate and what to do: such a
/// filter does nothing, so it cannot be what the loads went through. 50 Hz is accepted.
#[test]
fn a_loads_cut_off_above_half_the_sample_rate_is_refused() {
    let fit = |hz: &str| {
        mrsysid(&[
            "fit",
            "data/quad_x_flight_quadratic_drag.csv",
            "--vehicle",
            "data/vehicles/quad_x.toml",
            "--loads-low-pass",
            hz,
            "--no-diagnose",
            "--quiet",
        ])
    };
    let out = fit("60");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for needle in [
        "cut-off 60 Hz is above half the sample rate of quad_x_flight_quadratic_drag.csv (50.0 Hz",
        "--loads-low-pass estimate",
    ] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
    let out = fit("50");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `mrsysid accumulate` writes each log's first pass to a statistics file, and
/// `fit --from-stats` fits them without reading a log: the same estimates, σ (white),
/// fit, cross-validation and validation figures as the direct fit of the logs (whose
/// residual pass adds the coloured σ and the residual statistics a fit from statistics
/// cannot have). A corrupted file and an option that needs the samples are refused
/// (exit 2) naming what is wrong.
#[test]
fn a_fit_from_statistics_files_reports_what_the_direct_fit_reports() {
    let v = ["--vehicle", "data/vehicles/quad_x.toml"];
    let logs = [
        "data/quad_x_sweep.csv",
        "data/quad_x_flight_quadratic_drag.csv",
    ];
    let parts = [tmp("sweep.stats"), tmp("flight.stats")];
    for (log, part) in logs.iter().zip(&parts) {
        let part = part.to_str().unwrap();
        let out = mrsysid(&[&["accumulate", log, "-o", part][..], &v].concat());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let (direct, stats) = (tmp("direct.json"), tmp("from-stats.json"));
    let (p0, p1) = (parts[0].to_str().unwrap(), parts[1].to_str().unwrap());
    let out = mrsysid(
        &[
            &[
                "fit",
                logs[0],
                logs[1],
                "--no-diagnose",
                "--quiet",
                "--json",
            ][..],
            &[direct.to_str().unwrap()],
            &v,
        ]
        .concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = mrsysid(
        &[
            &["fit", "--from-stats", p0, p1, "--json"][..],
            &[stats.to_str().unwrap()],
            &v,
        ]
        .concat(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("fit from statistics: 2 logs, 5001 samples"),
        "{stderr}"
    );
    let (d, s) = (json(&direct), json(&stats));
    for key in [
        "samples",
        "validation_source",
        "axes",
        "validation",
        "cross_validation",
        "fsoa",
    ] {
        assert_eq!(d[key], s[key], "{key}");
    }
    let params = |r: &serde_json::Value| -> Vec<(String, f64, f64)> {
        let ps = r["parameters"].as_array().unwrap();
        ps.iter()
            .map(|p| {
                let name = p["name"].as_str().unwrap().to_string();
                (
                    name,
                    p["estimate"].as_f64().unwrap(),
                    p["std"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    assert_eq!(params(&d), params(&s));
    assert!(
        s["parameters"][0]["std_coloured"].is_null(),
        "no residual pass"
    );

    let bad = tmp("corrupted.stats");
    let mut bytes = std::fs::read(&parts[0]).unwrap();
    bytes[40] ^= 0xff;
    std::fs::write(&bad, bytes).unwrap();
    let out = mrsysid(&[&["fit", "--from-stats", bad.to_str().unwrap(), p1][..], &v].concat());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("corrupted.stats: checksum mismatch"),
        "{stderr}"
    );
    let plots = tmp("stats-plots");
    let out = mrsysid(
        &[
            &[
                "fit",
                "--from-stats",
                p0,
                p1,
                "--plots",
                plots.to_str().unwrap(),
            ][..],
            &v,
        ]
        .concat(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--plots needs the samples"), "{stderr}");
}

#[test]
fn fit_with_named_groups_cross_validates_and_diagnoses_group_by_group() {
    // Four quarters of the shipped 30 s flight, the first two one "day", the last two
    // another: the folds are the two groups, the diagnosis judges every candidate on
    // them (the drag is still found: it acts in every quarter), and the table says how
    // the folds were made.
    let text = std::fs::read_to_string(root().join("data/quad_x_flight_quadratic_drag.csv"))
        .expect("shipped flight");
    let mut lines = text.lines();
    let header = lines.next().expect("header");
    let rows: Vec<&str> = lines.collect();
    let logs: Vec<PathBuf> = rows
        .chunks(rows.len().div_ceil(4))
        .enumerate()
        .map(|(i, chunk)| {
            let path = tmp(&format!("groups_q{i}.csv"));
            std::fs::write(&path, format!("{header}\n{}\n", chunk.join("\n"))).expect("write");
            path
        })
        .collect();
    let report = tmp("groups.json");
    let mut args: Vec<&str> = logs.iter().map(|p| p.to_str().unwrap()).collect();
    args.splice(0..0, ["fit"]);
    args.extend([
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--groups",
        "day1,day1,day2,day2",
        "--json",
        report.to_str().unwrap(),
    ]);
    let out = mrsysid(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("each group of logs predicted by the model fitted on the other groups"),
        "{stdout}"
    );
    let v = json(&report);
    let names: Vec<&str> = v["cross_validation"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["group day1", "group day2", "pooled"]);
    let added: Vec<&str> = v["diagnosis"]["effects_added"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert!(
        added
            .iter()
            .any(|n| n.starts_with("quadratic airframe drag")),
        "{added:?}"
    );
    // One name per log, at least two groups.
    args.iter_mut()
        .filter(|a| a.starts_with("day1"))
        .for_each(|a| *a = "day1,day1,day1,day1");
    let out = mrsysid(&args);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("at least 2 distinct groups"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The shipped flight rewritten in the CSV layout of ETH's data-driven-dynamics (NED
/// velocity, specific force, angular acceleration, attitude, PWM motor outputs):
/// through `examples/ddd_csv.toml` (its actuator map scaled to this vehicle's speeds) it
/// fits to the estimates of the contract file itself without its logged Ω̇ (both derive
/// it from the rotor speeds). The rewrite is this test's own
/// arithmetic (R(q) v, F/m, I⁻¹(M − ω × Iω), PWM = 900 + Ω/4), so the mapping's frames,
/// units, load derivation and actuator map are checked against an independent
/// computation. The estimates agree to 1e-5 relative: the shipped quaternions are written
/// to six significant digits, so their norms differ from 1 by up to ~1e-6 and the
/// rotation matrix built from them is orthogonal only to that order: the velocity
/// rotated to NED here and back to body axes by the reader moves by ~1e-6 relative
/// (measured: 1.6e-7 on C_H_mub).
#[test]
fn a_data_driven_dynamics_csv_fits_as_the_contract_file() {
    let text = std::fs::read_to_string(root().join("data/quad_x_flight_quadratic_drag.csv"))
        .expect("shipped flight");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (mass, inertia) = (1.2, [0.011, 0.012, 0.021]);
    let contract_columns = "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz";
    let mut reference = format!("{contract_columns}\n");
    let mut out = String::from(
        "timestamp,u0,u1,u2,u3,vx,vy,vz,q0,q1,q2,q3,ang_vel_x,ang_vel_y,ang_vel_z,\
         acc_b_x,acc_b_y,acc_b_z,ang_acc_b_x,ang_acc_b_y,ang_acc_b_z\n",
    );
    for line in lines {
        let f: Vec<f64> = line
            .split(',')
            .map(|x| x.parse().expect("number"))
            .collect();
        let g = |name: &str| f[col(name)];
        let kept: Vec<String> = contract_columns
            .split(',')
            .map(|c| format!("{:e}", g(c)))
            .collect();
        reference.push_str(&kept.join(","));
        reference.push('\n');
        let (w, x, y, z) = (g("qw"), g("qx"), g("qy"), g("qz"));
        let r = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        let body = [g("u"), g("v"), g("w")];
        let ned: Vec<f64> = r
            .iter()
            .map(|row| (0..3).map(|k| row[k] * body[k]).sum())
            .collect();
        let rate = [g("p"), g("q"), g("r")];
        let h = [0, 1, 2].map(|k| inertia[k] * rate[k]);
        let gyroscopic = [
            rate[1] * h[2] - rate[2] * h[1],
            rate[2] * h[0] - rate[0] * h[2],
            rate[0] * h[1] - rate[1] * h[0],
        ];
        let moment = [g("mx"), g("my"), g("mz")];
        let mut row = vec![g("t") * 1e6];
        row.extend((1..=4).map(|i| 900.0 + g(&format!("omega_{i}")) / 4.0));
        row.extend(ned);
        row.extend([w, x, y, z]);
        row.extend(rate);
        row.extend([g("fx"), g("fy"), g("fz")].map(|f| f / mass));
        row.extend([0, 1, 2].map(|k| (moment[k] - gyroscopic[k]) / inertia[k]));
        let cells: Vec<String> = row.iter().map(|v| format!("{v:e}")).collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    let log = tmp("ddd_layout.csv");
    std::fs::write(&log, out).expect("write");
    // 0 rad/s at 900 µs, 4 rad/s per µs: a top speed of 4400 rad/s at 2000 µs.
    let mapping = std::fs::read_to_string(root().join("examples/ddd_csv.toml"))
        .expect("example mapping")
        .replace("max_speed = 1100.0", "max_speed = 4400.0");
    let mapping_file = tmp("ddd_layout.toml");
    std::fs::write(&mapping_file, mapping).expect("write mapping");
    let reference_log = tmp("ddd_reference.csv");
    std::fs::write(&reference_log, reference).expect("write reference");
    let contract = fit_without_diagnosis(&reference_log, "ddd_ref", &[]);
    let mapping_arg = ["--mapping", mapping_file.to_str().unwrap()];
    let mapped = fit_without_diagnosis(&log, "ddd_mapped", &mapping_arg);
    assert_eq!(mapped["samples"], contract["samples"]);
    let estimates = |v: &serde_json::Value| -> Vec<(String, f64)> {
        v["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| {
                (
                    p["name"].as_str().unwrap().to_string(),
                    p["estimate"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    for ((name, a), (other, b)) in estimates(&mapped).iter().zip(&estimates(&contract)) {
        assert_eq!(name, other);
        assert!(
            (a - b).abs() <= 1e-5 * b.abs().max(1e-12),
            "{name}: {a} vs {b}"
        );
    }
}

/// The diagnosis from statistics on the command line, as an engine that runs commands
/// would drive it: `accumulate --for-diagnosis` per log, `fit --from-stats --plan-out`,
/// `pass` per log, `fit --from-stats --passes --remainder-plan-out` (the flight pieces
/// are time series: their remainder pass is asked for), `pass --model` per fit log, and
/// `fit --from-stats --passes --remainders`: the JSON report equals the direct fit's of
/// the same logs, every field (the same statistics merged in the same order).
#[test]
fn the_diagnosis_from_statistics_files_reports_what_the_direct_fit_reports() {
    let v = ["--vehicle", "data/vehicles/quad_x.toml"];
    let text = std::fs::read_to_string(root().join("data/quad_x_flight_quadratic_drag.csv"))
        .expect("shipped flight");
    let (header, rows) = text.split_once('\n').expect("header");
    let rows: Vec<&str> = rows.lines().collect();
    let logs: Vec<String> = (0..4)
        .map(|k| {
            let path = tmp(&format!("passes-piece-{k}.csv"));
            let piece = &rows[k * rows.len() / 4..(k + 1) * rows.len() / 4];
            std::fs::write(&path, format!("{header}\n{}\n", piece.join("\n"))).unwrap();
            path.to_str().unwrap().to_string()
        })
        .collect();
    let file = |name: &str| tmp(name).to_str().unwrap().to_string();
    let run = |args: &[&str]| {
        let out = mrsysid(&[args, &v[..], &["--quiet"]].concat());
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        (out.status.code(), stderr)
    };
    let ok = |args: &[&str]| {
        let (code, stderr) = run(args);
        assert_eq!(code, Some(0), "{args:?}: {stderr}");
    };
    let direct = file("passes-direct.json");
    ok(&[
        "fit",
        &logs[0],
        &logs[1],
        &logs[2],
        "--validate",
        &logs[3],
        "--json",
        &direct,
    ]);
    let parts: Vec<String> = (0..4).map(|k| file(&format!("piece-{k}.stats"))).collect();
    for (log, part) in logs.iter().zip(&parts) {
        ok(&["accumulate", log, "--for-diagnosis", "-o", part]);
    }
    let from_stats = ["fit", "--from-stats", &parts[0], &parts[1], &parts[2]];
    let from_stats = [&from_stats[..], &["--validate", &parts[3]]].concat();
    let plan = file("pieces.plan");
    ok(&[&from_stats[..], &["--plan-out", &plan]].concat());
    let passes: Vec<String> = (0..4).map(|k| file(&format!("piece-{k}.pass"))).collect();
    for (log, pass) in logs.iter().zip(&passes) {
        ok(&["pass", log, "--plan", &plan, "-o", pass]);
    }
    let with_passes = [
        &from_stats[..],
        &["--passes"],
        &passes.iter().map(String::as_str).collect::<Vec<_>>()[..],
    ]
    .concat();
    let (code, stderr) = run(&with_passes);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("--remainder-plan-out"), "{stderr}");
    let model = file("pieces.model");
    ok(&[&with_passes[..], &["--remainder-plan-out", &model]].concat());
    let remainders: Vec<String> = (0..3).map(|k| file(&format!("piece-{k}.rem"))).collect();
    for (log, rem) in logs.iter().zip(&remainders) {
        ok(&["pass", log, "--plan", &plan, "--model", &model, "-o", rem]);
    }
    let stats = file("passes-from-stats.json");
    let rems: Vec<&str> = remainders.iter().map(String::as_str).collect();
    ok(&[
        &with_passes[..],
        &["--remainders"],
        &rems[..],
        &["--json", &stats],
    ]
    .concat());
    assert_eq!(json(Path::new(&stats)), json(Path::new(&direct)));
    // A pass file of another plan is refused by name.
    let other_plan = file("other.plan");
    ok(&[
        "fit",
        "--from-stats",
        &parts[0],
        &parts[1],
        &parts[2],
        "--plan-out",
        &other_plan,
    ]);
    ok(&[
        "pass",
        &logs[0],
        "--plan",
        &other_plan,
        "-o",
        &file("other.pass"),
    ]);
    let mut mixed = with_passes.clone();
    let at = mixed.iter().position(|a| *a == passes[0]).unwrap();
    let other_pass = file("other.pass");
    mixed[at] = &other_pass;
    let (code, stderr) = run(&mixed);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("made from another plan"), "{stderr}");
}
