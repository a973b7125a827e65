//! Trial fits: a sub-model of the base structure extended by every candidate, fitted on
//! all fit data and cross-validated on the folds from the accumulated statistics, and the
//! tests on it (joint Wald test, held-out likelihood ratio and its null threshold, gains).

use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

use crate::diagnose::candidate::Candidate;
use crate::diagnose::local::LocalFolds;
use crate::estimate::{
    self, CrossValidation, EstimateError, Fit, FitOptions, Folds, SingularValues,
};
use crate::model::{ModelStructure, ParamId};
use crate::stats::Accumulator;
/// Statistics of the base structure extended by every candidate.
pub struct CandidateStatistics<'a> {
    /// Base structure followed by every candidate (in `candidates` order).
    pub extended: &'a ModelStructure,
    /// The candidates, in the order they were added to `extended`.
    pub candidates: &'a [Candidate],
    /// The parameters in `extended` of each candidate.
    pub candidate_params: &'a [Vec<ParamId>],
    /// Number of base parameters (the first ones of `extended`).
    pub base_params: usize,
    /// Statistics of all fit data over `extended` (the estimates).
    pub fit: &'a Accumulator,
    /// Cross-validation folds of the fit data over `extended` (every decision).
    pub folds: &'a Folds,
    /// Reporting-only validation statistics over `extended` (no decision uses them).
    pub report: Option<&'a Accumulator>,
    /// Held-out statistics where each local candidate acts ([`crate::diagnose::local`]).
    pub local: &'a [LocalFolds],
}

impl CandidateStatistics<'_> {
    /// Indices of the columns of `extended` whose parameter satisfies `keep`, ascending.
    pub(super) fn columns_of(&self, keep: impl Fn(ParamId) -> bool) -> Vec<usize> {
        (0..self.extended.columns.len())
            .filter(|&j| keep(self.extended.columns[j].param))
            .collect()
    }
}

/// Fit of a sub-model of `stats.extended`: the estimates (FSOA tables left empty), σ and
/// P with the coloured-residual correction, its cross-validation, and the structure.
#[derive(Clone)]
pub(super) struct Trial {
    pub(super) fit: Fit,
    /// Standard deviations with the coloured-residual correction, per parameter.
    pub(super) std: Vec<f64>,
    /// Two-sided P-values of the t-tests, per parameter.
    pub(super) p: Vec<f64>,
    pub(super) cv: CrossValidation,
    pub(super) structure: ModelStructure,
    /// Column indices into `stats.extended`.
    pub(super) columns: Vec<usize>,
}

/// Fits the sub-model of `stats.extended` with columns `columns` (indices into
/// `extended.columns`, ascending) on all fit data and on every fold.
pub(super) fn trial(
    stats: &CandidateStatistics,
    columns: &[usize],
    options: &FitOptions,
    inflation: f64,
) -> Result<Trial, EstimateError> {
    let structure = stats.extended.select_columns(columns);
    let fit = fit_on_all(stats, &structure, columns, options)?;
    let cv = held_out(stats, &structure, columns, options)?;
    Ok(with_inference(fit, cv, structure, columns, inflation))
}

/// [`trial`] of columns whose held-out errors `cv` ([`held_out`]) are known already.
pub(super) fn trial_with_held_out(
    stats: &CandidateStatistics,
    columns: &[usize],
    cv: CrossValidation,
    options: &FitOptions,
    inflation: f64,
) -> Result<Trial, EstimateError> {
    let structure = stats.extended.select_columns(columns);
    let fit = fit_on_all(stats, &structure, columns, options)?;
    Ok(with_inference(fit, cv, structure, columns, inflation))
}

/// The fit of `structure`, the sub-model of `stats.extended` with columns `columns`, on
/// all fit data.
fn fit_on_all(
    stats: &CandidateStatistics,
    structure: &ModelStructure,
    columns: &[usize],
    options: &FitOptions,
) -> Result<Fit, EstimateError> {
    // The conditioning of a trial is not read: only the adopted model's is reported, from
    // a refit (`diagnose_on_threads`).
    estimate::fit_without_fsoa(
        structure,
        &stats.fit.select(columns),
        options,
        SingularValues::WhenRankInDoubt,
    )
}

/// The trial of `fit` and `cv`: σ and P with the coloured-residual correction
/// `inflation`.
fn with_inference(
    fit: Fit,
    cv: CrossValidation,
    structure: ModelStructure,
    columns: &[usize],
    inflation: f64,
) -> Trial {
    let mut std = vec![0.0; structure.params.len()];
    let mut p = vec![1.0; structure.params.len()];
    let inflation = inflation.max(1.0).sqrt();
    for (est, &i) in fit.mmr.parameters.iter().zip(&fit.mmr.param_index) {
        let i = i.index();
        std[i] = est.std_error * inflation;
        p[i] = crate::estimate::inference::t_test(est.estimate / std[i], fit.mmr.dof).0;
    }
    Trial {
        fit,
        std,
        p,
        cv,
        structure,
        columns: columns.to_vec(),
    }
}

/// The held-out errors on every fold of `structure`, the sub-model of `stats.extended`
/// with columns `columns`: what scores a [`trial`], without its fit on all data.
pub(super) fn held_out(
    stats: &CandidateStatistics,
    structure: &ModelStructure,
    columns: &[usize],
    options: &FitOptions,
) -> Result<CrossValidation, EstimateError> {
    estimate::cross_validate(structure, &stats.folds.select(columns), options)
}

/// P-value of the Wald test that the parameters `own` (of the trial's structure) are
/// all zero: W = θᵀ(κΣ)⁻¹θ against χ² with one degree of freedom per
/// estimated parameter, κ the coloured-residual variance inflation. A joint test, so a
/// candidate of several correlated parameters is not penalised for their correlation
/// (each one's t can be small while together they explain much). 1 when none of them
/// could be estimated.
pub(super) fn joint_p(t: &Trial, own: &[ParamId], inflation: f64) -> f64 {
    let at: Vec<usize> = own
        .iter()
        .filter_map(|p| t.fit.mmr.param_index.iter().position(|e| e == p))
        .collect();
    let k = at.len();
    let mmr = &t.fit.mmr;
    let n = mmr.param_index.len();
    let theta: Vec<f64> = at
        .iter()
        .map(|&i| mmr.theta[mmr.param_index[i].index()])
        .collect();
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
    crate::util::survival(&chi2, w)
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
pub(super) fn gains(before: &CrossValidation, after: &CrossValidation) -> [f64; 6] {
    let (b, a) = (before.balanced_nrmse(), after.balanced_nrmse());
    std::array::from_fn(|k| {
        if b[k] > 0.0 {
            (b[k] - a[k]) / b[k]
        } else {
            0.0
        }
    })
}

/// The `p` quantile of χ² with `k` degrees of freedom (∞ when undefined).
pub(super) fn chi2_quantile(k: f64, p: f64) -> f64 {
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
pub(super) fn required_lr(k: usize, folds: &Folds, inflation: f64, level: f64) -> f64 {
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
pub(super) fn held_out_lr(before: &CrossValidation, after: &CrossValidation) -> f64 {
    before
        .folds
        .iter()
        .zip(&after.folds)
        .flat_map(|(b, a)| b.iter().zip(a))
        .filter(|(b, _)| b.sse > 0.0 && b.n > 0.0)
        .map(|(b, a)| (b.sse - a.sse) / (b.sse / b.n))
        .sum()
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
}
