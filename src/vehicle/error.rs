//! Why a vehicle definition was refused ([`VehicleError`]: where it came from, what is
//! wrong) and the Assumption 2 breaches an accepted layout is noted with.

use std::fmt;
use std::path::PathBuf;

/// Where a vehicle definition came from, for error messages.
#[derive(Debug, Clone, PartialEq)]
pub enum VehicleSource {
    /// A TOML file.
    File(PathBuf),
    /// Built in code (preset or explicit table).
    Code,
}

impl fmt::Display for VehicleSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::File(p) => write!(f, "{}", p.display()),
            Self::Code => f.write_str("vehicle"),
        }
    }
}

/// Why a vehicle definition was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VehicleErrorKind {
    /// The file could not be read.
    #[error("cannot read file: {0}")]
    Io(String),
    /// TOML syntax error or a field of the wrong type / missing field.
    #[error("{0}")]
    Parse(String),
    /// A scalar field outside its physical range.
    #[error("field `{field}` = {value}: {requirement}")]
    OutOfRange {
        /// Field name as in the TOML file.
        field: &'static str,
        /// Offending value.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
    /// The inertia matrix is not symmetric positive definite.
    #[error("field `inertia`: {0}")]
    Inertia(String),
    /// Neither a rotor table nor a preset, or both.
    #[error("{0}")]
    Layout(String),
    /// A rotor entry is invalid on its own.
    #[error("rotor {rotor} (entry {rotor} of [[rotors]]): {problem}")]
    Rotor {
        /// 1-based rotor number.
        rotor: usize,
        /// What is wrong.
        problem: String,
    },
    /// A condition of the seed's Assumption 2 that the general planar model needs too
    /// (even rotor count, balanced spins, coplanar uncanted rotors, a mixing matrix of
    /// full rank) does not hold.
    #[error("Assumption 2 fails ({condition}): {detail}")]
    Assumption2 {
        /// The failing condition, e.g. "balanced spins".
        condition: &'static str,
        /// Which rotors and by how much.
        detail: String,
    },
}

/// A vehicle definition that was refused, with where it came from.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{source_name}: {kind}")]
pub struct VehicleError {
    /// File or code origin.
    pub source_name: VehicleSource,
    /// What is wrong.
    pub kind: VehicleErrorKind,
}

/// One condition of the seed's Assumption 2 that an accepted (general planar) layout
/// breaks. Reported as a note, not an error: the model stays exact (see `crate::model`).
#[derive(Debug, Clone, PartialEq)]
pub struct Assumption2Breach {
    /// The condition, e.g. "equal arms".
    pub condition: &'static str,
    /// Which rotors and by how much.
    pub detail: String,
}

impl fmt::Display for Assumption2Breach {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Assumption 2 does not hold ({}): {}",
            self.condition, self.detail
        )
    }
}
