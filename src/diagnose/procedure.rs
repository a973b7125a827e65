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
//! to enter, so a term near the bar does not enter and leave in turn. An effect
//! offered in several forms ([`EffectKind::is_family_of_forms`]) is then given the
//! form the held-out data now favour (largest held-out likelihood ratio). Terms of
//! the generic pool are a family of unnamed hypotheses: at most
//! [`DiagnoseOptions::max_generic`] of them enter a model. An added effect whose
//! held-out fit another candidate of the same kind, or another form of its family,
//! matches within noise (a weak rotor and a stronger rotor diagonally opposite, of
//! the same spin) is reported with it as one finding, not separable with these
//! data.
//!
//! Among accepted candidates, completions of the Eq. 22 structure (terms its own
//! assumptions drop, [`EffectKind::is_model_completion`]) are added before undeclared
//! effects; within each group the largest validation gain summed over the axes wins,
//! except that between forms of one effect within [`DiagnoseOptions::look_alike`] of
//! each other the largest held-out likelihood ratio wins.
//! A named effect that the winning completion takes the evidence of (no longer accepted
//! once the completion is in the model) while it explains about as much is reported as
//! the completion's look-alike; when it explains clearly more (by more than
//! [`DiagnoseOptions::look_alike`]) it is added first instead, the completion its
//! look-alike, tried again in the next step.
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
//! of one term on held-out residuals. Of two removals that score alike to rounding (one
//! column twice, e.g. an Eq. 22 term and its freed copy) the added effect's term goes,
//! so rounding never picks the term reported. Left-out terms are reported as "not
//! supported by these data". Control-effectiveness terms
//! ([`ModelStructure::is_control_effectiveness`]) are never left out.

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

use super::candidates::{Candidate, EffectKind};
use super::local::{ActivityParts, LocalFolds};
use crate::estimate::SingularValues;
use crate::estimate::{self, AxisMetrics, CrossValidation, EstimateError, Fit, FitOptions, Folds};
use crate::model::ModelStructure;
use crate::sample::Axis;
use crate::stats::{AccumulateError, Accumulator};
use crate::util::map_on_threads;

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
    /// Most generic-pool terms in a model (a stricter rule for the family of unnamed
    /// hypotheses than for named ones: each can only say "something of this shape").
    pub max_generic: usize,
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
            max_generic: 1,
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
    /// The search stopped at [`DiagnoseOptions::max_effects`] with candidates left.
    pub stopped_at_limit: bool,
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
    /// Held-out statistics where each local candidate acts ([`super::local`]).
    pub local: &'a [LocalFolds],
}

/// Physical range of a candidate parameter (by name prefix).
fn plausible(name: &str, value: f64) -> bool {
    let range = |lo: f64, hi: f64| (lo..=hi).contains(&value);
    match name {
        n if n.starts_with("thrust_scale_")
            || n.starts_with("in_plane_scale_")
            || n.starts_with("torque_scale_") =>
        {
            range(-0.6, 0.6)
        }
        "cg_dx" | "cg_dy" | "cg_dz" => range(-0.2, 0.2),
        n if n.starts_with("ground_effect_scale") => range(0.0, 3.0),
        "wake_thrust_loss" => range(0.0, 1.0),
        // Per unit advance ratio: a full loss at μ ≈ 0.3 is k ≈ 3.
        "wake_thrust_loss_advance" => range(0.0, 5.0),
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

/// Fit of a sub-model of `stats.extended`: the estimates (FSOA tables left empty), σ and
/// P with the coloured-residual correction, its cross-validation, and the structure.
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
    // The conditioning of a trial is not read: only the adopted model's is reported, from
    // a refit (`diagnose_on_threads`).
    let fit = estimate::fit_without_fsoa(
        &structure,
        &stats.fit.select(&columns),
        options,
        SingularValues::WhenRankInDoubt,
    )?;
    let cv = held_out(stats, &structure, &columns, options)?;
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

/// The held-out errors on every fold of `structure`, the sub-model of `stats.extended`
/// with columns `columns`: what scores a [`trial`], without its fit on all data.
fn held_out(
    stats: &CandidateStatistics,
    structure: &ModelStructure,
    columns: &[usize],
    options: &FitOptions,
) -> Result<CrossValidation, EstimateError> {
    estimate::cross_validate(structure, &stats.folds.select(columns), options)
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
    let kept: Vec<usize> = stats.columns_of(|p| p < stats.base_params);
    let base = trial(stats, &kept, fit_options, inflation)?;
    let mut search = Search {
        stats,
        fit_options,
        options,
        kept,
        current: base.clone(),
        tried: Vec::new(),
        in_model: Vec::new(),
        threads,
    };
    let mut steps = Vec::new();
    let mut stopped_at_limit = false;
    loop {
        if search.tried.len() >= options.max_effects {
            stopped_at_limit = search.tried.len() < stats.candidates.len();
            break;
        }
        let Some((mut step, winner)) = search.forward_step() else {
            break;
        };
        let Some((c, t)) = winner else {
            steps.push(step);
            break;
        };
        search.tried.push(c);
        search.kept = t.columns.clone();
        search.current = t;
        let said = finding(&step.ranking[0], &step.not_separable, &step.look_alikes);
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
    Ok(Diagnosis {
        steps,
        findings: in_model.iter().map(|(_, _, said)| said.clone()).collect(),
        effects_added: in_model.into_iter().map(|(_, s, _)| s).collect(),
        stopped_at_limit,
        unsupported,
        folds: stats.folds.names.clone(),
        before: base.cv.pooled_metrics(),
        after: current.cv.pooled_metrics(),
        before_folds: fold_metrics(&base.cv),
        after_folds: fold_metrics(&current.cv),
        validation,
        theta: fit.mmr.theta.clone(),
        std: current.std,
        structure: current.structure,
        fit,
    })
}

/// One sentence for an added effect: a weak or strong rotor by how much, else its name;
/// with the candidates of its kind the data cannot separate from it and the look-alikes
/// of other kinds that explain about as much.
fn finding(s: &CandidateScore, not_separable: &[String], look_alikes: &[String]) -> String {
    let mut said = describe(s);
    if !not_separable.is_empty() {
        said = format!(
            "{said} or {} (not separable with these data)",
            not_separable.join(" or ")
        );
    }
    if !look_alikes.is_empty() {
        said = format!("{said}; explains about as much: {}", look_alikes.join(", "));
    }
    said
}

/// "rotor 3 weaker by 9.8 %" for a rotor asymmetry, else the candidate's name.
fn describe(s: &CandidateScore) -> String {
    let thrust = s
        .parameters
        .iter()
        .find(|p| p.name.starts_with("thrust_scale_"));
    match (s.kind, thrust) {
        (EffectKind::RotorAsymmetry, Some(p)) => {
            let rotor = p.name.trim_start_matches("thrust_scale_");
            let how = if p.estimate < 0.0 {
                "weaker"
            } else {
                "stronger"
            };
            format!("rotor {rotor} {how} by {:.1} %", 100.0 * p.estimate.abs())
        }
        _ => s.name.clone(),
    }
}

/// The state of the forward search: the current model and what has been tried.
struct Search<'a> {
    stats: &'a CandidateStatistics<'a>,
    fit_options: &'a FitOptions,
    options: &'a DiagnoseOptions,
    /// Columns of the current model (indices into `stats.extended`).
    kept: Vec<usize>,
    current: Trial,
    /// Candidates added so far, withdrawn or not (never tried again).
    tried: Vec<usize>,
    /// Candidates in the current model: index, score when added, the finding.
    in_model: Vec<(usize, CandidateScore, String)>,
    /// Threads the trial fits of one step share.
    threads: usize,
}

impl Search<'_> {
    /// Bonferroni level of candidate `c` in a step: named candidates over those still in
    /// play; generic ones over the whole pool they were screened from.
    fn level(&self, c: usize) -> f64 {
        let stats = self.stats;
        let named = (0..stats.candidates.len())
            .filter(|c| !self.tried.contains(c))
            .filter(|&c| stats.candidates[c].kind != EffectKind::Generic)
            .count();
        match stats.candidates[c].kind {
            EffectKind::Generic => self.options.alpha / super::generic::pool_size() as f64,
            _ => self.options.alpha / named.max(1) as f64,
        }
    }

    /// True when the current model holds `max_generic` generic-pool terms.
    fn generic_full(&self) -> bool {
        let generic = self
            .in_model
            .iter()
            .filter(|(c, _, _)| self.stats.candidates[*c].kind == EffectKind::Generic)
            .count();
        generic >= self.options.max_generic
    }

    /// The held-out statistics where candidate `c` acts, with the cross-validation of
    /// the model with columns `columns` there; `None` for a candidate acting everywhere.
    fn local_before(&self, c: usize, t: &Trial) -> Option<(&LocalFolds, CrossValidation)> {
        let lf = self.stats.local.iter().find(|l| l.candidate == c)?;
        let cv =
            estimate::cross_validate(&t.structure, &lf.folds.select(&t.columns), self.fit_options)
                .ok()?;
        Some((lf, cv))
    }

    /// One forward step: every remaining candidate scored against the current model,
    /// ranked; the winner (candidate index and its trial) when one is acceptable. `None`
    /// when no candidate remains.
    fn forward_step(&self) -> Option<(DiagnosisStep, Option<(usize, Trial)>)> {
        let stats = self.stats;
        let options = self.options;
        // One form of an effect offered in several.
        let has_form = |kind: EffectKind| {
            kind.is_family_of_forms()
                && self
                    .in_model
                    .iter()
                    .any(|(c, _, _)| stats.candidates[*c].kind.family() == kind.family())
        };
        let remaining: Vec<usize> = (0..stats.candidates.len())
            .filter(|c| !self.tried.contains(c))
            .filter(|&c| !has_form(stats.candidates[c].kind))
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
                if generic_full && s.0.kind == EffectKind::Generic && s.0.rejected.is_none() {
                    s.0.rejected = Some(Rejection::GenericLimit {
                        limit: options.max_generic,
                    });
                }
                s
            });
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
        let best_ok = scored
            .first()
            .filter(|s| s.0.rejected.is_none())
            .map(|s| s.0.clone());
        let (mut look_alikes, not_separable) = best_ok
            .as_ref()
            .map(|best| self.alternatives(best, &scored[1..]))
            .unwrap_or_default();
        look_alikes.extend(confounded);
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

    /// A named effect confounded with the step's winner when that is a completion of
    /// Eq. 22: accepted, explaining at least 1 − [`DiagnoseOptions::look_alike`] of the
    /// completion's summed gain, and no longer accepted once the completion is in the
    /// model (the completion takes its evidence). Returns its index in `scored` and
    /// whether it goes first: only when it explains clearly more (by more than
    /// `look_alike`); otherwise the completion keeps its place and the effect is its
    /// look-alike.
    fn confounded_with_completion(
        &self,
        scored: &[(CandidateScore, usize, Option<Trial>)],
    ) -> Option<(usize, bool)> {
        let (first, _, Some(with_completion)) = scored.first()? else {
            return None;
        };
        if first.rejected.is_some() || !first.kind.is_model_completion() {
            return None;
        }
        let look_alike = self.options.look_alike;
        let (i, (effect, c, _)) = scored.iter().enumerate().skip(1).find(|(_, (s, _, _))| {
            s.rejected.is_none()
                && !s.kind.is_model_completion()
                && !s.kind.is_unspecific()
                && s.total_gain >= (1.0 - look_alike) * first.total_gain
        })?;
        let local = self.local_before(*c, with_completion);
        let local = local.as_ref().map(|(lf, cv)| (*lf, cv));
        let (after, _, _) = score(
            self,
            &with_completion.columns,
            *c,
            with_completion,
            local,
            self.level(*c),
            self.options.min_gain,
        );
        after.rejected.as_ref()?;
        Some((i, effect.total_gain > (1.0 + look_alike) * first.total_gain))
    }

    /// Look-alikes of `best` (candidates of other kinds in its group within `look_alike`
    /// of its gain, significant and plausible) and the findings of its own kind that fit the held-out
    /// data as well within noise (κ χ²₁(1 − α) of its likelihood ratio).
    fn alternatives(
        &self,
        best: &CandidateScore,
        others: &[(CandidateScore, usize, Option<Trial>)],
    ) -> (Vec<String>, Vec<String>) {
        let options = self.options;
        // A look-alike, or another form of the winner's effect, may miss a held-out bar
        // the winner just cleared: it explains as much, significantly and plausibly.
        let comparable: Vec<&CandidateScore> = others
            .iter()
            .map(|s| &s.0)
            .filter(|s| {
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
            .filter(|s| {
                s.kind.family() != best.kind.family()
                    && s.kind.is_model_completion() == best.kind.is_model_completion()
                    && s.total_gain >= (1.0 - options.look_alike) * best.total_gain
            })
            .map(|s| s.name.clone())
            .collect();
        let noise = self.lr_noise();
        let not_separable = comparable
            .iter()
            .filter(|s| s.kind.family() == best.kind.family() && s.kind != EffectKind::Generic)
            .filter(|s| s.rejected.is_none() || best.kind.is_family_of_forms())
            .filter(|s| (s.held_out_lr - best.held_out_lr).abs() <= noise)
            .map(|s| describe(s))
            .collect();
        (look_alikes, not_separable)
    }

    /// Held-out likelihood-ratio difference within which two candidates fit the held-out
    /// data alike: κ χ²₁(1 − α), one parameter's worth with coloured residuals.
    fn lr_noise(&self) -> f64 {
        let o = self.options;
        chi2_quantile(1.0, 1.0 - o.alpha) * o.variance_inflation.max(1.0)
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
            let (s, _, _) = score(self, &without, e, &reduced, local, self.level(e), stay);
            if let Some(why) = s.rejected {
                withdrawn.push(format!("{}: {why}", s.name));
                self.kept = without;
                self.current = reduced;
                self.in_model.retain(|(c, _, _)| *c != e);
            } else if let Some(said) = self.rechoose_form(e, &s, &without, &reduced, stay) {
                withdrawn.push(said);
            }
        }
        withdrawn
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
        let kind = stats.candidates[e].kind;
        if !kind.is_family_of_forms() {
            return None;
        }
        let in_model: Vec<usize> = self.in_model.iter().map(|(c, _, _)| *c).collect();
        let forms: Vec<usize> = (0..stats.candidates.len())
            .filter(|&f| {
                stats.candidates[f].kind.family() == kind.family() && !in_model.contains(&f)
            })
            .collect();
        let (best, c, trial) = map_on_threads(&forms, self.threads, |&f| {
            let local = self.local_before(f, reduced);
            let local = local.as_ref().map(|(lf, cv)| (*lf, cv));
            score(self, without, f, reduced, local, self.level(f), stay)
        })
        .into_iter()
        .filter(|(s, _, _)| s.rejected.is_none())
        .max_by(|a, b| a.0.held_out_lr.total_cmp(&b.0.held_out_lr))?;
        let trial = trial.filter(|_| best.held_out_lr > in_use.held_out_lr)?;
        let alike = if best.held_out_lr - in_use.held_out_lr <= self.lr_noise() {
            vec![describe(in_use)]
        } else {
            Vec::new()
        };
        let said = format!(
            "{}: the form {} fits the held-out data better now (likelihood ratio {:.1} against {:.1})",
            in_use.name, best.name, best.held_out_lr, in_use.held_out_lr
        );
        let entry = (c, best.clone(), finding(&best, &alike, &[]));
        if let Some(slot) = self.in_model.iter_mut().find(|(f, _, _)| *f == e) {
            *slot = entry;
        }
        self.tried.push(c);
        self.kept = trial.columns.clone();
        self.current = trial;
        Some(said)
    }
}

/// The `p` quantile of χ² with `k` degrees of freedom (∞ when undefined).
fn chi2_quantile(k: f64, p: f64) -> f64 {
    ChiSquared::new(k).map_or(f64::INFINITY, |d| d.inverse_cdf(p))
}

/// The held-out likelihood ratio a candidate of `k` parameters must reach at `level`.
///
/// With the candidate's true effect zero, its estimate θ̂ (fitted on the training data)
/// scatters with covariance κσ²(X_trᵀX_tr)⁻¹, and on held-out residuals e the statistic
/// S = (2eᵀXθ̂ − θ̂ᵀXᵀXθ̂)/σ² has mean −κkr and standard deviation 2κ√(kr) (r the ratio
/// of held-out to training samples, κ the coloured-residual inflation of both the
/// estimate's and the residuals' variance). S must lie z(1 − level) standard deviations
/// above that mean: κ(2z√(kr) − kr), at least 0 (the candidate must predict better).
fn required_lr(k: usize, folds: &Folds, inflation: f64, level: f64) -> f64 {
    let r = folds.test_samples() as f64 / folds.train_samples().max(1) as f64;
    held_out_threshold(k, r, inflation, level)
}

/// κ(2z√(kr) − kr), at least 0 (see [`required_lr`]).
fn held_out_threshold(k: usize, r: f64, inflation: f64, level: f64) -> f64 {
    let kr = k as f64 * r;
    let z = Normal::new(0.0, 1.0).map_or(f64::INFINITY, |n| n.inverse_cdf(1.0 - level));
    (inflation.max(1.0) * (2.0 * z * kr.sqrt() - kr)).max(0.0)
}

/// Held-out likelihood-ratio statistic of `after` against `before`:
/// Σ_j Σₐ (SSE_before − SSE_after)/σ̂²_ja, σ̂²_ja = SSE_before/n on fold j, axis a (for
/// Gaussian errors of that variance, twice the log-likelihood gain).
fn held_out_lr(before: &CrossValidation, after: &CrossValidation) -> f64 {
    before
        .folds
        .iter()
        .zip(&after.folds)
        .flat_map(|(b, a)| b.iter().zip(a))
        .filter(|(b, _)| b.sse > 0.0 && b.n > 0.0)
        .map(|(b, a)| (b.sse - a.sse) / (b.sse / b.n))
        .sum()
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

/// Cross-validation scores this close (relative) are one score: the same model to
/// rounding. A score is about six times the held-out sample count (each SSE in units of
/// its mean square), so 1e-12 of it stays far below the noise bound κ χ²₁(1 − α) ≥ 2.7
/// for any log, and far above the rounding of the sums (~1e-16 relative).
const SCORE_TIE: f64 = 1e-12;

/// Leaves out terms (a parameter's columns on one axis) of the model with columns `kept`
/// one at a time while it stays within noise of the best cross-validated score (module
/// docs); returns them in order.
fn prune(
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
        // Each removal scored on the folds only; the one chosen is then fitted in full.
        let mut removals: Vec<((usize, Axis), f64, Vec<usize>)> =
            map_on_threads(&terms, threads, |&term| {
                let without: Vec<usize> = kept
                    .iter()
                    .copied()
                    .filter(|&j| (column(j).param, column(j).axis) != term)
                    .collect();
                let structure = stats.extended.select_columns(&without);
                let cv = held_out(stats, &structure, &without, fit_options).ok()?;
                Some((term, cv_score(&cv, &scale), without))
            })
            .into_iter()
            .flatten()
            .collect();
        let chosen = loop {
            let Some(i) = cheapest(0..removals.len(), |&i| removals[i].1) else {
                break None;
            };
            if removals[i].1 > best + noise {
                break None;
            }
            // A removal whose fit on all data fails is no trial model: the next cheapest.
            match trial(
                stats,
                &removals[i].2,
                fit_options,
                options.variance_inflation,
            ) {
                Ok(t) => break Some((removals[i].0, removals[i].1, t)),
                Err(_) => {
                    removals.remove(i);
                }
            }
        };
        let Some(((param, axis), score, t)) = chosen else {
            break;
        };
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

/// Among the accepted forms of the winner's effect (a family of forms) whose ranking
/// gain is within `look_alike` of the winner's, the one with the largest held-out
/// likelihood ratio: the summed relative gains rank coarsely, and between forms of one
/// effect the held-out likelihood decides. Look-alikes of other kinds keep the gain
/// order (between two mechanisms a likelihood difference within noise is no evidence).
/// Its index in `scored`, when that is not the winner.
fn likeliest_in_band(
    scored: &[(CandidateScore, usize, Option<Trial>)],
    look_alike: f64,
) -> Option<usize> {
    let first = &scored.first()?.0;
    if first.rejected.is_some() || !first.kind.is_family_of_forms() {
        return None;
    }
    let bar = (1.0 - look_alike) * preference(first, look_alike);
    scored
        .iter()
        .enumerate()
        .filter(|(_, (s, _, _))| {
            s.rejected.is_none()
                && s.kind.family() == first.kind.family()
                && preference(s, look_alike) >= bar
        })
        .max_by(|a, b| a.1.0.held_out_lr.total_cmp(&b.1.0.held_out_lr))
        .map(|(i, _)| i)
        .filter(|&i| i != 0)
}

/// Scores candidate `c` added to the model with columns `kept` (`current`); `local`: the
/// held-out statistics where it acts with `current`'s cross-validation there; it must
/// gain `min_gain` (relative NRMSE) to be accepted.
fn score(
    search: &Search,
    kept: &[usize],
    c: usize,
    current: &Trial,
    local: Option<(&LocalFolds, &CrossValidation)>,
    level: f64,
    min_gain: f64,
) -> (CandidateScore, usize, Option<Trial>) {
    let (stats, options) = (search.stats, search.options);
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
        held_out_lr: 0.0,
        local_gain: None,
        active_share: local.map_or(1.0, |(lf, _)| lf.share),
        p: 1.0,
        rejected: None,
    };
    let t = match trial(
        stats,
        &columns,
        search.fit_options,
        options.variance_inflation,
    ) {
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
    s.held_out_lr = held_out_lr(&current.cv, &t.cv);
    s.local_gain = local.and_then(|(lf, before)| {
        let after = estimate::cross_validate(
            &t.structure,
            &lf.folds.select(&t.columns),
            search.fit_options,
        )
        .ok()?;
        Some(gains(before, &after)).filter(|g| g.iter().all(|x| x.is_finite()))
    });
    // The MMR couples the axes through shared parameters, so a candidate can pay on an
    // axis it has no column on (freeing a moment coefficient lets F_z fit itself):
    // gains count on every axis, losses too. A local effect counts where it acts, on
    // its own axes.
    s.total_gain = s.validation_gain.iter().sum();
    let (effect, on_axes): ([f64; 6], Vec<usize>) = match s.local_gain {
        Some(g) => (g, axes.iter().map(|&a| a as usize).collect()),
        None => (s.validation_gain, (0..6).collect()),
    };
    let best_axis = on_axes
        .iter()
        .map(|&a| effect[a])
        .fold(f64::NEG_INFINITY, f64::max);
    let net: f64 = effect.iter().sum();
    let worst = s.validation_gain.iter().fold(0.0_f64, |m, &g| m.min(g));
    let required_lr = required_lr(own.len(), stats.folds, options.variance_inflation, level);
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
    } else if s.held_out_lr < required_lr {
        Some(Rejection::NotPredictive {
            statistic: s.held_out_lr,
            required: required_lr,
        })
    } else if best_axis < min_gain {
        Some(Rejection::SmallGain {
            gain: best_axis,
            required: min_gain,
        })
    } else if net < min_gain {
        Some(Rejection::SmallNetGain {
            gain: net,
            required: min_gain,
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
        has_omega_ddot: first.is_some_and(|c| c.has_omega_ddot()),
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
    let mut local_parts = ActivityParts::default();
    let (mut active_ws, mut part_ws) = Default::default();
    for c in validation_data {
        extended
            .assemble(c, &mut ws)
            .map_err(AccumulateError::from)?;
        let parts = &mut local_parts;
        set.regions
            .push(c, &ws, &extended, parts, &mut active_ws, &mut part_ws)?;
    }
    let local_tests = set.regions.per_region(&local_parts, &extended)?;
    let folds = Folds::holdout("validation data", fa.clone(), va);
    let local: Vec<LocalFolds> = set
        .regions
        .candidates
        .iter()
        .zip(local_tests)
        .filter_map(|(&c, test)| LocalFolds::new(c, &folds, vec![test]))
        .collect();
    let stats = CandidateStatistics {
        extended: &extended,
        candidates: &set.candidates,
        candidate_params: &set.params,
        base_params: base.params.len(),
        fit: &fa,
        folds: &folds,
        report: None,
        local: &local,
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

    #[test]
    fn held_out_threshold_follows_the_null_distribution() {
        // One parameter, a quarter as many held-out as training samples, white
        // residuals, level 0.0228 (z = 2.0): 2·2·√0.25 − 0.25 = 1.75.
        let level = 1.0 - 0.977_249_868_051_820_8;
        let t = held_out_threshold(1, 0.25, 1.0, level);
        assert!((t - 1.75).abs() < 1e-6, "{t}");
        // Coloured residuals scale the null's mean and spread alike: κ times.
        let t = held_out_threshold(1, 0.25, 50.0, level);
        assert!((t - 87.5).abs() < 1e-4, "{t}");
        // Never below zero: a candidate must at least predict better.
        assert_eq!(held_out_threshold(4, 10.0, 1.0, 0.4), 0.0);
    }

    fn rotor_score(rotor: usize, scale: f64, lr: f64) -> CandidateScore {
        CandidateScore {
            name: format!("weak rotor {rotor}"),
            kind: EffectKind::RotorAsymmetry,
            axes: vec![Axis::Fz],
            parameters: vec![EffectParameter {
                name: format!("thrust_scale_{rotor}"),
                estimate: scale,
                std: 0.001,
                unit: "-".into(),
                p: 0.0,
            }],
            validation_gain: [0.0; 6],
            total_gain: 0.0,
            held_out_lr: lr,
            local_gain: None,
            active_share: 1.0,
            p: 0.0,
            rejected: None,
        }
    }

    #[test]
    fn a_rotor_asymmetry_is_reported_with_its_direction_and_its_equivalent() {
        let weak3 = rotor_score(3, -0.098, 500.0);
        let strong1 = rotor_score(1, 0.102, 499.0);
        assert_eq!(describe(&weak3), "rotor 3 weaker by 9.8 %");
        assert_eq!(describe(&strong1), "rotor 1 stronger by 10.2 %");
        assert_eq!(finding(&weak3, &[], &[]), "rotor 3 weaker by 9.8 %");
        assert_eq!(
            finding(&weak3, &[describe(&strong1)], &[]),
            "rotor 3 weaker by 9.8 % or rotor 1 stronger by 10.2 % (not separable with these data)"
        );
        assert_eq!(
            finding(&weak3, &[], &["CG offset".into()]),
            "rotor 3 weaker by 9.8 %; explains about as much: CG offset"
        );
    }

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
