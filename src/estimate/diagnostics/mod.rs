//! Residual diagnostics of the MMR model: a streaming, mergeable second pass.
//!
//! Per axis: a histogram with its fitted Gaussian and the linearity of ordered residuals
//! against the inverse normal CDF (seed Figure 3), and the residual autocorrelation up to
//! lag L. For the estimates: coloured-residual corrected standard errors after Morelli
//! (Morelli & Klein 2016, §5.2), generalised to the six-output weighted fit of Eq. 24:
//!
//! Cov(θ̂) = B⁻¹ [Σ_{k=−L}^{L} Σ_t Σ_ab H_{t,a}ᵀ (W Γ(k) W)_ab H_{t+k,b}] B⁻¹,
//!
//! with B = Hᵀ(R⁻¹⊗I)H, W = R⁻¹, and Γ(k)_ab = (1/N) Σ_t v_{t,a} v_{t+k,b} the residual
//! cross-correlation at lag k (the stationary R_vv of Morelli's formula). For white
//! residuals (Γ(k) = 0, k ≠ 0, Γ(0) = R) it reduces to B⁻¹. Lags beyond L are taken as
//! zero (rectangular window), so the pass costs O(N·L·p²) for p regressor columns
//! (computed per chunk as L matrix products): linear in N, never O(N²).
//!
//! The per-axis OLS estimates get Morelli's formula itself,
//! Cov(θ̂_i) = (X_iᵀX_i)⁻¹ [Σ_{k=−L}^{L} r_i(k) Σ_t x_t x_{t+k}ᵀ] (X_iᵀX_i)⁻¹, with r_i the
//! autocorrelation of that axis' OLS residuals.
//!
//! The pass keeps the lag products Σ_t x_t x_{t+k}ᵀ and Σ_t v_t v_{t+k}ᵀ and the first and
//! last L rows it saw, so two passes over consecutive segments merge exactly (the cross
//! terms across the seam are added at merge time). The regressors' lag products are kept
//! over the distinct column shapes, as the accumulator keeps its factor: a column that is
//! a constant multiple f of another (`u*dt` of F_x and `h*u*dt` of M_y) has lag products
//! f × those of the other, so quadrotor× needs 30 of its 38 columns (0.6× the flops).

mod math;
mod residual_pass;
mod scores;

use serde::{Deserialize, Serialize};

use crate::sample::Axis;

pub use residual_pass::{ResidualPass, ResidualSums};

/// Options of the residual pass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DiagnosticOptions {
    /// Largest lag L (samples) of the autocorrelation and of the coloured-residual
    /// correction. Choose it past the lag where the residual autocorrelation dies out.
    pub max_lag: usize,
    /// Histogram bins per axis.
    pub bins: usize,
    /// Histogram range ± this many residual standard deviations (σ̂ from the fit);
    /// residuals outside are counted in under/overflow cells.
    pub range_sigmas: f64,
}

impl Default for DiagnosticOptions {
    fn default() -> Self {
        Self {
            max_lag: 10,
            bins: 60,
            range_sigmas: 6.0,
        }
    }
}

/// Histogram of one axis' residuals.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// Lower edge of the first bin, N or N m.
    pub lo: f64,
    /// Upper edge of the last bin, N or N m.
    pub hi: f64,
    /// Counts per equal-width bin.
    pub counts: Vec<u64>,
    /// Residuals below `lo`.
    pub below: u64,
    /// Residuals at or above `hi`.
    pub above: u64,
    /// Smallest residual.
    pub min: f64,
    /// Largest residual.
    pub max: f64,
}

impl Histogram {
    /// `(lower edge, upper edge, count)` of every cell in order, the underflow cell
    /// spanning min..lo and the overflow cell hi..max (N or N m).
    pub fn cells(&self) -> Vec<(f64, f64, u64)> {
        let width = (self.hi - self.lo) / self.counts.len().max(1) as f64;
        let mut cells = Vec::with_capacity(self.counts.len() + 2);
        cells.push((self.min, self.lo, self.below));
        cells.extend(self.counts.iter().enumerate().map(|(b, &c)| {
            let lo = self.lo + b as f64 * width;
            (lo, lo + width, c)
        }));
        cells.push((self.hi, self.max, self.above));
        cells
    }
}

/// Residual diagnostics of one axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisResiduals {
    /// Output axis.
    pub axis: Axis,
    /// Mean of the fitted Gaussian (residual mean), N or N m.
    pub mean: f64,
    /// Standard deviation of the fitted Gaussian, N or N m.
    pub std_dev: f64,
    /// Histogram.
    pub histogram: Histogram,
    /// Correlation of ordered residuals with Φ⁻¹((i − 3/8)/(N + 1/4)) (Blom positions);
    /// order statistics are placed uniformly within histogram bins, so the value is
    /// resolved to about the bin width.
    pub normal_probability_correlation: f64,
    /// Autocorrelation ρ(k) = Γ_aa(k)/Γ_aa(0), k = 0..=L.
    pub autocorrelation: Vec<f64>,
    /// ±1.96/√N: the 95 % band of ρ(k) for white residuals.
    pub white_band95: f64,
}

/// Standard error of one MMR estimate, white and coloured-residual corrected.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColouredStdError {
    /// Parameter name.
    pub name: String,
    /// σ(θ̂) assuming white residuals (from the fit).
    pub white: f64,
    /// σ(θ̂) corrected for coloured residuals (Morelli); NaN if the truncated estimate of
    /// the variance came out negative.
    pub coloured: f64,
}

/// Result of the residual pass.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ResidualDiagnostics {
    /// Samples seen.
    pub samples: u64,
    /// Lag L used.
    pub max_lag: usize,
    /// Per axis, [`Axis`] order.
    pub axes: Vec<AxisResiduals>,
    /// Per estimated MMR parameter.
    pub std_errors: Vec<ColouredStdError>,
    /// Per axis ([`Axis`] order), per kept OLS term (named `param (label)`).
    pub ols_std_errors: Vec<Vec<ColouredStdError>>,
}
