//! What the procedure returns: each step's scored candidates, the effects added, the
//! findings, the terms left out, and the metrics before and after.

use serde::Serialize;

use crate::estimate::remainder::AxisRemainder;

use crate::diagnose::candidate::{EffectKind, Reading, Role};
use crate::estimate::{AxisMetrics, EstimateError, Fit};
use crate::model::{ModelStructure, ParamOrigin};
use crate::sample::Axis;
use crate::stats::AccumulateError;

/// One estimated candidate parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EffectParameter {
    /// Parameter name.
    pub name: String,
    /// Estimate.
    pub estimate: f64,
    /// Standard deviation.
    pub std: f64,
    /// Unit.
    pub unit: String,
    /// Two-sided P-value.
    pub p: f64,
    /// How the estimate reads (from the candidate's parameter).
    pub reading: Reading,
}

/// A candidate as scored in one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore {
    /// Candidate name.
    pub name: String,
    /// Effect kind.
    pub kind: EffectKind,
    /// What kind of hypothesis it is (from the candidate).
    pub role: Role,
    /// The effect it is one form of, for a form of an effect offered in several (from the
    /// candidate).
    pub forms_of: Option<EffectKind>,
    /// Axes it acts on.
    pub axes: Vec<Axis>,
    /// Estimates with the candidate added.
    pub parameters: Vec<EffectParameter>,
    /// Relative validation-NRMSE reduction per axis (positive = better), Fx…Mz.
    pub validation_gain: [f64; 6],
    /// Sum of the gains over all six axes (losses count negative).
    pub total_gain: f64,
    /// Held-out likelihood-ratio statistic against the model before it (module docs).
    pub held_out_lr: f64,
    /// For an effect confined to part of the envelope: the relative validation-NRMSE
    /// reduction per axis on the held-out samples where it acts, Fx…Mz.
    pub local_gain: Option<[f64; 6]>,
    /// Share of the held-out samples where it acts (1 for effects acting everywhere).
    pub active_share: f64,
    /// P-value of the joint Wald test that all its parameters are zero (one test per
    /// candidate, however many parameters it has).
    pub p: f64,
    /// Why it was not accepted (`None` when it was acceptable).
    pub rejected: Option<Rejection>,
}

impl CandidateScore {
    /// The effect it is a form of ([`CandidateScore::forms_of`]), else its kind.
    pub fn family(&self) -> EffectKind {
        self.forms_of.unwrap_or(self.kind)
    }
}

/// Why a candidate effect was not accepted in a step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Rejection {
    /// Its model could not be estimated (the message says why).
    NotEstimable(String),
    /// The joint Wald test does not reject "all its parameters are zero".
    NotSignificant {
        /// P-value of the joint test.
        p: f64,
        /// The (multiple-testing corrected) level it had to beat.
        level: f64,
    },
    /// The held-out likelihood ratio is within what chance gives.
    NotPredictive {
        /// Held-out likelihood-ratio statistic.
        statistic: f64,
        /// κ χ²_k(1 − level) it had to reach.
        required: f64,
    },
    /// The model already holds [`DiagnoseOptions::max_generic`] generic-pool terms.
    ///
    /// [`DiagnoseOptions::max_generic`]: crate::diagnose::DiagnoseOptions::max_generic
    GenericLimit {
        /// The limit.
        limit: usize,
    },
    /// A parameter outside its physical range.
    Implausible {
        /// Parameter name.
        parameter: String,
        /// Its estimate, in `unit`.
        value: f64,
        /// Unit of the estimate.
        unit: String,
    },
    /// No axis gains enough cross-validated NRMSE.
    SmallGain {
        /// Largest relative gain over the axes.
        gain: f64,
        /// Gain required.
        required: f64,
    },
    /// The gains summed over the axes (losses negative) are too small.
    SmallNetGain {
        /// Summed gain.
        gain: f64,
        /// Gain required.
        required: f64,
    },
    /// Cross-validated NRMSE rises too much on some axis.
    Loss {
        /// Largest relative loss.
        loss: f64,
    },
}

impl std::fmt::Display for Rejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotEstimable(m) => write!(f, "cannot be estimated: {m}"),
            Self::NotSignificant { p, level } => {
                write!(f, "not significant (P = {p:.2e} >= {level:.2e})")
            }
            Self::Implausible {
                parameter,
                value,
                unit,
            } => write!(f, "implausible {parameter} = {value:.4e} {unit}"),
            Self::SmallGain { gain, required } => write!(
                f,
                "validation gain {:.1} % below {:.1} %",
                100.0 * gain,
                100.0 * required
            ),
            Self::SmallNetGain { gain, required } => write!(
                f,
                "net validation gain over all axes {:.1} % below {:.1} %",
                100.0 * gain,
                100.0 * required
            ),
            Self::NotPredictive {
                statistic,
                required,
            } => write!(
                f,
                "held-out likelihood ratio {statistic:.1} below {required:.1}"
            ),
            Self::GenericLimit { limit } => {
                write!(f, "the model already holds {limit} generic term(s)")
            }
            Self::Loss { loss } => {
                write!(f, "validation worse by {:.1} % on an axis", 100.0 * loss)
            }
        }
    }
}

/// One step of the procedure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DiagnosisStep {
    /// Candidates, best first.
    pub ranking: Vec<CandidateScore>,
    /// The effect added in this step (index into `ranking`), if any.
    pub added: Option<usize>,
    /// Other kinds the data cannot tell apart from the added one.
    pub look_alikes: Vec<String>,
    /// Candidates of the added one's kind whose held-out fit equals it within noise, as
    /// findings (e.g. "rotor 1 stronger by 10.2 %").
    pub not_separable: Vec<String>,
    /// Earlier additions withdrawn after this one, or replaced by another form of their
    /// family, with the reason.
    pub withdrawn: Vec<String>,
}

/// A term (a parameter's columns on one axis) left out of the final model because
/// held-out data do not support it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unsupported {
    /// The term, `parameter on axis`.
    pub name: String,
    /// Rise of the cross-validation score Σ_j Σₐ SSE_ja/σ̂²_ja when it is left out, relative to
    /// the best model (negative: the model predicts better without it).
    pub score_change: f64,
}

/// Result of the procedure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// Steps in order; the last one adds nothing (or the effect limit was reached).
    pub steps: Vec<DiagnosisStep>,
    /// Effects added, in order (without those withdrawn later).
    pub effects_added: Vec<CandidateScore>,
    /// One sentence per effect added, with what the data cannot tell it from.
    pub findings: Vec<String>,
    /// Named effects the last step found significant, plausible and predictive on
    /// held-out data that gain too little to be added (but at least half the bar), one
    /// sentence each (`below_bar`).
    pub below_bar: Vec<String>,
    /// The search stopped at [`DiagnoseOptions::max_effects`] with candidates left.
    ///
    /// [`DiagnoseOptions::max_effects`]: crate::diagnose::DiagnoseOptions::max_effects
    pub stopped_at_limit: bool,
    /// Terms left out of the final model (of Eq. 22 or added), in order.
    pub unsupported: Vec<Unsupported>,
    /// Names of the cross-validation folds' test data (logs left out, or the hold-out).
    pub folds: Vec<String>,
    /// Cross-validated metrics of the base model, all folds pooled.
    pub before: [AxisMetrics; 6],
    /// Cross-validated metrics of the adopted model (the final model, predicting the axes
    /// of [`Diagnosis::eq22`] with Eq. 22), all folds pooled.
    pub after: [AxisMetrics; 6],
    /// Cross-validated metrics (all folds pooled) of the final model without its
    /// unspecific terms (freed coefficients, generic terms): what the named mechanisms
    /// and completions carry. `None` when the final model has no unspecific term.
    pub named_only: Option<[AxisMetrics; 6]>,
    /// Per fold, the base model's metrics.
    pub before_folds: Vec<[AxisMetrics; 6]>,
    /// Per fold, the adopted model's metrics.
    pub after_folds: Vec<[AxisMetrics; 6]>,
    /// Base and adopted model (each fitted on all fit data) on the reporting-only
    /// validation data, when given: no decision saw these data.
    pub validation: Option<[[AxisMetrics; 6]; 2]>,
    /// The axes the adopted model predicts with the Eq. 22 model, because the final model
    /// predicted their held-out data worse; `None` when there are none.
    pub eq22: Option<Eq22Axes>,
    /// What is left in each moment axis's residual of the final model: its correlation
    /// with the axis's rotor signals over lags (filled in by the fit pipeline on time
    /// series; empty otherwise).
    pub remainder: Vec<AxisRemainder>,
    /// θ̂ of the final model over `structure.params`.
    pub theta: Vec<f64>,
    /// Standard deviations of `theta` (0 for parameters dropped as unidentifiable).
    pub std: Vec<f64>,
    /// Structure of the final model.
    #[serde(skip)]
    pub structure: ModelStructure,
    /// The columns of the extended structure (base and candidate effects) that
    /// `structure` keeps, ascending.
    #[serde(skip)]
    pub columns: Vec<usize>,
    /// The final model's estimation on all fit data (FSOA tables, MMR estimates with
    /// white-residual σ and covariance, fit metrics).
    #[serde(skip)]
    pub fit: Fit,
}

/// The axes on which the final model predicts the held-out data (all folds pooled) worse
/// than the Eq. 22 model, beyond rounding (RMSE higher by more than 1e-9, relative). The
/// additions and removals are chosen on all axes together, through parameters the axes
/// share, so one axis can lose a little while the others gain much: the adopted model
/// predicts such an axis with the Eq. 22 model, which the held-out data favour there.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Eq22Axes {
    /// The axes, in [`Axis`] order.
    pub axes: Vec<Axis>,
    /// The final model's cross-validated metrics on them (all folds pooled).
    pub final_held_out: Vec<AxisMetrics>,
    /// The final model's metrics on them on the reporting-only validation data, when
    /// given.
    pub final_validation: Option<Vec<AxisMetrics>>,
    /// The Eq. 22 model's structure.
    #[serde(skip)]
    pub structure: ModelStructure,
    /// The Eq. 22 model's estimation on all fit data.
    #[serde(skip)]
    pub fit: Fit,
}

/// How the adopted model names the Eq. 22 parameter `name` copied to `axis`.
fn eq22_copy_name(name: &str, axis: Axis) -> String {
    format!("{name}@{axis} (Eq. 22)")
}

impl Diagnosis {
    /// The adopted model: the final model ([`Diagnosis::structure`]) with its columns on
    /// the [`Diagnosis::eq22`] axes replaced by the Eq. 22 model's, each Eq. 22 parameter
    /// there a parameter of its own, `<parameter>@<axis> (Eq. 22)`; and where each of its
    /// parameters takes its value from (own: the final model's θ̂, other: Eq. 22's).
    pub fn adopted(&self) -> (ModelStructure, Vec<ParamOrigin>) {
        match &self.eq22 {
            Some(e) => self
                .structure
                .with_axes_of(&e.structure, &e.axes, eq22_copy_name),
            None => (
                self.structure.clone(),
                self.structure.param_ids().map(ParamOrigin::Own).collect(),
            ),
        }
    }

    /// The values of the adopted model's parameters with `origins` (from
    /// [`Diagnosis::adopted`]): the final model's θ̂ and the Eq. 22 model's.
    pub fn adopted_values(&self, origins: &[ParamOrigin]) -> Vec<f64> {
        let eq22 = self.eq22.as_ref().map_or(&[][..], |e| &e.fit.mmr.theta[..]);
        origins.iter().map(|o| o.value(&self.theta, eq22)).collect()
    }

    /// The adopted model ([`Diagnosis::adopted`]) and its θ̂.
    pub fn adopted_theta(&self) -> (ModelStructure, Vec<f64>) {
        let (structure, origins) = self.adopted();
        let theta = self.adopted_values(&origins);
        (structure, theta)
    }

    /// Axes on which the adopted model predicts the reporting-only validation logs, when
    /// given, worse than the Eq. 22 model: no decision saw these data.
    pub fn worse_on_validation(&self) -> Vec<Axis> {
        self.validation
            .as_ref()
            .map_or_else(Vec::new, |[before, after]| worse_axes(before, after))
    }
}

/// Axes whose RMSE is higher `after` than `before` beyond rounding (1e-9 relative).
pub(super) fn worse_axes(before: &[AxisMetrics], after: &[AxisMetrics]) -> Vec<Axis> {
    before
        .iter()
        .zip(after)
        .filter(|(b, a)| a.rmse > b.rmse * (1.0 + 1e-9))
        .map(|(b, _)| b.axis)
        .collect()
}

/// Why the procedure could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// The base model itself could not be fitted from the statistics.
    #[error("diagnosis: {0}")]
    Fit(#[from] EstimateError),
    /// The data do not fit the model or its candidate effects (rotor count, missing
    /// signals, non-finite regressors).
    #[error("diagnosis: {0}")]
    Data(#[from] AccumulateError),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_axis_is_worse_only_beyond_rounding() {
        // The iris SITL log of ethz-asl/data-driven-dynamics, 80/20: Fx's RMSE on the
        // last 20 % went from 0.04813 to 0.04841 N; a change of 1e-12 relative is
        // rounding.
        let metrics = |rmse: [f64; 6]| {
            std::array::from_fn::<_, 6, _>(|k| AxisMetrics {
                axis: Axis::ALL[k],
                r2: 0.0,
                rmse: rmse[k],
                nrmse: 0.0,
                tic: 0.0,
            })
        };
        let before = metrics([0.04813, 0.117, 0.275, 0.08, 0.018, 0.007]);
        let after = metrics([0.04841, 0.074, 0.124, 0.08 * (1.0 + 1e-12), 0.01, 0.004]);
        assert_eq!(worse_axes(&before, &after), [Axis::Fx]);
        assert!(worse_axes(&after, &after).is_empty());
    }
}
