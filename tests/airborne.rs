//! Airborne segments: a log with ground time (idling rotors) before, between and after
//! two flights fits on the flights alone, and says what it kept.
//!
//! The flights are the simulator's (the shipped `data/quad_x_flight_quadratic_drag.csv`,
//! which `sim_data` regenerates byte for byte: 30 s at 100 Hz of the quad_x vehicle, its
//! hover rotor speed 2167.7 rad/s at C_T = 0.01). On the ground the rotors idle at
//! 650 rad/s (0.3 of the hover speed: at C_T,max = 0.03 they could carry 0.27 of the
//! weight) and the logged force is the ground's reaction to the weight, F_z = −m g (FRD,
//! gravity excluded: the normal force pushes up, −z), the accelerometer reads
//! a_z = −g, and nothing moves.

mod scratch;

use std::path::{Path, PathBuf};

use mrsysid::io::ReadOptions;
use mrsysid::{Identification, Vehicle};

const FLIGHT: &str = "data/quad_x_flight_quadratic_drag.csv";
/// Sample interval of the shipped flight, s.
const DT: f64 = 0.01;
/// Idle rotor speed on the ground, rad/s.
const IDLE: f64 = 650.0;
/// quad_x mass (1.2 kg) × g.
const WEIGHT: f64 = 1.2 * 9.80665;

/// The flight's rows as (t, the other fields), and its header.
fn flight() -> (String, Vec<(f64, String)>) {
    let text = std::fs::read_to_string(FLIGHT).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| {
            let (t, rest) = l.split_once(',').unwrap();
            (t.parse().unwrap(), rest.to_string())
        })
        .collect();
    (header, rows)
}

/// `n` ground rows from `t0` (s) at the flight's interval, in the columns of `header`.
fn ground(header: &str, t0: f64, n: usize, out: &mut Vec<String>) {
    for k in 0..n {
        let t = t0 + k as f64 * DT;
        let fields: Vec<String> = header
            .split(',')
            .map(|c| match c {
                "t" => format!("{t}"),
                "omega_1" | "omega_2" | "omega_3" | "omega_4" => format!("{IDLE}"),
                "fz" => format!("{}", -WEIGHT),
                "az" => "-9.80665".into(),
                "qw" => "1".into(),
                _ => "0".into(),
            })
            .collect();
        out.push(fields.join(","));
    }
}

/// The flight's rows with `from ≤ t_f < to`, shifted to start at `t0` (s).
fn part(rows: &[(f64, String)], from: f64, to: f64, t0: f64, out: &mut Vec<String>) -> f64 {
    let mut last = t0;
    for (t, rest) in rows
        .iter()
        .filter(|(t, _)| *t >= from - 1e-9 && *t < to - 1e-9)
    {
        last = t0 + (t - from);
        out.push(format!("{last},{rest}"));
    }
    last
}

fn write(path: &Path, header: &str, lines: &[String]) {
    let mut text = format!("{header}\n");
    for l in lines {
        text.push_str(l);
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// Writes the whole log (10 s idle, flight 1, 8 s idle, flight 2, 5 s idle) and the
/// flights alone at the same times, named after `tag`; returns their paths, the
/// flights' spans and the log's, s.
fn logs(tag: &str) -> (PathBuf, PathBuf, [f64; 3]) {
    let dir = scratch::dir("airborne");
    let (header, rows) = flight();
    let (mut whole, mut alone) = (Vec::new(), Vec::new());
    ground(&header, 0.0, 1000, &mut whole);
    let end1 = part(&rows, 0.0, 15.0, 10.0, &mut whole);
    part(&rows, 0.0, 15.0, 10.0, &mut alone);
    ground(&header, 25.0, 800, &mut whole);
    let end2 = part(&rows, 15.0, 30.0 + DT, 33.0, &mut whole);
    part(&rows, 15.0, 30.0 + DT, 33.0, &mut alone);
    ground(&header, end2 + DT, 500, &mut whole);
    let (a, b) = (
        dir.join(format!("{tag}-whole.csv")),
        dir.join(format!("{tag}-alone.csv")),
    );
    write(&a, &header, &whole);
    write(&b, &header, &alone);
    (a, b, [end1 - 10.0, end2 - 33.0, end2 + DT + 499.0 * DT])
}

fn quad() -> Vehicle {
    Vehicle::from_toml_file(Path::new("data/vehicles/quad_x.toml")).unwrap()
}

/// Every ground sample (1000 + 800 + 500) is left out and nothing else: two flights,
/// their spans to 1e-9 s (sums of the logged times), of the log's 53 s; the log is
/// split at the ground time (two segments) without counting it as a gap. The fit on the
/// whole log equals the fit on the flights alone (a file holding only them, split by its
/// 8 s time gap): the same samples in the same segments make the same sums, so the
/// estimates, fit metrics and cross-validation agree to 1e-12 relative (rounding only).
#[test]
fn ground_time_is_left_out_and_the_fit_is_that_of_the_flights() {
    let (whole, alone, spans) = logs("fit");
    let run = |path: &Path| {
        Identification::new(quad())
            .log(path.to_path_buf())
            .read_options(ReadOptions {
                airborne_only: true,
                ..ReadOptions::default()
            })
            .diagnose(false)
            .run()
            .unwrap()
    };
    let (w, a) = (run(&whole), run(&alone));
    let s = &w.outcome().summaries[0];
    let span = s.airborne.expect("ground time left out");
    assert_eq!(span.ground_samples, 2300);
    assert_eq!(span.flights, 2);
    assert!(
        (span.airborne_seconds - (spans[0] + spans[1])).abs() < 1e-9,
        "{} vs {spans:?}",
        span.airborne_seconds
    );
    assert_eq!(s.segments, 2);
    assert!(s.gaps.is_empty(), "{:?}", s.gaps);
    assert!(
        (s.span - spans[2]).abs() < 1e-9,
        "{} vs {}",
        s.span,
        spans[2]
    );
    let sa = &a.outcome().summaries[0];
    assert_eq!(sa.airborne, None);
    assert_eq!(s.samples, sa.samples);
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(y.abs()).max(1e-300);
    assert_eq!(w.theta().len(), a.theta().len());
    for (x, y) in w.theta().iter().zip(a.theta()) {
        assert!(close(*x, *y), "theta {x} vs {y}");
    }
    let (rw, ra) = (w.report(), a.report());
    for (x, y) in rw.axes.iter().zip(&ra.axes) {
        assert!(close(x.r2, y.r2), "{x:?} vs {y:?}");
    }
    for (fw, fa) in rw.cross_validation.iter().zip(&ra.cross_validation) {
        for (x, y) in fw.axes.iter().zip(&fa.axes) {
            assert!(close(x.r2, y.r2), "{}: {x:?} vs {y:?}", fw.name);
        }
    }
    assert_eq!(rw.airborne.len(), 1);
    let said = rw.airborne[0].describe();
    assert!(
        said.starts_with("2 flights, 30.0 s airborne of 53.0 s"),
        "{said}"
    );
    assert!(
        w.summary().contains("fit-whole.csv: 2 flights"),
        "{}",
        w.summary()
    );
    assert!(ra.airborne.is_empty());
}

/// Without `airborne_only` (the library's default) every row is a sample and the log
/// is one segment.
#[test]
fn the_library_keeps_every_sample_unless_asked() {
    let (whole, _, _) = logs("keep");
    let w = Identification::new(quad())
        .log(whole)
        .diagnose(false)
        .run()
        .unwrap();
    let s = &w.outcome().summaries[0];
    assert_eq!(s.airborne, None);
    assert_eq!(s.samples, s.rows_read);
    assert_eq!(s.segments, 1);
    assert!(w.report().airborne.is_empty());
}

fn mrsysid(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(args)
        .output()
        .unwrap()
}

/// The CLI says what it kept, in the text report and in the JSON report; a log that is
/// all ground time ends with exit 1 naming it and the way to keep it.
#[test]
fn cli_reports_what_was_kept_and_refuses_a_log_all_on_the_ground() {
    let (whole, _, _) = logs("cli");
    let json = whole.with_extension("json");
    let out = mrsysid(&[
        "fit",
        whole.to_str().unwrap(),
        "--vehicle",
        "data/vehicles/quad_x.toml",
        "--no-diagnose",
        "--json",
        json.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("airborne only: cli-whole.csv: 2 flights, 30.0 s airborne of 53.0 s (2300 samples on the ground left out)"),
        "{text}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let row = &report["airborne"][0];
    assert_eq!(row["flights"], 2);
    assert_eq!(row["ground_samples"], 2300);

    let (header, _) = flight();
    let mut idle = Vec::new();
    ground(&header, 0.0, 3000, &mut idle);
    let path = scratch::dir("airborne").join("cli-ground.csv");
    write(&path, &header, &idle);
    let out = mrsysid(&[
        "fit",
        path.to_str().unwrap(),
        "--vehicle",
        "data/vehicles/quad_x.toml",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "no sample left: 3000 of the 3000 rows read are on the ground: the rotors reach \
             650 rad/s at most (RMS over the rotors), below the 1400 rad/s a take-off needs \
             (1.25^0.5 times the 1252 rad/s"
        ) && err.contains("--keep-ground"),
        "{err}"
    );
}
