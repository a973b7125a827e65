//! The first pass over a log: read once, each sample routed to the fit or held-out
//! statistics (a single fit log's to its time units), the thinned screening samples
//! kept, the parsed chunks spilled for the second pass.

use super::blocks::{BlockPlan, Units};
use super::split::Role;
use super::stream::stream_log;
use super::{FitRequest, accumulate_error};
use crate::diagnose::{SCREENING_SAMPLES, Thinned};
use crate::error::Error;
use crate::io::Summary;
use crate::model::Workspace;
use crate::sample::Signals;
use crate::source::LogSource;
use crate::spill::{Spill, SpillWriter};
use crate::stats::Accumulator;

/// Statistics of one log: the samples fitted and those held out for reporting (all
/// samples of a validation log), or for a single fit log its time units, which the
/// blocks that cross-validate it are made of.
pub(super) struct LogStats {
    pub(super) fit: Accumulator,
    pub(super) held_out: Accumulator,
    /// The time units of a single fit log (all its samples), `None` for other logs.
    pub(super) units: Option<Units>,
    /// Thinned fit samples for the generic-pool screening.
    pub(super) screening: Thinned,
    pub(super) summary: Summary,
    /// Optional signals of the log's first chunk, `None` for a log without samples.
    pub(super) signals: Option<Signals>,
    /// The log's parsed chunks for the second pass (log files only, when it runs).
    pub(super) spill: Option<Spill>,
    /// Chunks the log was read in.
    pub(super) chunks: usize,
    /// Its runs of samples ([`Runs`]).
    pub(super) runs: Runs,
}

/// A break in the samples longer than this (s) starts a new run.
const RUN_BREAK_SECONDS: f64 = 0.1;

/// Samples per run, on average over a log, below which it is taken for a sweep's points
/// rather than a time series: a time series has long runs, a sweep's points come one or
/// two at a time.
const MIN_RUN_SAMPLES: u64 = 256;

/// Runs of samples without a break longer than [`RUN_BREAK_SECONDS`], counted from the
/// samples themselves as the pipeline streams them (so a log gives the same count from a
/// file and from memory, whatever its reader calls a segment).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub(super) struct Runs {
    samples: u64,
    runs: u64,
    last: Option<f64>,
}

impl Runs {
    fn push(&mut self, t: &[f64]) {
        for &tk in t {
            if self.last.is_none_or(|last| tk - last > RUN_BREAK_SECONDS) {
                self.runs += 1;
            }
            self.last = Some(tk);
        }
        self.samples += t.len() as u64;
    }

    /// True for a time series: long runs on average.
    pub(super) fn time_series(&self) -> bool {
        self.samples >= MIN_RUN_SAMPLES * self.runs.max(1)
    }
}

impl LogStats {
    /// Samples fitted and held out (for plot decimation).
    pub(super) fn kinds(&self) -> [u64; 2] {
        let fit = self.units.as_ref().map_or(0, Units::samples);
        [self.fit.count() + fit, self.held_out.count()]
    }
}

/// What the second pass needs to know of a log from the first, in job order.
#[derive(Debug, Clone)]
pub(super) struct LogCounts {
    /// Samples routed to fit and to validation (for plot decimation).
    pub(super) kinds: [u64; 2],
    /// Chunks the log is read in (the same in both passes).
    pub(super) chunks: usize,
    /// The log is a time series ([`Runs::time_series`]).
    pub(super) time_series: bool,
    /// The blocks of a single fit log.
    pub(super) plan: Option<BlockPlan>,
}

/// What a first pass keeps beside the statistics.
#[derive(Debug, Clone, Copy)]
pub(super) struct Keep {
    /// The thinned fit samples, for a diagnosis's screening.
    pub(super) screening: bool,
    /// A log file's parsed chunks, for a second pass in this process.
    pub(super) spill: bool,
}

impl Keep {
    /// What a fit of `req` in one process keeps.
    pub(super) fn for_fit(req: &FitRequest) -> Self {
        Self {
            screening: req.diagnose.is_some(),
            spill: req.second_pass || req.diagnose.is_some(),
        }
    }
}

/// Reads one log, routing each sample to the fit or validation statistics (a single fit
/// log's to its time units) and keeping what `keep` says; `share` is the number of
/// threads the job may use (see [`stream_log`]).
pub(super) fn read_log(
    source: &LogSource,
    role: Role,
    req: &FitRequest,
    share: usize,
    keep: Keep,
) -> Result<LogStats, Error> {
    let mut fit = Accumulator::new(&req.structure);
    let mut held_out = Accumulator::new(&req.structure);
    let mut units = (role == Role::Blocks).then(Units::new);
    let mut signals = None;
    let mut screening = Thinned::new(SCREENING_SAMPLES);
    let mut ws = Workspace::default();
    let mut spill = match source {
        LogSource::File(_) if keep.spill => Some(SpillWriter::create()?),
        _ => None,
    };
    let mut chunks = 0;
    let mut runs = Runs::default();
    let summary = stream_log(source, req, share, |chunk| {
        chunks += 1;
        runs.push(&chunk.t);
        signals.get_or_insert_with(|| chunk.signals());
        let n = chunk.len() as u64;
        let pushed = if role.validates() {
            held_out.push(&req.structure, chunk, &mut ws)
        } else {
            if keep.screening {
                screening.push(chunk);
            }
            match units.as_mut() {
                Some(units) => units.push(chunk, &req.structure, &mut ws),
                None => fit.push(&req.structure, chunk, &mut ws),
            }
        };
        pushed.map_err(accumulate_error(source))?;
        let kinds = if role.validates() { [0, n] } else { [n, 0] };
        if let Some(w) = spill.as_mut() {
            w.write(chunk, kinds)?;
        }
        Ok(())
    })?;
    Ok(LogStats {
        fit,
        held_out,
        units,
        screening,
        summary,
        signals,
        spill: spill.map(SpillWriter::finish).transpose()?,
        chunks,
        runs,
    })
}
