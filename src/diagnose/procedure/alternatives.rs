//! What the data cannot tell from the winner of a step: another form of its effect that
//! the held-out likelihood favours, a named effect a winning completion takes the evidence
//! of, look-alikes of other kinds that explain about as much, and candidates of its own
//! family that fit the held-out data as well within noise (not separable).

use super::findings::describe;
use super::outcome::{CandidateScore, Rejection};
use super::score::score;
use super::state::Search;
use super::trial::{Trial, chi2_quantile};
use crate::diagnose::candidate::Role;

/// Among the accepted forms of the winner's effect (a family of forms) whose ranking
/// gain is within `look_alike` of the winner's, the one with the largest held-out
/// likelihood ratio: the summed relative gains rank coarsely, and between forms of one
/// effect the held-out likelihood decides. Look-alikes of other kinds keep the gain
/// order (between two mechanisms a likelihood difference within noise is no evidence).
/// Its index in `scored`, when that is not the winner.
pub(super) fn likeliest_in_band(
    scored: &[(CandidateScore, usize, Option<Trial>)],
    look_alike: f64,
) -> Option<usize> {
    let first = &scored.first()?.0;
    if first.rejected.is_some() || first.forms_of.is_none() {
        return None;
    }
    // Forms of one family share their role, so their gains compare as they are.
    let bar = (1.0 - look_alike) * first.total_gain;
    scored
        .iter()
        .enumerate()
        .filter(|(_, (s, _, _))| {
            s.rejected.is_none() && s.family() == first.family() && s.total_gain >= bar
        })
        .max_by(|a, b| a.1.0.held_out_lr.total_cmp(&b.1.0.held_out_lr))
        .map(|(i, _)| i)
        .filter(|&i| i != 0)
}

impl Search<'_> {
    /// A named effect confounded with the step's winner when that is a completion of
    /// Eq. 22: accepted, explaining at least 1 − [`look_alike`] of the
    /// completion's summed gain, and no longer accepted once the completion is in the
    /// model (the completion takes its evidence). Returns its index in `scored` and
    /// whether it goes first: only when it explains clearly more (by more than
    /// `look_alike`); otherwise the completion keeps its place and the effect is its
    /// look-alike.
    ///
    /// [`look_alike`]: crate::diagnose::DiagnoseOptions::look_alike
    pub(super) fn confounded_with_completion(
        &self,
        scored: &[(CandidateScore, usize, Option<Trial>)],
    ) -> Option<(usize, bool)> {
        let (first, _, Some(with_completion)) = scored.first()? else {
            return None;
        };
        if first.rejected.is_some() || !first.role.is_model_completion() {
            return None;
        }
        let look_alike = self.options.look_alike;
        let (i, (effect, c, _)) = scored.iter().enumerate().skip(1).find(|(_, (s, _, _))| {
            s.rejected.is_none()
                && !s.role.is_model_completion()
                && !s.role.is_unspecific()
                && s.total_gain >= (1.0 - look_alike) * first.total_gain
        })?;
        self.scored_in(*c, with_completion).rejected.as_ref()?;
        Some((i, effect.total_gain > (1.0 + look_alike) * first.total_gain))
    }

    /// A completion of Eq. 22 that explains about as much as the step's winner, a named
    /// effect: the completion missed only the held-out bar (it predicts the held-out data
    /// better than the current model, by less than the bar asks), and the two are within
    /// [`look_alike`] of each other's summed gain; of several, the likeliest.
    /// Completions go before undeclared effects (an effect is judged against a model
    /// with the terms Eq. 22's own assumptions drop), so when the effect is no longer
    /// accepted once the completion is in the model (the completion takes its
    /// evidence), the completion goes first and the effect is its look-alike, as in
    /// [`Self::confounded_with_completion`]; otherwise the effect keeps its place and
    /// the completion is its look-alike. Returns the completion's index in `scored` and
    /// whether it goes first.
    ///
    /// [`look_alike`]: crate::diagnose::DiagnoseOptions::look_alike
    pub(super) fn completion_under_effect(
        &self,
        scored: &[(CandidateScore, usize, Option<Trial>)],
    ) -> Option<(usize, bool)> {
        let (first, c, _) = scored.first()?;
        if first.rejected.is_some() || first.role != Role::Mechanism {
            return None;
        }
        let look_alike = self.options.look_alike;
        let (i, (_, _, Some(with_completion))) = scored
            .iter()
            .enumerate()
            .skip(1)
            .filter(|(_, (s, _, t))| {
                t.is_some()
                    && s.role.is_model_completion()
                    && matches!(s.rejected, Some(Rejection::NotPredictive { .. }))
                    && s.held_out_lr > 0.0
                    && s.total_gain >= (1.0 - look_alike) * first.total_gain
                    && first.total_gain <= (1.0 + look_alike) * s.total_gain
            })
            .max_by(|a, b| a.1.0.held_out_lr.total_cmp(&b.1.0.held_out_lr))?
        else {
            return None;
        };
        Some((i, self.scored_in(*c, with_completion).rejected.is_some()))
    }

    /// Candidate `c` scored against `model` at this step's level and bar.
    fn scored_in(&self, c: usize, model: &Trial) -> CandidateScore {
        let local = self.local_before(c, model);
        let local = local.as_ref().map(|(lf, cv)| (*lf, cv));
        let level = self.level(c);
        score(
            self,
            &model.columns,
            c,
            model,
            local,
            level,
            self.options.min_gain,
        )
        .0
    }

    /// Look-alikes of `best` (candidates of other kinds in its group within `look_alike`
    /// of its gain, significant and plausible) and the findings of its own kind that fit
    /// the held-out data as well within noise (κ χ²₁(1 − α) of its likelihood ratio).
    pub(super) fn alternatives(
        &self,
        best: &CandidateScore,
        others: &[(CandidateScore, usize, Option<Trial>)],
    ) -> (Vec<String>, Vec<String>) {
        let options = self.options;
        // A look-alike, or another form of the winner's effect, may miss a held-out bar
        // the winner just cleared: it explains as much, significantly and plausibly.
        let comparable: Vec<(&CandidateScore, usize)> = others
            .iter()
            .map(|(s, c, _)| (s, *c))
            .filter(|(s, _)| {
                matches!(
                    s.rejected,
                    None | Some(
                        Rejection::NotPredictive { .. }
                            | Rejection::SmallGain { .. }
                            | Rejection::SmallNetGain { .. }
                    )
                )
            })
            .collect();
        let look_alikes = comparable
            .iter()
            .filter(|(s, _)| {
                s.family() != best.family()
                    && s.role.is_model_completion() == best.role.is_model_completion()
                    && s.total_gain >= (1.0 - options.look_alike) * best.total_gain
            })
            .map(|(s, _)| s.name.clone())
            .collect();
        let noise = self.lr_noise();
        let not_separable = comparable
            .iter()
            .filter(|(s, _)| s.family() == best.family() && s.role != Role::Generic)
            .filter(|(s, _)| s.rejected.is_none() || best.forms_of.is_some())
            .filter(|(s, _)| (s.held_out_lr - best.held_out_lr).abs() <= noise)
            .map(|(s, c)| describe(&self.stats.candidates[*c], s))
            .collect();
        (look_alikes, not_separable)
    }

    /// Held-out likelihood-ratio difference within which two candidates fit the held-out
    /// data alike: κ χ²₁(1 − α), one parameter's worth with coloured residuals.
    pub(super) fn lr_noise(&self) -> f64 {
        let o = self.options;
        chi2_quantile(1.0, 1.0 - o.alpha) * o.variance_inflation.max(1.0)
    }
}
