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
//! # Modules
//!
//! After the seed's sections:
//! - [`vehicle`]: geometry, mass properties, Assumption 2 checks, Definition 1 (§2, §4.2);
//! - [`rotor`]: single-rotor closed form and lumped parameters (§3, Eq. 2–8);
//! - [`airframe`]: per-rotor loads carried to the airframe and summed (§4.1, Eq. 10–18);
//! - [`mixing`]: virtual actuators (Eq. 19–21);
//! - [`model`]: the Eq. 22 regressors as data, batch assembly, prediction;
//! - [`sample`]: the data contract, as structure-of-arrays chunks;
//! - [`stats`]: one-pass mergeable statistics of the regressors and outputs;
//! - [`estimate`]: the two-step estimation of §5 (OLS, FSOA, MMR, inference,
//!   diagnostics, identifiability, cross-validation);
//! - [`diagnose`]: closing the loop: candidate effects the model lacks, tested on
//!   held-out data.
//!
//! The product around them:
//! - [`identify`]: the fit builder [`Identification`] and its [`Results`];
//! - [`pipeline`]: the streaming fit over logs (both passes, threads, hold-out);
//! - [`source`]: where samples come from (files, or [`source::MemoryLog`]);
//! - [`inputs`]: checks of a request's files (a log given twice, an output that is an
//!   input);
//! - [`io`]: log readers (CSV contract and mapped CSV, MCAP, PX4 ULog) and writers;
//! - [`identified`]: the saved model file, prediction with an identified model;
//! - [`report`]: the report (tables, JSON) and, with the `plots` feature, plots;
//! - [`error`]: the library's [`Error`];
//! - [`util`]: vector algebra, quaternion rotation, atomic file writes;
//! - [`sim`]: the truth simulator (blade-element rotors, effects, sweeps, flights).
//!
//! # Features
//!
//! `cli` (default) builds the `mrsysid` binary (clap, indicatif); `plots` (default)
//! adds [`report::plots`] (plotters). `default-features = false` gives the library
//! alone.

#![warn(missing_docs)]

pub mod airframe;
mod consistent_filter;
pub mod diagnose;
pub mod error;
pub mod estimate;
mod held;
pub mod identified;
pub mod identify;
pub mod inputs;
pub mod io;
pub mod mixing;
pub mod model;
pub mod pipeline;
pub mod report;
pub mod rotor;
pub mod sample;
pub mod sim;
mod slow;
mod smooth;
pub mod source;
mod spill;
pub mod stats;
pub mod util;
pub mod vehicle;

pub use error::Error;
pub use identified::IdentifiedModel;
pub use identify::{Identification, Results};
pub use sample::{Axis, CHUNK_SAMPLES, Sample, SampleChunk};
pub use slow::TRIM_BANDS_HZ;
pub use source::{LogSource, MemoryLog};
pub use vehicle::Vehicle;
