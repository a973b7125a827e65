//! Hold-out routing: which samples of each log fit and which validate ([`Role`]), the
//! jobs of a request in order, and the [`Splitter`] that cuts a single log's chunks into
//! runs of fit and held-out samples by its [`Holdout`] segments.

use super::{FitRequest, Holdout};
use crate::error::Error;
use crate::sample::{CHUNK_SAMPLES, SampleChunk};
use crate::source::LogSource;

/// How a log's samples are used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Role {
    /// All samples fit.
    Fit,
    /// All samples validate.
    Validation,
    /// Time segments split between the two.
    Split(Holdout),
}

/// Cuts chunks into runs of fit and validation samples.
pub(super) struct Splitter {
    role: Role,
    pub(super) t0: Option<f64>,
    /// Fit and validation samples waiting for a full chunk.
    pub(super) parts: [SampleChunk; 2],
    /// Indices of the routed chunk's samples of each kind not yet in `parts`.
    rows: [Vec<usize>; 2],
}

impl Splitter {
    /// A splitter whose hold-out segments count from `t0` (s), or from the first sample
    /// it routes when `None`.
    pub(super) fn new(role: Role, t0: Option<f64>) -> Self {
        Self {
            role,
            t0,
            parts: Default::default(),
            rows: Default::default(),
        }
    }

    /// Routes the samples of `chunk` to `sink(part, to_validation)`: whole chunks when
    /// the log has one role, else runs of one kind gathered into chunks of at least
    /// [`CHUNK_SAMPLES`] (time order kept within each kind). Call [`Splitter::finish`]
    /// after the last chunk. Returns the chunk's samples of each kind (fit, validation).
    pub(super) fn route(
        &mut self,
        chunk: &SampleChunk,
        sink: &mut impl FnMut(&SampleChunk, bool) -> Result<(), Error>,
    ) -> Result<[u64; 2], Error> {
        let n = chunk.len() as u64;
        let holdout = match self.role {
            Role::Fit => return sink(chunk, false).map(|()| [n, 0]),
            Role::Validation => return sink(chunk, true).map(|()| [0, n]),
            Role::Split(h) => h,
        };
        let mut kinds = [0u64; 2];
        if chunk.is_empty() {
            return Ok(kinds);
        }
        let t0 = *self.t0.get_or_insert(chunk.t[0]);
        let mut start = 0;
        while start < chunk.len() {
            let kind = holdout.holds_out(chunk.t[start], t0);
            let mut end = start + 1;
            while end < chunk.len() && holdout.holds_out(chunk.t[end], t0) == kind {
                end += 1;
            }
            let k = usize::from(kind);
            kinds[k] += (end - start) as u64;
            // Runs are gathered by index, a kind's at a time: the part is handed on
            // after the run that fills it, as if each run were appended on its own.
            self.rows[k].extend(start..end);
            if self.parts[k].len() + self.rows[k].len() >= CHUNK_SAMPLES {
                self.parts[k].extend_from_rows(chunk, &self.rows[k]);
                self.rows[k].clear();
                sink(&self.parts[k], kind)?;
                self.parts[k].clear();
            }
            start = end;
        }
        for (part, rows) in self.parts.iter_mut().zip(&mut self.rows) {
            part.extend_from_rows(chunk, rows);
            rows.clear();
        }
        Ok(kinds)
    }

    /// Hands over the samples still waiting.
    pub(super) fn finish(
        &mut self,
        sink: &mut impl FnMut(&SampleChunk, bool) -> Result<(), Error>,
    ) -> Result<(), Error> {
        for (k, part) in self.parts.iter_mut().enumerate() {
            if !part.is_empty() {
                sink(part, k == 1)?;
                part.clear();
            }
        }
        Ok(())
    }
}

/// Fit logs first (a single one split by the hold-out), then the validation logs.
pub(super) fn jobs(req: &FitRequest) -> Vec<(LogSource, Role)> {
    let fit_role = if req.logs.len() == 1 {
        Role::Split(req.holdout)
    } else {
        Role::Fit
    };
    req.logs
        .iter()
        .map(|p| (p.clone(), fit_role))
        .chain(req.validate.iter().map(|p| (p.clone(), Role::Validation)))
        .collect()
}
