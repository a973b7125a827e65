//! Statistics as data (issue 43, first pass): each log's first pass kept as a
//! [`StatsPart`] that serialises to a versioned, checksummed byte format
//! (`docs/stats-format.md`), merges with the parts of other logs made with the same
//! settings, and fits Eq. 22 with leave-one-log-out cross-validation and validation
//! logs without reading any log again ([`run_from_parts`]). Any engine can drive it:
//! one task per log ([`accumulate`]), a merge, one fit.
//!
//! A part holds, per log, what the fit needs of it: the statistics of all its samples
//! (the streaming QR of [X | Z], [`Accumulator`]), its reading summary, which optional
//! signals it has, and whether it is a time series. It does not hold the samples, so
//! nothing that needs them again runs from parts: the residual pass (residual
//! diagnostics, the coloured-residual correction of σ, plot series) and the diagnosis.
//! A fit from parts therefore equals a fit of the same logs with
//! [`crate::Identification::residual_pass`] off and without the diagnosis.

use serde::{Deserialize, Serialize};

use super::first_pass::{Keep, LogStats, Runs, read_log};
use super::framing::{self, fnv1a};
use super::split::Role;
use super::threads::run_jobs;
use super::{FitOutcome, FitRequest, check, first_fit, first_pass_size};
use crate::diagnose::{SCREENING_SAMPLES, Thinned};
use crate::error::{Error, StatsError};
use crate::io::Summary;
use crate::progress::Phase;
use crate::sample::Signals;
use crate::source::LogSource;
use crate::stats::Accumulator;

/// First bytes of every statistics file.
const MAGIC: &[u8; 16] = b"mrsysid-stats\r\n\x1a";

/// The first-pass statistics of one or more logs, made with one set of settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatsPart {
    /// FNV-1a hash of the settings the logs were read and accumulated with
    /// ([`settings`]): parts merge, and a request fits them, only when it is equal.
    fingerprint: u64,
    /// The settings in words, for the message when they differ.
    settings: String,
    logs: Vec<LogPart>,
}

/// One log's first pass.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct LogPart {
    summary: Summary,
    /// Statistics of all its samples.
    stats: Accumulator,
    signals: Option<Signals>,
    chunks: usize,
    runs: Runs,
    /// Its thinned fit samples for the diagnosis's screening; `None` when accumulated
    /// with the diagnosis off.
    screening: Option<Thinned>,
}

/// What the statistics of a log depend on, in words: the vehicle, the model structure,
/// the mapping, the options that change the samples read and the consistent filter's
/// cut-off. (Not the thread count or the CSV range size, which change nothing.)
pub(super) fn settings(req: &FitRequest) -> String {
    let r = &req.read;
    format!(
        "vehicle {:?}; structure {:?}; mapping {:?}; invalid samples {:?}, max gap {:?} s, \
         derive {:?}, airborne only {}; loads low-pass {:?} Hz",
        req.vehicle,
        req.structure,
        req.mapping,
        r.invalid,
        r.max_gap,
        r.derive,
        r.airborne_only,
        req.effective_loads_low_pass()
    )
}

/// Reads every fit log of `req` (its validation logs are ignored) and keeps each one's
/// first pass as a part, on `req.threads` threads, with its screening sample when `req`
/// diagnoses; the logs are checked as [`crate::Identification::run`] checks them (a log
/// given twice is refused).
pub fn accumulate(req: &FitRequest) -> Result<StatsPart, Error> {
    // The diagnosis's derived signals (the slow thrusts) go into the screening sample.
    let keep = Keep {
        screening: req.diagnose.is_some(),
        spill: false,
    };
    let mut req = req.clone();
    req.validate.clear();
    req.second_pass = false;
    super::request::check_groups(&req)?;
    check(&req)?;
    let jobs: Vec<(LogSource, Role)> = req.logs.iter().map(|l| (l.clone(), Role::Fit)).collect();
    req.enter(Phase::Reading, first_pass_size(&jobs));
    let per_log = run_jobs(&jobs, &req, |_, source, role, share| {
        read_log(source, role, &req, share, keep)
    })?;
    let settings = settings(&req);
    Ok(StatsPart {
        fingerprint: fnv1a(settings.as_bytes()),
        settings,
        logs: per_log
            .into_iter()
            .map(|s| LogPart {
                summary: s.summary,
                stats: s.fit,
                signals: s.signals,
                chunks: s.chunks,
                runs: s.runs,
                screening: keep.screening.then_some(s.screening),
            })
            .collect(),
    })
}

/// Fits `fit`'s logs (at least two: each is a fold of leave one log out) and reports on
/// `validate`'s, as `req` would fit and validate the logs themselves with the residual
/// pass off and without the diagnosis. `req`'s own logs are ignored; its settings must
/// be those the parts were made with.
pub fn run_from_parts(
    req: &FitRequest,
    fit: &StatsPart,
    validate: Option<&StatsPart>,
) -> Result<FitOutcome, Error> {
    let logs = from_parts(req, fit, validate, false)?;
    first_fit(&logs.req, logs.per_log).map(|(outcome, _)| outcome)
}

/// The logs of statistics parts as the pipeline holds them after their first pass.
pub(super) struct PartLogs {
    /// The request with the parts' logs (their names) as its fit and validation logs.
    pub(super) req: FitRequest,
    /// Each log and its role, fit logs first.
    pub(super) jobs: Vec<(LogSource, Role)>,
    /// Each log's first pass, in the order of `jobs`.
    pub(super) per_log: Vec<LogStats>,
}

/// The logs of `fit` (at least two) and `validate` as the pipeline holds them after the
/// first pass, for `req` (whose settings must be those the parts were made with), with
/// the fit logs' screening samples when `screening` (refused for parts accumulated
/// without).
pub(super) fn from_parts(
    req: &FitRequest,
    fit: &StatsPart,
    validate: Option<&StatsPart>,
    screening: bool,
) -> Result<PartLogs, Error> {
    let settings = settings(req);
    let fingerprint = fnv1a(settings.as_bytes());
    for part in std::iter::once(fit).chain(validate) {
        if part.fingerprint != fingerprint {
            return Err(StatsError::OtherSettings {
                logs: part.log_names().join(", "),
                part: part.settings.clone(),
                request: settings,
            }
            .into());
        }
    }
    for part in std::iter::once(fit).chain(validate) {
        part.check_layout(&req.structure)?;
    }
    if fit.logs.len() < 2 {
        return Err(StatsError::TooFewLogs {
            logs: fit.logs.len(),
        }
        .into());
    }
    let mut all = fit.clone();
    if let Some(v) = validate {
        // The same log among fit and validation logs would be validated in-sample.
        all.merge(v)?;
    }
    let unscreened: Vec<&str> = (fit.logs.iter())
        .filter(|l| l.screening.is_none())
        .map(|l| l.summary.file.as_str())
        .collect();
    if screening && !unscreened.is_empty() {
        return Err(StatsError::NotDiagnosable {
            logs: unscreened.join(", "),
        }
        .into());
    }
    let source = |p: &LogPart| LogSource::File(p.summary.file.clone().into());
    let mut req = req.clone();
    req.logs = fit.logs.iter().map(source).collect();
    req.validate = validate.map_or_else(Vec::new, |v| v.logs.iter().map(source).collect());
    let jobs: Vec<(LogSource, Role)> = (req.logs.iter().map(|l| (l.clone(), Role::Fit)))
        .chain(req.validate.iter().map(|l| (l.clone(), Role::Validation)))
        .collect();
    let per_log = all
        .logs
        .into_iter()
        .zip(&jobs)
        .map(|(log, (_, role))| {
            let empty = Accumulator::new(&req.structure);
            let (fit, held_out) = match role {
                Role::Validation => (empty, log.stats),
                _ => (log.stats, empty),
            };
            // As in a fit of the logs themselves, only fit logs are screened.
            let screening = log.screening.filter(|_| screening && !role.validates());
            LogStats {
                fit,
                held_out,
                units: None,
                screening: screening.unwrap_or_else(|| Thinned::new(SCREENING_SAMPLES)),
                summary: log.summary,
                signals: log.signals,
                spill: None,
                chunks: log.chunks,
                runs: log.runs,
            }
        })
        .collect();
    Ok(PartLogs { req, jobs, per_log })
}

impl StatsPart {
    /// The names of its logs, in order.
    pub fn log_names(&self) -> Vec<String> {
        self.logs.iter().map(|l| l.summary.file.clone()).collect()
    }

    /// Refuses a part whose statistics are not laid out as `structure`'s (a file made
    /// with the same settings but altered, whose checksum was made to match).
    fn check_layout(&self, structure: &crate::model::ModelStructure) -> Result<(), StatsError> {
        let empty = Accumulator::new(structure);
        let rotors = structure.rotor_count();
        let screening_fits = |l: &LogPart| {
            (l.screening.as_ref()).is_none_or(|t| t.is_consistent(SCREENING_SAMPLES, rotors))
        };
        let altered = |l: &&LogPart| !l.stats.has_layout_of(&empty) || !screening_fits(l);
        match self.logs.iter().find(altered) {
            Some(log) => Err(StatsError::Format {
                file: log.summary.file.clone(),
                what: "statistics not laid out for the requested model (columns, shapes or \
                       buffer sizes differ, or screening samples inconsistent): the part was \
                       altered"
                    .into(),
            }),
            None => Ok(()),
        }
    }

    /// Samples of all its logs.
    pub fn samples(&self) -> u64 {
        self.logs.iter().map(|l| l.stats.count()).sum()
    }

    /// Appends the logs of `other`, made with the same settings. A log of the same name
    /// as one already in is refused (the same log twice would be cross-validated
    /// in-sample).
    pub fn merge(&mut self, other: &StatsPart) -> Result<(), StatsError> {
        if other.fingerprint != self.fingerprint {
            return Err(StatsError::OtherSettings {
                logs: other.log_names().join(", "),
                part: other.settings.clone(),
                request: self.settings.clone(),
            });
        }
        for log in &other.logs {
            let name = &log.summary.file;
            if self.logs.iter().any(|l| &l.summary.file == name) {
                return Err(StatsError::DuplicateLog { log: name.clone() });
            }
            self.logs.push(log.clone());
        }
        Ok(())
    }

    /// The part in the statistics byte format (`docs/stats-format.md`): a 16-byte magic
    /// string, the format version, the payload's length and CRC-32, then the payload
    /// (postcard 1.0 encoding of the part).
    pub fn to_bytes(&self) -> Vec<u8> {
        framing::to_bytes(MAGIC, self)
    }

    /// Reads a part from `bytes` in the statistics byte format; `file` names it in
    /// errors.
    pub fn from_bytes(bytes: &[u8], file: &str) -> Result<Self, StatsError> {
        framing::from_bytes(MAGIC, "statistics file", bytes, file)
    }

    /// Writes the part to `path` (whole or not at all).
    pub fn save(&self, path: &std::path::Path) -> Result<(), StatsError> {
        framing::save(path, &self.to_bytes())
    }

    /// Reads a part written by [`StatsPart::save`].
    pub fn load(path: &std::path::Path) -> Result<Self, StatsError> {
        Self::from_bytes(&framing::load(path)?, &path.display().to_string())
    }
}
