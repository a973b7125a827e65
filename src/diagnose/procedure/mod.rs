//! The closing-the-loop procedure: score every candidate effect on the residual of the
//! current model, add the best one that is significant, plausible and pays on data the
//! model was not fitted on, refit, repeat; then leave out every term, of Eq. 22 or added,
//! that the held-out data do not support.
//!
//! All candidates' columns are accumulated once, next to the base columns, for the fit
//! data and for each cross-validation fold ([`Folds`](crate::estimate::Folds): leave one
//! log out with two or more logs, the segment hold-out of a single log); every trial model
//! is then a column subset of those statistics
//! ([`Accumulator::select`](crate::stats::Accumulator::select)), so no trial re-reads the
//! data.
//! Every decision is made on the folds; data given only for reporting
//! ([`CandidateStatistics::report`], `--validate` logs) are evaluated at the end and
//! never steer a choice, so their figures stay unbiased.
//!
//! A candidate is accepted when
//! 1. its MMR estimates are significant: the joint Wald test of all its parameters has a
//!    P-value below α / (number of named candidates scored in the step) (Bonferroni);
//! 2. it is plausible: every estimate lies in the physical range of its parameter
//!    ([`super::CandidateParameter::range`]);
//! 3. it predicts held-out data better than chance: the held-out likelihood-ratio
//!    statistic Σ_j Σₐ (SSE_before − SSE_after)/σ̂²_ja (σ̂²_ja the current model's held-out
//!    mean square error on fold j, axis a) lies above what a candidate with no effect
//!    reaches at the Bonferroni level (`required_lr`: its null distribution with
//!    coloured residuals): a test on the validation data itself, so the verdict scales
//!    with their noise and length;
//! 4. it pays enough to matter: on some axis the cross-validated NRMSE (the mean over
//!    folds, so each log counts alike) falls by at least [`DiagnoseOptions::min_gain`]
//!    (relative), so does the sum over all axes,
//!    and no axis gets worse by more than [`DiagnoseOptions::max_loss`]. All axes count:
//!    the MMR couples them through shared parameters, so a candidate can pay on an axis
//!    it has no column on. An effect confined to part of the envelope
//!    ([`super::local`]: ground effect, wake interaction, vortex ring) is judged on the
//!    held-out samples where it acts and on the axes it acts on, so a short stretch near
//!    the ground is not diluted by a long flight away from it.
//!
//! After each addition every earlier addition is tested again against the model
//! without it, and withdrawn when it would no longer be accepted (a term that only
//! stood in for the effect found later); to stay it needs half the gain it needed
//! to enter, so a term near the bar does not enter and leave in turn. A withdrawn
//! addition is not offered again, except once when the addition whose retest withdrew
//! it is withdrawn in its turn (it gave way to a term that no longer holds). An effect
//! offered in several forms ([`super::Candidate::forms_of`]) is then given the
//! form the held-out data now favour (largest held-out likelihood ratio). Terms of
//! the generic pool are a family of unnamed hypotheses: at most
//! [`DiagnoseOptions::max_generic`] of them enter a model. An added effect whose
//! held-out fit another candidate of the same kind, or another form of its family,
//! matches within noise (a weak rotor and a stronger rotor diagonally opposite, of
//! the same spin) is reported with it as one finding, not separable with these
//! data.
//!
//! Among accepted candidates, completions of the Eq. 22 structure (terms its own
//! assumptions drop, [`super::Role::Completion`]) are added before undeclared
//! effects; within each group the largest validation gain summed over the axes wins,
//! except that between forms of one effect within [`DiagnoseOptions::look_alike`] of
//! each other the largest held-out likelihood ratio wins.
//! A named effect that the winning completion takes the evidence of (no longer accepted
//! once the completion is in the model) while it explains about as much is reported as
//! the completion's look-alike; when it explains clearly more (by more than
//! [`DiagnoseOptions::look_alike`]) it is added first instead, the completion its
//! look-alike, tried again in the next step. The other way round, a completion that
//! explains about as much as a winning named effect but missed the held-out bar (while
//! still predicting the held-out data better than the current model) is added instead
//! when the effect is no longer accepted once the completion is in, the effect its
//! look-alike; otherwise it is the effect's look-alike.
//! Terms of the
//! generic pool ([`super::generic`]: residual structure with no name, whose Bonferroni
//! divisor is the whole pool it was screened from) and moment coefficients freed from
//! the forces ([`super::Role::is_unspecific`]) compete with named mechanisms, but a named
//! mechanism's gain counts 1 + [`DiagnoseOptions::look_alike`] times: it is preferred
//! when it explains about as much. Candidates of other kinds in the same
//! group whose gain is within [`DiagnoseOptions::look_alike`] of the winner's are
//! reported as look-alikes the data cannot tell apart.
//!
//! **Parsimony.** After the last addition, terms (a parameter's columns on one axis: a
//! row of the FSOA table, or a candidate's columns there) are left out one at a time,
//! the one whose removal costs least first, while the model stays within noise of the best
//! cross-validated score seen: with σ̂²_ja the held-out mean square error of the model
//! after the last addition on fold j and axis a, the score is Σ_j Σₐ SSE_ja/σ̂²_ja and a
//! removal is within noise when it
//! raises the score by at most κ χ²₁(1 − α) above the best, κ the coloured-residual
//! variance inflation ([`DiagnoseOptions::variance_inflation`]): a likelihood-ratio test
//! of one term on held-out residuals. Of two removals that score alike to rounding (one
//! column twice, e.g. an Eq. 22 term and its freed copy) the added effect's term goes,
//! so rounding never picks the term reported. Left-out terms are reported as "not
//! supported by these data". Control-effectiveness terms
//! ([`crate::model::ModelStructure::is_control_effectiveness`]) are never left out.
//!
//! **Eq. 22 where it predicts better.** An axis whose held-out data (all folds pooled)
//! the final model predicts worse than the Eq. 22 model is predicted by the Eq. 22
//! model in the adopted model (`eq22_axes`): the MMR couples the axes through shared
//! parameters, so additions that pay on some axes can cost another a little, and each
//! axis's prediction is its own columns' sum. The report names such axes.
//!
//! The parts, one file each: `outcome` (what the procedure returns), `trial` (a
//! sub-model's fit, cross-validation and tests), `score` (the acceptance rules for one
//! candidate), `state` (the search's current model and what it has tried), `search`
//! (the forward search, with withdrawals and forms chosen again),
//! `alternatives` (look-alikes, and candidates not separable from the winner),
//! `parsimony` (terms left out at the end), `eq22_axes` (the per-axis fallback to Eq.
//! 22), `findings` (one sentence per effect), `below_bar` (named effects the data show
//! that gain too little to be added).

mod alternatives;
mod below_bar;
mod eq22_axes;
mod findings;
mod outcome;
mod parsimony;
mod score;
mod search;
mod state;
mod trial;

pub use super::options::DiagnoseOptions;
pub use outcome::{
    CandidateScore, DiagnoseError, Diagnosis, DiagnosisStep, EffectParameter, Eq22Axes, Rejection,
    Unsupported,
};
pub use search::{diagnose, diagnose_on_threads};
pub use trial::CandidateStatistics;
