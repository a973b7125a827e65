//! A tool that parses its own logs and fits them with the library: the same log is fitted
//! once from the file and once from samples in memory, through the same pipeline
//! (hold-out, cross-validation, coloured-residual correction, diagnosis), and the two
//! results are compared bit for bit.
//!
//! ```sh
//! cargo run --release --example fit_from_memory                       # shipped flight
//! cargo run --release --example fit_from_memory -- log.csv vehicle.toml  # a contract CSV
//! ```

use std::error::Error;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use mrsysid::{Identification, Sample, Vehicle};

/// Reads a contract CSV (columns named as in `docs/data-contract.md`) with the csv
/// crate: the caller's own parser, independent of the library's readers.
fn parse(path: &Path, rotors: usize) -> Result<Vec<Sample>, Box<dyn Error>> {
    let mut reader = csv::Reader::from_path(path)?;
    let header = reader.headers()?.clone();
    let index = |name: &str| header.iter().position(|h| h == name);
    let need = |name: &str| index(name).ok_or_else(|| format!("no column {name:?}"));
    let mut samples = Vec::new();
    for record in reader.records() {
        let record = record?;
        let value = |i: usize| -> Result<f64, Box<dyn Error>> { Ok(record[i].trim().parse()?) };
        let get = |name: &str| -> Result<f64, Box<dyn Error>> { value(need(name)?) };
        let optional = |name: &str| index(name).map(value).transpose();
        let per_rotor = |prefix: &str| -> Result<Vec<f64>, Box<dyn Error>> {
            (1..=rotors)
                .map(|i| get(&format!("{prefix}_{i}")))
                .collect()
        };
        let omega_dot = if index("omega_dot_1").is_some() {
            per_rotor("omega_dot")?
        } else {
            Vec::new()
        };
        let quaternion = ["qw", "qx", "qy", "qz"].map(optional);
        let attitude = match quaternion {
            [Ok(Some(w)), Ok(Some(x)), Ok(Some(y)), Ok(Some(z))] => Some([w, x, y, z]),
            _ => None,
        };
        samples.push(Sample {
            t: get("t")?,
            velocity: [get("u")?, get("v")?, get("w")?],
            rates: [get("p")?, get("q")?, get("r")?],
            omega: per_rotor("omega")?,
            omega_dot,
            wrench: [
                get("fx")?,
                get("fy")?,
                get("fz")?,
                get("mx")?,
                get("my")?,
                get("mz")?,
            ],
            height: optional("height")?,
            attitude,
        });
    }
    Ok(samples)
}

fn run() -> Result<bool, Box<dyn Error>> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let log = args
        .next()
        .unwrap_or_else(|| root.join("data/quad_x_flight_quadratic_drag.csv"));
    let vehicle = args
        .next()
        .unwrap_or_else(|| root.join("data/vehicles/quad_x.toml"));
    let vehicle = Vehicle::from_toml_file(&vehicle)?;
    let samples = parse(&log, vehicle.rotor_count())?;
    println!("{}: {} samples parsed", log.display(), samples.len());

    let request = Identification::new(vehicle);
    let from_file = request.clone().log(log.clone()).run()?;
    let from_memory = request.samples("in memory", samples).run()?;

    let same = from_file.theta() == from_memory.theta()
        && from_file.covariance() == from_memory.covariance()
        && from_file.outcome().diagnosis == from_memory.outcome().diagnosis
        && from_file.validation_metrics() == from_memory.validation_metrics();
    println!("{}", from_memory.summary());
    println!("Final model:\n{}", from_memory.equations());
    println!(
        "file and memory fits {}",
        if same { "are bit-identical" } else { "DIFFER" }
    );
    Ok(same)
}

fn main() -> ExitCode {
    match run() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
