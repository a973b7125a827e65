//! The second pass, after the Eq. 22 fit: every log streamed again (a file from its
//! spill) in segments on the log's threads, for the residual diagnostics of the fit
//! samples, decimated plot series of both parts and, when diagnosing, the statistics of
//! every candidate effect, which it hands to the diagnosis with the folds of the first
//! pass.

use super::FirstPass;
use super::folds::{arrange, grouped, local_folds, merge};
use super::pass_share::{Extended, LogPass, PassContext, Start};
use super::remainder::remainder;
use super::request::check_cancel;
use super::segment_pass::SegmentPass;
use super::split::Role;
use super::stream::stream_log;
use super::threads::{run_in_order, run_jobs, segments};
use super::{FitOutcome, FitRequest, PlotSeries, accumulate_error};
use crate::diagnose::{
    CandidateContext, CandidateStatistics, DiagnoseOptions, Diagnosis, candidate_set_on_threads,
    diagnose_on_threads, hover_thrust_coefficient,
};
use crate::error::Error;
use crate::estimate::{DiagnosticOptions, Fit, ResidualDiagnostics, ResidualPass};
use crate::progress::Phase;
use crate::sample::{SampleChunk, Signals};
use crate::source::LogSource;
use crate::spill::Spill;
use crate::stats::{Accumulator, stored_columns_of};

/// Counts `chunk` in the request's progress, after checking its cancellation flag.
pub(super) fn count_progress(req: &FitRequest, chunk: &SampleChunk) -> Result<(), Error> {
    check_cancel(req.cancel.as_deref())?;
    if let Some(p) = &req.progress {
        p.add_samples(chunk.len() as u64);
    }
    Ok(())
}

/// Points kept per plotted series: buckets of the whole run keep their first sample.
const PLOT_POINTS: u64 = 4000;

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
        let force_theta = fit.own_axis_estimates(req.structure.columns.len());
        let ctx = CandidateContext {
            vehicle: &req.vehicle,
            structure: &req.structure,
            theta: &fit.mmr.theta,
            force_theta: &force_theta,
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

/// The candidate effects of a diagnosis of logs with the first-pass signals `signals`
/// and screening sample `screening` from the Eq. 22 `fit` (`time_series`: every fit log
/// is a time series); `None` without a diagnosis, or without samples to tell the
/// signals.
pub(super) fn extended(
    req: &FitRequest,
    fit: &Fit,
    time_series: bool,
    signals: Option<Signals>,
    screening: &SampleChunk,
) -> Result<Option<Extended>, Error> {
    let (Some(options), Some(s)) = (&req.diagnose, signals) else {
        return Ok(None);
    };
    // Time series, not a sweep's points: the slow thrusts have a slow part.
    let slow = s.omega_squared_slow && time_series;
    Extended::new(req, fit, s, slow, screening, options).map(Some)
}

/// Streams the data again (each log file from its spill, in job order with `jobs`):
/// residual diagnostics of the fit samples, decimated series of both parts for plots,
/// and the statistics of every candidate effect. Logs are passed on up to `req.threads`
/// threads and their shares merged in job order, so the result does not depend on the
/// thread count.
pub(super) fn second_pass(
    req: &FitRequest,
    jobs: &[(LogSource, Role)],
    first: &FirstPass,
    out: &mut FitOutcome,
) -> Result<(), Error> {
    let counts = &first.counts;
    let stride = |n: u64| n.div_ceil(PLOT_POINTS).max(1);
    if req.diagnose.is_some() {
        req.enter(Phase::Screening, 0);
    }
    let screening = first.screening.samples();
    let time_series = first.fit_logs_time_series(req);
    let extended = extended(req, &out.fit, time_series, first.signals, screening)?;
    let theta = out.fit.mmr.theta.clone();
    let ctx = PassContext {
        req,
        theta: &theta,
        residuals: ResidualPass::new(&req.structure, &out.fit, DiagnosticOptions::default()),
        extended: extended.as_ref(),
        plan: counts.iter().find_map(|c| c.plan.as_ref()),
        strides: Some([0, 1].map(|k| stride(counts.iter().map(|c| c.kinds[k]).sum()))),
    };
    req.enter(
        Phase::SecondPass,
        counts.iter().map(|c| c.kinds[0] + c.kinds[1]).sum(),
    );
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
        };
        let log = Log {
            source: path,
            spill: first.spills[i].as_ref(),
            role,
            chunks: counts[i].chunks,
        };
        pass_log(&ctx, &log, threads, at)
    })?;
    let Some(mut diagnosis) = reduce(&ctx, jobs, shares, out)? else {
        return Ok(());
    };
    if time_series {
        req.enter(Phase::Remainder, 0);
        diagnosis.remainder = remainder(req, jobs, &first.spills, &diagnosis)?;
    }
    for series in [&mut out.fit_series, &mut out.validation_series] {
        series.predict_final(&diagnosis).map_err(Error::from)?;
    }
    out.diagnosis = Some(diagnosis);
    Ok(())
}

/// The shares of every log's second pass (`shares`, in the order of `jobs`) merged into
/// `out` (residual diagnostics, plot series), and the diagnosis from their candidate
/// statistics when `ctx` has candidates, without its remainder (a third pass).
pub(super) fn reduce(
    ctx: &PassContext,
    jobs: &[(LogSource, Role)],
    mut shares: Vec<LogPass>,
    out: &mut FitOutcome,
) -> Result<Option<Diagnosis>, Error> {
    let req = ctx.req;
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
        return Ok(None);
    };
    let diagnostics = residuals.finish();
    let inflation = coloured_variance_inflation(&diagnostics);
    out.variance_inflation = inflation;
    out.diagnostics = Some(diagnostics);
    let (Some(mut options), Some(ext)) = (req.diagnose, ctx.extended) else {
        return Ok(None);
    };
    let local_parts: Vec<Vec<Accumulator>> = (shares.iter_mut())
        .take(req.logs.len())
        .flat_map(|share| std::mem::take(&mut share.regions))
        .collect();
    let per_log: Vec<Vec<Accumulator>> = shares
        .into_iter()
        .filter_map(|s| s.candidates)
        .map(|pieces| {
            let empty = || Accumulator::new(&ext.structure);
            pieces
                .into_iter()
                .map(|p| p.unwrap_or_else(empty))
                .collect()
        })
        .collect();
    let n_fit = req.logs.len();
    if per_log.len() != jobs.len() {
        return Ok(None);
    }
    let parts: Vec<&[Accumulator]> = per_log[..n_fit].iter().map(Vec::as_slice).collect();
    let (folds, fit) = arrange(req, &ext.structure, ctx.plan, &parts)?;
    let mut report = Accumulator::new(&ext.structure);
    for pieces in &per_log[n_fit..] {
        merge(&mut report, &pieces[0])?;
    }
    let local_parts = match grouped(&req.groups, &local_parts, |a, b| {
        a.iter_mut().zip(b).try_for_each(|(a, b)| merge(a, b))
    })? {
        Some(groups) => groups.into_iter().map(|(_, regions)| regions).collect(),
        None => local_parts,
    };
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
    req.enter(Phase::Diagnosis, 0);
    diagnose_on_threads(&stats, &req.fit, &options, req.threads)
        .map(Some)
        .map_err(Error::from)
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
        series.keep_samples(&part.samples);
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

/// A log as its second pass reads it.
pub(super) struct Log<'a> {
    pub(super) source: &'a LogSource,
    /// Its parsed chunks, for a log file.
    pub(super) spill: Option<&'a Spill>,
    pub(super) role: Role,
    /// Chunks it is read in (from the first pass).
    pub(super) chunks: usize,
}

/// The second pass over one log, from its spill when there is one, in the segments
/// [`segments`] cuts: each segment is passed from a fresh state (on up to `threads`
/// threads when read from a spill) and the segments' shares are merged in order, so the
/// result depends on the log alone, never on the thread count or on whether the log
/// came from a file or from memory.
pub(super) fn pass_log(
    ctx: &PassContext,
    log: &Log,
    threads: usize,
    at: Start,
) -> Result<LogPass, Error> {
    let (source, role) = (log.source, log.role);
    let mut share = LogPass::empty(ctx, role);
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
                let start = Start { seen, in_log };
                let mut pass = SegmentPass::new(ctx, source, role, start);
                // Spilled with its Ω̈ (derived in the first pass).
                spill.stream_chunks(chunks, |chunk| {
                    count_progress(ctx.req, chunk)?;
                    pass.push(chunk)
                })?;
                Ok(pass.finish())
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
                    append(std::mem::replace(&mut pass, next).finish())?;
                    segment += 1;
                }
                read += 1;
                pass.push(chunk)
            })?;
            append(pass.finish())?;
        }
    }
    share.times_from_start();
    if let Some(ext) = ctx.extended {
        let local = std::mem::take(&mut share.local);
        share.regions = (local.iter())
            .map(|group| ext.regions.per_region(group, &ext.structure))
            .collect::<Result<_, _>>()
            .map_err(accumulate_error(source))?;
    }
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
