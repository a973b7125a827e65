//! The state of the forward search (the current model, what has been tried) and what a
//! step asks of it: a candidate's significance level, the generic-pool limit, the
//! held-out statistics where a local candidate acts.

use super::outcome::CandidateScore;
use super::trial::{CandidateStatistics, Trial};
use crate::diagnose::candidate::Role;
use crate::diagnose::generic;
use crate::diagnose::local::LocalFolds;
use crate::diagnose::options::DiagnoseOptions;
use crate::estimate::{self, CrossValidation, FitOptions};

/// The state of the forward search: the current model and what has been tried.
pub(super) struct Search<'a> {
    pub(super) stats: &'a CandidateStatistics<'a>,
    pub(super) fit_options: &'a FitOptions,
    pub(super) options: &'a DiagnoseOptions,
    /// Columns of the current model (indices into `stats.extended`).
    pub(super) kept: Vec<usize>,
    pub(super) current: Trial,
    /// Candidates added so far, withdrawn or not (not tried again, but see `displaced`).
    pub(super) tried: Vec<usize>,
    /// Withdrawn candidates with the addition whose retest withdrew them: when that
    /// addition is withdrawn in its turn, the candidate is offered again (once).
    pub(super) displaced: Vec<(usize, usize)>,
    /// Candidates offered again after their displacer left (never a second time).
    pub(super) offered_again: Vec<usize>,
    /// Candidates in the current model: index, score when added, the finding.
    pub(super) in_model: Vec<(usize, CandidateScore, String)>,
    /// Named candidates scored in the steps before the current one (the search-wide
    /// Bonferroni count, [`Search::level`]).
    pub(super) earlier_tests: usize,
    /// For each candidate added: the earlier tests when it entered (its later tests,
    /// whether it stays or gives way to another form, are at its entry level).
    pub(super) entry_tests: Vec<(usize, usize)>,
    /// Threads the trial fits of one step share.
    pub(super) threads: usize,
}

impl Search<'_> {
    /// Bonferroni level of candidate `c` in the current step: a named one over every
    /// named candidate scored in the search so far, this step's included (each step
    /// picks the best of those in play, and an unlimited search makes many steps: the
    /// noise of the selection grows with every test, so later additions must pay more);
    /// a generic one over the whole pool it was screened from.
    pub(super) fn level(&self, c: usize) -> f64 {
        self.level_after(c, self.earlier_tests)
    }

    /// [`Search::level`] with `earlier` named tests before the current step.
    pub(super) fn level_after(&self, c: usize, earlier: usize) -> f64 {
        match self.stats.candidates[c].role {
            Role::Generic => self.options.alpha / generic::pool_size() as f64,
            _ => self.options.alpha / (earlier + self.named_in_play()).max(1) as f64,
        }
    }

    /// Named candidates not tried yet.
    pub(super) fn named_in_play(&self) -> usize {
        let stats = self.stats;
        (0..stats.candidates.len())
            .filter(|c| !self.tried.contains(c))
            .filter(|&c| stats.candidates[c].role != Role::Generic)
            .count()
    }

    /// The level candidate `c`, in the model, entered at.
    pub(super) fn entry_level(&self, c: usize) -> f64 {
        let earlier = self
            .entry_tests
            .iter()
            .rev()
            .find(|(e, _)| *e == c)
            .map_or(self.earlier_tests, |(_, t)| *t);
        self.level_after(c, earlier)
    }

    /// True when the current model holds `max_generic` generic-pool terms.
    pub(super) fn generic_full(&self) -> bool {
        let generic = self
            .in_model
            .iter()
            .filter(|(c, _, _)| self.stats.candidates[*c].role == Role::Generic)
            .count();
        generic >= self.options.max_generic
    }

    /// The held-out statistics where candidate `c` acts, with the cross-validation of
    /// the model with columns `columns` there; `None` for a candidate acting everywhere.
    pub(super) fn local_before(
        &self,
        c: usize,
        t: &Trial,
    ) -> Option<(&LocalFolds, CrossValidation)> {
        let lf = self.stats.local.iter().find(|l| l.candidate == c)?;
        let cv =
            estimate::cross_validate(&t.structure, &lf.folds.select(&t.columns), self.fit_options)
                .ok()?;
        Some((lf, cv))
    }
}
