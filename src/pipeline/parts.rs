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

use super::first_pass::{LogStats, Runs, read_log};
use super::split::Role;
use super::threads::run_jobs;
use super::{FitOutcome, FitRequest, after_first_pass, check, first_pass_size};
use crate::diagnose::{SCREENING_SAMPLES, Thinned};
use crate::error::{Error, StatsError};
use crate::io::Summary;
use crate::progress::Phase;
use crate::sample::Signals;
use crate::source::LogSource;
use crate::stats::Accumulator;

/// Version of the byte format written by [`StatsPart::to_bytes`]; a file of another
/// version is refused.
pub const STATS_FORMAT_VERSION: u32 = 1;

/// First bytes of every statistics file.
const MAGIC: &[u8; 16] = b"mrsysid-stats\r\n\x1a";

/// Bytes before the payload: magic, version (u32), payload length (u64), CRC-32 of the
/// payload (u32), all little-endian.
const HEADER_BYTES: usize = 16 + 4 + 8 + 4;

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
}

/// What the statistics of a log depend on, in words: the vehicle, the model structure,
/// the mapping, the options that change the samples read and the consistent filter's
/// cut-off. (Not the thread count or the CSV range size, which change nothing.)
fn settings(req: &FitRequest) -> String {
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

/// 64-bit FNV-1a of `bytes`: a stable hash (std's is not stable across releases).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Reads every fit log of `req` (its validation logs are ignored) and keeps each one's
/// first pass as a part, on `req.threads` threads; the logs are checked as
/// [`crate::Identification::run`] checks them (a log given twice is refused).
pub fn accumulate(req: &FitRequest) -> Result<StatsPart, Error> {
    let mut req = req.clone();
    req.validate.clear();
    req.second_pass = false;
    req.diagnose = None;
    super::request::check_groups(&req)?;
    check(&req)?;
    let jobs: Vec<(LogSource, Role)> = req.logs.iter().map(|l| (l.clone(), Role::Fit)).collect();
    req.enter(Phase::Reading, first_pass_size(&jobs));
    let per_log = run_jobs(&jobs, &req, |_, source, role, share| {
        read_log(source, role, &req, share)
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
    let source = |p: &LogPart| LogSource::File(p.summary.file.clone().into());
    let mut req = req.clone();
    req.logs = fit.logs.iter().map(source).collect();
    req.validate = validate.map_or_else(Vec::new, |v| v.logs.iter().map(source).collect());
    req.second_pass = false;
    req.diagnose = None;
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
            LogStats {
                fit,
                held_out,
                units: None,
                screening: Thinned::new(SCREENING_SAMPLES),
                summary: log.summary,
                signals: log.signals,
                spill: None,
                chunks: log.chunks,
                runs: log.runs,
            }
        })
        .collect();
    after_first_pass(&req, &jobs, per_log)
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
        match self.logs.iter().find(|l| !l.stats.has_layout_of(&empty)) {
            Some(log) => Err(StatsError::Format {
                file: log.summary.file.clone(),
                what: "statistics not laid out for the requested model (columns, shapes or \
                       buffer sizes differ): the part was altered"
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
        // Serialising plain data into a Vec cannot fail.
        let payload = postcard::to_stdvec(self).unwrap_or_default();
        let mut out = Vec::with_capacity(HEADER_BYTES + payload.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&STATS_FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        out
    }

    /// Reads a part from `bytes` in the statistics byte format; `file` names it in
    /// errors.
    pub fn from_bytes(bytes: &[u8], file: &str) -> Result<Self, StatsError> {
        let bad = |what: String| StatsError::Format {
            file: file.to_string(),
            what,
        };
        if bytes.len() < HEADER_BYTES || &bytes[..16] != MAGIC {
            return Err(bad("not a mrsysid statistics file (bad magic bytes)".into()));
        }
        let word = |at: usize, n: usize| {
            let mut b = [0u8; 8];
            b[..n].copy_from_slice(&bytes[at..at + n]);
            u64::from_le_bytes(b)
        };
        let version = word(16, 4);
        if version != u64::from(STATS_FORMAT_VERSION) {
            return Err(bad(format!(
                "format version {version}, this mrsysid reads version {STATS_FORMAT_VERSION}"
            )));
        }
        let (length, crc) = (word(20, 8), word(28, 4));
        let payload = &bytes[HEADER_BYTES..];
        if payload.len() as u64 != length {
            return Err(bad(format!(
                "truncated or padded: the header gives {length} payload bytes, the file has {}",
                payload.len()
            )));
        }
        if u64::from(crc32fast::hash(payload)) != crc {
            return Err(bad("checksum mismatch: the file is corrupted".into()));
        }
        postcard::from_bytes(payload).map_err(|e| bad(format!("payload: {e}")))
    }

    /// Writes the part to `path` (whole or not at all).
    pub fn save(&self, path: &std::path::Path) -> Result<(), StatsError> {
        crate::util::write_atomically(path, &self.to_bytes()).map_err(|e| StatsError::Io {
            file: path.display().to_string(),
            what: e.to_string(),
        })
    }

    /// Reads a part written by [`StatsPart::save`].
    pub fn load(path: &std::path::Path) -> Result<Self, StatsError> {
        let bytes = std::fs::read(path).map_err(|e| StatsError::Io {
            file: path.display().to_string(),
            what: e.to_string(),
        })?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }
}
