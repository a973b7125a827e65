//! The seed's two-step estimation (§5), from one pass of mergeable statistics
//! ([`crate::stats::Accumulator`]):
//!
//! 1. per axis: OLS on all columns ([`ols`]) and the FSOA R² tables ([`mod@fsoa`],
//!    Algorithm 1, Tables 2–3), residual variances σ̂²;
//! 2. the residual covariance R (6 × 6) of the per-axis fits weights the multivariate
//!    multiple regression of Eq. 24 ([`mmr`]), with σ, t₀ and P-values
//!    ([`inference`], Table 5) and per-axis R², NRMSE and TIC (Table 4);
//! 3. a streaming second pass ([`diagnostics`]) for residual histograms, normal
//!    probability linearity (Figure 3), autocorrelation and coloured-residual corrected
//!    standard errors.
//!
//! [`identifiability`] guards every solve: parameters the data cannot separate are
//! reported and refused or dropped, never estimated.

pub mod crossval;
pub mod diagnostics;
pub mod fsoa;
pub mod identifiability;
pub mod inference;
mod lstsq;
pub mod mmr;
pub mod ols;
pub mod remainder;

use serde::Serialize;

pub use crossval::{CrossValidation, Folds, cross_validate};
pub use diagnostics::{DiagnosticOptions, ResidualDiagnostics, ResidualPass, ResidualSums};
pub use fsoa::{Addition, FsoaStep, FsoaTable, fsoa, score_addition};
pub use identifiability::{DroppedTerm, ProblemConditioning};
pub use inference::{
    AxisMetrics, ErrorSums, OverallMetrics, ParameterEstimate, error_sums, evaluate,
};
pub(crate) use lstsq::SingularValues;
pub use mmr::Weighting;
pub use ols::{AxisOls, axis_ols};

use crate::model::{ModelStructure, ParamId};
use crate::sample::Axis;
use crate::stats::Accumulator;

/// What to do with parameters the data cannot separate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum UnidentifiablePolicy {
    /// Fail with [`EstimateError::Unidentifiable`] naming the parameters involved.
    Refuse,
    /// Drop them one at a time (largest weight in the weakest singular direction first)
    /// and list them in the identifiability report.
    #[default]
    Drop,
}

/// Options of [`fit`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FitOptions {
    /// A design whose equilibrated (unit-norm columns) smallest singular value is at
    /// most `rank_tol` times its largest is treated as singular. Default 1e-10: at
    /// σ_min/σ_max = 1e-10 a double-precision QR still keeps about 6 significant digits.
    pub rank_tol: f64,
    /// Refuse or drop unidentifiable parameters.
    pub unidentifiable: UnidentifiablePolicy,
    /// F_in of the partial-F stopping rule marked in the FSOA tables (Morelli suggests
    /// 4 to 5 for large N).
    pub f_in: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            rank_tol: 1e-10,
            unidentifiable: UnidentifiablePolicy::Drop,
            f_in: 4.0,
        }
    }
}

/// Why a fit could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EstimateError {
    /// The data cannot separate these parameters (and the policy is to refuse).
    #[error(
        "{problem}: the data cannot separate {parameters:?} (condition number of the equilibrated design {condition_number:.3e}); excite them independently or drop them"
    )]
    Unidentifiable {
        /// `OLS Fx` … or `MMR`.
        problem: String,
        /// Parameters (or terms) in the near-null directions.
        parameters: Vec<String>,
        /// Condition number of the equilibrated design.
        condition_number: f64,
    },
    /// Not more samples than parameters.
    #[error("{samples} samples cannot estimate {parameters} parameters")]
    TooFewSamples {
        /// Samples accumulated.
        samples: u64,
        /// Parameters to estimate.
        parameters: usize,
    },
    /// The data hold too little information for any fit of the model: one repeated
    /// state, fewer distinct states than parameters, or an output that never changes.
    /// The message says why and names what cannot be identified.
    #[error("the data cannot support a fit: {reason}")]
    Unsupported {
        /// Why, naming the parameters or outputs concerned.
        reason: String,
    },
    /// θ, structure and accumulator do not belong together.
    #[error(
        "shape mismatch: structure has {parameters} parameters and {columns} columns, θ has {theta} values, accumulator has {accumulated} columns"
    )]
    ShapeMismatch {
        /// Parameters of the structure.
        parameters: usize,
        /// Length of θ.
        theta: usize,
        /// Columns of the structure.
        columns: usize,
        /// Columns of the accumulator.
        accumulated: usize,
    },
}

/// Per-axis results of step 1.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisFit {
    /// OLS on all identifiable columns of the axis.
    pub ols: AxisOls,
    /// FSOA table (seed Tables 2–3).
    pub fsoa: FsoaTable,
}

/// The MMR estimates (seed Eq. 24, Table 5).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MmrEstimates {
    /// Estimated parameters, in structure order (dropped ones omitted).
    pub parameters: Vec<ParameterEstimate>,
    /// Each estimated parameter of the structure.
    pub param_index: Vec<ParamId>,
    /// Full θ over `ModelStructure::params` (0 for dropped parameters), for
    /// [`evaluate`] and prediction.
    pub theta: Vec<f64>,
    /// Parameter covariance (Hᵀ(R⁻¹⊗I)H)⁻¹, row-major over `parameters`.
    pub covariance: Vec<f64>,
    /// Degrees of freedom of the t-tests, N − n_θ.
    pub dof: f64,
    /// Why σ, t and P carry no information (the model interpolates the data, or the
    /// residual covariance is singular), when they do not: they are then not reported.
    pub inference_withheld: Option<String>,
    /// Weighting actually used.
    pub weighting: Weighting,
    /// R⁻¹ used as weight, row-major 6 × 6.
    pub weight: [[f64; 6]; 6],
}

/// Everything the two-step estimation produces (seed Tables 2–5).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fit {
    /// Samples used N.
    pub samples: u64,
    /// Step 1, one entry per axis in [`Axis`] order.
    pub axes: Vec<AxisFit>,
    /// Residual covariance R of the per-axis fits, R_ij = e_iᵀe_j/√((N − p_i)(N − p_j)).
    pub residual_covariance: [[f64; 6]; 6],
    /// Step 2.
    pub mmr: MmrEstimates,
    /// Goodness of fit of the MMR model per axis (Table 4).
    pub metrics: [AxisMetrics; 6],
    /// Means over axes.
    pub overall: OverallMetrics,
    /// Conditioning and dropped terms of every solve.
    pub identifiability: Vec<ProblemConditioning>,
}

impl Fit {
    /// Step 1's estimates, one per column of a structure of `columns` columns: each
    /// column's estimate in its own axis's OLS (0 where that fit dropped it). A
    /// parameter shared between axes has one value per axis here.
    pub fn own_axis_estimates(&self, columns: usize) -> Vec<f64> {
        let mut out = vec![0.0; columns];
        for ols in self.axes.iter().map(|a| &a.ols) {
            for (&j, &th) in ols.columns.iter().zip(&ols.theta) {
                out[j] = th;
            }
        }
        out
    }
}

/// Runs the two-step estimation of the seed on the statistics in `acc`.
pub fn fit(
    structure: &ModelStructure,
    acc: &Accumulator,
    options: &FitOptions,
) -> Result<Fit, EstimateError> {
    let mut fit = fit_without_fsoa(structure, acc, options, SingularValues::Always)?;
    add_fsoa_tables(&mut fit, structure, acc, options)?;
    Ok(fit)
}

/// [`fit`] with empty FSOA tables (no steps), which the estimates do not depend on: for
/// the many refits of cross-validation and of a diagnosis that use only the estimates
/// (with [`SingularValues::WhenRankInDoubt`], which leaves the estimates as they are and
/// the condition numbers NaN).
pub(crate) fn fit_without_fsoa(
    structure: &ModelStructure,
    acc: &Accumulator,
    options: &FitOptions,
    singular_values: SingularValues,
) -> Result<Fit, EstimateError> {
    let Solved {
        axes,
        residual_covariance,
        sol,
        mut identifiability,
    } = solve_both_steps(structure, acc, options, singular_values)?;
    identifiability.push(sol.conditioning);
    let n = acc.count() as f64;
    let k = sol.params.len();
    let dof = n - k as f64;
    let mut theta = vec![0.0; structure.params.len()];
    let parameters = sol
        .params
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            theta[p.index()] = sol.ls.theta[j];
            let estimate = sol.ls.theta[j];
            let std_error = sol.ls.xtx_inv[j * k + j].sqrt();
            let t = estimate / std_error;
            let (p_value, t975) = inference::t_test(t, dof);
            ParameterEstimate {
                name: structure.param(p).name.clone(),
                unit: structure.param(p).unit.clone(),
                estimate,
                std_error,
                t,
                p_value,
                ci95_half_width: t975 * std_error,
            }
        })
        .collect();
    let metrics = evaluate(structure, &theta, acc)?;
    let inference_withheld = inference_withheld(acc, &axes, sol.weighting);
    Ok(Fit {
        samples: acc.count(),
        axes,
        residual_covariance,
        mmr: MmrEstimates {
            parameters,
            param_index: sol.params,
            theta,
            covariance: sol.ls.xtx_inv,
            dof,
            inference_withheld,
            weighting: sol.weighting,
            weight: sol.weight,
        },
        overall: OverallMetrics::of(&metrics),
        metrics,
        identifiability,
    })
}

/// The MMR estimates θ̂ (one per parameter of `structure`) of [`fit_without_fsoa`], bit
/// for bit, and its errors, without what only a report reads (t-tests, metrics, the
/// estimates' names): for cross-validation folds, which use θ̂ alone.
pub(crate) fn theta_only(
    structure: &ModelStructure,
    acc: &Accumulator,
    options: &FitOptions,
    singular_values: SingularValues,
) -> Result<Vec<f64>, EstimateError> {
    let Solved { sol, .. } = solve_both_steps(structure, acc, options, singular_values)?;
    let mut theta = vec![0.0; structure.params.len()];
    for (j, &p) in sol.params.iter().enumerate() {
        theta[p.index()] = sol.ls.theta[j];
    }
    Ok(theta)
}

/// Both steps of the estimation: the per-axis OLS fits, their residual covariance and
/// the MMR solution.
struct Solved {
    axes: Vec<AxisFit>,
    residual_covariance: [[f64; 6]; 6],
    sol: mmr::MmrSolution,
    /// The per-axis fits' conditioning (the MMR's is in `sol`).
    identifiability: Vec<ProblemConditioning>,
}

/// Steps 1 and 2 of [`fit_without_fsoa`] with its checks: the data support a fit and
/// there are more samples than estimated parameters.
fn solve_both_steps(
    structure: &ModelStructure,
    acc: &Accumulator,
    options: &FitOptions,
    singular_values: SingularValues,
) -> Result<Solved, EstimateError> {
    if acc.n_columns() != structure.columns.len() {
        return Err(EstimateError::ShapeMismatch {
            parameters: structure.params.len(),
            theta: structure.params.len(),
            columns: structure.columns.len(),
            accumulated: acc.n_columns(),
        });
    }
    check_support(structure, acc)?;
    let n = acc.count() as f64;
    let mut axes = Vec::with_capacity(6);
    let mut identifiability = Vec::new();
    for axis in Axis::ALL {
        let (ols, report) = ols::axis_ols_with(structure, acc, axis, options, singular_values)?;
        identifiability.push(report);
        let fsoa = FsoaTable::empty(axis, options.f_in);
        axes.push(AxisFit { ols, fsoa });
    }
    let residual_covariance = residual_covariance(acc, &axes);
    // Each variance is at least (ε · rms z_i)², the rounding level of the output.
    let floor = Axis::ALL.map(|a| {
        let zc = acc.output_index(a);
        (f64::EPSILON.powi(2) * acc.cross(zc, zc) / n).max(f64::MIN_POSITIVE)
    });
    let sol = mmr::solve(
        structure,
        acc,
        &residual_covariance,
        &floor,
        options,
        singular_values,
    )?;
    let k = sol.params.len();
    if n <= k as f64 {
        return Err(EstimateError::TooFewSamples {
            samples: acc.count(),
            parameters: k,
        });
    }
    Ok(Solved {
        axes,
        residual_covariance,
        sol,
        identifiability,
    })
}

/// Fills in the FSOA tables (Algorithm 1) of `fit`, a [`fit_without_fsoa`] of
/// `structure` on `acc`.
pub(crate) fn add_fsoa_tables(
    fit: &mut Fit,
    structure: &ModelStructure,
    acc: &Accumulator,
    options: &FitOptions,
) -> Result<(), EstimateError> {
    for (axis, a) in Axis::ALL.into_iter().zip(&mut fit.axes) {
        a.fsoa = fsoa(structure, acc, axis, options.f_in)?;
    }
    Ok(())
}

/// R_ij = e_iᵀe_j/√((N − p_i)(N − p_j)) from the per-axis OLS residuals e_i = A w_i,
/// computed as (R w_i)ᵀ(R w_j).
fn residual_covariance(acc: &Accumulator, axes: &[AxisFit]) -> [[f64; 6]; 6] {
    let images: Vec<Vec<f64>> = axes
        .iter()
        .map(|a| acc.combination(&a.ols.residual_weights(acc)))
        .collect();
    let mut r = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            let e: f64 = images[i].iter().zip(&images[j]).map(|(a, b)| a * b).sum();
            r[i][j] = e / (axes[i].ols.dof * axes[j].ols.dof).sqrt();
        }
    }
    r
}

/// Names of `params`, comma-separated.
fn param_names(structure: &ModelStructure, params: impl IntoIterator<Item = ParamId>) -> String {
    params
        .into_iter()
        .map(|p| structure.param(p).name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Refuses data that cannot support any fit of `structure`: a single repeated state
/// (every regressor constant, so no excitation), fewer distinct states than parameters
/// (the model interpolates them and the residual is not information), or an output
/// that is constant while regressors of its axis vary (e.g. a moment logged as all
/// zeros).
fn check_support(structure: &ModelStructure, acc: &Accumulator) -> Result<(), EstimateError> {
    let n_theta = structure.params.len();
    let all = || param_names(structure, structure.param_ids());
    match acc.distinct_rows() {
        Some(0) => {
            return Err(EstimateError::TooFewSamples {
                samples: acc.count(),
                parameters: n_theta,
            });
        }
        Some(1) => {
            return Err(EstimateError::Unsupported {
                reason: format!(
                    "all {} samples hold the same state (one distinct state: velocity, rates \
                     and rotor speeds never change), so there is no excitation and none of \
                     the {n_theta} parameters can be identified ({})",
                    acc.count(),
                    all()
                ),
            });
        }
        Some(d) if d < n_theta => {
            return Err(EstimateError::Unsupported {
                reason: format!(
                    "the {} samples hold only {d} distinct states, fewer than the {n_theta} \
                     parameters of the model, so no axis can determine more than {d} \
                     combinations of its parameters and the fit would interpolate the \
                     data; too little excitation to identify {}",
                    acc.count(),
                    all()
                ),
            });
        }
        _ => {}
    }
    for axis in Axis::ALL {
        let (lo, hi) = acc.measured_range(axis);
        // Constant where the model says it should respond: some regressor of the axis
        // varies. (With no excitation of the axis at all, e.g. F_x in pure vertical
        // flight, its terms are dropped as unidentifiable instead.)
        let excited = structure
            .axis_columns(axis)
            .any(|c| acc.min(c) != acc.max(c));
        if lo == hi && excited {
            let only_here: Vec<ParamId> = structure
                .param_ids()
                .filter(|&p| {
                    let mut cols = structure.columns.iter().filter(|c| c.param == p);
                    cols.clone().next().is_some() && cols.all(|c| c.axis == axis)
                })
                .collect();
            let lost = if only_here.is_empty() {
                String::new()
            } else {
                format!(
                    "; the parameters only {axis} determines cannot be identified ({})",
                    param_names(structure, only_here)
                )
            };
            return Err(EstimateError::Unsupported {
                reason: format!(
                    "output {axis} is {lo} {} in all {} samples: an output that never \
                     changes carries no information (was it logged?){lost}",
                    axis.unit(),
                    acc.count()
                ),
            });
        }
    }
    Ok(())
}

/// Relative residual level at or below which a fit is exact to rounding: the model
/// interpolates the data (no real log comes within orders of magnitude of it).
const INTERPOLATION_LEVEL: f64 = 1e-9;

/// Why σ, t and P of the MMR carry no information, if they do not: some axis is fitted
/// to rounding level (RMS residual ≤ [`INTERPOLATION_LEVEL`] × RMS output: zero residuals
/// are not information about the noise), or R had to be replaced by its diagonal.
fn inference_withheld(acc: &Accumulator, axes: &[AxisFit], weighting: Weighting) -> Option<String> {
    let exact: Vec<&str> = axes
        .iter()
        .filter(|a| {
            let zc = acc.output_index(a.ols.axis);
            a.ols.sse <= INTERPOLATION_LEVEL.powi(2) * acc.cross(zc, zc)
        })
        .map(|a| a.ols.axis.name())
        .collect();
    if !exact.is_empty() {
        Some(format!(
            "the model interpolates the data: the residuals of {} are at rounding level \
             (RMS at most {INTERPOLATION_LEVEL:e} of the output's), so σ, t and P carry no \
             information",
            exact.join(", ")
        ))
    } else if weighting == Weighting::Diagonal {
        Some(
            "the residual covariance R of the per-axis fits is singular, so the residuals \
             of some axes are exact combinations of others; σ, t and P carry no information"
                .into(),
        )
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{ModelOptions, Workspace};
    use crate::sample::{Sample, SampleChunk};

    /// The refits of cross-validation and of a diagnosis skip Algorithm 1; adding its
    /// tables afterwards gives exactly the fit of [`fit`] (equal as values, so every
    /// estimate, σ and metric is the same bits), and the estimates never depend on it.
    #[test]
    fn a_fit_without_fsoa_completed_equals_the_full_fit() {
        let v = crate::model::test_quad();
        let structure = ModelStructure::eq22(&v, ModelOptions::default());
        let mut chunk = SampleChunk::with_capacity(4, 2000, true);
        for k in 0..2000 {
            let f = k as f64;
            let omega: Vec<f64> = (0..4)
                .map(|i| 700.0 + 200.0 * (0.01 * f + i as f64).sin())
                .collect();
            chunk.push(&Sample {
                t: 0.01 * f,
                velocity: [
                    3.0 * (0.003 * f).sin(),
                    2.0 * (0.005 * f).cos(),
                    (0.007 * f).sin(),
                ],
                rates: [
                    (0.011 * f).sin(),
                    (0.013 * f).cos(),
                    0.5 * (0.017 * f).sin(),
                ],
                omega_dot: omega.iter().map(|w| 0.1 * w).collect(),
                wrench: std::array::from_fn(|a| {
                    (0.002 * f * (a + 1) as f64).sin() + omega[a % 4] * 1e-3
                }),
                omega,
                ..Sample::default()
            });
        }
        let mut acc = Accumulator::new(&structure);
        acc.push(&structure, &chunk, &mut Workspace::default())
            .unwrap();
        let options = FitOptions::default();
        let full = fit(&structure, &acc, &options).unwrap();
        let mut lean =
            fit_without_fsoa(&structure, &acc, &options, SingularValues::Always).unwrap();
        assert!(lean.axes.iter().all(|a| a.fsoa.steps.is_empty()));
        assert_eq!(lean.mmr, full.mmr);
        assert!(full.axes.iter().all(|a| !a.fsoa.steps.is_empty()));
        add_fsoa_tables(&mut lean, &structure, &acc, &options).unwrap();
        assert_eq!(lean, full);
    }
}
