//! What the parts of the second pass share: the context every log's pass reads, the
//! candidate effects it gathers statistics for, one log's share of the result, and where
//! a segment of a log starts. Both the pass over all logs (`second_pass`) and the pass
//! over one segment (`segment_pass`) use these; neither imports the other's internals.

use super::blocks::BlockPlan;
use super::{FitRequest, PlotSeries};
use crate::diagnose::Candidate;
use crate::diagnose::local::{ActivityParts, LocalRegions};
use crate::estimate::ResidualPass;
use crate::model::{ModelStructure, ParamId, Reuse};
use crate::stats::Accumulator;

/// Candidate effects added to the base structure, with their parameters.
pub(super) struct Extended {
    pub(super) structure: ModelStructure,
    pub(super) candidates: Vec<Candidate>,
    pub(super) params: Vec<Vec<ParamId>>,
    pub(super) regions: LocalRegions,
    /// The columns its accumulators store, and how they are assembled from each other.
    pub(super) stored: Vec<bool>,
    pub(super) plan: Vec<Option<Reuse>>,
}

/// What every log's second pass shares (read only).
pub(super) struct PassContext<'a> {
    pub(super) req: &'a FitRequest,
    /// MMR estimates θ̂ in `req.structure.params` order.
    pub(super) theta: &'a [f64],
    /// An empty residual pass to start each log from.
    pub(super) residuals: ResidualPass,
    /// Candidate effects, when diagnosing.
    pub(super) extended: Option<&'a Extended>,
    /// The blocks of a single fit log.
    pub(super) plan: Option<&'a BlockPlan>,
    /// Plot decimation: every `stride`-th sample of the whole run (fit, validation);
    /// `None` for no plot series.
    pub(super) strides: Option<[u64; 2]>,
}

/// One log's share of the second pass. Shares merge in job order into the result of a
/// pass over all logs one after another.
pub(super) struct LogPass {
    pub(super) residuals: ResidualPass,
    /// Plot series (fit, validation); time counted from `span.0` of the kind.
    pub(super) series: [PlotSeries; 2],
    /// First and last sample time of each kind in this log, s (NaN when none).
    pub(super) span: [(f64, f64); 2],
    /// Candidate-effect statistics when diagnosing: of the whole log, or of each piece
    /// of a single fit log's blocks (`None` while a piece has no sample).
    pub(super) candidates: Option<Vec<Option<Accumulator>>>,
    /// The same over the samples where local candidates act, by activity pattern, per
    /// [`LocalGroup`] of the log, while the log is passed.
    pub(super) local: Vec<ActivityParts>,
    /// Each local region's statistics per [`LocalGroup`], made from `local` (then
    /// emptied) once the whole log is passed ([`super::second_pass::pass_log`]).
    pub(super) regions: Vec<Vec<Accumulator>>,
}

/// The local-region statistics a run of samples goes to: those of the held-out data of
/// a fold, which is each of several fit logs whole (group 0) or each block of a single
/// fit log (group = block); `None` for a validation log (it reports, never decides).
/// [`super::folds::local_folds`] uses nothing else.
pub(super) type LocalGroup = Option<usize>;

/// Where a segment of a log's second pass starts.
#[derive(Debug, Clone, Copy)]
pub(super) struct Start {
    /// Samples of each kind (fit, validation) before it, in this log and the logs before.
    pub(super) seen: [u64; 2],
    /// The same in this log only.
    pub(super) in_log: [u64; 2],
}
