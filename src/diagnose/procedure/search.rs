//! The forward search: every remaining candidate scored against the current model, the
//! best acceptable one added, earlier additions tested again (withdrawn, or given another
//! form of their family), until none is acceptable or the effect limit is reached; then
//! the parsimony pass.

use super::alternatives::likeliest_in_band;
use super::below_bar::below_bar;
use super::eq22_axes::fall_back_to_eq22;
use super::findings::{describe, finding};
use super::outcome::{CandidateScore, DiagnoseError, Diagnosis, DiagnosisStep, Rejection};
use super::parsimony::prune;
use super::score::{preference, score};
use super::state::Search;
use super::trial::{CandidateStatistics, Trial, trial};
use crate::diagnose::candidate::Role;
use crate::diagnose::options::DiagnoseOptions;
use crate::estimate::{self, CrossValidation, FitOptions, SingularValues};
use crate::model::ParamId;
use crate::util::map_on_threads;

/// Runs the procedure on accumulated candidate statistics.
pub fn diagnose(
    stats: &CandidateStatistics,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    diagnose_on_threads(stats, fit_options, options, 1)
}

/// [`diagnose`] with the independent trial fits of each step (every candidate scored
/// against the current model, every term left out in turn) on up to `threads` threads;
/// the result does not depend on `threads`.
pub fn diagnose_on_threads(
    stats: &CandidateStatistics,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
    threads: usize,
) -> Result<Diagnosis, DiagnoseError> {
    let inflation = options.variance_inflation;
    let kept: Vec<usize> = stats.columns_of(|p| p.index() < stats.base_params);
    let base = trial(stats, &kept, fit_options, inflation)?;
    let mut search = Search {
        stats,
        fit_options,
        options,
        kept,
        current: base.clone(),
        tried: Vec::new(),
        displaced: Vec::new(),
        offered_again: Vec::new(),
        in_model: Vec::new(),
        earlier_tests: 0,
        entry_tests: Vec::new(),
        threads,
    };
    let mut steps = Vec::new();
    let mut stopped_at_limit = false;
    loop {
        // Every addition counts, a candidate offered again and added twice included.
        if search.tried.len() + search.offered_again.len() >= options.max_effects {
            stopped_at_limit = search.tried.len() < stats.candidates.len();
            break;
        }
        let in_play = search.named_in_play();
        let Some((mut step, winner)) = search.forward_step() else {
            break;
        };
        let Some((c, t)) = winner else {
            steps.push(step);
            break;
        };
        search.entry_tests.push((c, search.earlier_tests));
        search.earlier_tests += in_play;
        search.tried.push(c);
        search.kept = t.columns.clone();
        search.current = t;
        let said = finding(
            &stats.candidates[c],
            &step.ranking[0],
            &step.not_separable,
            &step.look_alikes,
        );
        search.in_model.push((c, step.ranking[0].clone(), said));
        step.withdrawn = search.retest(c);
        steps.push(step);
    }
    let Search {
        mut kept,
        mut current,
        in_model,
        ..
    } = search;
    let unsupported = prune(
        stats,
        &mut kept,
        &mut current,
        fit_options,
        options,
        threads,
    );
    let named_only = named_only(stats, &current, &in_model, fit_options, inflation)?;
    let validation = stats
        .report
        .map(|r| -> Result<_, DiagnoseError> {
            let on_report = |t: &Trial| {
                estimate::evaluate(&t.structure, &t.fit.mmr.theta, &r.select(&t.columns))
            };
            Ok([on_report(&base)?, on_report(&current)?])
        })
        .transpose()?;
    let fold_metrics =
        |cv: &CrossValidation| (0..cv.folds.len()).map(|j| cv.fold_metrics(j)).collect();
    let fitted = stats.fit.select(&current.columns);
    // The adopted model's trial fit again, with its condition numbers: the same estimates.
    let mut fit = estimate::fit_without_fsoa(
        &current.structure,
        &fitted,
        fit_options,
        SingularValues::Always,
    )?;
    estimate::add_fsoa_tables(&mut fit, &current.structure, &fitted, fit_options)?;
    let before_folds = fold_metrics(&base.cv);
    let findings = in_model.iter().map(|(_, _, said)| said.clone()).collect();
    let effects_added: Vec<CandidateScore> = in_model.into_iter().map(|(_, s, _)| s).collect();
    let mut diagnosis = Diagnosis {
        below_bar: below_bar(steps.last(), &effects_added, options.min_gain),
        steps,
        findings,
        effects_added,
        stopped_at_limit,
        unsupported,
        folds: stats.folds.names.clone(),
        before: base.cv.pooled_metrics(),
        after: current.cv.pooled_metrics(),
        named_only,
        before_folds,
        after_folds: fold_metrics(&current.cv),
        validation,
        eq22: None,
        remainder: Vec::new(),
        theta: fit.mmr.theta.clone(),
        std: current.std,
        structure: current.structure,
        columns: current.columns,
        fit,
    };
    fall_back_to_eq22(&mut diagnosis, base);
    Ok(diagnosis)
}

/// The cross-validated metrics of `current` without the columns of its unspecific
/// additions (`in_model`), all folds pooled; `None` when it has none.
fn named_only(
    stats: &CandidateStatistics,
    current: &Trial,
    in_model: &[(usize, CandidateScore, String)],
    fit_options: &FitOptions,
    inflation: f64,
) -> Result<Option<[crate::estimate::AxisMetrics; 6]>, DiagnoseError> {
    let unspecific: Vec<ParamId> = in_model
        .iter()
        .filter(|(c, _, _)| stats.candidates[*c].role.is_unspecific())
        .flat_map(|(c, _, _)| stats.candidate_params[*c].iter().copied())
        .collect();
    let named: Vec<usize> = current
        .columns
        .iter()
        .copied()
        .filter(|&j| !unspecific.contains(&stats.extended.columns[j].param))
        .collect();
    if named.len() == current.columns.len() {
        return Ok(None);
    }
    Ok(Some(
        trial(stats, &named, fit_options, inflation)?
            .cv
            .pooled_metrics(),
    ))
}

impl Search<'_> {
    /// One forward step: every remaining candidate scored against the current model,
    /// ranked; the winner (candidate index and its trial) when one is acceptable. `None`
    /// when no candidate remains.
    fn forward_step(&self) -> Option<(DiagnosisStep, Option<(usize, Trial)>)> {
        let stats = self.stats;
        let options = self.options;
        // A form of an effect offered in several, one of which is in the model.
        let has_form = |c: usize| {
            stats.candidates[c].forms_of.is_some_and(|family| {
                self.in_model
                    .iter()
                    .any(|(m, _, _)| stats.candidates[*m].family() == family)
            })
        };
        let remaining: Vec<usize> = (0..stats.candidates.len())
            .filter(|c| !self.tried.contains(c))
            .filter(|&c| !has_form(c))
            .collect();
        if remaining.is_empty() {
            return None;
        }
        let generic_full = self.generic_full();
        let mut scored: Vec<(CandidateScore, usize, Option<Trial>)> =
            map_on_threads(&remaining, self.threads, |&c| {
                let local = self.local_before(c, &self.current);
                let local = local.as_ref().map(|(lf, cv)| (*lf, cv));
                let mut s = score(
                    self,
                    &self.kept,
                    c,
                    &self.current,
                    local,
                    self.level(c),
                    options.min_gain,
                );
                if generic_full && s.0.role == Role::Generic && s.0.rejected.is_none() {
                    s.0.rejected = Some(Rejection::GenericLimit {
                        limit: options.max_generic,
                    });
                }
                s
            });
        // Accepted first; among them completions of the Eq. 22 structure before
        // undeclared effects (so an effect is judged against a model that already has
        // the terms its own assumptions drop), and named hypotheses before unspecific
        // ones unless those explain clearly more (`unspecific_margin`); then by
        // validation gain.
        let (look_alike, margin) = (options.look_alike, options.unspecific_margin);
        scored.sort_by(|a, b| {
            let key = |s: &CandidateScore| {
                let ok = s.rejected.is_none();
                (ok, ok && s.role.is_model_completion())
            };
            key(&a.0)
                .cmp(&key(&b.0))
                .then(preference(&a.0, margin).total_cmp(&preference(&b.0, margin)))
                .reverse()
        });
        if let Some(i) = likeliest_in_band(&scored, look_alike) {
            let likeliest = scored.remove(i);
            scored.insert(0, likeliest);
        }
        let confounded = self
            .confounded_with_completion(&scored)
            .map(|(i, first)| {
                if first {
                    let effect = scored.remove(i);
                    scored.insert(0, effect);
                    1
                } else {
                    i
                }
            })
            .map(|i| scored[i].0.name.clone());
        let under_effect = self.completion_under_effect(&scored).map(|(i, first)| {
            if first {
                let mut completion = scored.remove(i);
                completion.0.rejected = None;
                scored.insert(0, completion);
                scored[1].0.name.clone()
            } else {
                scored[i].0.name.clone()
            }
        });
        let best_ok = scored
            .first()
            .filter(|s| s.0.rejected.is_none())
            .map(|s| s.0.clone());
        let (mut look_alikes, not_separable) = best_ok
            .as_ref()
            .map(|best| self.alternatives(best, &scored[1..]))
            .unwrap_or_default();
        look_alikes.extend(confounded);
        look_alikes.extend(under_effect);
        let mut ranking: Vec<CandidateScore> = Vec::with_capacity(scored.len());
        let mut winner = None;
        for (i, (s, c, t)) in scored.into_iter().enumerate() {
            if i == 0 && s.rejected.is_none() {
                winner = t.map(|t| (c, t));
            }
            ranking.push(s);
        }
        let step = DiagnosisStep {
            ranking,
            added: winner.as_ref().map(|_| 0),
            look_alikes,
            not_separable,
            withdrawn: Vec::new(),
        };
        Some((step, winner))
    }

    /// Tests every earlier addition again against the current model without it, and
    /// withdraws those no longer accepted (all but `latest`); returns them with the
    /// reason.
    fn retest(&mut self, latest: usize) -> Vec<String> {
        let mut withdrawn = Vec::new();
        let earlier: Vec<usize> = self
            .in_model
            .iter()
            .map(|(c, _, _)| *c)
            .filter(|&c| c != latest)
            .collect();
        for e in earlier {
            let stats = self.stats;
            let own = stats.columns_of(|p| stats.candidate_params[e].contains(&p));
            let without: Vec<usize> = self
                .kept
                .iter()
                .copied()
                .filter(|j| !own.contains(j))
                .collect();
            let Ok(reduced) = trial(
                stats,
                &without,
                self.fit_options,
                self.options.variance_inflation,
            ) else {
                continue;
            };
            let local = self.local_before(e, &reduced);
            let local = local.as_ref().map(|(lf, cv)| (*lf, cv));
            // Half the entry gain to stay (a stepwise rule's removal threshold below its
            // entry threshold, so a term near the bar does not enter and leave in turn).
            let stay = 0.5 * self.options.min_gain;
            let level = self.entry_level(e);
            let (s, _, _) = score(self, &without, e, &reduced, local, level, stay);
            if let Some(why) = s.rejected {
                withdrawn.push(format!("{}: {why}", s.name));
                self.kept = without;
                self.current = reduced;
                self.in_model.retain(|(c, _, _)| *c != e);
                self.withdraw(e, latest);
            } else if let Some(said) = self.rechoose_form(e, &s, &without, &reduced, stay) {
                withdrawn.push(said);
            }
        }
        withdrawn
    }

    /// Records that the retest after adding `latest` withdrew `e`, and offers again the
    /// candidates `e`'s own addition had withdrawn: they gave way to a term that no
    /// longer holds, so the search judges them against the model without it (each
    /// once, so that the search ends).
    fn withdraw(&mut self, e: usize, latest: usize) {
        let (again, kept): (Vec<_>, Vec<_>) = self
            .displaced
            .iter()
            .partition(|&&(d, by)| by == e && !self.offered_again.contains(&d));
        self.displaced = kept;
        for (d, _) in again {
            self.tried.retain(|&c| c != d);
            self.offered_again.push(d);
        }
        self.displaced.push((e, latest));
    }

    /// For an earlier addition `e` offered in several forms (`in_use` its score against
    /// `reduced`, the model without it, whose columns are `without`): the form the
    /// held-out data now favour, chosen again after later additions (an earlier choice
    /// can rest on structure a later term took). Swaps it in when another form of the
    /// family is accepted (at the bar to stay, as the form in use) with a larger held-out
    /// likelihood ratio and says so; forms within noise of each other are reported as not
    /// separable.
    fn rechoose_form(
        &mut self,
        e: usize,
        in_use: &CandidateScore,
        without: &[usize],
        reduced: &Trial,
        stay: f64,
    ) -> Option<String> {
        let stats = self.stats;
        let family = stats.candidates[e].forms_of?;
        let in_model: Vec<usize> = self.in_model.iter().map(|(c, _, _)| *c).collect();
        let forms: Vec<usize> = (0..stats.candidates.len())
            .filter(|&f| stats.candidates[f].family() == family && !in_model.contains(&f))
            .collect();
        let (best, c, trial) = map_on_threads(&forms, self.threads, |&f| {
            let local = self.local_before(f, reduced);
            let local = local.as_ref().map(|(lf, cv)| (*lf, cv));
            score(self, without, f, reduced, local, self.entry_level(e), stay)
        })
        .into_iter()
        .filter(|(s, _, _)| s.rejected.is_none())
        .max_by(|a, b| a.0.held_out_lr.total_cmp(&b.0.held_out_lr))?;
        let trial = trial.filter(|_| best.held_out_lr > in_use.held_out_lr)?;
        let alike = if best.held_out_lr - in_use.held_out_lr <= self.lr_noise() {
            vec![describe(&stats.candidates[e], in_use)]
        } else {
            Vec::new()
        };
        let said = format!(
            "{}: the form {} fits the held-out data better now (likelihood ratio {:.1} against {:.1})",
            in_use.name, best.name, best.held_out_lr, in_use.held_out_lr
        );
        let entry = (
            c,
            best.clone(),
            finding(&stats.candidates[c], &best, &alike, &[]),
        );
        if let Some(slot) = self.in_model.iter_mut().find(|(f, _, _)| *f == e) {
            *slot = entry;
        }
        let entered = self
            .entry_tests
            .iter()
            .find(|(f, _)| *f == e)
            .map(|&(_, t)| t);
        self.entry_tests.extend(entered.map(|t| (c, t)));
        self.tried.push(c);
        self.kept = trial.columns.clone();
        self.current = trial;
        Some(said)
    }
}
