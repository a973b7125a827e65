//! What the pipeline hands back: the Eq. 22 fit with its cross-validation and
//! validation figures, the second pass's residual diagnostics and plot series, and the
//! diagnosis.

use super::FitRequest;
use super::blocks::BlockPlan;
use crate::diagnose::Diagnosis;
use crate::estimate::{AxisMetrics, CrossValidation, Fit, ResidualDiagnostics};
use crate::io::Summary;
use crate::model::{ModelError, Workspace};
use crate::sample::{Axis, SampleChunk};
use crate::stats::Accumulator;

/// Decimated measured/predicted series for plots, per axis.
#[derive(Debug, Clone, Default)]
pub struct PlotSeries {
    /// Time, s (logs are laid end to end).
    pub t: Vec<f64>,
    /// Measured output per axis (N, N m).
    pub measured: [Vec<f64>; 6],
    /// The Eq. 22 model's output per axis (N, N m).
    pub predicted: [Vec<f64>; 6],
    /// The adopted model's output per axis (N, N m): the final (diagnosed) model's, the
    /// Eq. 22 model's on the axes it predicts better; empty when the diagnosis did not
    /// run.
    pub final_predicted: [Vec<f64>; 6],
    /// Per effect the diagnosis added, on the axis it improved most: its load against
    /// the residual it explains (a partial-residual plot). Empty without the diagnosis.
    pub effects: Vec<EffectSeries>,
    /// The samples kept, as the regressors saw them, for the final model's output.
    pub(crate) samples: SampleChunk,
}

/// One added effect at the samples kept: the load it adds in the final model, the
/// residual of the final model without it (before) and with it (after). Where the
/// effect explains what Eq. 22 missed, "before" lies along the load and "after" is
/// flat.
#[derive(Debug, Clone)]
pub struct EffectSeries {
    /// The effect's name.
    pub name: String,
    /// The axis shown: where its load is the largest share of the measured variation.
    pub axis: Axis,
    /// The effect's load in the final model (N or N m).
    pub load: Vec<f64>,
    /// Measured minus the final model without the effect (N or N m).
    pub before: Vec<f64>,
    /// Measured minus the final model (N or N m).
    pub after: Vec<f64>,
}

impl PlotSeries {
    /// Appends `samples` to the samples kept (a chunk of no samples, which may have no
    /// rotor series at all, adds nothing).
    pub(crate) fn keep_samples(&mut self, samples: &SampleChunk) {
        if !samples.is_empty() {
            self.samples.extend_from(samples, 0..samples.len());
        }
    }

    /// Fills [`PlotSeries::final_predicted`] and [`PlotSeries::effects`] from the
    /// diagnosis `d`: the adopted model's output at the samples kept, and each added
    /// effect's load (the final model's output less its output with the effect's
    /// parameters set to zero).
    pub(crate) fn predict_final(&mut self, d: &Diagnosis) -> Result<(), ModelError> {
        if self.samples.is_empty() {
            return Ok(());
        }
        let mut ws = Workspace::default();
        // One assembly serves every θ: the final model's and each with an effect removed.
        let full = d
            .structure
            .predict_chunk(&d.theta, &self.samples, &mut ws)?;
        let mut effects = Vec::new();
        for effect in &d.effects_added {
            let mut theta = d.theta.clone();
            for p in &effect.parameters {
                if let Some(j) = d.structure.param_id(&p.name) {
                    theta[j.index()] = 0.0;
                }
            }
            let without = d.structure.predict_assembled(&theta, &self.samples, &ws);
            let share = |a: usize| {
                let load: f64 = full[a]
                    .iter()
                    .zip(&without[a])
                    .map(|(f, w)| (f - w).powi(2))
                    .sum();
                load / centred_sum_of_squares(&self.samples.wrench[a]).max(f64::MIN_POSITIVE)
            };
            let a = (0..6)
                .max_by(|&i, &j| share(i).total_cmp(&share(j)))
                .unwrap_or(0);
            let measured = &self.samples.wrench[a];
            effects.push(EffectSeries {
                name: effect.name.clone(),
                axis: Axis::ALL[a],
                load: full[a]
                    .iter()
                    .zip(&without[a])
                    .map(|(f, w)| f - w)
                    .collect(),
                before: measured
                    .iter()
                    .zip(&without[a])
                    .map(|(z, w)| z - w)
                    .collect(),
                after: measured.iter().zip(&full[a]).map(|(z, f)| z - f).collect(),
            });
        }
        self.final_predicted = match &d.eq22 {
            Some(_) => {
                let (structure, theta) = d.adopted_theta();
                structure.predict_chunk(&theta, &self.samples, &mut Workspace::default())?
            }
            None => full,
        };
        self.effects = effects;
        Ok(())
    }
}

/// What the pipeline produced.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    /// The estimates.
    pub fit: Fit,
    /// Fit statistics (for refits with candidate effects).
    pub fit_stats: Accumulator,
    /// Statistics of the reporting-only validation logs (no samples without them).
    pub validation_stats: Accumulator,
    /// Goodness of fit of the Eq. 22 model on the validation logs when given, else
    /// cross-validated (all folds pooled).
    pub validation: [AxisMetrics; 6],
    /// Samples behind `validation`.
    pub validation_samples: u64,
    /// Cross-validation of the Eq. 22 model: fold names and held-out errors.
    pub cross_validation: (Vec<String>, CrossValidation),
    /// Residual diagnostics of the fit data (second pass).
    pub diagnostics: Option<ResidualDiagnostics>,
    /// Fit-data series for plots (second pass).
    pub fit_series: PlotSeries,
    /// Validation-data series for plots (second pass).
    pub validation_series: PlotSeries,
    /// One reader summary per log, fit logs first.
    pub summaries: Vec<Summary>,
    /// Description of the validation data.
    pub validation_source: String,
    /// Closing-the-loop result.
    pub diagnosis: Option<Diagnosis>,
    /// Coloured-residual variance inflation κ = (1 + ρ)/(1 − ρ) of the Eq. 22 fit's
    /// residuals (ρ the largest lag-1 autocorrelation over the axes), ≥ 1; 1 when the
    /// second pass did not run. σ² of white residuals times κ is the corrected variance.
    pub variance_inflation: f64,
}

/// Where the validation figures of a request come from, for the report (`plan`: the
/// blocks of a single fit log).
pub(super) fn validation_source(req: &FitRequest, plan: Option<&BlockPlan>) -> String {
    let n_fit = req.logs.len();
    if !req.validate.is_empty() {
        format!(
            "{} validation log(s), not used for any decision",
            req.validate.len()
        )
    } else if let Some(plan) = plan {
        format!(
            "{} contiguous blocks of the fit log, each predicted by the model fitted on the others less {} s on each side of it, pooled",
            plan.blocks(),
            plan.guard_seconds()
        )
    } else {
        format!(
            "leave one log out over {n_fit} logs (each predicted by the model fitted on the others), pooled"
        )
    }
}

/// Σ (x − x̄)².
fn centred_sum_of_squares(x: &[f64]) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len().max(1) as f64;
    x.iter().map(|v| (v - mean).powi(2)).sum()
}
