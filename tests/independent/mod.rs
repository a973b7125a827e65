//! A second, independent source of truth for the diagnosis: a simple multirotor model
//! written for the tests (its own rotor formula, airframe, controller and sensors; the
//! crate's truth simulator `mrsysid::internals::sim` is not used), five hidden effects in forms of
//! its own, and a harness that scores the product's diagnosis on them. It flies the
//! shipped quadrotor × and, grown by similarity to its size, the shipped Gazebo iris
//! ([`physics::Scale`]).
//!
//! - [`physics`]: the rotor and airframe loads;
//! - [`effects`]: the hidden effects;
//! - [`surface`]: the response-surface data kind;
//! - [`flight`]: the closed-loop flight data kind;
//! - [`score`]: cases, the diagnosis through the public library, and its score.
//!
//! Used by `tests/independent_truth.rs` (a small subset) and
//! `examples/independent_truth.rs` (the whole table over many seeds).

// The example and the test use different subsets of the harness.
#![allow(dead_code)]

pub mod effects;
pub mod flight;
pub mod physics;
pub mod score;
pub mod surface;
