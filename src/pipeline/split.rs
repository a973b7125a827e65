//! What each log's samples are for ([`Role`]) and the jobs of a request in order: every
//! sample of a fit log is fitted, a single fit log's samples are also cut into the
//! contiguous blocks that cross-validate it ([`super::blocks`]), and every sample of a
//! validation log is held out for reporting.

use super::FitRequest;
use crate::source::LogSource;

/// How a log's samples are used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Role {
    /// All samples fit; the log is one fold of leave one log out.
    Fit,
    /// All samples validate (reporting only).
    Validation,
    /// All samples fit, and contiguous blocks of them cross-validate (a single fit log).
    Blocks,
}

impl Role {
    /// True for a validation log (its samples are of the held-out kind).
    pub(super) fn validates(self) -> bool {
        self == Role::Validation
    }
}

/// Fit logs first (a single one cross-validated on its blocks), then the validation
/// logs.
pub(super) fn jobs(req: &FitRequest) -> Vec<(LogSource, Role)> {
    let fit_role = if req.logs.len() == 1 {
        Role::Blocks
    } else {
        Role::Fit
    };
    req.logs
        .iter()
        .map(|p| (p.clone(), fit_role))
        .chain(req.validate.iter().map(|p| (p.clone(), Role::Validation)))
        .collect()
}
