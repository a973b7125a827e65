//! A downstream tool using an identified model: load the model file written by
//! `mrsysid fit … --model-out model.toml` and evaluate force and moment at run time, e.g.
//! inside a simulator or a controller's feed-forward.
//!
//! ```sh
//! cargo run --release -- fit data/quad_x_sweep.csv --vehicle data/vehicles/quad_x.toml --model-out /tmp/model.toml --quiet
//! cargo run --release --example use_identified_model -- /tmp/model.toml
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use mrsysid::{IdentifiedModel, Sample};

fn main() -> ExitCode {
    let Some(path) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: use_identified_model MODEL.toml");
        return ExitCode::from(2);
    };
    let model = match IdentifiedModel::load(&path) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let n = model.vehicle.rotor_count();
    println!(
        "{}: {} parameters",
        model.vehicle.name,
        model.parameters.len()
    );
    // Trim: the equal rotor speed whose thrust carries the weight (bisection on F_z).
    let weight = model.vehicle.props.mass * mrsysid::vehicle::STANDARD_GRAVITY;
    // A state: body velocity (m/s), rates (rad/s), equal rotor speeds (rad/s).
    let state = |velocity: [f64; 3], rates: [f64; 3], w: f64| Sample {
        velocity,
        rates,
        omega: vec![w; n],
        omega_dot: vec![0.0; n],
        ..Sample::default()
    };
    let fz = |w: f64| model.predict(&state([0.0; 3], [0.0; 3], w)).map(|y| y[2]);
    let (mut lo, mut hi) = (1.0, 20_000.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        match fz(mid) {
            Ok(f) if -f < weight => lo = mid,
            Ok(_) => hi = mid,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(1);
            }
        }
    }
    let hover = 0.5 * (lo + hi);
    println!("hover rotor speed {hover:.1} rad/s carries {weight:.2} N");
    for (label, velocity, rates) in [
        ("hover", [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
        ("10 m/s forward, rolling", [10.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
    ] {
        let s = state(velocity, rates, hover);
        let sigma = match model.prediction_std(&s) {
            Ok(Some(sd)) => format!(" (σ F_z {:.3} N from the parameter covariance)", sd[2]),
            _ => String::new(),
        };
        match model.predict(&s) {
            Ok(y) => println!(
                "{label:>24}: F = [{:8.3} {:8.3} {:8.3}] N, M = [{:8.4} {:8.4} {:8.4}] N m{sigma}",
                y[0], y[1], y[2], y[3], y[4], y[5]
            ),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(1);
            }
        }
    }
    ExitCode::SUCCESS
}
