//! The library's error: one enum over the layers a call passes through, each wrapping
//! that layer's typed error, so a caller can match on what failed and the binary picks
//! its exit code from the variant ([`Error::exit_code`]).

use crate::diagnose::DiagnoseError;
use crate::estimate::EstimateError;
use crate::identified::ModelFileError;
use crate::io::IoError;
use crate::model::ModelError;
use crate::stats::AccumulateError;
use crate::vehicle::VehicleError;

/// Why a library call failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The vehicle file or definition is invalid.
    #[error(transparent)]
    Vehicle(#[from] VehicleError),
    /// A log, mapping file or in-memory sample is malformed; names the file (or memory
    /// log), the line, message, byte or sample, and the field.
    #[error(transparent)]
    Input(#[from] IoError),
    /// The data lack a signal the model needs, or have another rotor count.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A log's regressors could not be accumulated (a non-finite regressor).
    #[error("{log}: {source}")]
    Accumulate {
        /// The log (file name or memory log name).
        log: String,
        /// What went wrong.
        source: AccumulateError,
    },
    /// The data cannot support the fit.
    #[error(transparent)]
    Estimate(#[from] EstimateError),
    /// The closing-the-loop diagnosis could not run.
    #[error(transparent)]
    Diagnose(#[from] DiagnoseError),
    /// A model file could not be read or written.
    #[error(transparent)]
    ModelFile(#[from] ModelFileError),
    /// The request itself cannot be carried out.
    #[error(transparent)]
    Request(#[from] RequestError),
    /// The temporary file holding a log's parsed samples between the two passes could
    /// not be written or read back (e.g. the temp dir is full or not writable).
    #[error("temporary sample file {}: {source}", path.display())]
    Spill {
        /// The temporary file.
        path: std::path::PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
}

impl Error {
    /// Process exit code of the binary: 1 when the data cannot support the fit, 2 for
    /// bad input (files, samples, vehicle, request).
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Estimate(_) | Self::Diagnose(_) => 1,
            Self::Request(RequestError::NoSamples) => 1,
            _ => 2,
        }
    }
}

/// A fit request that cannot be carried out as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RequestError {
    /// No log to fit.
    #[error("no log to fit")]
    NoLogs,
    /// The fit logs hold no sample.
    #[error("no samples to fit")]
    NoSamples,
    /// A single fit log shorter than one hold-out cycle.
    #[error(
        "no held-out samples: the log is shorter than one hold-out cycle ({every} segments of {segment_seconds} s); give two or more logs (each is then predicted from the others) or shorter hold-out segments"
    )]
    HoldoutTooShort {
        /// Segment length, s.
        segment_seconds: f64,
        /// Every `every`-th segment is held out.
        every: usize,
    },
    /// Hold-out segments that are not a positive length, or a cycle of fewer than two.
    #[error(
        "hold-out segment length {segment_seconds} s must be a positive number of seconds and the cycle ({every}) at least 2"
    )]
    InvalidHoldout {
        /// Segment length given, s.
        segment_seconds: f64,
        /// Cycle given.
        every: usize,
    },
    /// The model structure was built for another vehicle.
    #[error(
        "the model structure is for {structure} rotors but the vehicle has {vehicle}: build it from this vehicle"
    )]
    StructureMismatch {
        /// Rotors of the structure.
        structure: usize,
        /// Rotors of the vehicle.
        vehicle: usize,
    },
    /// A worker thread stopped without a result (a bug: please report it).
    #[error("a worker thread stopped without a result")]
    WorkerStopped,
}
