//! The `mrsysid fit` pipeline, as a library call: read logs in parallel into mergeable
//! statistics (fit data and hold-out validation data), estimate (seed §5), then a
//! streaming second pass for residual diagnostics and plot series. The text of a log
//! file is read once: the first pass spills its parsed chunks to a temporary binary file
//! that the second pass streams back (the `spill` module's docs explain the choice), in
//! segments of equal length (`segments`, cut by the log's length alone) passed on all
//! the log's threads and merged in order (`pass_log`): results never depend on
//! `--threads`.
//!
//! Hold-out: without explicit validation logs, each log's time axis is cut into
//! contiguous segments of [`Holdout::segment_seconds`] from its first sample, and every
//! [`Holdout::every`]-th segment (the last of each group) is held out for validation —
//! [`Holdout::DEFAULT`] by default. Rows of a time series are never
//! sampled at random.
//!
//! One concept a file: `request` (what is asked, and its checks), `split` (hold-out
//! routing of each log's samples), `stream` (reading a log in the pipeline's chunks),
//! `feed` (Ω̈, progress and slow rotor thrusts on the way), `first_pass`, `folds`
//! (cross-validation folds of both passes), `second_pass` and `segment_pass`,
//! `threads` (jobs, segments, ordered results), `outcome` (what [`run`] returns).

use crate::diagnose::{SCREENING_SAMPLES, Thinned};
use crate::error::{Error, RequestError};
use crate::estimate;
use crate::io::Summary;
use crate::source::LogSource;
use crate::spill::Spill;
use crate::stats::{AccumulateError, Accumulator};

mod feed;
mod first_pass;
mod folds;
mod outcome;
mod remainder;
mod request;
mod second_pass;
mod segment_pass;
mod split;
mod stream;
mod threads;

pub use feed::stream_for_model;
pub use outcome::{FitOutcome, PlotSeries};
pub use request::{FitRequest, Holdout};

use first_pass::{LogCounts, read_log};
use folds::{arrange, merge};
use outcome::validation_source;
use request::{check, no_holdout};
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

/// Runs the pipeline.
pub fn run(req: &FitRequest) -> Result<FitOutcome, Error> {
    check(req)?;
    let jobs = jobs(req);
    let per_log = run_jobs(&jobs, req, |_, path, role, share| {
        read_log(path, role, req, share)
    })?;
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
    let counts: Vec<LogCounts> = per_log
        .iter()
        .map(|s| LogCounts {
            kinds: [s.fit.count(), s.held_out.count()],
            t0: s.t0,
            chunks: s.chunks,
            time_series: s.runs.time_series(),
        })
        .collect();
    let parts: Vec<[&Accumulator; 2]> = per_log[..n_fit]
        .iter()
        .map(|s| [&s.fit, &s.held_out])
        .collect();
    if parts.iter().all(|p| p[0].count() + p[1].count() == 0) {
        return Err(RequestError::NoSamples.into());
    }
    if let [single] = &parts[..]
        && single[1].count() == 0
    {
        return Err(no_holdout(req, &per_log[0]));
    }
    let (folds, fit_stats) = arrange(req, &parts)?;
    let (summaries, spills): (Vec<Summary>, Vec<Option<Spill>>) =
        per_log.into_iter().map(|s| (s.summary, s.spill)).unzip();
    let fit = estimate::fit(&req.structure, &fit_stats, &req.fit)?;
    let cv = estimate::cross_validate(&req.structure, &folds, &req.fit)?;
    let (validation, validation_samples) = if validation_stats.count() > 0 {
        let v = estimate::evaluate(&req.structure, &fit.mmr.theta, &validation_stats)?;
        (v, validation_stats.count())
    } else {
        (cv.pooled_metrics(), folds.test_samples())
    };
    let validation_source = validation_source(req);
    let mut outcome = FitOutcome {
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
    if req.second_pass || req.diagnose.is_some() {
        second_pass(
            req,
            &jobs,
            &spills,
            &counts,
            signals,
            screening.samples(),
            &mut outcome,
        )?;
    }
    Ok(outcome)
}
