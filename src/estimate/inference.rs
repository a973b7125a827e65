//! Inference on the MMR estimates (seed Table 5) and goodness of fit (Table 4).
//!
//! t₀ = θ̂/σ(θ̂); H₀: θ = 0 is tested two-sided against Student's t with N − n_θ degrees
//! of freedom (seed §5.2), N the sample count and n_θ the number of estimated parameters;
//! P = 2·S(|t₀|) with the survival function S, so tiny P-values keep full relative
//! precision instead of underflowing as 1 − CDF would.

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, StudentsT};

use super::EstimateError;
use crate::model::ModelStructure;
use crate::sample::Axis;
use crate::stats::Accumulator;

/// One estimated parameter with its statistics (a row of seed Table 5).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterEstimate {
    /// Parameter name.
    pub name: String,
    /// Unit of the estimate.
    pub unit: String,
    /// θ̂.
    pub estimate: f64,
    /// σ(θ̂) from (Hᵀ(R⁻¹⊗I)H)⁻¹ (white residuals).
    pub std_error: f64,
    /// t₀ = θ̂/σ.
    pub t: f64,
    /// Two-sided P-value of H₀: θ = 0.
    pub p_value: f64,
    /// Half-width of the 95 % confidence interval, t(0.975, dof)·σ.
    pub ci95_half_width: f64,
}

/// Two-sided P-value and 97.5 % quantile of Student's t with `dof` degrees of freedom.
/// A t that is not a number (0/0: zero estimate with zero standard error) has no
/// P-value (NaN); |t| = ∞ has P = 0. statrs is never called with a non-finite argument
/// (its regularised beta panics outside [0, 1]).
pub(crate) fn t_test(t: f64, dof: f64) -> (f64, f64) {
    let d = match StudentsT::new(0.0, 1.0, dof) {
        Ok(d) if dof.is_finite() => d,
        _ => return (f64::NAN, f64::NAN),
    };
    let p = if t.is_nan() {
        f64::NAN
    } else if t.is_infinite() {
        0.0
    } else {
        2.0 * d.sf(t.abs())
    };
    (p, t_quantile_975(&d, dof))
}

/// Degrees of freedom above which the t quantile comes from its expansion in 1/ν:
/// statrs' inverse regularised beta, which `inverse_cdf` uses, has no iteration limit
/// and ran for minutes at ν ≈ 1.6e7 (16 M samples).
const LARGE_DOF: f64 = 1000.0;

/// 97.5 % quantile of `d` (Student's t with `dof` degrees of freedom). For large ν the
/// Cornish–Fisher expansion about the normal quantile z (Abramowitz & Stegun 26.7.5),
/// t = z + g₁/ν + g₂/ν² + g₃/ν³, whose next term is below 1e-11 at ν = 1000.
fn t_quantile_975(d: &StudentsT, dof: f64) -> f64 {
    if dof <= LARGE_DOF {
        return d.inverse_cdf(0.975);
    }
    let z: f64 = 1.959_963_984_540_054;
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    let g1 = (z3 + z) / 4.0;
    let g2 = (5.0 * z5 + 16.0 * z3 + 3.0 * z) / 96.0;
    let g3 = (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / 384.0;
    z + g1 / dof + g2 / dof.powi(2) + g3 / dof.powi(3)
}

/// Goodness of fit of one axis (a row of seed Table 4).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AxisMetrics {
    /// Output axis.
    pub axis: Axis,
    /// Centred R² = 1 − SSE/Σ(z − z̄)² (may be negative).
    pub r2: f64,
    /// Root-mean-square error √(SSE/N), N or N m.
    pub rmse: f64,
    /// RMSE/(max z − min z).
    pub nrmse: f64,
    /// Theil's inequality coefficient RMSE/(rms(ŷ) + rms(z)).
    pub tic: f64,
}

/// Goodness of fit over all axes: the mean of the six per-axis values (the axes have
/// different units, so no pooled sum is meaningful).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OverallMetrics {
    /// Mean centred R².
    pub r2: f64,
    /// Mean NRMSE.
    pub nrmse: f64,
    /// Mean TIC.
    pub tic: f64,
}

impl OverallMetrics {
    /// Means of `axes`.
    pub fn of(axes: &[AxisMetrics; 6]) -> Self {
        let mean = |f: fn(&AxisMetrics) -> f64| axes.iter().map(f).sum::<f64>() / 6.0;
        Self {
            r2: mean(|a| a.r2),
            nrmse: mean(|a| a.nrmse),
            tic: mean(|a| a.tic),
        }
    }
}

/// Sums of one axis' prediction errors on some data, from which R², NRMSE and TIC
/// follow; sums of disjoint data sets (cross-validation folds) pool by [`ErrorSums::add`]
/// into the metrics of the concatenated predictions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ErrorSums {
    /// Output axis.
    pub axis: Axis,
    /// Samples.
    pub n: f64,
    /// Σ(z − ŷ)², in the axis unit squared.
    pub sse: f64,
    /// Σŷ² of the model output.
    pub predicted_ss: f64,
    /// Mean of the measured (corrected) output z̄.
    pub mean: f64,
    /// Σ(z − z̄)².
    pub centred_ss: f64,
    /// Σz².
    pub output_ss: f64,
    /// Smallest z.
    pub min: f64,
    /// Largest z.
    pub max: f64,
}

impl ErrorSums {
    /// No data.
    pub fn empty(axis: Axis) -> Self {
        Self {
            axis,
            n: 0.0,
            sse: 0.0,
            predicted_ss: 0.0,
            mean: 0.0,
            centred_ss: 0.0,
            output_ss: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }

    /// Adds the sums of disjoint data (moments combined by Chan et al.'s pairwise update).
    pub fn add(&mut self, other: &ErrorSums) {
        let n = self.n + other.n;
        if n == 0.0 {
            return;
        }
        let delta = other.mean - self.mean;
        self.centred_ss += other.centred_ss + delta * delta * self.n * other.n / n;
        self.mean += delta * other.n / n;
        self.n = n;
        self.sse += other.sse;
        self.predicted_ss += other.predicted_ss;
        self.output_ss += other.output_ss;
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    /// R², RMSE, NRMSE and TIC of these sums.
    pub fn metrics(&self) -> AxisMetrics {
        let n = self.n;
        let rmse = (self.sse / n).sqrt();
        AxisMetrics {
            axis: self.axis,
            r2: 1.0 - self.sse / self.centred_ss,
            rmse,
            nrmse: rmse / (self.max - self.min),
            tic: rmse / ((self.predicted_ss / n).sqrt() + (self.output_ss / n).sqrt()),
        }
    }
}

/// Prediction-error sums per axis of the model `structure` with parameters `theta` (one
/// per `structure.params`) on the data summarised by `acc`: no pass over the samples is
/// needed.
pub fn error_sums(
    structure: &ModelStructure,
    theta: &[f64],
    acc: &Accumulator,
) -> Result<[ErrorSums; 6], EstimateError> {
    if theta.len() != structure.params.len() || acc.n_columns() != structure.columns.len() {
        return Err(EstimateError::ShapeMismatch {
            parameters: structure.params.len(),
            theta: theta.len(),
            columns: structure.columns.len(),
            accumulated: acc.n_columns(),
        });
    }
    if acc.count() == 0 {
        return Err(EstimateError::TooFewSamples {
            samples: 0,
            parameters: theta.len(),
        });
    }
    Ok(Axis::ALL.map(|axis| {
        let mut fit = vec![0.0; acc.m()];
        for c in structure.axis_columns(axis) {
            fit[c] = theta[structure.columns[c].param.index()];
        }
        let zc = acc.output_index(axis);
        let mut resid: Vec<f64> = fit.iter().map(|v| -v).collect();
        resid[zc] = 1.0;
        ErrorSums {
            axis,
            n: acc.count() as f64,
            sse: acc.combination_norm2(&resid),
            predicted_ss: acc.combination_norm2(&fit),
            mean: acc.output_mean(axis),
            centred_ss: acc.output_centred_ss(axis),
            output_ss: acc.cross(zc, zc),
            min: acc.min(zc),
            max: acc.max(zc),
        }
    }))
}

/// R², NRMSE and TIC per axis of the model `structure` with parameters `theta` (one per
/// `structure.params`) on the data summarised by `acc` (e.g. validation data): no pass
/// over the samples is needed.
pub fn evaluate(
    structure: &ModelStructure,
    theta: &[f64],
    acc: &Accumulator,
) -> Result<[AxisMetrics; 6], EstimateError> {
    Ok(error_sums(structure, theta, acc)?.map(|s| s.metrics()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantile_is_continuous_and_fast_at_huge_dof() {
        // At the switch the expansion and statrs' inversion agree to 1e-9 (the
        // expansion's truncation error there is ~1e-11, statrs' tolerance ~1e-9).
        let d = StudentsT::new(0.0, 1.0, LARGE_DOF).unwrap();
        let exact = d.inverse_cdf(0.975);
        let just_above = t_test(0.0, LARGE_DOF * (1.0 + 1e-12)).1;
        assert!((exact - just_above).abs() < 1e-9, "{exact} vs {just_above}");
        // 16 M samples (two 10 M-row logs) once hung in statrs; the quantile tends to
        // the normal z, and the P-value of t = 3 to the normal 2.6998e-3.
        let (p, q) = t_test(3.0, 1.6e7);
        assert!((q - 1.959_963_984_540_054).abs() < 1e-6, "{q}");
        assert!((p - 2.699_796_063_260_2e-3).abs() < 1e-8, "{p}");
    }

    #[test]
    fn non_finite_t_and_dof_give_nan_not_a_panic() {
        // 0/0 (zero estimate, zero standard error) once reached statrs' beta function.
        let zero = 0.0_f64;
        let (p, q) = t_test(zero / zero, 10.0);
        assert!(p.is_nan());
        assert!((q - 2.228_139).abs() < 1e-6, "{q}");
        assert_eq!(t_test(f64::INFINITY, 10.0).0, 0.0);
        assert_eq!(t_test(f64::NEG_INFINITY, 10.0).0, 0.0);
        assert!(t_test(1.0, f64::NAN).0.is_nan());
        assert!(t_test(1.0, 0.0).0.is_nan());
        assert!(t_test(1.0, f64::INFINITY).0.is_nan());
    }
}
