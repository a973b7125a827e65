//! The `mrsysid fit` pipeline, as a library call: read logs in parallel into mergeable
//! statistics (fit data and hold-out validation data), estimate (seed §5), then a
//! streaming second pass for residual diagnostics and plot series. The text of a log
//! file is read once: the first pass spills its parsed chunks to a temporary binary file
//! that the second pass streams back (the `spill` module's docs explain the choice), in
//! segments of equal length (`segments`, cut by the log's length alone) passed on all
//! the log's threads and merged in order (`pass_log`): results never depend on
//! `--threads`.
//!
//! Cross-validation: several fit logs are each predicted by the model fitted on the
//! others; a single fit log is cut into [`Holdout::blocks`] contiguous blocks, each
//! predicted by the model fitted on the rest of the log less [`Holdout::guard_seconds`]
//! on each side of it ([`Holdout::DEFAULT`] by default; `blocks` says why). Every fit
//! sample is fitted by the final model; rows of a time series are never sampled at
//! random.
//!
//! One concept a file: `request` (what is asked, and its checks), `split` (what each
//! log's samples are for), `blocks` (the contiguous blocks of a single log), `stream`
//! (reading a log in the pipeline's chunks), `feed` (Ω̈, progress and slow rotor thrusts
//! on the way), `first_pass`, `folds` (cross-validation folds of both passes),
//! `second_pass` and `segment_pass`, `remainder` (the third pass), `threads` (jobs,
//! segments, ordered results), `outcome` (what [`run`] returns). Statistics as data:
//! `framing` (the byte frame of every file kind), `parts` (first-pass parts) and
//! `pass_parts` (the second and third passes as map-reduce).

use crate::diagnose::{SCREENING_SAMPLES, Thinned};
use crate::error::{Error, RequestError};
use crate::estimate;
use crate::io::Summary;
use crate::progress::Phase;
use crate::sample::Signals;
use crate::source::LogSource;
use crate::spill::Spill;
use crate::stats::{AccumulateError, Accumulator};

mod blocks;
mod feed;
mod first_pass;
mod folds;
mod framing;
mod log_checks;
mod outcome;
mod parts;
mod pass_parts;
mod pass_share;
mod remainder;
mod request;
mod second_pass;
mod segment_pass;
mod split;
mod stream;
mod threads;

pub use feed::stream_for_model;
pub use framing::STATS_FORMAT_VERSION;
pub use outcome::{EffectSeries, FitOutcome, PlotSeries};
pub use parts::{StatsPart, accumulate, run_from_parts};
pub use pass_parts::{
    PassPart, PassPlan, PendingFit, PlannedFit, PreparedPass, RemainderPart, RemainderPlan,
    plan_fit,
};
pub use request::{FitRequest, Holdout};

use first_pass::{Keep, LogCounts, LogStats, read_log};
use folds::{arrange, merge};
use log_checks::{low_pass_error, time_unit_error, too_short};
use outcome::validation_source;
use request::check;
use second_pass::second_pass;
use split::jobs;
use threads::run_jobs;

/// The error of accumulating a chunk of the log `source`.
fn accumulate_error(source: &LogSource) -> impl Fn(AccumulateError) -> Error + '_ {
    move |e| Error::Accumulate {
        log: source.name(),
        source: e,
    }
}

/// The units of the first pass over `jobs`: the bytes of each log file, the samples of
/// each log in memory ([`Progress::done`](crate::Progress::done)).
fn first_pass_size(jobs: &[(LogSource, split::Role)]) -> u64 {
    jobs.iter()
        .map(|(source, _)| match source {
            LogSource::File(path) => std::fs::metadata(path).map_or(0, |m| m.len()),
            LogSource::Memory(log) => log.len(),
        })
        .sum()
}

/// Runs the pipeline.
pub fn run(req: &FitRequest) -> Result<FitOutcome, Error> {
    check(req)?;
    let jobs = jobs(req);
    req.enter(Phase::Reading, first_pass_size(&jobs));
    let per_log = run_jobs(&jobs, req, |_, path, role, share| {
        read_log(path, role, req, share, Keep::for_fit(req))
    })?;
    after_first_pass(req, &jobs, per_log)
}

/// The pipeline once every log's first pass is done (`per_log`, in the order of
/// `jobs`): the checks that need the logs read, the fit and its cross-validation, and
/// the second pass when asked for.
fn after_first_pass(
    req: &FitRequest,
    jobs: &[(LogSource, split::Role)],
    per_log: Vec<LogStats>,
) -> Result<FitOutcome, Error> {
    let (mut outcome, first) = first_fit(req, per_log)?;
    if req.second_pass || req.diagnose.is_some() {
        second_pass(req, jobs, &first, &mut outcome)?;
    }
    Ok(outcome)
}

/// What the second pass needs of the first pass over the logs, in job order.
pub(super) struct FirstPass {
    /// Each log file's parsed chunks.
    spills: Vec<Option<Spill>>,
    counts: Vec<LogCounts>,
    /// The optional signals of the first log with samples.
    signals: Option<Signals>,
    /// The thinned fit samples of all logs, merged in order.
    screening: Thinned,
}

impl FirstPass {
    /// True when every fit log of `req` is a time series.
    fn fit_logs_time_series(&self, req: &FitRequest) -> bool {
        self.counts[..req.logs.len()].iter().all(|c| c.time_series)
    }
}

/// The checks that need the logs read (`per_log`, in job order), the Eq. 22
/// fit, its cross-validation and validation figures; and what the second pass needs.
fn first_fit(
    req: &FitRequest,
    mut per_log: Vec<LogStats>,
) -> Result<(FitOutcome, FirstPass), Error> {
    time_unit_error(req, &per_log)?;
    low_pass_error(req, &per_log)?;
    let n_fit = req.logs.len();
    let mut validation_stats = Accumulator::new(&req.structure);
    let mut screening = Thinned::new(SCREENING_SAMPLES);
    let signals = per_log.iter().find_map(|s| s.signals);
    for s in &per_log {
        screening.merge(&s.screening);
    }
    for s in &per_log[n_fit..] {
        merge(&mut validation_stats, &s.held_out)?;
    }
    let mut counts: Vec<LogCounts> = per_log
        .iter()
        .map(|s| LogCounts {
            kinds: s.kinds(),
            chunks: s.chunks,
            time_series: s.runs.time_series(),
            plan: None,
        })
        .collect();
    if counts[..n_fit].iter().all(|c| c.kinds[0] == 0) {
        return Err(RequestError::NoSamples.into());
    }
    // A single fit log: its blocks, and the statistics of their pieces.
    let mut plan = None;
    let mut parts: Vec<Vec<Accumulator>> = Vec::with_capacity(n_fit);
    for s in &mut per_log[..n_fit] {
        let pieces = match s.units.take() {
            Some(units) => {
                let blocks = units.plan(req.holdout);
                let blocks = blocks.map_err(|short| too_short(req, s, short))?;
                let pieces = units.into_pieces(&blocks, &req.structure);
                plan = Some(blocks);
                pieces.map_err(|source| Error::Accumulate {
                    log: s.summary.file.clone(),
                    source,
                })?
            }
            None => vec![std::mem::replace(
                &mut s.fit,
                Accumulator::new(&req.structure),
            )],
        };
        parts.push(pieces);
    }
    let parts: Vec<&[Accumulator]> = parts.iter().map(Vec::as_slice).collect();
    let (folds, fit_stats) = arrange(req, &req.structure, plan.as_ref(), &parts)?;
    let (summaries, spills): (Vec<Summary>, Vec<Option<Spill>>) =
        per_log.into_iter().map(|s| (s.summary, s.spill)).unzip();
    req.enter(Phase::Fitting, 0);
    let fit = estimate::fit(&req.structure, &fit_stats, &req.fit)?;
    let cv = estimate::cross_validate(&req.structure, &folds, &req.fit)?;
    let (validation, validation_samples) = if validation_stats.count() > 0 {
        let v = estimate::evaluate(&req.structure, &fit.mmr.theta, &validation_stats)?;
        (v, validation_stats.count())
    } else {
        (cv.pooled_metrics(), folds.test_samples())
    };
    let validation_source = validation_source(req, plan.as_ref());
    if let [single] = &mut counts[..n_fit] {
        single.plan = plan;
    }
    let outcome = FitOutcome {
        fit,
        fit_stats,
        validation_stats,
        validation,
        validation_samples,
        cross_validation: (folds.names.clone(), cv),
        diagnostics: None,
        fit_series: PlotSeries::default(),
        validation_series: PlotSeries::default(),
        summaries,
        validation_source,
        diagnosis: None,
        variance_inflation: 1.0,
    };
    let first = FirstPass {
        spills,
        counts,
        signals,
        screening,
    };
    Ok((outcome, first))
}
