//! The `simulate` command as a library function: everything the CLI does, testable
//! without spawning the binary.

use std::path::{Path, PathBuf};

use super::effects::{Effect, Effects};
use super::flight::{FlightConfig, fly};
use super::output::LogTable;
use super::test_matrix::{Design, Ranges, sweep};
use super::truth::{RotorFile, TruthModel};
use crate::vehicle::{Vehicle, VehicleSource};

/// The shipped example vehicles, usable by name (`--preset`).
pub const EXAMPLE_VEHICLES: [(&str, &str); 3] = [
    ("quad_x", include_str!("../../data/vehicles/quad_x.toml")),
    (
        "quad_plus",
        include_str!("../../data/vehicles/quad_plus.toml"),
    ),
    ("hexa_x", include_str!("../../data/vehicles/hexa_x.toml")),
];

/// Where the vehicle comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum VehicleChoice {
    /// A vehicle TOML file.
    File(PathBuf),
    /// One of [`EXAMPLE_VEHICLES`] by name.
    Example(String),
}

/// Sweep or flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// Response-surface test matrix of `points` points.
    Sweep {
        /// Sampling design.
        design: Design,
        /// Number of test points.
        points: usize,
    },
    /// Time-domain flight.
    Flight(FlightConfig),
}

/// Options of `mrsysid simulate`.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateOptions {
    /// Vehicle.
    pub vehicle: VehicleChoice,
    /// Optional rotor/airframe description file.
    pub rotor_file: Option<PathBuf>,
    /// What to simulate.
    pub mode: Mode,
    /// Undeclared effects.
    pub effects: Vec<Effect>,
    /// Random seed.
    pub seed: u64,
}

/// Loads the vehicle of `choice`.
pub fn load_vehicle(choice: &VehicleChoice) -> Result<Vehicle, String> {
    match choice {
        VehicleChoice::File(p) => Vehicle::from_toml_file(p).map_err(|e| e.to_string()),
        VehicleChoice::Example(name) => {
            let text = EXAMPLE_VEHICLES
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, t)| *t)
                .ok_or_else(|| {
                    let names: Vec<_> = EXAMPLE_VEHICLES.iter().map(|(n, _)| *n).collect();
                    format!(
                        "unknown example vehicle `{name}`; known: {}",
                        names.join(", ")
                    )
                })?;
            Vehicle::from_toml_str(text, VehicleSource::Code).map_err(|e| e.to_string())
        }
    }
}

/// Builds the truth model the options describe.
pub fn build_model(opts: &SimulateOptions) -> Result<TruthModel, String> {
    let vehicle = load_vehicle(&opts.vehicle)?;
    let file = match &opts.rotor_file {
        Some(p) => RotorFile::from_toml_file(p)?,
        None => RotorFile::default(),
    };
    let effects = Effects::new(opts.effects.clone(), &vehicle)?;
    if matches!(opts.mode, Mode::Sweep { .. })
        && let Some(e) = effects.iter().find(|e| e.needs_flight())
    {
        let what = if e.is_logging_effect() {
            "acts on a flight log"
        } else {
            "acts over time in a flight"
        };
        return Err(format!(
            "effect `{}` {what} and needs `--mode flight`",
            e.name()
        ));
    }
    let src = |e: String| match &opts.rotor_file {
        Some(p) => format!("{}: {e}", p.display()),
        None => e,
    };
    TruthModel::new(&vehicle, &file, effects).map_err(src)
}

/// Runs the simulation and returns the log table.
pub fn simulate(opts: &SimulateOptions) -> Result<LogTable, String> {
    let model = build_model(opts)?;
    match opts.mode {
        Mode::Sweep { design, points } => {
            if points == 0 {
                return Err("--points must be at least 1".into());
            }
            let chunk = sweep(
                &model,
                &Ranges::scaled_to(&model),
                design,
                points,
                opts.seed,
            );
            Ok(LogTable::from_chunk(&chunk, true))
        }
        Mode::Flight(config) => Ok(fly(&model, &config, opts.seed)?.table),
    }
}

/// Runs the simulation and writes the CSV atomically to `out`; returns the row count.
pub fn simulate_to_file(opts: &SimulateOptions, out: &Path) -> Result<usize, String> {
    let table = simulate(opts)?;
    table.write_csv(out)?;
    Ok(table.len())
}
