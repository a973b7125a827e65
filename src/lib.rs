//! `mrsysid`: offline nonlinear system identification of multirotor aircraft, after
//! Hopwood & Woolsey, "Towards Large-Domain Nonlinear System Identification of
//! Multirotor Aircraft" (2023), called "the seed" in these docs.
//!
//! Modules follow the seed's sections:
//! - [`vehicle`]: geometry, mass properties, Assumption 2 checks, Definition 1 (§2, §4.2);
//! - [`rotor`]: single-rotor closed form and lumped parameters (§3, Eq. 2–8);
//! - [`airframe`]: per-rotor loads carried to the airframe and summed (§4.1, Eq. 10–18);
//! - [`mixing`]: virtual actuators (Eq. 19–21);
//! - [`model`]: the Eq. 22 regressors as data, batch assembly;
//! - [`sample`]: the data contract, as structure-of-arrays chunks;
//! - [`stats`]: one-pass mergeable statistics of the regressors and outputs;
//! - [`estimate`]: the two-step estimation of §5 (OLS, FSOA, MMR, inference,
//!   diagnostics, identifiability).
//! - [`sim`]: the truth simulator (blade-element rotors, effects, sweeps, flights).

#![warn(missing_docs)]

pub mod airframe;
pub mod diagnose;
pub mod estimate;
pub mod identified;
pub mod io;
pub mod mixing;
pub mod model;
pub mod pipeline;
pub mod report;
pub mod rotor;
pub mod sample;
pub mod sim;
pub mod stats;
pub mod vehicle;

/// Number of samples per chunk in streaming passes: one place that decides it.
/// 1024 samples × ~40 regressor columns × 8 bytes stays inside a core's L2 cache.
pub const CHUNK_SAMPLES: usize = 1024;
