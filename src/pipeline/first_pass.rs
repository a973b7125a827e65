//! The first pass over a log: read once, each sample routed to the fit or held-out
//! statistics, the thinned screening samples kept, the parsed chunks spilled for the
//! second pass.

use super::split::{Role, Splitter};
use super::stream::stream_log;
use super::{FitRequest, accumulate_error};
use crate::diagnose::{SCREENING_SAMPLES, Thinned};
use crate::error::Error;
use crate::io::Summary;
use crate::model::Workspace;
use crate::sample::{SampleChunk, Signals};
use crate::source::LogSource;
use crate::spill::{Spill, SpillWriter};
use crate::stats::Accumulator;

/// Statistics of one log: the samples fitted and those held out (its hold-out segments,
/// or all samples of a validation log).
pub(super) struct LogStats {
    pub(super) fit: Accumulator,
    pub(super) held_out: Accumulator,
    /// Thinned fit samples for the generic-pool screening.
    pub(super) screening: Thinned,
    pub(super) summary: Summary,
    /// Optional signals of the log's first chunk, `None` for a log without samples.
    pub(super) signals: Option<Signals>,
    /// The log's parsed chunks for the second pass (log files only, when it runs).
    pub(super) spill: Option<Spill>,
    /// Time the hold-out segments count from (the first sample's), s.
    pub(super) t0: Option<f64>,
    /// Chunks the log was read in.
    pub(super) chunks: usize,
}

/// What the second pass needs to know of a log from the first, in job order.
#[derive(Debug, Clone, Copy)]
pub(super) struct LogCounts {
    /// Samples routed to fit and to validation (for plot decimation).
    pub(super) kinds: [u64; 2],
    /// Time the log's hold-out segments count from, s.
    pub(super) t0: Option<f64>,
    /// Chunks the log is read in (the same in both passes).
    pub(super) chunks: usize,
}

/// Reads one log, routing each sample to the fit or validation statistics; `share` is
/// the number of threads the job may use (see [`stream_log`]).
pub(super) fn read_log(
    source: &LogSource,
    role: Role,
    req: &FitRequest,
    share: usize,
) -> Result<LogStats, Error> {
    let mut fit = Accumulator::new(&req.structure);
    let mut held_out = Accumulator::new(&req.structure);
    let mut signals = None;
    let mut screening = Thinned::new(SCREENING_SAMPLES);
    let keep_screening = req.diagnose.is_some();
    let mut ws = Workspace::default();
    let mut split = Splitter::new(role, None);
    let mut spill = match source {
        LogSource::File(_) if req.second_pass || req.diagnose.is_some() => {
            Some(SpillWriter::create()?)
        }
        _ => None,
    };
    let mut sink = |part: &SampleChunk, to_validation: bool| {
        let acc = if to_validation {
            &mut held_out
        } else {
            if keep_screening {
                screening.push(part);
            }
            &mut fit
        };
        acc.push(&req.structure, part, &mut ws)
            .map_err(accumulate_error(source))
    };
    let mut chunks = 0;
    let summary = stream_log(source, req, share, |chunk| {
        chunks += 1;
        signals.get_or_insert_with(|| chunk.signals());
        let kinds = split.route(chunk, &mut sink)?;
        if let Some(w) = spill.as_mut() {
            w.write(chunk, kinds)?;
        }
        Ok(())
    })?;
    split.finish(&mut sink)?;
    Ok(LogStats {
        fit,
        held_out,
        screening,
        summary,
        signals,
        spill: spill.map(SpillWriter::finish).transpose()?,
        t0: split.t0,
        chunks,
    })
}
