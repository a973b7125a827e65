//! The closing-the-loop procedure: score every candidate effect on the residual of the
//! current model, add the best one that is significant, plausible and pays on data the
//! model was not fitted on, refit, repeat; then leave out every term, of Eq. 22 or added,
//! that the held-out data do not support.
//!
//! All candidates' columns are accumulated once, next to the base columns, for the fit
//! data and for each cross-validation fold ([`Folds`]: leave one log out with two or
//! more logs, the segment hold-out of a single log); every trial model is then a column
//! subset of those statistics ([`Accumulator::select`]), so no trial re-reads the data.
//! Every decision is made on the folds; data given only for reporting
//! ([`CandidateStatistics::report`], `--validate` logs) are evaluated at the end and
//! never steer a choice, so their figures stay unbiased.
//!
//! A candidate is accepted when
//! 1. its MMR estimates are significant: the joint Wald test of all its parameters has a
//!    P-value below α / (number of named candidates scored in the step) (Bonferroni);
//! 2. it is plausible: every estimate lies in the physical range of its parameter;
//! 3. it pays on held-out data: on some axis the cross-validated NRMSE (the mean over
//!    folds, so each log counts alike) falls by at least [`DiagnoseOptions::min_gain`]
//!    (relative), so does the sum over all axes,
//!    and no axis gets worse by more than [`DiagnoseOptions::max_loss`]. All axes count:
//!    the MMR couples them through shared parameters, so a candidate can pay on an axis
//!    it has no column on.
//!
//! Among accepted candidates, completions of the Eq. 22 structure (terms its own
//! assumptions drop, [`EffectKind::is_model_completion`]) are added before undeclared
//! effects; within each group the largest validation gain summed over the axes wins.
//! Terms of the
//! generic pool ([`super::generic`]: residual structure with no name, whose Bonferroni
//! divisor is the whole pool it was screened from) and moment coefficients freed from
//! the forces ([`EffectKind::is_unspecific`]) compete with named mechanisms, but a named
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
//! of one term on held-out residuals. Left-out terms are reported as "not supported by
//! these data". Control-effectiveness terms
//! ([`ModelStructure::is_control_effectiveness`]) are never left out.

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::candidates::{Candidate, EffectKind};
use crate::estimate::{self, AxisMetrics, CrossValidation, EstimateError, Fit, FitOptions, Folds};
use crate::model::ModelStructure;
use crate::sample::Axis;
use crate::stats::{AccumulateError, Accumulator};

/// Thresholds of the procedure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DiagnoseOptions {
    /// Family-wise significance level per step.
    pub alpha: f64,
    /// Smallest relative validation-NRMSE reduction on an affected axis that counts.
    pub min_gain: f64,
    /// Largest relative validation-NRMSE increase tolerated on any one axis.
    pub max_loss: f64,
    /// Relative gain difference below which two kinds are look-alikes.
    pub look_alike: f64,
    /// Most effects added.
    pub max_effects: usize,
    /// Factor on the parameter variances before the significance test, for coloured
    /// residuals: with lag-1 residual autocorrelation ρ, about (1 + ρ)/(1 − ρ) (an AR(1)
    /// effective sample size). 1 for independent samples (sweeps).
    pub variance_inflation: f64,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            alpha: 0.01,
            min_gain: 0.05,
            max_loss: 0.30,
            look_alike: 0.1,
            max_effects: 8,
            variance_inflation: 1.0,
        }
    }
}

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
}

/// A candidate as scored in one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore {
    /// Candidate name.
    pub name: String,
    /// Effect kind.
    pub kind: EffectKind,
    /// Axes it acts on.
    pub axes: Vec<Axis>,
    /// Estimates with the candidate added.
    pub parameters: Vec<EffectParameter>,
    /// Relative validation-NRMSE reduction per axis (positive = better), Fx…Mz.
    pub validation_gain: [f64; 6],
    /// Sum of the gains over all six axes (losses count negative).
    pub total_gain: f64,
    /// P-value of the joint Wald test that all its parameters are zero (one test per
    /// candidate, however many parameters it has).
    pub p: f64,
    /// Why it was not accepted (`None` when it was acceptable).
    pub rejected: Option<Rejection>,
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
    /// Effects added, in order.
    pub effects_added: Vec<CandidateScore>,
    /// Terms left out of the final model (of Eq. 22 or added), in order.
    pub unsupported: Vec<Unsupported>,
    /// Names of the cross-validation folds' test data (logs left out, or the hold-out).
    pub folds: Vec<String>,
    /// Cross-validated metrics of the base model, all folds pooled.
    pub before: [AxisMetrics; 6],
    /// Cross-validated metrics of the final model, all folds pooled.
    pub after: [AxisMetrics; 6],
    /// Per fold, the base model's metrics.
    pub before_folds: Vec<[AxisMetrics; 6]>,
    /// Per fold, the final model's metrics.
    pub after_folds: Vec<[AxisMetrics; 6]>,
    /// Base and final model (each fitted on all fit data) on the reporting-only
    /// validation data, when given: no decision saw these data.
    pub validation: Option<[[AxisMetrics; 6]; 2]>,
    /// θ̂ of the final model over `structure.params`.
    pub theta: Vec<f64>,
    /// Standard deviations of `theta` (0 for parameters dropped as unidentifiable).
    pub std: Vec<f64>,
    /// Structure of the final model.
    #[serde(skip)]
    pub structure: ModelStructure,
    /// The final model's estimation on all fit data (FSOA tables, MMR estimates with
    /// white-residual σ and covariance, fit metrics).
    #[serde(skip)]
    pub fit: Fit,
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

/// Statistics of the base structure extended by every candidate.
pub struct CandidateStatistics<'a> {
    /// Base structure followed by every candidate (in `candidates` order).
    pub extended: &'a ModelStructure,
    /// The candidates, in the order they were added to `extended`.
    pub candidates: &'a [Candidate],
    /// Parameter indices in `extended` of each candidate.
    pub candidate_params: &'a [Vec<usize>],
    /// Number of base parameters (the first ones of `extended`).
    pub base_params: usize,
    /// Statistics of all fit data over `extended` (the estimates).
    pub fit: &'a Accumulator,
    /// Cross-validation folds of the fit data over `extended` (every decision).
    pub folds: &'a Folds,
    /// Reporting-only validation statistics over `extended` (no decision uses them).
    pub report: Option<&'a Accumulator>,
}

/// Physical range of a candidate parameter (by name prefix).
fn plausible(name: &str, value: f64) -> bool {
    let range = |lo: f64, hi: f64| (lo..=hi).contains(&value);
    match name {
        n if n.starts_with("thrust_scale_") || n.starts_with("torque_scale_") => range(-0.6, 0.6),
        "cg_dx" | "cg_dy" | "cg_dz" => range(-0.2, 0.2),
        "ground_effect_scale" => range(0.0, 3.0),
        "wake_thrust_loss" => range(0.0, 1.0),
        // Measured vortex-ring thrust losses are tens of percent; a fitted loss beyond
        // 60 % is a bump shape fitting inflow-model error, not the state itself.
        "vortex_ring_thrust_loss" => range(0.0, 0.6),
        n if n.starts_with("drag_area_") => range(0.0, 2.0),
        "rotor_speed_delay" => range(-0.05, 0.2),
        "wind_north" | "wind_east" | "wind_down" => range(-30.0, 30.0),
        // Consumer MEMS accelerometers stay within ~1 m/s² of zero bias.
        n if n.starts_with("accel_bias_") => range(-2.0, 2.0),
        _ => value.is_finite(),
    }
}

impl CandidateStatistics<'_> {
    /// Indices of the columns of `extended` whose parameter satisfies `keep`, ascending.
    fn columns_of(&self, keep: impl Fn(usize) -> bool) -> Vec<usize> {
        (0..self.extended.columns.len())
            .filter(|&j| keep(self.extended.columns[j].param))
            .collect()
    }
}

/// Fit of a sub-model of `stats.extended`: the estimates, σ and P with the coloured-
/// residual correction, its cross-validation, and the structure.
#[derive(Clone)]
struct Trial {
    fit: Fit,
    std: Vec<f64>,
    p: Vec<f64>,
    cv: CrossValidation,
    structure: ModelStructure,
    /// Column indices into `stats.extended`.
    columns: Vec<usize>,
}

/// Fits the sub-model of `stats.extended` with columns `columns` (indices into
/// `extended.columns`, ascending) on all fit data and on every fold.
fn trial(
    stats: &CandidateStatistics,
    columns: &[usize],
    options: &FitOptions,
    inflation: f64,
) -> Result<Trial, EstimateError> {
    let structure = stats.extended.select_columns(columns);
    let columns = columns.to_vec();
    let fit = estimate::fit(&structure, &stats.fit.select(&columns), options)?;
    let cv = estimate::cross_validate(&structure, &stats.folds.select(&columns), options)?;
    let mut std = vec![0.0; structure.params.len()];
    let mut p = vec![1.0; structure.params.len()];
    let inflation = inflation.max(1.0).sqrt();
    for (est, &i) in fit.mmr.parameters.iter().zip(&fit.mmr.param_index) {
        std[i] = est.std_error * inflation;
        p[i] = crate::estimate::inference::t_test(est.estimate / std[i], fit.mmr.dof).0;
    }
    Ok(Trial {
        fit,
        std,
        p,
        cv,
        structure,
        columns,
    })
}

/// P-value of the Wald test that the parameters `own` (indices into the trial's
/// structure) are all zero: W = θᵀ(κΣ)⁻¹θ against χ² with one degree of freedom per
/// estimated parameter, κ the coloured-residual variance inflation. A joint test, so a
/// candidate of several correlated parameters is not penalised for their correlation
/// (each one's t can be small while together they explain much). 1 when none of them
/// could be estimated.
fn joint_p(t: &Trial, own: &[usize], inflation: f64) -> f64 {
    let at: Vec<usize> = own
        .iter()
        .filter_map(|p| t.fit.mmr.param_index.iter().position(|e| e == p))
        .collect();
    let k = at.len();
    let mmr = &t.fit.mmr;
    let n = mmr.param_index.len();
    let theta: Vec<f64> = at.iter().map(|&i| mmr.theta[mmr.param_index[i]]).collect();
    let cov: Vec<f64> = at
        .iter()
        .flat_map(|&i| at.iter().map(move |&j| (i, j)))
        .map(|(i, j)| mmr.covariance[i * n + j] * inflation.max(1.0))
        .collect();
    let (Some(w), Ok(chi2)) = (
        quadratic_form_inverse(&cov, &theta),
        ChiSquared::new(k as f64),
    ) else {
        return 1.0;
    };
    chi2.sf(w)
}

/// xᵀA⁻¹x for a symmetric positive definite k × k `a` (row-major), by Cholesky; `None`
/// when `a` is empty or not positive definite.
#[allow(clippy::needless_range_loop)] // triangular index arithmetic reads clearest
fn quadratic_form_inverse(a: &[f64], x: &[f64]) -> Option<f64> {
    let k = x.len();
    if k == 0 {
        return None;
    }
    let mut l = vec![0.0; k * k];
    for i in 0..k {
        for j in 0..=i {
            let s: f64 = a[i * k + j] - (0..j).map(|m| l[i * k + m] * l[j * k + m]).sum::<f64>();
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return None;
                }
                l[i * k + i] = s.sqrt();
            } else {
                l[i * k + j] = s / l[j * k + j];
            }
        }
    }
    // L y = x, then xᵀA⁻¹x = ‖y‖².
    let mut y = vec![0.0; k];
    for i in 0..k {
        y[i] = (x[i] - (0..i).map(|m| l[i * k + m] * y[m]).sum::<f64>()) / l[i * k + i];
    }
    Some(y.iter().map(|v| v * v).sum())
}

/// Relative reduction per axis of the cross-validated NRMSE, each fold weighted alike
/// ([`CrossValidation::balanced_nrmse`]): a term must predict every log better on
/// average, not only the one with the largest loads.
fn gains(before: &CrossValidation, after: &CrossValidation) -> [f64; 6] {
    let (b, a) = (before.balanced_nrmse(), after.balanced_nrmse());
    std::array::from_fn(|k| {
        if b[k] > 0.0 {
            (b[k] - a[k]) / b[k]
        } else {
            0.0
        }
    })
}

/// Runs the procedure on accumulated candidate statistics.
pub fn diagnose(
    stats: &CandidateStatistics,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let inflation = options.variance_inflation;
    let mut kept: Vec<usize> = stats.columns_of(|p| p < stats.base_params);
    let base = trial(stats, &kept, fit_options, inflation)?;
    let mut current = base.clone();
    let mut added: Vec<usize> = Vec::new();
    let mut steps = Vec::new();
    let mut effects_added = Vec::new();
    while added.len() < options.max_effects {
        let Some(step) = forward_step(stats, &kept, &added, &current, fit_options, options) else {
            break;
        };
        let (step, winner) = step;
        steps.push(step);
        let Some((c, t)) = winner else {
            break;
        };
        added.push(c);
        kept = t.columns.clone();
        current = t;
        let last = steps.last().expect("pushed");
        effects_added.push(last.ranking[0].clone());
    }
    let unsupported = prune(stats, &mut kept, &mut current, fit_options, options);
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
    Ok(Diagnosis {
        steps,
        effects_added,
        unsupported,
        folds: stats.folds.names.clone(),
        before: base.cv.pooled_metrics(),
        after: current.cv.pooled_metrics(),
        before_folds: fold_metrics(&base.cv),
        after_folds: fold_metrics(&current.cv),
        validation,
        theta: current.fit.mmr.theta.clone(),
        std: current.std,
        structure: current.structure,
        fit: current.fit,
    })
}

/// One forward step: every remaining candidate scored against the current model
/// (parameters `kept`), ranked; the winner (candidate index and its trial) when one is
/// acceptable. `None` when no candidate remains.
fn forward_step(
    stats: &CandidateStatistics,
    kept: &[usize],
    added: &[usize],
    current: &Trial,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
) -> Option<(DiagnosisStep, Option<(usize, Trial)>)> {
    let remaining: Vec<usize> = (0..stats.candidates.len())
        .filter(|c| !added.contains(c))
        .collect();
    if remaining.is_empty() {
        return None;
    }
    // Bonferroni: named candidates over those still in play; generic ones over the
    // whole pool they were screened from.
    let named = remaining
        .iter()
        .filter(|&&c| stats.candidates[c].kind != EffectKind::Generic)
        .count();
    let level = |c: usize| match stats.candidates[c].kind {
        EffectKind::Generic => options.alpha / super::generic::pool_size() as f64,
        _ => options.alpha / named.max(1) as f64,
    };
    let mut scored: Vec<(CandidateScore, usize, Option<Trial>)> = remaining
        .iter()
        .map(|&c| score(stats, kept, c, current, fit_options, options, level(c)))
        .collect();
    // Accepted first; among them completions of the Eq. 22 structure before
    // undeclared effects (so an effect is judged against a model that already has
    // the terms its own assumptions drop), and named effects before generic terms;
    // then by validation gain.
    let look_alike = options.look_alike;
    scored.sort_by(|a, b| {
        let key = |s: &CandidateScore| {
            let ok = s.rejected.is_none();
            (ok, ok && s.kind.is_model_completion())
        };
        key(&a.0)
            .cmp(&key(&b.0))
            .then(preference(&a.0, look_alike).total_cmp(&preference(&b.0, look_alike)))
            .reverse()
    });
    let best_ok = scored
        .first()
        .filter(|s| s.0.rejected.is_none())
        .map(|s| s.0.clone());
    let look_alikes = best_ok
        .as_ref()
        .map(|best| {
            scored[1..]
                .iter()
                .filter(|s| {
                    s.0.rejected.is_none()
                        && s.0.kind != best.kind
                        && s.0.kind.is_model_completion() == best.kind.is_model_completion()
                        && s.0.total_gain >= (1.0 - options.look_alike) * best.total_gain
                })
                .map(|s| s.0.name.clone())
                .collect()
        })
        .unwrap_or_default();
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
    };
    Some((step, winner))
}

/// Cross-validation score Σ_j Σₐ SSE_ja/σ̂²_ja of `cv`: each fold j's held-out errors on
/// axis a in units of the reference model's mean square error there (`scale`).
fn cv_score(cv: &CrossValidation, scale: &[[f64; 6]]) -> f64 {
    cv.folds
        .iter()
        .zip(scale)
        .flat_map(|(f, v)| f.iter().zip(v).map(|(s, v)| s.sse / v))
        .sum()
}

/// Leaves out terms (a parameter's columns on one axis) of the model with columns `kept`
/// one at a time while it stays within noise of the best cross-validated score (module
/// docs); returns them in order.
fn prune(
    stats: &CandidateStatistics,
    kept: &mut Vec<usize>,
    current: &mut Trial,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
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
        let mut terms: Vec<(usize, Axis)> = kept
            .iter()
            .filter(|&&j| !stats.extended.is_control_effectiveness(j))
            .map(|&j| (column(j).param, column(j).axis))
            .collect();
        terms.sort_unstable();
        terms.dedup();
        if terms.is_empty() {
            break;
        }
        let cheapest = terms
            .iter()
            .filter_map(|&term| {
                let without: Vec<usize> = kept
                    .iter()
                    .copied()
                    .filter(|&j| (column(j).param, column(j).axis) != term)
                    .collect();
                let t = trial(stats, &without, fit_options, options.variance_inflation).ok()?;
                Some((term, cv_score(&t.cv, &scale), t))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some(((param, axis), score, t)) = cheapest else {
            break;
        };
        if score > best + noise {
            break;
        }
        out.push(Unsupported {
            name: format!("{} on {axis}", stats.extended.params[param].name),
            score_change: score - best,
        });
        best = best.min(score);
        *kept = t.columns.clone();
        *current = t;
    }
    out
}

/// Validation gain used to rank accepted candidates of one group: a named mechanism's
/// gain counts `1 + look_alike` times, so it is preferred over an unspecific hypothesis
/// (a generic term, a freed moment coefficient) that explains about as much, but not
/// over one that explains clearly more.
fn preference(s: &CandidateScore, look_alike: f64) -> f64 {
    if s.kind.is_unspecific() {
        s.total_gain
    } else {
        s.total_gain * (1.0 + look_alike)
    }
}

/// Scores candidate `c` added to the model with columns `kept`.
fn score(
    stats: &CandidateStatistics,
    kept: &[usize],
    c: usize,
    current: &Trial,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
    level: f64,
) -> (CandidateScore, usize, Option<Trial>) {
    let cand = &stats.candidates[c];
    let own_params = &stats.candidate_params[c];
    let mut columns = kept.to_vec();
    columns.extend(stats.columns_of(|p| own_params.contains(&p)));
    columns.sort_unstable();
    let axes = cand.axes();
    let mut s = CandidateScore {
        name: cand.name.clone(),
        kind: cand.kind,
        axes: axes.clone(),
        parameters: Vec::new(),
        validation_gain: [0.0; 6],
        total_gain: 0.0,
        p: 1.0,
        rejected: None,
    };
    let t = match trial(stats, &columns, fit_options, options.variance_inflation) {
        Ok(t) => t,
        Err(e) => {
            s.rejected = Some(Rejection::NotEstimable(e.to_string()));
            return (s, c, None);
        }
    };
    let own: Vec<usize> = stats.candidate_params[c]
        .iter()
        .map(|&p| {
            let name = &stats.extended.params[p].name;
            t.structure
                .param_index(name)
                .expect("candidate parameter in trial")
        })
        .collect();
    s.parameters = own
        .iter()
        .map(|&i| EffectParameter {
            name: t.structure.params[i].name.clone(),
            estimate: t.fit.mmr.theta[i],
            std: t.std[i],
            unit: t.structure.params[i].unit.clone(),
            p: t.p[i],
        })
        .collect();
    s.p = joint_p(&t, &own, options.variance_inflation);
    s.validation_gain = gains(&current.cv, &t.cv);
    // The MMR couples the axes through shared parameters, so a candidate can pay on an
    // axis it has no column on (freeing a moment coefficient lets F_z fit itself):
    // gains count on every axis, losses too.
    s.total_gain = s.validation_gain.iter().sum();
    let worst = s.validation_gain.iter().fold(0.0_f64, |m, &g| m.min(g));
    let best_axis = s
        .validation_gain
        .iter()
        .fold(f64::NEG_INFINITY, |m, &g| m.max(g));
    s.rejected = if s.p >= level {
        Some(Rejection::NotSignificant { p: s.p, level })
    } else if let Some(p) = s
        .parameters
        .iter()
        .find(|p| !plausible(&p.name, p.estimate))
    {
        Some(Rejection::Implausible {
            parameter: p.name.clone(),
            value: p.estimate,
            unit: p.unit.clone(),
        })
    } else if best_axis < options.min_gain {
        Some(Rejection::SmallGain {
            gain: best_axis,
            required: options.min_gain,
        })
    } else if s.total_gain < options.min_gain {
        Some(Rejection::SmallNetGain {
            gain: s.total_gain,
            required: options.min_gain,
        })
    } else if worst < -options.max_loss {
        Some(Rejection::Loss { loss: -worst })
    } else {
        None
    };
    (s, c, Some(t))
}

/// The procedure alone on in-memory data: fits `base` on `fit_data`, builds the
/// candidates from its estimates, accumulates them over both parts and runs
/// [`diagnose`] with `validation_data` as the one cross-validation fold (for sweeps,
/// whose points are independent, so any split is a fair hold-out). Unlike
/// [`crate::Identification`] it applies only `options.variance_inflation` (no residual
/// pass estimates the coloured-residual correction): use the builder for flight logs.
pub fn diagnose_chunks(
    vehicle: &crate::vehicle::Vehicle,
    base: &ModelStructure,
    fit_data: &[crate::sample::SampleChunk],
    validation_data: &[crate::sample::SampleChunk],
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let mut ws = crate::model::Workspace::default();
    let mut acc = Accumulator::new(base);
    for c in fit_data {
        acc.push(base, c, &mut ws)?;
    }
    let fit = estimate::fit(base, &acc, fit_options)?;
    let first = fit_data.first();
    let ctx = super::CandidateContext {
        vehicle,
        structure: base,
        theta: &fit.mmr.theta,
        has_height: first.is_some_and(|c| !c.is_empty() && c.has_height()),
        has_omega_dot: first.is_some_and(|c| c.has_omega_dot()),
        has_attitude: first.is_some_and(|c| !c.is_empty() && c.has_attitude()),
    };
    let mut thinned = super::Thinned::new(super::SCREENING_SAMPLES);
    fit_data.iter().for_each(|c| thinned.push(c));
    let set = super::candidate_set(&ctx, Some(thinned.samples()), options)
        .map_err(AccumulateError::from)?;
    let extended = set.extended;
    let (mut fa, mut va) = (Accumulator::new(&extended), Accumulator::new(&extended));
    for (acc, data) in [(&mut fa, fit_data), (&mut va, validation_data)] {
        for c in data {
            acc.push(&extended, c, &mut ws)?;
        }
    }
    let folds = Folds::holdout("validation data", fa.clone(), va);
    let stats = CandidateStatistics {
        extended: &extended,
        candidates: &set.candidates,
        candidate_params: &set.params,
        base_params: base.params.len(),
        fit: &fa,
        folds: &folds,
        report: None,
    };
    diagnose(&stats, fit_options, options)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wald_quadratic_form_matches_the_closed_form() {
        // One parameter: θ²/σ². Two correlated ones, A = [[4, 2], [2, 3]], x = (1, 2):
        // A⁻¹ = [[3, −2], [−2, 4]]/8, so xᵀA⁻¹x = (3 − 8 + 16)/8 = 11/8.
        assert_eq!(quadratic_form_inverse(&[4.0], &[3.0]), Some(2.25));
        let w = quadratic_form_inverse(&[4.0, 2.0, 2.0, 3.0], &[1.0, 2.0]).unwrap();
        assert!((w - 11.0 / 8.0).abs() < 1e-15, "{w}");
        // Not positive definite, or nothing to test.
        assert_eq!(
            quadratic_form_inverse(&[1.0, 2.0, 2.0, 1.0], &[1.0, 1.0]),
            None
        );
        assert_eq!(quadratic_form_inverse(&[], &[]), None);
    }
}
