//! The per-axis fallback to Eq. 22: an axis whose held-out data (all folds pooled) the
//! final model predicts worse than the Eq. 22 model is predicted by the Eq. 22 model in
//! the adopted model ([`Eq22Axes`]).
//!
//! The additions and removals are chosen on all axes together, and the MMR couples the
//! axes through shared parameters, so an addition that pays on the moments can move a
//! force's shared coefficients and cost that force a little. Each axis's prediction is a
//! sum of its own columns, so the adopted model can take each axis from whichever model
//! the held-out data favour there: the decision is made on the folds, like every other,
//! and the reporting-only validation logs only measure it.

use super::outcome::{Diagnosis, Eq22Axes, worse_axes};
use super::trial::Trial;
use crate::estimate::AxisMetrics;

/// Makes the adopted model of `d` predict with the Eq. 22 model (`base`) every axis on
/// which the final model predicts the held-out data worse: records the final model's
/// metrics there and replaces them, pooled, per fold and on the validation data, with the
/// Eq. 22 model's.
pub(super) fn fall_back_to_eq22(d: &mut Diagnosis, base: Trial) {
    let axes = worse_axes(&d.before, &d.after);
    if axes.is_empty() {
        return;
    }
    let on_axes = |m: &[AxisMetrics; 6]| -> Vec<AxisMetrics> {
        axes.iter().map(|&a| m[a as usize]).collect()
    };
    let final_held_out = on_axes(&d.after);
    let final_validation = d.validation.as_ref().map(|[_, after]| on_axes(after));
    for &a in &axes {
        let i = a as usize;
        d.after[i] = d.before[i];
        for (before, after) in d.before_folds.iter().zip(&mut d.after_folds) {
            after[i] = before[i];
        }
        if let Some([before, after]) = &mut d.validation {
            after[i] = before[i];
        }
    }
    d.eq22 = Some(Eq22Axes {
        axes,
        final_held_out,
        final_validation,
        structure: base.structure,
        fit: base.fit,
    });
}
