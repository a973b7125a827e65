//! `mrsysid`: offline nonlinear system identification of multirotor aircraft, after
//! Hopwood & Woolsey, "Towards Large-Domain Nonlinear System Identification of
//! Multirotor Aircraft" (2023), called "the seed" in these docs.
//!
//! # Use
//!
//! [`Identification`] fits a vehicle's logs, from files or from samples in memory,
//! through the one pipeline of `mrsysid fit`, and returns [`Results`] for the final
//! model; [`IdentifiedModel`] saves, loads and predicts with it. Every failure is an
//! [`Error`]; no public function panics on user data.
//!
//! ```
//! use mrsysid::{Identification, IdentifiedModel, Sample, Vehicle};
//! # fn main() -> Result<(), mrsysid::Error> {
//! let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
//! let vehicle = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml"))?;
//! let results = Identification::new(vehicle)
//!     .log(root.join("data/quad_x_flight_quadratic_drag.csv"))
//!     .diagnose(false)
//!     .run()?;
//! let model: IdentifiedModel = results.to_identified_model();
//! // At rest, equal rotor speeds (rad/s), no rotor acceleration (the J_z terms need it).
//! let hover = Sample { omega: vec![700.0; 4], omega_dot: vec![0.0; 4], ..Sample::default() };
//! let [_, _, fz, ..] = model.predict(&hover)?;
//! assert!(fz < 0.0, "thrust points up (body z down)");
//! # Ok(())
//! # }
//! ```
//!
//! # The front
//!
//! What a user needs is at the crate root: the fit builder [`Identification`] with
//! its options ([`ModelOptions`], [`Holdout`], [`ReadOptions`], [`Mapping`]), its
//! [`Results`] and [`FitOutcome`], the saved model [`IdentifiedModel`] (prediction,
//! [`Validation`] on other logs), the [`Vehicle`], the data contract ([`Sample`],
//! [`SampleChunk`], [`MemoryLog`]) and the [`Error`]. Beside them:
//! - [`io`]: log readers (CSV contract and mapped CSV, MCAP, PX4 ULog, ArduPilot
//!   DataFlash) and the vehicle skeletons read off an autopilot's parameters;
//! - [`vehicle`]: geometry, mass properties, Assumption 2 checks, Definition 1 (§2,
//!   §4.2);
//! - [`report`]: the report (tables, JSON) and, with the `plots` feature, plots;
//! - [`simulate`]: the truth simulator's front (sweeps and flights to a contract CSV);
//! - [`error`]: the library's [`Error`] and the request's errors.
//!
//! [`internals`] opens the modules below for the crate's benchmarks, examples, tests
//! and Python package: the seed's sections (rotor, airframe, Eq. 22 model, statistics,
//! estimation, diagnosis), the streaming pipeline and the simulator. It is no stable
//! interface.
//!
//! # Features
//!
//! `cli` (default) builds the `mrsysid` binary (clap, indicatif); `plots` (default)
//! adds [`report::plots`] (plotters). `default-features = false` gives the library
//! alone.

#![warn(missing_docs)]

mod airframe;
mod consistent_filter;
mod diagnose;
pub mod error;
mod estimate;
mod held;
mod identified;
mod identify;
mod inputs;
pub mod io;
mod loads_scan;
mod mixing;
mod model;
mod on_logs;
mod pipeline;
mod progress;
pub mod report;
mod rotor;
mod sample;
mod sim;
mod slow;
mod smooth;
mod source;
mod spill;
mod stats;
mod util;
pub mod vehicle;

pub use error::{Error, RequestError, StatsError};
pub use estimate::{AxisMetrics, ResidualDiagnostics};
pub use identified::{IdentifiedModel, ModelFileError};
pub use identify::{Identification, InformationCriteria, ParameterResult, Results};
pub use inputs::same_file;
pub use io::{InvalidSamples, IoError, Mapping, ReadOptions};
pub use loads_scan::{LowPassScan, ScanPoint};
pub use model::{
    InflowCorrection, ModelError, ModelOptions, ModelStructure, ParamOrigin, RotorInertiaTerms,
    Workspace,
};
pub use on_logs::Validation;
pub use pipeline::{
    EffectSeries, FitOutcome, Holdout, PassPart, PassPlan, PendingFit, PlannedFit, PlotSeries,
    PreparedPass, RemainderPart, RemainderPlan, STATS_FORMAT_VERSION, StatsPart,
};
pub use progress::{Phase, Progress};
pub use report::summary::Report;
pub use sample::{Axis, CHUNK_SAMPLES, Sample, SampleChunk, TRIM_BANDS_HZ};
pub use source::{LogSource, MemoryLog};
pub use util::write_atomically;
pub use vehicle::{Vehicle, VehicleSource};

/// The truth simulator's front, as `mrsysid simulate` uses it: a response-surface sweep
/// or a flight (controller, sensors, undeclared effects) written as a contract CSV.
pub mod simulate {
    pub use crate::sim::Effect;
    pub use crate::sim::effects::EffectError;
    pub use crate::sim::flight::FlightConfig;
    pub use crate::sim::run::{Mode, SimError, SimulateOptions, VehicleChoice, simulate_to_file};
    pub use crate::sim::test_matrix::Design;
}

/// The crate's inner modules, opened for its benchmarks, examples, tests and Python
/// package, which exercise the seed's steps one by one. Not a stable interface: a user
/// of the library needs only the crate root and its public modules.
pub mod internals {
    /// Per-rotor loads carried to the airframe and summed (§4.1, Eq. 10–18).
    pub mod airframe {
        pub use crate::airframe::*;
    }
    /// Closing the loop: candidate effects the model lacks, tested on held-out data.
    pub mod diagnose {
        pub use crate::diagnose::*;
    }
    /// The two-step estimation of §5 (OLS, FSOA, MMR, inference, diagnostics,
    /// identifiability, cross-validation).
    pub mod estimate {
        pub use crate::estimate::*;
    }
    /// The saved model file, prediction with an identified model.
    pub mod identified {
        pub use crate::identified::*;
    }
    /// Virtual actuators (Eq. 19–21).
    pub mod mixing {
        pub use crate::mixing::*;
    }
    /// The Eq. 22 regressors as data, batch assembly, prediction.
    pub mod model {
        pub use crate::model::*;
    }
    /// The streaming fit over logs (both passes, threads, hold-out).
    pub mod pipeline {
        pub use crate::pipeline::*;
    }
    /// Single-rotor closed form and lumped parameters (§3, Eq. 2–8).
    pub mod rotor {
        pub use crate::rotor::*;
    }
    /// The data contract, as structure-of-arrays chunks.
    pub mod sample {
        pub use crate::sample::*;
    }
    /// The truth simulator (blade-element rotors, effects, sweeps, flights).
    pub mod sim {
        pub use crate::sim::*;
    }
    /// One-pass mergeable statistics of the regressors and outputs.
    pub mod stats {
        pub use crate::stats::*;
    }
    /// Vector algebra, quaternion rotation, atomic file writes.
    pub mod util {
        pub use crate::util::*;
    }
}
