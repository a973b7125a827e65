//! The cross-validation folds of the fit logs' statistics, the same for the Eq. 22 model
//! (first pass) and for the candidate effects (second pass): leave one log out with two
//! or more fit logs, else a single log's hold-out segments.

use super::FitRequest;
use crate::diagnose::local::{LocalFolds, LocalRegions};
use crate::error::Error;
use crate::estimate::Folds;
use crate::stats::Accumulator;

/// Merges statistics of the same structure (they always have its shape).
pub(super) fn merge(into: &mut Accumulator, other: &Accumulator) -> Result<(), Error> {
    into.merge(other).map_err(|source| Error::Accumulate {
        log: "merged statistics".into(),
        source,
    })
}

/// The fit logs' statistics ((fit, held-out) per log, job order) arranged for
/// cross-validation and the final fit: leave one log out with two or more logs, else the
/// log's hold-out segments (which `run` has checked hold samples). Returns the folds and
/// the final fit data: all fit logs, the held-out segments of a single log included only
/// when validation logs report instead.
pub(super) fn arrange(
    req: &FitRequest,
    parts: &[[&Accumulator; 2]],
) -> Result<(Folds, Accumulator), Error> {
    let merged = |pair: &[&Accumulator; 2]| -> Result<Accumulator, Error> {
        let mut a = pair[0].clone();
        merge(&mut a, pair[1])?;
        Ok(a)
    };
    if let [single] = parts {
        let folds = Folds::holdout("hold-out segments", single[0].clone(), single[1].clone());
        let fit = if req.validate.is_empty() {
            single[0].clone()
        } else {
            merged(single)?
        };
        return Ok((folds, fit));
    }
    let logs = parts
        .iter()
        .zip(&req.logs)
        .map(|(pair, source)| Ok((source.name(), merged(pair)?)))
        .collect::<Result<Vec<_>, Error>>()?;
    let folds = Folds::leave_one_out(&logs).map_err(|source| Error::Accumulate {
        log: "leave-one-out folds".into(),
        source,
    })?;
    let mut fit = logs[0].1.clone();
    for (_, a) in &logs[1..] {
        merge(&mut fit, a)?;
    }
    Ok((folds, fit))
}

/// The held-out statistics where each local candidate acts, per fold as [`arrange`]
/// builds the folds (`parts`: each fit log's local statistics, see
/// [`super::second_pass::local_kind`]): the hold-out part of a single log, or each whole
/// log left out. A region with no active held-out sample in some fold is left out
/// (judged globally).
pub(super) fn local_folds(
    regions: &LocalRegions,
    parts: &[Vec<Accumulator>],
    folds: &Folds,
) -> Vec<LocalFolds> {
    let regions = regions.candidates.iter().enumerate();
    regions
        .filter_map(|(r, &candidate)| {
            let tests = parts.iter().map(|log| log[r].clone()).collect();
            LocalFolds::new(candidate, folds, tests)
        })
        .collect()
}
