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
    /// How much more an unspecific hypothesis (a freed coefficient, a generic term) must
    /// explain than the best accepted named one (a mechanism or a completion of Eq. 22)
    /// to be added before it: its cross-validated gain must exceed the named one's by
    /// this fraction. An unspecific term has the freedom of a shape fitted to the
    /// residual and says only "something of this shape"; a named mechanism is held to
    /// its physics, so when both explain the residual the named one goes first unless
    /// it falls clearly short (by a third at 0.5: far outside the `look_alike` band of
    /// gains within noise of each other). Added first, a catch-all would also mask the
    /// physics that follows it.
    pub unspecific_margin: f64,
    /// Most effects added (no limit by default: the search stops when no candidate pays
    /// on held-out data).
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
            unspecific_margin: 0.5,
            max_effects: usize::MAX,
            max_generic: 1,
            variance_inflation: 1.0,
        }
    }
}
