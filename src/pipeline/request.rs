//! What a fit is asked to do ([`FitRequest`], with the single log's [`Holdout`]) and the
//! checks that refuse a request before or right after the first pass.

use std::sync::Arc;
use std::sync::atomic::AtomicU64;

use super::first_pass::LogStats;
use crate::diagnose::DiagnoseOptions;
use crate::error::{Error, RequestError};
use crate::estimate::FitOptions;
use crate::io::{self, Mapping, ReadOptions};
use crate::model::ModelStructure;
use crate::source::LogSource;
use crate::vehicle::Vehicle;

/// Time-segment hold-out of the fit logs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Holdout {
    /// Segment length, s.
    pub segment_seconds: f64,
    /// Every `every`-th segment is held out (fraction 1/every).
    pub every: usize,
}

impl Default for Holdout {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Holdout {
    /// The hold-out of a single fit log unless asked otherwise, the one place it is
    /// written: every 5th 2 s segment (20 % of the log, the first held-out segment
    /// from 8 s on).
    pub const DEFAULT: Holdout = Holdout {
        segment_seconds: 2.0,
        every: 5,
    };

    /// True when the sample at `t` (s), in a log starting at `t0` (s), is held out.
    pub fn holds_out(&self, t: f64, t0: f64) -> bool {
        let segment = ((t - t0) / self.segment_seconds).floor() as usize;
        self.every > 0 && segment % self.every == self.every - 1
    }
}

/// Everything `fit` needs.
#[derive(Debug, Clone)]
pub struct FitRequest {
    /// Logs to fit.
    pub logs: Vec<LogSource>,
    /// The vehicle.
    pub vehicle: Vehicle,
    /// Mapping for logs that do not follow the contract.
    pub mapping: Option<Mapping>,
    /// Reader options.
    pub read: ReadOptions,
    /// Eq. 22 structure.
    pub structure: ModelStructure,
    /// Estimation options.
    pub fit: FitOptions,
    /// Segment hold-out of a single fit log (cross-validation of one log).
    pub holdout: Holdout,
    /// Reporting-only validation logs: evaluated, never used for a decision.
    pub validate: Vec<LogSource>,
    /// Threads for reading, accumulating and the diagnosis (≥ 1).
    pub threads: usize,
    /// Run the second pass (residual diagnostics, plot series).
    pub second_pass: bool,
    /// Run the closing-the-loop diagnosis (in the second pass).
    pub diagnose: Option<DiagnoseOptions>,
    /// Samples read so far, over both passes, for a progress display.
    pub progress: Option<Arc<AtomicU64>>,
}

/// Refuses a request that cannot be carried out, before any log is read.
pub(super) fn check(req: &FitRequest) -> Result<(), RequestError> {
    if req.logs.is_empty() {
        return Err(RequestError::NoLogs);
    }
    let h = req.holdout;
    if !(h.segment_seconds.is_finite() && h.segment_seconds > 0.0 && h.every >= 2) {
        return Err(RequestError::InvalidHoldout {
            segment_seconds: h.segment_seconds,
            every: h.every,
        });
    }
    let (structure, vehicle) = (req.structure.rotor_count(), req.vehicle.rotor_count());
    if structure != vehicle {
        return Err(RequestError::StructureMismatch { structure, vehicle });
    }
    crate::inputs::check_logs(&req.logs, &req.validate)
}

/// The error of a single fit log none of whose samples was held out (`log`, read as
/// `req.logs[0]`): its time looks logged in ms or µs (bad input), else it is too short
/// for the hold-out, or sampled more coarsely than its segments.
pub(super) fn no_holdout(req: &FitRequest, log: &LogStats) -> Error {
    let s = &log.summary;
    let (span, median_step) = match &req.logs[0] {
        LogSource::Memory(m) => {
            let first = m.chunks().first().and_then(|c| c.t.first());
            let last = m.chunks().last().and_then(|c| c.t.last());
            (first.zip(last).map_or(0.0, |(a, b)| b - a), None)
        }
        LogSource::File(_) => (s.span, s.median_time_step),
    };
    let samples = log.fit.count() + log.held_out.count();
    let consequence = ", so no sample falls in a held-out segment";
    if let Some(text) = io::time_unit_suspect(median_step, span, samples, consequence) {
        return io::IoError::new(
            &s.file,
            io::Location::File,
            None,
            io::ErrorKind::Mapping(text),
        )
        .into();
    }
    RequestError::HoldoutTooShort {
        log: s.file.clone(),
        samples,
        span,
        median_step,
        segment_seconds: req.holdout.segment_seconds,
        every: req.holdout.every,
    }
    .into()
}
