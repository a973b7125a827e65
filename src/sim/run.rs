//! The `simulate` command as a library function: everything the CLI does, testable
//! without spawning the binary.

use std::path::{Path, PathBuf};

use super::effects::{Effect, EffectError, Effects};
use super::flight::{FlightConfig, FlightError, fly};
use super::output::{CsvWriteError, LogTable};
use super::test_matrix::{Design, Ranges, sweep};
use super::truth::{RotorError, RotorFile, RotorFileError, TruthModel};
use crate::vehicle::{Vehicle, VehicleError, VehicleSource};

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

/// Why a simulation could not be run or written.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The vehicle file or example is invalid.
    #[error(transparent)]
    Vehicle(#[from] VehicleError),
    /// No example vehicle of that name.
    #[error("unknown example vehicle `{name}`; known: {}", example_names())]
    UnknownExample {
        /// The name asked for.
        name: String,
    },
    /// The rotor file cannot be used.
    #[error(transparent)]
    RotorFile(#[from] RotorFileError),
    /// The default rotor cannot be used for this vehicle (no rotor file given).
    #[error(transparent)]
    Rotor(#[from] RotorError),
    /// An effect that cannot be set on this vehicle.
    #[error(transparent)]
    Effect(#[from] EffectError),
    /// An effect that needs a flight, asked of a sweep.
    #[error(
        "effect `{effect}` {} and needs `--mode flight`",
        if *logging { "acts on a flight log" } else { "acts over time in a flight" }
    )]
    NeedsFlight {
        /// The effect's name.
        effect: &'static str,
        /// It acts on the log (else over time on the vehicle).
        logging: bool,
    },
    /// A sweep of no points.
    #[error("--points must be at least 1")]
    NoPoints,
    /// The flight cannot be flown, or diverged.
    #[error(transparent)]
    Flight(#[from] FlightError),
    /// The CSV could not be written.
    #[error(transparent)]
    Write(#[from] CsvWriteError),
}

/// The names of [`EXAMPLE_VEHICLES`], comma separated.
fn example_names() -> String {
    let names: Vec<_> = EXAMPLE_VEHICLES.iter().map(|(n, _)| *n).collect();
    names.join(", ")
}

/// Loads the vehicle of `choice`.
pub fn load_vehicle(choice: &VehicleChoice) -> Result<Vehicle, SimError> {
    match choice {
        VehicleChoice::File(p) => Ok(Vehicle::from_toml_file(p)?),
        VehicleChoice::Example(name) => {
            let text = EXAMPLE_VEHICLES
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, t)| *t)
                .ok_or_else(|| SimError::UnknownExample { name: name.clone() })?;
            Ok(Vehicle::from_toml_str(text, VehicleSource::Code)?)
        }
    }
}

/// Builds the truth model the options describe.
pub fn build_model(opts: &SimulateOptions) -> Result<TruthModel, SimError> {
    let vehicle = load_vehicle(&opts.vehicle)?;
    let file = match &opts.rotor_file {
        Some(p) => RotorFile::from_toml_file(p)?,
        None => RotorFile::default(),
    };
    let effects = Effects::new(opts.effects.clone(), &vehicle)?;
    if matches!(opts.mode, Mode::Sweep { .. })
        && let Some(e) = effects.iter().find(|e| e.needs_flight())
    {
        return Err(SimError::NeedsFlight {
            effect: e.name(),
            logging: e.is_logging_effect(),
        });
    }
    TruthModel::new(&vehicle, &file, effects).map_err(|source| match &opts.rotor_file {
        Some(p) => RotorFileError {
            path: p.clone(),
            source,
        }
        .into(),
        None => source.into(),
    })
}

/// Runs the simulation and returns the log table.
pub fn simulate(opts: &SimulateOptions) -> Result<LogTable, SimError> {
    let model = build_model(opts)?;
    match opts.mode {
        Mode::Sweep { design, points } => {
            if points == 0 {
                return Err(SimError::NoPoints);
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
pub fn simulate_to_file(opts: &SimulateOptions, out: &Path) -> Result<usize, SimError> {
    let table = simulate(opts)?;
    table.write_csv(out)?;
    Ok(table.len())
}
