//! The thresholds of the diagnosis (screening and search), shared by the candidate set
//! and the procedure.

use serde::Serialize;

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
