//! An ArduPilot flight end to end through the CLI: `mrsysid vehicle --from-log` on a
//! DataFlash log (FRAME_CLASS 1 / FRAME_TYPE 1, quad X in ArduPilot's motor order), the
//! simulator flying that vehicle with a known CG offset, the flight written as a
//! DataFlash `.bin` (IMU, EKF attitude and velocity, ESC telemetry), and `mrsysid fit`
//! with `examples/ardupilot.toml`: the diagnosis recovers the CG offset, and the Eq. 22
//! parameters agree with a fit of the same flight written as a contract CSV.

mod scratch;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mrsysid::internals::sim::flight::{FlightConfig, fly};
use mrsysid::internals::sim::{Effect, Effects, RotorFile, TruthModel};
use mrsysid::io::fixtures::dataflash::{DataflashWriter, write_flight};
use mrsysid::vehicle::{Vehicle, VehicleSource};

fn tmp(name: &str) -> PathBuf {
    scratch::dir("ardupilot").join(name)
}

fn mrsysid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

fn ok(out: Output, what: &str) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{what}: {err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const PARAMS: [(&str, f64); 7] = [
    ("FRAME_CLASS", 1.0),
    ("FRAME_TYPE", 1.0),
    ("MOT_PWM_MIN", 1000.0),
    ("MOT_PWM_MAX", 2000.0),
    ("MOT_SPIN_MIN", 0.15),
    ("MOT_SPIN_MAX", 0.95),
    ("MOT_THST_EXPO", 0.65),
];

/// The skeleton filled in with the mass properties of `data/vehicles/quad_x.toml`.
fn fill_in(skeleton: &str) -> String {
    skeleton
        .replace("# mass = 1.5", "mass = 1.2")
        .replace(
            "# inertia = [[0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.04]]",
            "inertia = [[0.011, 0, 0], [0, 0.012, 0], [0, 0, 0.021]]",
        )
        .replace("# rotor_radius = 0.12", "rotor_radius = 0.0635")
        .replace("# hub_height = 0.02", "hub_height = 0.02")
        .replace("# rotor_inertia = 0.0", "rotor_inertia = 3.0e-5")
}

fn parameters(report: &Path) -> Vec<(String, f64)> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report).unwrap()).unwrap();
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
}

#[test]
fn ardupilot_flight_fits_end_to_end() {
    // 1. The vehicle from the log's parameters (arm 0.225 m, quad_x's 0.159 m · √2).
    let mut w = DataflashWriter::standard();
    for (name, v) in PARAMS {
        w.param(name, v);
    }
    let params_only = tmp("params.bin");
    std::fs::write(&params_only, w.bytes()).unwrap();
    let out = mrsysid(&[
        "vehicle",
        "--from-log",
        s(&params_only),
        "--arm-length",
        "0.225",
    ]);
    let skeleton = String::from_utf8(out.stdout.clone()).unwrap();
    let notes = ok(out, "vehicle --from-log");
    assert!(skeleton.contains("satisfies Assumption 2"), "{skeleton}");
    assert!(
        notes.contains("pwm_min = 1150\npwm_max = 1950\nthr_mdl_fac = 0.65"),
        "{notes}"
    );
    let text = fill_in(&skeleton);
    let vehicle = Vehicle::from_toml_str(&text, VehicleSource::Code).unwrap();
    // ArduPilot's motor 1 is front right and turns counter-clockwise.
    assert!(vehicle.rotors()[0].x > 0.0 && vehicle.rotors()[0].y > 0.0);
    assert_eq!(vehicle.rotors()[0].spin, -1.0);
    let vehicle_path = tmp("vehicle.toml");
    std::fs::write(&vehicle_path, &text).unwrap();

    // 2. A 30 s flight of that vehicle with its CG 10 mm forward and 8 mm left of the
    // reference (sensor noise and bias, quantised eRPM telemetry), as DataFlash and as
    // the contract CSV (IMU only: no force or moment columns, both derived on read).
    let effect: Effect = "cg_offset=0.01,-0.008,0".parse().unwrap();
    let truth = TruthModel::new(
        &vehicle,
        &RotorFile::default(),
        Effects::new(vec![effect], &vehicle).unwrap(),
    )
    .unwrap();
    let cfg = FlightConfig {
        duration: 30.0,
        imu_only: true,
        ..Default::default()
    };
    let log = fly(&truth, &cfg, 7).unwrap();
    let bin = tmp("flight.bin");
    std::fs::write(
        &bin,
        write_flight(&log.samples, &log.specific_force, &PARAMS, None, 1),
    )
    .unwrap();
    let csv = tmp("flight.csv");
    // Rotor accelerations are derived on read from the rotor speeds in both (the sim's
    // CSV carries the true ones; a DataFlash log has none).
    let mut table = log.table.clone();
    table.columns.retain(|(n, _)| !n.starts_with("omega_dot"));
    table.write_csv(&csv).unwrap();
    let out = mrsysid(&["vehicle", "--from-log", s(&bin), "--arm-length", "0.225"]);
    // The same rotor table from the flight's log (its name is the firmware's MSG text).
    let rotors = |t: &str| t[t.find("[[rotors]]").unwrap()..].to_string();
    let from_flight = String::from_utf8(out.stdout.clone()).unwrap();
    assert!(
        from_flight.contains("name = \"ArduCopter V4.5.7"),
        "{from_flight}"
    );
    assert_eq!(rotors(&from_flight), rotors(&skeleton));

    // 3. Fit the .bin with and without the diagnosis, and the CSV without.
    let (diag_report, bin_report, csv_report) =
        (tmp("diag.json"), tmp("bin.json"), tmp("csv.json"));
    let fit = |log: &Path, mapping: bool, report: &Path, diagnose: bool| {
        let mut a = vec![
            "fit",
            s(log),
            "--vehicle",
            s(&vehicle_path),
            "--json",
            s(report),
            "--quiet",
        ];
        if mapping {
            a.extend(["--mapping", "examples/ardupilot.toml"]);
        }
        if !diagnose {
            a.push("--no-diagnose");
        }
        ok(mrsysid(&a), s(report));
    };
    fit(&bin, true, &diag_report, true);
    fit(&bin, true, &bin_report, false);
    fit(&csv, false, &csv_report, false);

    // The diagnosis names the CG offset within the bounds of the CSV path's test
    // (`cli_fit.rs`: 1 mm and 0.8 mm, 10 %).
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&diag_report).unwrap()).unwrap();
    let cg = r["diagnosis"]["effects_added"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["name"].as_str().unwrap().starts_with("CG offset"))
        .unwrap_or_else(|| panic!("no CG offset in {}", r["diagnosis"]["effects_added"]));
    let get = |n: &str| {
        cg["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == n)
            .unwrap()["estimate"]
            .as_f64()
            .unwrap()
    };
    let (dx, dy) = (get("cg_dx"), get("cg_dy"));
    println!("CG offset from the .bin: dx = {dx:.5} m, dy = {dy:.5} m");
    assert!((dx - 0.010).abs() < 0.001, "{dx}");
    assert!((dy + 0.008).abs() < 0.0008, "{dy}");

    // The Eq. 22 fit of the .bin against the CSV's (both IMU only, all messages at
    // 100 Hz): the paths differ only by the .bin's f32 storage and the CSV's 6
    // significant digits; every parameter to 1e-3 relative (1.3e-4 measured, on
    // C_Q_muw2).
    let csv = parameters(&csv_report);
    let bin = parameters(&bin_report);
    assert_eq!(bin.len(), csv.len());
    for ((name, b), (csv_name, c)) in bin.iter().zip(&csv) {
        assert_eq!(name, csv_name);
        println!("{name}: .bin {b:.6e}, .csv {c:.6e}");
        assert!((b / c - 1.0).abs() < 1e-3, "{name}: {b} vs {c}");
    }
}
