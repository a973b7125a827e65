//! Builds a vehicle from a TOML file, prints its Eq. 22 structure, and evaluates the
//! regressors at one hover-like and one fast-forward-flight state.
//!
//! `cargo run --release --example regressors -- data/vehicles/quad_x.toml`

use std::path::PathBuf;
use std::process::ExitCode;

use mrsysid::vehicle::Vehicle;
use mrsysid::{Axis, Sample, SampleChunk};
use mrsysid::{ModelOptions, ModelStructure, Workspace};

fn main() -> ExitCode {
    let path = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("data/vehicles/quad_x.toml"));
    let vehicle = match Vehicle::from_toml_file(&path) {
        Ok(v) => v,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    println!(
        "{}: {} rotors, class {}, arm {:.4} m, nu0 {:.3} m/s",
        vehicle.name,
        vehicle.rotor_count(),
        vehicle.class(),
        vehicle.arm_length(),
        vehicle.hover_induced_velocity()
    );
    let model = ModelStructure::eq22(&vehicle, ModelOptions::default());
    let n = vehicle.rotor_count();
    let hover = Sample {
        omega: vec![600.0; n],
        omega_dot: vec![0.0; n],
        ..Sample::default()
    };
    let fast = Sample {
        velocity: [12.0, -2.0, 1.0],
        rates: [1.5, -0.8, 0.3],
        omega: (0..n).map(|i| 550.0 + 40.0 * i as f64).collect(),
        omega_dot: vec![100.0; n],
        ..Sample::default()
    };
    let mut chunk = SampleChunk::with_capacity(n, 2, true);
    chunk.push(&hover);
    chunk.push(&fast);
    let mut ws = Workspace::default();
    if let Err(e) = model.assemble(&chunk, &mut ws) {
        eprintln!("error: {e}");
        return ExitCode::from(1);
    }
    println!(
        "{} parameters, {} regressor columns",
        model.params.len(),
        model.columns.len()
    );
    println!(
        "{:<4} {:<14} {:<18} {:>14} {:>14}",
        "axis", "parameter", "regressor", "hover", "fast flight"
    );
    for axis in Axis::ALL {
        for j in model.axis_columns(axis) {
            let c = &model.columns[j];
            let x = ws.column(j);
            println!(
                "{:<4} {:<14} {:<18} {:>14.6e} {:>14.6e}",
                axis.name(),
                model.param(c.param).name,
                c.label,
                x[0],
                x[1]
            );
        }
    }
    ExitCode::SUCCESS
}
