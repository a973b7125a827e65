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
//! 20 % of the data in 2 s segments by default. Rows of a time series are never
//! sampled at random.

use std::sync::atomic::Ordering;

use crate::diagnose::local::{ActivityParts, LocalRegions};
use crate::diagnose::{
    Candidate, CandidateContext, CandidateStatistics, DiagnoseOptions, Diagnosis,
    SCREENING_SAMPLES, Thinned, candidate_set_on_threads, diagnose_on_threads,
    hover_thrust_coefficient,
};
use crate::error::{Error, RequestError};
use crate::estimate::{
    self, AxisMetrics, CrossValidation, DiagnosticOptions, Fit, ResidualDiagnostics, ResidualPass,
};
use crate::io::Summary;
use crate::model::{ModelStructure, Reuse};
use crate::sample::{SampleChunk, Signals};
use crate::source::LogSource;
use crate::spill::Spill;
use crate::stats::{AccumulateError, Accumulator, stored_columns_of};

mod feed;
mod first_pass;
mod folds;
mod request;
mod segment_pass;
mod split;
mod stream;
mod threads;

pub use feed::stream_for_model;
pub use request::{FitRequest, Holdout};

use first_pass::{LogCounts, read_log};
use folds::{arrange, local_folds, merge};
use request::{check, no_holdout};
use segment_pass::SegmentPass;
use split::{Role, jobs};
use stream::stream_log;
use threads::{run_in_order, run_jobs, segments};

/// Decimated measured/predicted series for plots, per axis.
#[derive(Debug, Clone, Default)]
pub struct PlotSeries {
    /// Time, s (logs are laid end to end).
    pub t: Vec<f64>,
    /// Measured output per axis.
    pub measured: [Vec<f64>; 6],
    /// Model output per axis.
    pub predicted: [Vec<f64>; 6],
}

/// What the pipeline produced.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    /// The estimates.
    pub fit: Fit,
    /// Fit statistics (for refits with candidate effects).
    pub fit_stats: Accumulator,
    /// Statistics of the reporting-only validation logs (no samples without them).
    pub validation_stats: Accumulator,
    /// Goodness of fit of the Eq. 22 model on the validation logs when given, else
    /// cross-validated (all folds pooled).
    pub validation: [AxisMetrics; 6],
    /// Samples behind `validation`.
    pub validation_samples: u64,
    /// Cross-validation of the Eq. 22 model: fold names and held-out errors.
    pub cross_validation: (Vec<String>, CrossValidation),
    /// Residual diagnostics of the fit data (second pass).
    pub diagnostics: Option<ResidualDiagnostics>,
    /// Fit-data series for plots (second pass).
    pub fit_series: PlotSeries,
    /// Validation-data series for plots (second pass).
    pub validation_series: PlotSeries,
    /// One reader summary per log, fit logs first.
    pub summaries: Vec<Summary>,
    /// Description of the validation data.
    pub validation_source: String,
    /// Closing-the-loop result.
    pub diagnosis: Option<Diagnosis>,
    /// Coloured-residual variance inflation κ = (1 + ρ)/(1 − ρ) of the Eq. 22 fit's
    /// residuals (ρ the largest lag-1 autocorrelation over the axes), ≥ 1; 1 when the
    /// second pass did not run. σ² of white residuals times κ is the corrected variance.
    pub variance_inflation: f64,
}

/// The error of accumulating a chunk of the log `source`.
fn accumulate_error(source: &LogSource) -> impl Fn(AccumulateError) -> Error + '_ {
    move |e| Error::Accumulate {
        log: source.name(),
        source: e,
    }
}

/// Samples per segment, on average over a fit log, below which the log is taken for a
/// sweep's points rather than a time series (no trim-moment candidates).
const MIN_SEGMENT_SAMPLES: u64 = 256;

fn count_progress(req: &FitRequest, chunk: &SampleChunk) {
    if let Some(p) = &req.progress {
        p.fetch_add(chunk.len() as u64, Ordering::Relaxed);
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
    let validation_source = if !req.validate.is_empty() {
        format!(
            "{} validation log(s), not used for any decision",
            req.validate.len()
        )
    } else if n_fit > 1 {
        format!(
            "leave one log out over {n_fit} logs (each predicted by the model fitted on the others), pooled"
        )
    } else {
        format!(
            "hold-out: every {}th {:.1} s segment of the fit log",
            req.holdout.every, req.holdout.segment_seconds
        )
    };
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

/// Points kept per plotted series: buckets of the whole run keep their first sample.
const PLOT_POINTS: u64 = 4000;

/// Candidate effects added to the base structure, with their parameter indices.
struct Extended {
    structure: ModelStructure,
    candidates: Vec<Candidate>,
    params: Vec<Vec<usize>>,
    regions: LocalRegions,
    /// The columns its accumulators store, and how they are assembled from each other.
    stored: Vec<bool>,
    plan: Vec<Option<Reuse>>,
}

impl Extended {
    /// Named candidates for data with `signals`, plus the generic-pool terms that
    /// survive screening on `screening` (thinned fit samples).
    fn new(
        req: &FitRequest,
        fit: &Fit,
        signals: Signals,
        slow_thrust: bool,
        screening: &SampleChunk,
        options: &DiagnoseOptions,
    ) -> Result<Self, Error> {
        let ctx = CandidateContext {
            vehicle: &req.vehicle,
            structure: &req.structure,
            theta: &fit.mmr.theta,
            has_height: signals.height,
            has_omega_dot: signals.omega_dot,
            has_omega_ddot: signals.omega_ddot,
            has_attitude: signals.attitude,
            has_slow_thrust: slow_thrust,
            hover_thrust_coefficient: hover_thrust_coefficient(&req.vehicle, &[screening]),
        };
        let set = candidate_set_on_threads(&ctx, Some(screening), options, req.threads)?;
        let stored = stored_columns_of(&set.extended);
        Ok(Self {
            plan: set.extended.reuse_plan(&stored),
            stored,
            structure: set.extended,
            candidates: set.candidates,
            params: set.params,
            regions: set.regions,
        })
    }
}

/// What every log's second pass shares (read only).
struct PassContext<'a> {
    req: &'a FitRequest,
    /// MMR estimates θ̂ in `req.structure.params` order.
    theta: &'a [f64],
    /// An empty residual pass to start each log from.
    residuals: ResidualPass,
    /// Candidate effects, when diagnosing.
    extended: Option<Extended>,
    /// Plot decimation: every `stride`-th sample of the whole run (fit, validation).
    strides: [u64; 2],
}

/// One log's share of the second pass. Shares merge in job order into the result of a
/// pass over all logs one after another.
struct LogPass {
    residuals: ResidualPass,
    /// Plot series (fit, validation); time counted from `span.0` of the kind.
    series: [PlotSeries; 2],
    /// First and last sample time of each kind in this log, s (NaN when none).
    span: [(f64, f64); 2],
    /// Candidate-effect statistics (fitted, held-out samples), when diagnosing.
    candidates: Option<[Accumulator; 2]>,
    /// The same over the samples where local candidates act, by activity pattern, from
    /// the kind [`local_kind`] names (empty for a validation log).
    local: ActivityParts,
}

/// Which samples of a log (fit: false, held-out: true) the local-region statistics are
/// built from: the held-out part of a single fit log, every sample of each of several
/// fit logs (each is left out in turn), none of a validation log (it reports, never
/// decides). [`local_folds`] uses nothing else.
fn local_kind(role: Role) -> Option<bool> {
    match role {
        Role::Fit => Some(false),
        Role::Split(_) => Some(true),
        Role::Validation => None,
    }
}

/// Streams the data again (each log file from its spill, in job order with `jobs`):
/// residual diagnostics of the fit samples, decimated series of both parts for plots,
/// and the statistics of every candidate effect. Logs are passed on up to `req.threads`
/// threads and their shares merged in job order, so the result does not depend on the
/// thread count.
fn second_pass(
    req: &FitRequest,
    jobs: &[(LogSource, Role)],
    spills: &[Option<Spill>],
    counts: &[LogCounts],
    signals: Option<Signals>,
    screening: &SampleChunk,
    out: &mut FitOutcome,
) -> Result<(), Error> {
    let stride = |n: u64| n.div_ceil(PLOT_POINTS).max(1);
    let ctx = PassContext {
        req,
        theta: &out.fit.mmr.theta,
        residuals: ResidualPass::new(&req.structure, &out.fit, DiagnosticOptions::default()),
        extended: match (&req.diagnose, signals) {
            (Some(options), Some(s)) => {
                // Time series, not a sweep's points: the slow thrusts have a slow part.
                let fit_logs = &out.summaries[..req.logs.len()];
                let time_series = fit_logs
                    .iter()
                    .all(|s| s.samples >= MIN_SEGMENT_SAMPLES * s.segments.max(1) as u64);
                let slow = s.omega_squared_slow && time_series;
                Some(Extended::new(req, &out.fit, s, slow, screening, options)?)
            }
            _ => None,
        },
        strides: [0, 1].map(|k| stride(counts.iter().map(|c| c.kinds[k]).sum())),
    };
    // Samples of each kind before each log: its first sample's place in the decimation.
    let starts: Vec<[u64; 2]> = counts
        .iter()
        .scan([0u64; 2], |seen, c| {
            let start = *seen;
            seen[0] += c.kinds[0];
            seen[1] += c.kinds[1];
            Some(start)
        })
        .collect();
    let shares = run_jobs(jobs, req, |i, path, role, threads| {
        let at = Start {
            seen: starts[i],
            in_log: [0; 2],
            t0: counts[i].t0,
        };
        let log = Log {
            source: path,
            spill: spills[i].as_ref(),
            role,
            chunks: counts[i].chunks,
        };
        pass_log(&ctx, &log, threads, at)
    })?;
    let mut residuals: Option<ResidualPass> = None;
    let mut t_offset = [0.0f64; 2];
    for share in &shares {
        match residuals.as_mut() {
            Some(r) => r.merge(&share.residuals),
            None => residuals = Some(share.residuals.clone()),
        }
        lay_end_to_end(
            share,
            &mut t_offset,
            &mut out.fit_series,
            &mut out.validation_series,
        );
    }
    let Some(residuals) = residuals else {
        return Ok(());
    };
    let diagnostics = residuals.finish();
    let inflation = coloured_variance_inflation(&diagnostics);
    out.variance_inflation = inflation;
    out.diagnostics = Some(diagnostics);
    let (Some(mut options), Some(ext)) = (req.diagnose, ctx.extended) else {
        return Ok(());
    };
    let local_parts = shares
        .iter()
        .zip(jobs)
        .take(req.logs.len())
        .map(|(s, (source, _))| {
            let regions = ext.regions.per_region(&s.local, &ext.structure);
            regions.map_err(accumulate_error(source))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let per_log: Vec<[Accumulator; 2]> = shares.into_iter().filter_map(|s| s.candidates).collect();
    let n_fit = req.logs.len();
    if per_log.len() != jobs.len() {
        return Ok(());
    }
    let parts: Vec<[&Accumulator; 2]> = per_log[..n_fit].iter().map(|[a, b]| [a, b]).collect();
    let (folds, fit) = arrange(req, &parts)?;
    let mut report = Accumulator::new(&ext.structure);
    for [_, held_out] in &per_log[n_fit..] {
        merge(&mut report, held_out)?;
    }
    let local = local_folds(&ext.regions, &local_parts, &folds);
    options.variance_inflation = options.variance_inflation.max(inflation);
    let stats = CandidateStatistics {
        extended: &ext.structure,
        candidates: &ext.candidates,
        candidate_params: &ext.params,
        base_params: req.structure.params.len(),
        fit: &fit,
        folds: &folds,
        report: (report.count() > 0).then_some(&report),
        local: &local,
    };
    out.diagnosis = Some(diagnose_on_threads(
        &stats,
        &req.fit,
        &options,
        req.threads,
    )?);
    Ok(())
}

/// Appends a log's plot series after the logs before it on the plots' time axis
/// (`t_offset`: time already laid out per kind, s).
fn lay_end_to_end(
    share: &LogPass,
    t_offset: &mut [f64; 2],
    fit: &mut PlotSeries,
    validation: &mut PlotSeries,
) {
    for (k, series) in [fit, validation].into_iter().enumerate() {
        let part = &share.series[k];
        series.t.extend(part.t.iter().map(|t| t + t_offset[k]));
        for a in 0..6 {
            series.measured[a].extend_from_slice(&part.measured[a]);
            series.predicted[a].extend_from_slice(&part.predicted[a]);
        }
        let (first, last) = share.span[k];
        if first.is_finite() {
            t_offset[k] += last - first;
        }
    }
}

/// Where a segment of a log's second pass starts.
#[derive(Debug, Clone, Copy)]
struct Start {
    /// Samples of each kind (fit, validation) before it, in this log and the logs before.
    seen: [u64; 2],
    /// The same in this log only.
    in_log: [u64; 2],
    /// Time the log's hold-out segments count from, s.
    t0: Option<f64>,
}

/// A log as its second pass reads it.
struct Log<'a> {
    source: &'a LogSource,
    /// Its parsed chunks, for a log file.
    spill: Option<&'a Spill>,
    role: Role,
    /// Chunks it is read in (from the first pass).
    chunks: usize,
}

/// The second pass over one log, from its spill when there is one, in the segments
/// [`segments`] cuts: each segment is passed from a fresh state (on up to `threads`
/// threads when read from a spill) and the segments' shares are merged in order, so the
/// result depends on the log alone, never on the thread count or on whether the log
/// came from a file or from memory.
fn pass_log(ctx: &PassContext, log: &Log, threads: usize, at: Start) -> Result<LogPass, Error> {
    let (source, role) = (log.source, log.role);
    let mut share = LogPass::empty(ctx);
    let mut append = |part: LogPass| share.append(part).map_err(accumulate_error(source));
    let cuts = segments(log.spill.map_or(log.chunks, Spill::chunks));
    match log.spill {
        Some(spill) => {
            let pass_segment = |s: usize| {
                let chunks = cuts[s].clone();
                let in_log = if chunks.is_empty() {
                    [0; 2]
                } else {
                    spill.before(chunks.start)
                };
                let seen = [0, 1].map(|k| at.seen[k] + in_log[k]);
                let start = Start { seen, in_log, ..at };
                let mut pass = SegmentPass::new(ctx, source, role, start);
                // Spilled with its Ω̈ (derived in the first pass).
                spill.stream_chunks(chunks, |chunk| {
                    count_progress(ctx.req, chunk);
                    pass.push(chunk)
                })?;
                pass.finish()
            };
            run_in_order(cuts.len(), threads, pass_segment, &mut append)?;
        }
        None => {
            let mut pass = SegmentPass::new(ctx, source, role, at);
            // Chunks read so far, and the segment being passed.
            let (mut read, mut segment) = (0, 0);
            stream_log(source, ctx.req, threads, |chunk| {
                if cuts.get(segment + 1).is_some_and(|next| next.start == read) {
                    let next = SegmentPass::new(ctx, source, role, pass.next_start());
                    append(std::mem::replace(&mut pass, next).finish()?)?;
                    segment += 1;
                }
                read += 1;
                pass.push(chunk)
            })?;
            append(pass.finish()?)?;
        }
    }
    share.times_from_start();
    Ok(share)
}

/// (1 + ρ)/(1 − ρ) for the largest lag-1 residual autocorrelation ρ over the axes (an
/// AR(1) effective-sample-size correction of parameter variances), held in [1, 100].
fn coloured_variance_inflation(d: &ResidualDiagnostics) -> f64 {
    let rho = d
        .axes
        .iter()
        .filter_map(|a| a.autocorrelation.get(1).copied())
        .filter(|r| r.is_finite())
        .fold(0.0_f64, f64::max)
        .min(0.98);
    ((1.0 + rho) / (1.0 - rho)).clamp(1.0, 100.0)
}
