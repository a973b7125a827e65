//! Statistics as data, second and third passes (issue 43): the closing of the loop as
//! map-reduce over logs that are read on other machines.
//!
//! 1. The driver fits Eq. 22 on the merged first-pass parts and plans the second pass
//!    ([`plan_fit`]): the [`PassPlan`] holds what every log's second pass needs from all
//!    logs' first passes (the Eq. 22 fit's statistics, the merged screening sample, the
//!    signals, each log's chunk count).
//! 2. Each task prepares the plan once ([`PreparedPass::new`]: the Eq. 22 fit and the
//!    candidate effects, rebuilt exactly as the driver builds them) and passes its log
//!    into a [`PassPart`]: the log's residual sums and candidate statistics.
//! 3. The driver reduces the parts ([`PlannedFit::diagnose`]): residual diagnostics and
//!    the diagnosis, as one process would make them. Its [`PendingFit`] gives the
//!    [`RemainderPlan`] (the final model), which each task passes its fit log with
//!    ([`PreparedPass::remainder_part`]); [`PendingFit::finish`] merges those.
//!
//! Every step is a pure function of its inputs, so the result equals
//! [`crate::Identification::run`] of the same logs in the same order without plots.
//! Each file kind is framed as the first-pass parts are (`docs/stats-format.md`) and
//! names the plan it was made from by the plan's hash, so parts of another fit are
//! refused.

use serde::{Deserialize, Serialize};

use super::FitRequest;
use super::first_fit;
use super::framing::{self, fnv1a};
use super::outcome::FitOutcome;
use super::parts::{StatsPart, from_parts, settings};
use super::pass_share::{Extended, LogPass, PassContext, Start};
use super::remainder::log_remainder;
use super::second_pass::{Log, extended, pass_log, reduce};
use super::split::Role;
use crate::diagnose::Diagnosis;
use crate::error::{Error, StatsError};
use crate::estimate::remainder::Remainder;
use crate::estimate::{self, DiagnosticOptions, Fit, ResidualPass, ResidualSums};
use crate::sample::{SampleChunk, Signals};
use crate::source::LogSource;
use crate::stats::Accumulator;

const PLAN_MAGIC: &[u8; 16] = b"mrsysid-passplan";
const PASS_MAGIC: &[u8; 16] = b"mrsysid-passpart";
const REMAINDER_PLAN_MAGIC: &[u8; 16] = b"mrsysid-remplan\x1a";
const REMAINDER_MAGIC: &[u8; 16] = b"mrsysid-rempart\x1a";

/// What every log's second pass needs from the first passes of all logs of a fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassPlan {
    /// The settings it was made with ([`plan_settings`]) and their hash.
    settings: String,
    fingerprint: u64,
    /// The statistics the Eq. 22 model is fitted on (all fit logs merged in order).
    fit_stats: Accumulator,
    /// The thinned fit samples of all logs, merged in order (the diagnosis's screening).
    screening: SampleChunk,
    /// The optional signals of the first log with samples.
    signals: Option<Signals>,
    /// Every fit log is a time series.
    time_series: bool,
    /// Every log of the fit, fit logs first.
    logs: Vec<PlanLog>,
}

/// One log of a [`PassPlan`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct PlanLog {
    /// Its name, as its first-pass part names it.
    name: String,
    /// Chunks it was read in (the second pass cuts its segments by them).
    chunks: usize,
    /// A validation log (reports, never decides).
    validation: bool,
}

/// One log's second pass.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PassPart {
    /// Hash of the bytes of the plan it was made from.
    plan: u64,
    log: String,
    residuals: ResidualSums,
    /// First and last sample time of each kind (fit, validation), s.
    span: [(f64, f64); 2],
    candidates: Option<Vec<Option<Accumulator>>>,
    /// Where local candidates act: each region's statistics (the log's one local group
    /// of a fit log; none for a validation log).
    local: Vec<Vec<Accumulator>>,
}

/// The final model of a diagnosis, for the remainder pass over each fit log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RemainderPlan {
    /// Hash of the bytes of the second-pass plan.
    plan: u64,
    /// The columns of the plan's extended structure the final model keeps.
    columns: Vec<usize>,
    /// θ̂ of the final model.
    theta: Vec<f64>,
}

/// One fit log's remainder sums.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RemainderPart {
    /// Hash of the bytes of the remainder plan it was made from.
    plan: u64,
    log: String,
    sums: Remainder,
}

/// A plan prepared for passing logs: the Eq. 22 fit and the candidate effects.
pub struct PreparedPass {
    req: FitRequest,
    plan: PassPlan,
    digest: u64,
    fit: Fit,
    extended: Option<Extended>,
    residuals: ResidualPass,
}

/// The driver's state between the plan and the reduce: the Eq. 22 fit of the parts'
/// logs and the plan of their second pass ([`plan_fit`]).
#[derive(Debug)]
pub struct PlannedFit {
    /// The request with the parts' logs as its logs.
    req: FitRequest,
    plan: PassPlan,
    outcome: FitOutcome,
}

/// The fit and diagnosis from second-pass parts, waiting for the remainder pass.
#[derive(Debug)]
pub struct PendingFit {
    outcome: FitOutcome,
    diagnosis: Option<Diagnosis>,
    /// The remainder plan and the fit logs that need passing with it, when the fit logs
    /// are time series.
    remainder: Option<(RemainderPlan, Vec<String>)>,
}

/// What a plan depends on beyond the parts: their settings, the fit and diagnosis
/// options.
fn plan_settings(req: &FitRequest) -> String {
    format!(
        "{}; fit {:?}; diagnosis {:?}",
        settings(req),
        req.fit,
        req.diagnose
    )
}

/// Refuses `part`'s plan hash `plan` unless it is `digest`.
fn same_plan(plan: u64, digest: u64, log: &str) -> Result<(), StatsError> {
    match plan == digest {
        true => Ok(()),
        false => Err(StatsError::OtherPlan { file: log.into() }),
    }
}

/// The Eq. 22 fit of the logs of `fit` (at least two) and `validate` from their parts,
/// made with `req`'s settings and with the diagnosis on when `req` diagnoses, and the
/// plan of their second pass: the driver's first step.
pub fn plan_fit(
    req: &FitRequest,
    fit: &StatsPart,
    validate: Option<&StatsPart>,
) -> Result<PlannedFit, Error> {
    let logs = from_parts(req, fit, validate, req.diagnose.is_some())?;
    let (outcome, first) = first_fit(&logs.req, logs.per_log)?;
    let settings = plan_settings(req);
    let plan = PassPlan {
        fingerprint: fnv1a(settings.as_bytes()),
        settings,
        fit_stats: outcome.fit_stats.clone(),
        screening: first.screening.samples().clone(),
        signals: first.signals,
        time_series: first.fit_logs_time_series(&logs.req),
        logs: (logs.jobs.iter().zip(&first.counts))
            .map(|((source, role), c)| PlanLog {
                name: source.name(),
                chunks: c.chunks,
                validation: role.validates(),
            })
            .collect(),
    };
    Ok(PlannedFit {
        req: logs.req,
        plan,
        outcome,
    })
}

impl PreparedPass {
    /// Prepares `plan` for `req` (the settings it was made with): fits Eq. 22 on its
    /// statistics and builds the candidate effects from its screening sample.
    pub fn new(req: &FitRequest, plan: PassPlan) -> Result<Self, Error> {
        let settings = plan_settings(req);
        if fnv1a(settings.as_bytes()) != plan.fingerprint {
            return Err(StatsError::OtherSettings {
                logs: "the second-pass plan".into(),
                part: plan.settings,
                request: settings,
            }
            .into());
        }
        let altered = |what: &str| StatsError::Format {
            file: "the second-pass plan".into(),
            what: format!("{what}: the plan was altered"),
        };
        if !plan
            .fit_stats
            .has_layout_of(&Accumulator::new(&req.structure))
        {
            return Err(altered("statistics not laid out for the requested model").into());
        }
        let rotors = req.vehicle.rotor_count();
        let screening = &plan.screening;
        if screening.check_lengths().is_err()
            || (!screening.is_empty() && screening.rotor_count() != rotors)
        {
            return Err(altered("screening samples of inconsistent lengths or rotors").into());
        }
        let digest = fnv1a(&plan.to_bytes());
        let fit = estimate::fit(&req.structure, &plan.fit_stats, &req.fit)?;
        let extended = extended(req, &fit, plan.time_series, plan.signals, screening)?;
        let residuals = ResidualPass::new(&req.structure, &fit, DiagnosticOptions::default());
        Ok(Self {
            req: req.clone(),
            plan,
            digest,
            fit,
            extended,
            residuals,
        })
    }

    /// The context every log's second pass reads (no plot series).
    fn context(&self) -> PassContext<'_> {
        PassContext {
            req: &self.req,
            theta: &self.fit.mmr.theta,
            residuals: self.residuals.clone(),
            extended: self.extended.as_ref(),
            plan: None,
            strides: None,
        }
    }

    /// The plan's entry for `log`.
    fn entry(&self, log: &LogSource) -> Result<&PlanLog, Error> {
        let name = log.name();
        let entry = self.plan.logs.iter().find(|l| l.name == name);
        entry.ok_or_else(|| StatsError::NotInPlan { log: name }.into())
    }

    /// The second pass over `log`, one of the plan's logs (named as its first-pass part
    /// names it), read again from its file or memory.
    pub fn pass_part(&self, log: &LogSource) -> Result<PassPart, Error> {
        let entry = self.entry(log)?;
        let role = match entry.validation {
            true => Role::Validation,
            false => Role::Fit,
        };
        let ctx = self.context();
        let pass = Log {
            source: log,
            spill: None,
            role,
            chunks: entry.chunks,
        };
        let start = Start {
            seen: [0; 2],
            in_log: [0; 2],
        };
        let share = pass_log(&ctx, &pass, self.req.threads, start)?;
        Ok(PassPart {
            plan: self.digest,
            log: entry.name.clone(),
            residuals: share.residuals.sums(),
            span: share.span,
            candidates: share.candidates,
            local: share.regions,
        })
    }

    /// The remainder pass of `log`, a fit log of the plan, with the final model of
    /// `model`.
    pub fn remainder_part(
        &self,
        model: &RemainderPlan,
        log: &LogSource,
    ) -> Result<RemainderPart, Error> {
        let entry = self.entry(log)?;
        same_plan(model.plan, self.digest, "the remainder plan")?;
        let altered = StatsError::Format {
            file: "the remainder plan".into(),
            what: "columns or estimates that do not fit the plan's candidates: the plan was \
                   altered"
                .into(),
        };
        let Some(ext) = &self.extended else {
            return Err(altered.into());
        };
        let p = ext.structure.columns.len();
        let ascending = model.columns.windows(2).all(|w| w[0] < w[1]);
        if !ascending || model.columns.last().is_some_and(|&c| c >= p) {
            return Err(altered.into());
        }
        let structure = ext.structure.select_columns(&model.columns);
        if structure.params.len() != model.theta.len() {
            return Err(altered.into());
        }
        let sums = log_remainder(&self.req, log, None, (&structure, &model.theta))?;
        Ok(RemainderPart {
            plan: fnv1a(&model.to_bytes()),
            log: entry.name.clone(),
            sums,
        })
    }
}

impl PlannedFit {
    /// The plan of the second pass, for [`PreparedPass::new`] on every worker.
    pub fn plan(&self) -> &PassPlan {
        &self.plan
    }

    /// The fit and diagnosis of the logs from their second-pass parts `passes` (one per
    /// log, any order; more are ignored) made from [`PlannedFit::plan`].
    pub fn diagnose(self, passes: Vec<PassPart>) -> Result<PendingFit, Error> {
        let PlannedFit {
            req,
            plan,
            mut outcome,
        } = self;
        let prepared = PreparedPass::new(&req, plan)?;
        let ctx = prepared.context();
        let empty = prepared
            .extended
            .as_ref()
            .map(|e| Accumulator::new(&e.structure));
        let mut passes: Vec<Option<PassPart>> = passes.into_iter().map(Some).collect();
        let mut shares = Vec::with_capacity(prepared.plan.logs.len());
        let mut jobs = Vec::with_capacity(prepared.plan.logs.len());
        for entry in &prepared.plan.logs {
            let part = passes
                .iter_mut()
                .find(|p| p.as_ref().is_some_and(|p| p.log == entry.name))
                .and_then(Option::take);
            let part = part.ok_or_else(|| StatsError::MissingPass {
                log: entry.name.clone(),
                pass: "second-pass".into(),
            })?;
            same_plan(part.plan, prepared.digest, &part.log)?;
            shares.push(share_of(&ctx, part, entry, empty.as_ref())?);
            let role = match entry.validation {
                true => Role::Validation,
                false => Role::Fit,
            };
            jobs.push((LogSource::File(entry.name.clone().into()), role));
        }
        let diagnosis = reduce(&ctx, &jobs, shares, &mut outcome)?;
        let fit_logs = (prepared.plan.logs.iter())
            .filter(|l| !l.validation)
            .map(|l| l.name.clone())
            .collect();
        let remainder = match &diagnosis {
            Some(d) if prepared.plan.time_series => Some((
                RemainderPlan {
                    plan: prepared.digest,
                    columns: d.columns.clone(),
                    theta: d.theta.clone(),
                },
                fit_logs,
            )),
            _ => None,
        };
        Ok(PendingFit {
            outcome,
            diagnosis,
            remainder,
        })
    }
}

/// `part` as the share of its log's second pass (`entry`), checked against `ctx`'s
/// layout (`empty`: an empty accumulator of the candidate effects).
fn share_of(
    ctx: &PassContext,
    part: PassPart,
    entry: &PlanLog,
    empty: Option<&Accumulator>,
) -> Result<LogPass, Error> {
    let log = part.log;
    let altered = || StatsError::Format {
        file: log.clone(),
        what: "second-pass statistics not laid out for this plan: the part was altered".into(),
    };
    let residuals = ctx.residuals.with_sums(part.residuals);
    let residuals = residuals.ok_or_else(altered)?;
    let laid_out = |a: &Accumulator| empty.is_some_and(|e| a.has_layout_of(e));
    let candidates_fit = match (&part.candidates, empty) {
        (Some(pieces), Some(_)) => pieces.len() == 1 && pieces.iter().flatten().all(laid_out),
        (None, None) => true,
        _ => false,
    };
    let groups = usize::from(!entry.validation && empty.is_some());
    let regions = ctx.extended.map_or(0, |e| e.regions.len());
    let local_fit = part.local.len() == groups
        && (part.local.iter()).all(|l| l.len() == regions && l.iter().all(laid_out));
    if !candidates_fit || !local_fit {
        return Err(altered().into());
    }
    Ok(LogPass {
        residuals,
        series: Default::default(),
        span: part.span,
        candidates: part.candidates,
        local: Vec::new(),
        regions: part.local,
    })
}

impl PendingFit {
    /// The final model for the remainder pass over each fit log
    /// ([`PreparedPass::remainder_part`]) and those logs' names; `None` when there is no
    /// remainder pass (no diagnosis, or fit logs that are not time series).
    pub fn remainder_plan(&self) -> Option<(&RemainderPlan, &[String])> {
        self.remainder
            .as_ref()
            .map(|(p, logs)| (p, logs.as_slice()))
    }

    /// The fit with its diagnosis, the remainder merged from `parts` (one per fit log
    /// of [`PendingFit::remainder_plan`], any order; none when it is `None`).
    pub fn finish(self, parts: &[RemainderPart]) -> Result<FitOutcome, Error> {
        let mut outcome = self.outcome;
        let Some(mut diagnosis) = self.diagnosis else {
            return Ok(outcome);
        };
        if let Some((plan, logs)) = &self.remainder {
            let digest = fnv1a(&plan.to_bytes());
            let mut all = Remainder::default();
            for log in logs {
                let part = parts.iter().find(|p| &p.log == log);
                let part = part.ok_or_else(|| StatsError::MissingPass {
                    log: log.clone(),
                    pass: "remainder".into(),
                })?;
                same_plan(part.plan, digest, log)?;
                if !part.sums.has_layout() {
                    return Err(StatsError::Format {
                        file: log.clone(),
                        what: "remainder sums not laid out as this version's: the part was \
                               altered"
                            .into(),
                    }
                    .into());
                }
                all.merge(&part.sums);
            }
            diagnosis.remainder = all.evidence();
        }
        outcome.diagnosis = Some(diagnosis);
        Ok(outcome)
    }
}

/// `to_bytes` and `from_bytes` of a file kind of this module, under `magic`.
macro_rules! framed {
    ($kind:ty, $magic:expr, $what:literal) => {
        impl $kind {
            #[doc = concat!("The ", $what, " in its byte format (`docs/stats-format.md`).")]
            pub fn to_bytes(&self) -> Vec<u8> {
                framing::to_bytes($magic, self)
            }

            #[doc = concat!("Reads a ", $what, " from `bytes`; `file` names it in errors.")]
            pub fn from_bytes(bytes: &[u8], file: &str) -> Result<Self, StatsError> {
                framing::from_bytes($magic, $what, bytes, file)
            }

            #[doc = concat!("Writes the ", $what, " to `path` (whole or not at all).")]
            pub fn save(&self, path: &std::path::Path) -> Result<(), StatsError> {
                framing::save(path, &self.to_bytes())
            }

            #[doc = concat!("Reads a ", $what, " written by `save`.")]
            pub fn load(path: &std::path::Path) -> Result<Self, StatsError> {
                Self::from_bytes(&framing::load(path)?, &path.display().to_string())
            }
        }
    };
}

framed!(PassPlan, PLAN_MAGIC, "second-pass plan");
framed!(PassPart, PASS_MAGIC, "second-pass part");
framed!(RemainderPlan, REMAINDER_PLAN_MAGIC, "remainder plan");
framed!(RemainderPart, REMAINDER_MAGIC, "remainder part");

impl PassPart {
    /// The log it is the second pass of.
    pub fn log(&self) -> &str {
        &self.log
    }
}

impl RemainderPart {
    /// The log it is the remainder pass of.
    pub fn log(&self) -> &str {
        &self.log
    }
}
