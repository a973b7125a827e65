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
    /// Candidates added so far, withdrawn or not (never tried again).
    pub(super) tried: Vec<usize>,
    /// Candidates in the current model: index, score when added, the finding.
    pub(super) in_model: Vec<(usize, CandidateScore, String)>,
    /// Threads the trial fits of one step share.
    pub(super) threads: usize,
}

impl Search<'_> {
    /// Bonferroni level of candidate `c` in a step: named candidates over those still in
    /// play; generic ones over the whole pool they were screened from.
    pub(super) fn level(&self, c: usize) -> f64 {
        let stats = self.stats;
        let named = (0..stats.candidates.len())
            .filter(|c| !self.tried.contains(c))
            .filter(|&c| stats.candidates[c].role != Role::Generic)
            .count();
        match stats.candidates[c].role {
            Role::Generic => self.options.alpha / generic::pool_size() as f64,
            _ => self.options.alpha / named.max(1) as f64,
        }
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
