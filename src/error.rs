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
            Self::Request(e @ RequestError::HoldoutTooShort { .. }) if e.log_too_short() => 1,
            Self::Input(e) if matches!(e.kind, ErrorKind::TooShort(_)) => 1,
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
    /// A single fit log none of whose samples falls in a held-out segment: shorter than
    /// the first held-out segment's start, or sampled more coarsely than the segments.
    #[error("{}", holdout_text(log, *samples, *span, *median_step, *segment_seconds, *every))]
    HoldoutTooShort {
        /// The log (file name or memory log name).
        log: String,
        /// Its samples.
        samples: u64,
        /// Time from its first sample to its last, s.
        span: f64,
        /// Median step between its samples' times, s (`None` when not known).
        median_step: Option<f64>,
        /// Segment length, s.
        segment_seconds: f64,
        /// Every `every`-th segment is held out.
        every: usize,
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
    /// The caller set the request's cancellation flag ([`crate::Identification::cancel`])
    /// and the fit stopped at the next chunk. The binary never sets it.
    #[error("the fit was cancelled")]
    Cancelled,
}

impl RequestError {
    /// True for [`RequestError::HoldoutTooShort`] of a log shorter than the start of its
    /// first held-out segment (the data cannot support the fit), false for one long
    /// enough but sampled more coarsely than its segments (a hold-out that does not fit
    /// the data) and for every other error.
    pub fn log_too_short(&self) -> bool {
        match self {
            Self::HoldoutTooShort {
                span,
                segment_seconds,
                every,
                ..
            } => *span < first_held_out(*segment_seconds, *every),
            _ => false,
        }
    }
}

/// Start of the first held-out segment of a log, s from its first sample: every
/// `every`-th segment of `segment_seconds` is held out.
fn first_held_out(segment_seconds: f64, every: usize) -> f64 {
    segment_seconds * every.saturating_sub(1) as f64
}

/// `x` s with at most three decimals.
fn seconds(x: f64) -> String {
    let text = format!("{x:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// "1st", "2nd", "3rd", "4th" … of `n`.
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (1, x) if x != 11 => "st",
        (2, x) if x != 12 => "nd",
        (3, x) if x != 13 => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// The text of [`RequestError::HoldoutTooShort`] (its fields).
fn holdout_text(
    log: &str,
    samples: u64,
    span: f64,
    median_step: Option<f64>,
    segment_seconds: f64,
    every: usize,
) -> String {
    let start = first_held_out(segment_seconds, every);
    let need = seconds(start);
    let cycle = format!(
        "every {} {} s segment is held out",
        ordinal(every),
        seconds(segment_seconds)
    );
    let counted = match samples {
        1 => "1 sample".to_string(),
        n => format!("{n} samples"),
    };
    let span_text = seconds(span);
    if span < start {
        // Shorter segments help when each would still hold ten samples or more.
        let short_segment = span / every as f64;
        let mut remedies = vec![
            "a longer log".to_string(),
            "two or more logs (each is then predicted from the others)".to_string(),
        ];
        if span > 0.0 && median_step.is_none_or(|s| short_segment >= 10.0 * s) {
            remedies.push(format!(
                "shorter hold-out segments (at most {} s here)",
                seconds(short_segment)
            ));
        }
        let last = remedies.pop().unwrap_or_default();
        format!(
            "{log}: too short to fit and cross-validate: {counted} spanning {span_text} s, \
             while a single fit log must span at least {need} s ({cycle}, the first from \
             {need} s on); give {}, or {last}",
            remedies.join(", ")
        )
    } else {
        let apart = median_step.map_or(String::new(), |s| {
            format!(", {} s apart (median),", seconds(s))
        });
        format!(
            "{log}: no sample falls in a held-out segment: its {counted} span {span_text} \
             s{apart} and {cycle}; give hold-out segments longer than the sample interval, \
             or two or more logs (each is then predicted from the others)"
        )
    }
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

    fn no_holdout(span: f64, median_step: f64, segment_seconds: f64) -> Error {
        Error::Request(RequestError::HoldoutTooShort {
            log: "log.csv".into(),
            samples: 1 + (span / median_step).round() as u64,
            span,
            median_step: Some(median_step),
            segment_seconds,
            every: 5,
        })
    }

    /// A log shorter than the first held-out segment's start cannot support the fit
    /// (exit 1); a long one sampled more coarsely than its segments has a hold-out that
    /// does not fit it (exit 2). Shorter segments are suggested only when each would
    /// still hold ten samples.
    #[test]
    fn hold_out_failures_say_what_is_short() {
        let short = no_holdout(4.98, 0.01, 2.0);
        assert_eq!(short.exit_code(), 1);
        assert_eq!(
            short.to_string(),
            "log.csv: too short to fit and cross-validate: 499 samples spanning 4.98 s, while \
             a single fit log must span at least 8 s (every 5th 2 s segment is held out, the \
             first from 8 s on); give a longer log, two or more logs (each is then predicted \
             from the others), or shorter hold-out segments (at most 0.996 s here)"
        );
        let tiny = no_holdout(0.09, 0.01, 2.0);
        assert!(
            tiny.to_string().ends_with(
                "give a longer log, or two or more logs (each is then predicted from the others)"
            ),
            "{tiny}"
        );
        let coarse = no_holdout(20.0, 0.5, 0.1);
        assert_eq!(coarse.exit_code(), 2);
        assert_eq!(
            coarse.to_string(),
            "log.csv: no sample falls in a held-out segment: its 41 samples span 20 s, 0.5 s \
             apart (median), and every 5th 0.1 s segment is held out; give hold-out segments \
             longer than the sample interval, or two or more logs (each is then predicted \
             from the others)"
        );
        assert_eq!(ordinal(2), "2nd");
        assert_eq!(ordinal(11), "11th");
        assert_eq!(ordinal(23), "23rd");
    }
}
