//! The cross-validation folds of the fit logs' statistics, the same for the Eq. 22 model
//! (first pass) and for the candidate effects (second pass): leave one log out with two
//! or more fit logs, else a single log's contiguous blocks.

use super::FitRequest;
use super::blocks::BlockPlan;
use super::request::group_order;
use crate::diagnose::local::{LocalFolds, LocalRegions};
use crate::error::Error;
use crate::estimate::Folds;
use crate::model::ModelStructure;
use crate::stats::Accumulator;

/// Merges statistics of the same structure (they always have its shape).
pub(super) fn merge(into: &mut Accumulator, other: &Accumulator) -> Result<(), Error> {
    into.merge(other).map_err(|source| Error::Accumulate {
        log: "merged statistics".into(),
        source,
    })
}

/// The fit logs' statistics (per fit log in job order, its pieces: one for each of
/// several logs, the pieces of `plan` for a single log) arranged for cross-validation
/// and the final fit: leave one log out with two or more logs, else the single log's
/// contiguous blocks ([`BlockPlan::folds`]). Returns the folds and the final fit data,
/// all fit samples.
pub(super) fn arrange(
    req: &FitRequest,
    structure: &ModelStructure,
    plan: Option<&BlockPlan>,
    parts: &[&[Accumulator]],
) -> Result<(Folds, Accumulator), Error> {
    if let (Some(plan), [single]) = (plan, parts) {
        return plan
            .folds(structure, single)
            .map_err(|source| Error::Accumulate {
                log: "block folds".into(),
                source,
            });
    }
    let logs = parts
        .iter()
        .zip(&req.logs)
        .map(|(pieces, source)| (source.name(), pieces[0].clone()))
        .collect::<Vec<_>>();
    let left_out = match grouped(&req.groups, &logs, |a, b| merge(&mut a.1, &b.1))? {
        Some(groups) => groups
            .into_iter()
            .map(|(name, (_, stats))| (name, stats))
            .collect(),
        None => logs.clone(),
    };
    let folds = Folds::leave_one_out(&left_out).map_err(|source| Error::Accumulate {
        log: "leave-one-out folds".into(),
        source,
    })?;
    let mut fit = logs[0].1.clone();
    for (_, a) in &logs[1..] {
        merge(&mut fit, a)?;
    }
    Ok((folds, fit))
}

/// The fit logs' `per_log` items (in fit-log order) merged per cross-validation group of
/// `groups` (one name per log), the groups in order of first appearance and each
/// group's logs merged in log order, named `group <name>`; `None` without groups (each
/// log is its own fold).
pub(super) fn grouped<T: Clone>(
    groups: &[String],
    per_log: &[T],
    mut merge: impl FnMut(&mut T, &T) -> Result<(), Error>,
) -> Result<Option<Vec<(String, T)>>, Error> {
    if groups.is_empty() {
        return Ok(None);
    }
    let mut out = Vec::new();
    for name in group_order(groups) {
        let mut members = groups.iter().zip(per_log).filter(|(g, _)| *g == name);
        let Some((_, first)) = members.next() else {
            continue;
        };
        let mut merged = first.clone();
        for (_, item) in members {
            merge(&mut merged, item)?;
        }
        out.push((format!("group {name}"), merged));
    }
    Ok(Some(out))
}

/// The held-out statistics where each local candidate acts, per fold as [`arrange`]
/// builds the folds (`parts`: the local statistics of each fold's held-out samples, per
/// region, see [`super::pass_share::LocalGroup`]): a block of a single log, or a whole
/// log left out. A region with fewer active held-out samples than it needs in some fold
/// is left out (judged globally).
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
