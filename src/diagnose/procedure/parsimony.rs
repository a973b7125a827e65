//! Parsimony: after the last addition, terms (a parameter's columns on one axis) are left
//! out one at a time, the cheapest first, while the model stays within noise of the best
//! cross-validated score (module docs of the procedure).

use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::outcome::Unsupported;
use super::trial::{CandidateStatistics, Trial, held_out, trial_with_held_out};
use crate::diagnose::options::DiagnoseOptions;
use crate::estimate::{CrossValidation, FitOptions};
use crate::model::ParamId;
use crate::sample::Axis;
use crate::util::map_on_threads;

/// Cross-validation score Σ_j Σₐ SSE_ja/σ̂²_ja of `cv`: each fold j's held-out errors on
/// axis a in units of the reference model's mean square error there (`scale`).
fn cv_score(cv: &CrossValidation, scale: &[[f64; 6]]) -> f64 {
    cv.folds
        .iter()
        .zip(scale)
        .flat_map(|(f, v)| f.iter().zip(v).map(|(s, v)| s.sse / v))
        .sum()
}

/// Cross-validation scores this close (relative) are one score: the same model to
/// rounding. A score is about six times the held-out sample count (each SSE in units of
/// its mean square), so 1e-12 of it stays far below the noise bound κ χ²₁(1 − α) ≥ 2.7
/// for any log, and far above the rounding of the sums (~1e-16 relative).
const SCORE_TIE: f64 = 1e-12;

/// Leaving out one term of the current model, as scored on the folds.
struct Removal {
    /// The term: a parameter's columns on one axis.
    term: (ParamId, Axis),
    /// Cross-validation score of the model without it.
    score: f64,
    /// Columns of the model without it (indices into `stats.extended`).
    without: Vec<usize>,
    /// Its held-out errors.
    cv: CrossValidation,
}

/// Leaves out terms (a parameter's columns on one axis) of the model with columns `kept`
/// one at a time while it stays within noise of the best cross-validated score (module
/// docs); returns them in order.
pub(super) fn prune(
    stats: &CandidateStatistics,
    kept: &mut Vec<usize>,
    current: &mut Trial,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
    threads: usize,
) -> Vec<Unsupported> {
    let scale: Vec<[f64; 6]> = current
        .cv
        .folds
        .iter()
        .map(|f| f.map(|s| (s.sse / s.n).max(f64::MIN_POSITIVE)))
        .collect();
    let Ok(chi2) = ChiSquared::new(1.0) else {
        return Vec::new();
    };
    let noise = options.variance_inflation.max(1.0) * chi2.inverse_cdf(1.0 - options.alpha);
    let mut best = cv_score(&current.cv, &scale);
    let mut out = Vec::new();
    loop {
        let column = |j: usize| &stats.extended.columns[j];
        // Control-effectiveness terms stay: a model without them is no use for control
        // design, whatever their share of the held-out variance.
        let mut terms: Vec<(ParamId, Axis)> = kept
            .iter()
            .filter(|&&j| !stats.extended.is_control_effectiveness(j))
            .map(|&j| (column(j).param, column(j).axis))
            .collect();
        terms.sort_unstable();
        terms.dedup();
        if terms.is_empty() {
            break;
        }
        // Each removal scored on the folds only; the one chosen is then fitted in full.
        let mut removals: Vec<Removal> = map_on_threads(&terms, threads, |&term| {
            let without: Vec<usize> = kept
                .iter()
                .copied()
                .filter(|&j| (column(j).param, column(j).axis) != term)
                .collect();
            let structure = stats.extended.select_columns(&without);
            let cv = held_out(stats, &structure, &without, fit_options).ok()?;
            Some(Removal {
                term,
                score: cv_score(&cv, &scale),
                without,
                cv,
            })
        })
        .into_iter()
        .flatten()
        .collect();
        let chosen = loop {
            let Some(i) = cheapest(0..removals.len(), |&i| removals[i].score) else {
                break None;
            };
            if removals[i].score > best + noise {
                break None;
            }
            // A removal whose fit on all data fails is no trial model: the next cheapest.
            // Its held-out errors are those just scored.
            let r = &removals[i];
            match trial_with_held_out(
                stats,
                &r.without,
                r.cv.clone(),
                fit_options,
                options.variance_inflation,
            ) {
                Ok(t) => break Some((r.term, r.score, t)),
                Err(_) => {
                    removals.remove(i);
                }
            }
        };
        let Some(((param, axis), score, t)) = chosen else {
            break;
        };
        out.push(Unsupported {
            name: format!("{} on {axis}", stats.extended.param(param).name),
            score_change: score - best,
        });
        best = best.min(score);
        *kept = t.columns.clone();
        *current = t;
    }
    out
}

/// The removal with the smallest `score` among `removals` (in term order, (parameter,
/// axis)); of two that score alike to rounding ([`SCORE_TIE`]: one column twice, e.g. an
/// Eq. 22 term and its freed copy) the later, an added effect's term before Eq. 22's,
/// whatever the rounding.
fn cheapest<T>(removals: impl IntoIterator<Item = T>, score: impl Fn(&T) -> f64) -> Option<T> {
    removals.into_iter().reduce(|cheapest, next| {
        let s = score(&cheapest);
        if score(&next) <= s + SCORE_TIE * s.abs() {
            next
        } else {
            cheapest
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The smallest score is left out first; scores equal to rounding go to the later
    /// term, so a rounding of 1e-16 never picks which of two equal columns is reported.
    #[test]
    fn removals_that_tie_to_rounding_leave_out_the_later_term() {
        let score = |r: &(char, f64)| r.1;
        let tied = 1.2e6 * (1.0 + 1e-15);
        assert_eq!(
            cheapest([('a', 1.2e6), ('b', tied), ('c', 1.3e6)], score),
            Some(('b', tied))
        );
        assert_eq!(
            cheapest([('a', tied), ('b', 1.2e6)], score),
            Some(('b', 1.2e6))
        );
        // Apart by far less than any noise bound, but more than rounding: the smaller.
        assert_eq!(
            cheapest([('a', 1.2e6), ('b', 1.2e6 + 1e-3)], score),
            Some(('a', 1.2e6))
        );
        assert_eq!(
            cheapest([('a', 3.0), ('b', 2.0), ('c', 4.0)], score),
            Some(('b', 2.0))
        );
        assert_eq!(cheapest(Vec::<(char, f64)>::new(), score), None);
    }
}
