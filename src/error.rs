//! The library's error: one enum over the layers a call passes through, each wrapping
//! that layer's typed error, so a caller can match on what failed and the binary picks
//! its exit code from the variant ([`Error::exit_code`]).

use crate::diagnose::DiagnoseError;
use crate::estimate::EstimateError;
use crate::identified::ModelFileError;
use crate::io::{ErrorKind, IoError};
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
    /// A statistics file or part cannot be read, merged or fitted.
    #[error(transparent)]
    Stats(#[from] StatsError),
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
    /// Process exit code of the binary: 1 when the data cannot support the fit (too
    /// little excitation, too few samples, a log too short to cross-validate), 2 for bad
    /// input (files, samples, vehicle, request).
    pub fn exit_code(&self) -> u8 {
        match self {
            Self::Estimate(_) | Self::Diagnose(_) => 1,
            Self::Request(RequestError::NoSamples) => 1,
            Self::Request(RequestError::HoldoutTooShort { .. }) => 1,
            Self::Input(e) if matches!(e.kind, ErrorKind::TooShort(_)) => 1,
            _ => 2,
        }
    }
}

/// A statistics part ([`crate::StatsPart`]) that cannot be read, merged or fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StatsError {
    /// The file could not be read or written.
    #[error("{file}: {what}")]
    Io {
        /// The file.
        file: String,
        /// What went wrong.
        what: String,
    },
    /// The file is not a statistics file of this version, or is corrupted.
    #[error("{file}: {what}")]
    Format {
        /// The file.
        file: String,
        /// What is wrong.
        what: String,
    },
    /// The part was made with other settings (vehicle, model options, mapping, reading
    /// options, consistent filter) than the request or the part it is merged with.
    #[error(
        "statistics of {logs} were made with other settings than this fit's: accumulate them again with the fit's vehicle, mapping and options\n  part:    {part}\n  this fit: {request}"
    )]
    OtherSettings {
        /// The part's logs.
        logs: String,
        /// The part's settings.
        part: String,
        /// The request's (or the other part's) settings.
        request: String,
    },
    /// The same log in two parts.
    #[error("{log} is in two statistics parts: a log may be fitted or validated once")]
    DuplicateLog {
        /// The log.
        log: String,
    },
    /// Parts made without the diagnosis's screening samples, asked to be diagnosed.
    #[error(
        "statistics of {logs} were accumulated with the diagnosis off, without its screening samples: accumulate them again with the diagnosis on to diagnose from statistics"
    )]
    NotDiagnosable {
        /// The logs without screening samples.
        logs: String,
    },
    /// A second- or third-pass part made from another plan than the one given (another
    /// fit, other settings or another diagnosis).
    #[error(
        "{file} was made from another plan than this one (another fit, settings or diagnosis): pass its log again with this plan"
    )]
    OtherPlan {
        /// The part (its log).
        file: String,
    },
    /// A log asked to be passed with a plan that does not name it.
    #[error(
        "{log} is not one of the plan's logs (plans name each log as its first-pass part does, by its file name)"
    )]
    NotInPlan {
        /// The log.
        log: String,
    },
    /// A log of the fit without its second- or third-pass part.
    #[error("no {pass} part for {log}: every log of the fit needs one, made from this plan")]
    MissingPass {
        /// The log.
        log: String,
        /// Which pass ("second-pass" or "remainder").
        pass: String,
    },
    /// Fewer than two fit logs: leave one log out needs two.
    #[error(
        "a fit from statistics needs at least two fit logs (each is a fold of leave one log out), got {logs}; fit a single log directly"
    )]
    TooFewLogs {
        /// Fit logs given.
        logs: usize,
    },
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
    /// A single fit log too short to be cut into its cross-validation blocks: it spans
    /// less than a guard per block, or has fewer samples than blocks, or some block's
    /// fold would have no sample to fit.
    #[error("{}", holdout_text(log, *samples, *span, *blocks, *guard_seconds))]
    HoldoutTooShort {
        /// The log (file name or memory log name).
        log: String,
        /// Its samples.
        samples: u64,
        /// Time from its first sample to its last, s.
        span: f64,
        /// Median step between its samples' times, s (`None` when not known).
        median_step: Option<f64>,
        /// Contiguous blocks it is cut into.
        blocks: usize,
        /// Guard on each side of a held-out block, s.
        guard_seconds: f64,
    },
    /// The same log given twice as a fit log: the same file, a file of identical
    /// content, or logs in memory holding the same samples.
    #[error("{}", duplicate_text(first, second))]
    DuplicateLog {
        /// The first (path as given, or memory log name).
        first: String,
        /// The second.
        second: String,
    },
    /// A reporting-only validation log that is also a fit log (the same file, a copy
    /// of it, or the same samples in memory).
    #[error("{}", validation_text(validation, fit))]
    ValidationIsFitLog {
        /// The validation log (path as given, or memory log name).
        validation: String,
        /// The fit log it is.
        fit: String,
    },
    /// Fewer than two cross-validation blocks, or a guard that is not a number of
    /// seconds ≥ 0.
    #[error(
        "a single fit log is cross-validated on at least 2 blocks (got {blocks}) with a guard of 0 s or more (got {guard_seconds} s)"
    )]
    InvalidHoldout {
        /// Blocks given.
        blocks: usize,
        /// Guard given, s.
        guard_seconds: f64,
    },
    /// Cross-validation groups that do not name each fit log, or name fewer than two
    /// groups.
    #[error(
        "cross-validation groups must name each of the {logs} fit logs, in order, with at least 2 distinct groups (got {groups} names, {distinct} distinct)"
    )]
    InvalidGroups {
        /// Group names given.
        groups: usize,
        /// Distinct names among them.
        distinct: usize,
        /// Fit logs.
        logs: usize,
    },
    /// A loads low-pass cut-off that is not a positive number of Hz.
    #[error("the loads' low-pass cut-off must be a positive number of Hz (got {hz})")]
    InvalidLoadsLowPass {
        /// Cut-off given, Hz.
        hz: f64,
    },
    /// A declared loads low-pass cut-off above half a log's sample rate: such a filter
    /// does nothing there, so the declaration cannot be what the log's processing did.
    #[error(
        "the loads' low-pass cut-off {hz} Hz is above half the sample rate of {log} ({:.1} \
         Hz, a sample every {step} s): a filter there does nothing; declare the cut-off of \
         the filter the loads went through (below {:.1} Hz), or `--loads-low-pass estimate`",
        0.5 / step,
        0.5 / step
    )]
    LoadsLowPassAboveNyquist {
        /// Cut-off declared, Hz.
        hz: f64,
        /// The log's file name.
        log: String,
        /// Its median sample step, s.
        step: f64,
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
    /// The caller set the request's cancellation flag ([`crate::Identification::cancel`])
    /// and the fit stopped at the next chunk. The binary never sets it.
    #[error("the fit was cancelled")]
    Cancelled,
}

/// `x` s with at most three decimals.
fn seconds(x: f64) -> String {
    let text = format!("{x:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The text of [`RequestError::HoldoutTooShort`] (its fields).
fn holdout_text(log: &str, samples: u64, span: f64, blocks: usize, guard_seconds: f64) -> String {
    let need = seconds(blocks as f64 * guard_seconds);
    let counted = match samples {
        1 => "1 sample".to_string(),
        n => format!("{n} samples"),
    };
    let mut remedies = vec![
        "a longer log".to_string(),
        "two or more logs (each is then predicted from the others)".to_string(),
    ];
    let shorter = span / blocks as f64;
    if guard_seconds > 0.0 && shorter < guard_seconds && samples >= blocks as u64 {
        remedies.push(format!(
            "a shorter guard (--holdout-guard, at most {} s here)",
            seconds(shorter)
        ));
    }
    let last = remedies.pop().unwrap_or_default();
    format!(
        "{log}: too short to fit and cross-validate: {counted} spanning {} s, while a single \
         fit log must span at least {need} s and hold {blocks} samples (it is cut into \
         {blocks} contiguous blocks, each predicted by the model fitted on the others less \
         {} s on each side of it); give {}, or {last}",
        seconds(span),
        seconds(guard_seconds),
        remedies.join(", ")
    )
}

fn duplicate_text(first: &str, second: &str) -> String {
    let what = if first == second {
        format!("the same log {first} is given twice")
    } else {
        format!("the logs {first} and {second} are the same log (identical content)")
    };
    format!(
        "{what}: leaving one log out would predict it from its own copy, so the \
         cross-validated figures would be in-sample; give each log once"
    )
}

fn validation_text(validation: &str, fit: &str) -> String {
    let what = if validation == fit {
        format!("the validation log {validation} is also a fit log")
    } else {
        format!("the validation log {validation} is the fit log {fit} (identical content)")
    };
    format!(
        "{what}: its figures would come from data the fit has seen, not from unseen data; \
         validate on a log that is not fitted"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn too_short(samples: u64, span: f64, guard_seconds: f64) -> Error {
        Error::Request(RequestError::HoldoutTooShort {
            log: "log.csv".into(),
            samples,
            span,
            median_step: Some(0.01),
            blocks: 5,
            guard_seconds,
        })
    }

    /// A single log too short for its blocks cannot support the fit (exit 1); the message
    /// says what is needed, and suggests a shorter guard only when the log holds a sample
    /// per block and a guard per block is what it lacks.
    #[test]
    fn hold_out_failures_say_what_is_short() {
        let short = too_short(499, 4.98, 2.0);
        assert_eq!(short.exit_code(), 1);
        assert_eq!(
            short.to_string(),
            "log.csv: too short to fit and cross-validate: 499 samples spanning 4.98 s, while \
             a single fit log must span at least 10 s and hold 5 samples (it is cut into 5 \
             contiguous blocks, each predicted by the model fitted on the others less 2 s on \
             each side of it); give a longer log, two or more logs (each is then predicted \
             from the others), or a shorter guard (--holdout-guard, at most 0.996 s here)"
        );
        let tiny = too_short(3, 0.02, 2.0);
        assert!(
            tiny.to_string().ends_with(
                "give a longer log, or two or more logs (each is then predicted from the others)"
            ),
            "{tiny}"
        );
    }
}
