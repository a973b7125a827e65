//! The second pass over one segment of a log: the fit samples' residuals, the plotted
//! samples' predictions and, when diagnosing, every candidate effect's statistics (a
//! single fit log's per piece of its blocks) folded into the segment's [`LogPass`]
//! share.

use super::accumulate_error;
use super::pass_share::{LocalGroup, LogPass, PassContext, Start};
use super::split::Role;
use crate::diagnose::local::ActivityParts;
use crate::error::Error;
use crate::model::Workspace;
use crate::sample::SampleChunk;
use crate::source::LogSource;
use crate::stats::{AccumulateError, Accumulator};

/// The second pass over one segment of a log.
pub(super) struct SegmentPass<'a> {
    source: &'a LogSource,
    /// A run of samples of one piece cut from a chunk (a single fit log's blocks).
    run: SampleChunk,
    state: SegmentState<'a>,
}

/// What a segment's sink works on.
struct SegmentState<'a> {
    ctx: &'a PassContext<'a>,
    role: Role,
    share: LogPass,
    /// Samples of each kind before the segment's next sample (plot decimation).
    seen: [u64; 2],
    /// Samples of each kind in the log before the segment's next sample.
    in_log: [u64; 2],
    /// The same before the segment's first sample (error positions count from them).
    first: [u64; 2],
    ws: Workspace,
    active_ws: Workspace,
    /// The samples the plots keep of a part, and their regressors.
    plot_rows: SampleChunk,
    plot_ws: Workspace,
}

impl<'a> SegmentPass<'a> {
    pub(super) fn new(
        ctx: &'a PassContext<'a>,
        source: &'a LogSource,
        role: Role,
        at: Start,
    ) -> Self {
        Self {
            source,
            run: SampleChunk::default(),
            state: SegmentState {
                ctx,
                role,
                share: LogPass::empty(ctx, role),
                seen: at.seen,
                in_log: at.in_log,
                first: at.in_log,
                ws: Workspace::default(),
                active_ws: Workspace::default(),
                plot_rows: SampleChunk::default(),
                plot_ws: Workspace::default(),
            },
        }
    }

    /// Where the segment after this one starts (call after its last chunk).
    pub(super) fn next_start(&self) -> Start {
        Start {
            seen: self.state.seen,
            in_log: self.state.in_log,
        }
    }

    /// Folds in the samples of `chunk`: whole, or for a single fit log in runs of one
    /// piece of its blocks each.
    pub(super) fn push(&mut self, chunk: &SampleChunk) -> Result<(), Error> {
        let (state, source, run) = (&mut self.state, self.source, &mut self.run);
        match (state.role, state.ctx.plan) {
            (Role::Blocks, Some(plan)) => plan.route(chunk, |rows, piece| {
                let group = Some(plan.group_of(piece));
                if rows.len() == chunk.len() {
                    return state.sink(source, chunk, false, piece, group);
                }
                run.clear();
                run.extend_from(chunk, rows);
                state.sink(source, run, false, piece, group)
            }),
            (role, _) => {
                let validates = role.validates();
                state.sink(source, chunk, validates, 0, (!validates).then_some(0))
            }
        }
    }

    /// The segment's share.
    pub(super) fn finish(self) -> LogPass {
        self.state.share
    }
}

impl SegmentState<'_> {
    /// Folds a run of samples of one kind (`to_validation`) and one piece of the log
    /// (`piece`, 0 unless it is a single fit log) into the segment's share, and into the
    /// local statistics of `group` (see [`LocalGroup`]).
    fn sink(
        &mut self,
        source: &LogSource,
        part: &SampleChunk,
        to_validation: bool,
        piece: usize,
        group: LocalGroup,
    ) -> Result<(), Error> {
        let k = usize::from(to_validation);
        let ctx = self.ctx;
        let share = &mut self.share;
        let ws = &mut self.ws;
        let at = |e: AccumulateError| accumulate_error(source)(e.after(self.first[k]));
        if let (Some(ext), Some(pieces)) = (&ctx.extended, share.candidates.as_mut()) {
            let assembled = ext
                .structure
                .assemble_reusing(part, ws, &ext.stored, &ext.plan);
            assembled.map_err(|e| at(e.into()))?;
            let acc = pieces[piece].get_or_insert_with(|| Accumulator::new(&ext.structure));
            // The accumulator counts its own samples; the error names the log's.
            let offset = self.in_log[k] - acc.count();
            acc.push_assembled(ws)
                .map_err(|e| accumulate_error(source)(e.after(offset)))?;
            if let Some(g) = group {
                ext.regions
                    .push(
                        part,
                        ws,
                        &ext.structure,
                        &mut share.local[g],
                        &mut self.active_ws,
                    )
                    .map_err(accumulate_error(source))?;
            }
        }
        if !to_validation {
            share.residuals.push(part, ws).map_err(at)?;
        }
        let span = &mut share.span[k];
        if span.0.is_nan() {
            span.0 = part.t[0];
        }
        span.1 = part.t[part.len() - 1];
        self.plot(part, k)?;
        self.seen[k] += part.len() as u64;
        self.in_log[k] += part.len() as u64;
        Ok(())
    }

    /// Appends the samples of `part` (of kind `k`) that the plots keep, with their
    /// predictions: only those samples are assembled (each regressor is a function of
    /// its own sample, so their values are those of the whole part).
    fn plot(&mut self, part: &SampleChunk, k: usize) -> Result<(), Error> {
        let ctx = self.ctx;
        let Some(strides) = ctx.strides else {
            return Ok(());
        };
        let stride = strides[k];
        let seen = self.seen[k];
        let kept: Vec<usize> = (0..part.len())
            .filter(|&i| (seen + i as u64).is_multiple_of(stride))
            .collect();
        if kept.is_empty() {
            return Ok(());
        }
        let rows = &mut self.plot_rows;
        rows.clear();
        rows.extend_from_rows(part, &kept);
        ctx.req.structure.assemble(rows, &mut self.plot_ws)?;
        let predicted = ctx
            .req
            .structure
            .predict_assembled(ctx.theta, rows, &self.plot_ws);
        let series = &mut self.share.series[k];
        // Absolute time; [`LogPass::times_from_start`] makes it relative.
        series.t.extend_from_slice(&rows.t);
        series.keep_samples(rows);
        for (a, y) in predicted.into_iter().enumerate() {
            series.measured[a].extend_from_slice(&rows.wrench[a]);
            series.predicted[a].extend(y);
        }
        Ok(())
    }
}

impl LogPass {
    /// The share of no samples of a log of `role`.
    pub(super) fn empty(ctx: &PassContext, role: Role) -> Self {
        let (pieces, groups) = match (role, ctx.plan) {
            (Role::Blocks, Some(plan)) => (plan.pieces.len(), plan.blocks()),
            (Role::Validation, _) => (1, 0),
            _ => (1, 1),
        };
        Self {
            residuals: ctx.residuals.clone(),
            series: Default::default(),
            span: [(f64::NAN, f64::NAN); 2],
            candidates: ctx.extended.as_ref().map(|_| vec![None; pieces]),
            local: vec![ActivityParts::default(); groups],
            regions: Vec::new(),
        }
    }

    /// Appends `later`, the share of the samples that directly follow this one's.
    pub(super) fn append(&mut self, later: LogPass) -> Result<(), AccumulateError> {
        self.residuals.merge(&later.residuals);
        for (k, mut part) in later.series.into_iter().enumerate() {
            let series = &mut self.series[k];
            series.t.append(&mut part.t);
            series.keep_samples(&part.samples);
            for a in 0..6 {
                series.measured[a].append(&mut part.measured[a]);
                series.predicted[a].append(&mut part.predicted[a]);
            }
            let (span, (first, last)) = (&mut self.span[k], later.span[k]);
            if span.0.is_nan() {
                span.0 = first;
            }
            if !last.is_nan() {
                span.1 = last;
            }
        }
        if let (Some(mine), Some(theirs)) = (self.candidates.as_mut(), later.candidates) {
            for (a, b) in mine.iter_mut().zip(theirs) {
                match (a.as_mut(), b) {
                    (Some(a), Some(b)) => a.merge(&b)?,
                    (None, b) => *a = b,
                    (Some(_), None) => {}
                }
            }
        }
        for (a, b) in self.local.iter_mut().zip(&later.local) {
            a.merge(b)?;
        }
        Ok(())
    }

    /// Counts the plotted times from the log's first sample of their kind.
    pub(super) fn times_from_start(&mut self) {
        for (series, span) in self.series.iter_mut().zip(self.span) {
            series.t.iter_mut().for_each(|t| *t -= span.0);
        }
    }
}
