//! Truth simulator: the crate's own high-fidelity multirotor model, used to test the
//! Eq. 22 identification on data it did not generate.
//!
//! - [`blade_element`]: rotor loads by numerical blade-element integration;
//! - [`inflow`]: implicit momentum inflow coupled to the blade thrust;
//! - [`truth`]: the vehicle wrench (seed §4.1 transmission, airframe drag, effects);
//! - [`effects`]: named undeclared effects with physical parameters;
//! - [`disturbance`]: the slowly varying airframe moment of the `trim_moment` effect;
//! - [`filter`]: zero-phase Butterworth smoothing of a log (`smoothed_loads`);
//! - [`test_matrix`]: response-surface sweeps (uniform, Latin hypercube);
//! - [`flight`], [`controller`], [`sensors`]: time-domain flights with a cascaded
//!   controller and IMU / eRPM sensors;
//! - [`output`]: the CSV data contract, written atomically.

pub mod blade_element;
pub mod controller;
pub mod disturbance;
pub mod effects;
pub mod filter;
pub mod flight;
pub mod inflow;
pub mod output;
pub mod run;
pub mod sensors;
pub mod test_matrix;
pub mod truth;

pub use effects::{Effect, Effects};
pub use truth::{RotorFile, TruthInput, TruthModel};
