//! What a fit is asked to do ([`FitRequest`], with the single log's [`Holdout`]) and the
//! checks that refuse a request before any log is read.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::diagnose::DiagnoseOptions;
use crate::error::{Error, RequestError};
use crate::estimate::FitOptions;
use crate::io::{Mapping, ReadOptions};
use crate::model::ModelStructure;
use crate::progress::{Phase, Progress};
use crate::source::LogSource;
use crate::vehicle::Vehicle;

/// How a single fit log is cross-validated: cut into contiguous blocks, each predicted
/// by the model fitted on the rest of the log less a guard on each side of it
/// (`super::blocks` explains the choice). Several fit logs are cross-validated by
/// leaving one log out instead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Holdout {
    /// Contiguous blocks of (nearly) equal sample counts the log is cut into, each held
    /// out in turn (at least 2; 1/blocks of the log per fold).
    pub blocks: usize,
    /// Time on each side of a held-out block that its fold neither fits nor scores, s
    /// (≥ 0; rounded up to the pipeline's time units, 1/16 s for a log of up to 32 s).
    pub guard_seconds: f64,
}

impl Default for Holdout {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Holdout {
    /// The cross-validation of a single fit log unless asked otherwise, the one place
    /// it is written: 5 contiguous blocks (20 % of the log each, the last predicted from
    /// the first 80 %), 2 s guards.
    pub const DEFAULT: Holdout = Holdout {
        blocks: 5,
        guard_seconds: 2.0,
    };

    /// Shortest span of a single fit log that can be cross-validated so, s: a guard per
    /// block.
    pub fn min_span(&self) -> f64 {
        self.blocks as f64 * self.guard_seconds
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
    /// Cross-validation of a single fit log on contiguous blocks.
    pub holdout: Holdout,
    /// Reporting-only validation logs: evaluated, never used for a decision.
    pub validate: Vec<LogSource>,
    /// Cross-validation groups of the fit logs, one name per log in `logs` order: the
    /// logs of one group are left out together (e.g. one group per flight day, so a day's
    /// wind and battery do not leak into its own prediction). Empty: each log is its own
    /// group (leave one log out).
    pub groups: Vec<String>,
    /// Threads for reading, accumulating and the diagnosis (≥ 1).
    pub threads: usize,
    /// Run the second pass (residual diagnostics, plot series).
    pub second_pass: bool,
    /// Run the closing-the-loop diagnosis (in the second pass).
    pub diagnose: Option<DiagnoseOptions>,
    /// What the fit has done so far, for a progress display.
    pub progress: Option<Arc<Progress>>,
    /// Set by the caller to stop the fit: checked before every chunk of every pass
    /// (where `progress` is counted), the fit then ends with
    /// [`RequestError::Cancelled`].
    pub cancel: Option<Arc<AtomicBool>>,
    /// The cut-off (Hz) at which the logs' loads were low-passed when they were made: the
    /// regressor signals pass through the same kind of filter (consistent filtering,
    /// [`crate::io::LoadsProcessing`]); `None`: as the mapping's `[loads]` says, else
    /// not filtered.
    pub loads_low_pass_hz: Option<f64>,
}

impl FitRequest {
    /// The cut-off (Hz) the regressor signals are low-passed at: the request's, else the
    /// mapping file's `[loads] low_pass_hz`.
    pub fn effective_loads_low_pass(&self) -> Option<f64> {
        self.loads_low_pass_hz.or_else(|| {
            self.mapping
                .as_ref()
                .and_then(|m| m.loads)
                .map(|l| l.low_pass_hz)
        })
    }
}

impl FitRequest {
    /// Enters `phase` of `total` units in the request's progress, if any.
    pub(super) fn enter(&self, phase: Phase, total: u64) {
        if let Some(p) = &self.progress {
            p.start(phase, total);
        }
    }
}

/// [`RequestError::Cancelled`] once `cancel` is set.
pub(super) fn check_cancel(cancel: Option<&AtomicBool>) -> Result<(), Error> {
    match cancel {
        Some(c) if c.load(Ordering::Relaxed) => Err(RequestError::Cancelled.into()),
        _ => Ok(()),
    }
}

/// Refuses a request that cannot be carried out, before any log is read.
pub(super) fn check(req: &FitRequest) -> Result<(), RequestError> {
    if req.logs.is_empty() {
        return Err(RequestError::NoLogs);
    }
    let h = req.holdout;
    if !(h.guard_seconds.is_finite() && h.guard_seconds >= 0.0 && h.blocks >= 2) {
        return Err(RequestError::InvalidHoldout {
            blocks: h.blocks,
            guard_seconds: h.guard_seconds,
        });
    }
    if let Some(hz) = req.loads_low_pass_hz
        && !(hz.is_finite() && hz > 0.0)
    {
        return Err(RequestError::InvalidLoadsLowPass { hz });
    }
    let (structure, vehicle) = (req.structure.rotor_count(), req.vehicle.rotor_count());
    if structure != vehicle {
        return Err(RequestError::StructureMismatch { structure, vehicle });
    }
    check_groups(req)?;
    crate::inputs::check_logs(&req.logs, &req.validate)
}

/// Groups, when given, name every fit log and at least two distinct groups.
pub(super) fn check_groups(req: &FitRequest) -> Result<(), RequestError> {
    if req.groups.is_empty() {
        return Ok(());
    }
    let distinct = group_order(&req.groups).len();
    if req.groups.len() != req.logs.len() || distinct < 2 {
        return Err(RequestError::InvalidGroups {
            groups: req.groups.len(),
            distinct,
            logs: req.logs.len(),
        });
    }
    Ok(())
}

/// The distinct group names of `groups`, in order of first appearance.
pub(super) fn group_order(groups: &[String]) -> Vec<&str> {
    let mut order: Vec<&str> = Vec::new();
    for g in groups {
        if !order.contains(&g.as_str()) {
            order.push(g);
        }
    }
    order
}
