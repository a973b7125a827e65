//! The versioned JSON report of `mrsysid fit` (schema documented in docs/report-schema.md)
//! and its construction from an [`estimate::Fit`](crate::estimate::Fit).
//!
//! The printed tables ([`super::tables`]) are rendered from this same structure, so a
//! number printed equals the number in the JSON to the printed precision.

use serde::{Deserialize, Serialize};

use crate::diagnose::{CandidateScore, Diagnosis, Reading, Role};
use crate::estimate::remainder::AxisRemainder;
use crate::estimate::{AxisMetrics, CrossValidation, Fit, ResidualDiagnostics};
use crate::loads_scan::LowPassScan;
use crate::model::{ModelOptions, ModelStructure};
use crate::sample::Axis;
use crate::vehicle::Vehicle;

/// Version of the JSON report layout; bumped on any incompatible change.
pub const REPORT_SCHEMA_VERSION: u32 = 2;

/// The whole report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// [`REPORT_SCHEMA_VERSION`].
    pub schema_version: u32,
    /// `mrsysid` version that wrote the report.
    pub tool_version: String,
    /// Samples used to fit.
    pub samples: u64,
    /// Samples used for the validation figures.
    pub validation_samples: u64,
    /// Where the validation data came from.
    pub validation_source: String,
    /// The vehicle.
    pub vehicle: VehicleSummary,
    /// Eq. 22 variant.
    pub model: ModelOptions,
    /// The cut-off (Hz) the regressor signals were low-passed at, as the loads had been
    /// (consistent filtering); absent when they were not filtered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loads_low_pass_hz: Option<f64>,
    /// When the cut-off was estimated: each cut-off tried (Hz, `null` unfiltered) with
    /// the final model's held-out score (mean ln RMSE over the axes) and R² per axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loads_low_pass_scan: Option<LowPassScan>,
    /// Per log whose ground time was left out, what was kept (absent when every log
    /// was kept whole).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub airborne: Vec<AirborneRow>,
    /// Degrees of freedom of the t-tests (N − n_θ, N = fit samples).
    pub degrees_of_freedom: f64,
    /// When set, why the parameters' `std`, `t` and `p` carry no information (the model
    /// interpolates the data, or the residual covariance is singular); they are then
    /// not printed and must not be read.
    #[serde(default)]
    pub inference_withheld: Option<String>,
    /// MMR estimates (seed Table 5).
    pub parameters: Vec<ParameterRow>,
    /// Parameters the data could not identify, dropped before the MMR.
    pub dropped_parameters: Vec<DroppedRow>,
    /// MMR fit per axis on the fit data (seed Table 4).
    pub axes: Vec<AxisRow>,
    /// The same on the validation data (the validation logs, else cross-validated).
    pub validation: Vec<AxisRow>,
    /// Cross-validation of the Eq. 22 model: each fold's held-out metrics (a log
    /// predicted by the model fitted on the others, or a single log's blocks), then all
    /// folds pooled.
    pub cross_validation: Vec<FoldRow>,
    /// FSOA table per axis (seed Tables 2–3).
    pub fsoa: Vec<FsoaReport>,
    /// Residual covariance R of the per-axis fits, axes in Fx…Mz order.
    pub residual_covariance: [[f64; 6]; 6],
    /// Residual normality and whiteness per axis (second pass), when computed.
    pub normality: Vec<NormalityRow>,
    /// Conditioning of every solve.
    pub identifiability: Vec<ConditioningRow>,
    /// Closing the loop: effects the model lacked, added and checked on validation data
    /// (absent with `--no-diagnose`).
    pub diagnosis: Option<DiagnosisReport>,
}

/// What the airborne detection kept of one log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AirborneRow {
    /// The log's file name.
    pub log: String,
    /// Flights kept: runs of airborne samples between ground time.
    pub flights: usize,
    /// Time airborne, s (the flights' spans).
    pub airborne_seconds: f64,
    /// Time from the log's first row to its last, s.
    pub total_seconds: f64,
    /// Samples left out on the ground.
    pub ground_samples: u64,
}

impl AirborneRow {
    /// The row of a log's reader summary, `None` when nothing was left out.
    pub fn of(summary: &crate::io::Summary) -> Option<Self> {
        summary.airborne.map(|a| Self {
            log: summary.file.clone(),
            flights: a.flights,
            airborne_seconds: a.airborne_seconds,
            total_seconds: summary.span,
            ground_samples: a.ground_samples,
        })
    }

    /// "2 flights, 412 s airborne of 980 s".
    pub fn describe(&self) -> String {
        format!(
            "{} flight{}, {:.1} s airborne of {:.1} s ({} samples on the ground left out)",
            self.flights,
            if self.flights == 1 { "" } else { "s" },
            self.airborne_seconds,
            self.total_seconds,
            self.ground_samples
        )
    }
}

/// Held-out metrics of one cross-validation fold (or of all pooled).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoldRow {
    /// The held-out data: a log's file name, a block of a single log, or `pooled`.
    pub name: String,
    /// Metrics per axis.
    pub axes: Vec<AxisRow>,
}

/// Held-out metrics before and after the diagnosis on one data set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BeforeAfterRow {
    /// The held-out data: a log's file name, a block of a single log, `pooled`, or
    /// `validation logs`.
    pub name: String,
    /// Eq. 22 model, per axis.
    pub before: Vec<AxisRow>,
    /// Final model, per axis.
    pub after: Vec<AxisRow>,
}

/// A parameter left out of the final model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnsupportedRow {
    /// Parameter name.
    pub name: String,
    /// Rise of the cross-validation score when left out (module `diagnose::procedure`).
    pub score_change: f64,
}

/// The closing-the-loop result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DiagnosisReport {
    /// Effects added, in order.
    pub effects_added: Vec<EffectRow>,
    /// Parameters left out of the final model: not supported by held-out data.
    pub unsupported: Vec<UnsupportedRow>,
    /// Cross-validated metrics before any effect was added (all folds pooled).
    pub before: Vec<AxisRow>,
    /// Cross-validated metrics of the final model (all folds pooled).
    pub after: Vec<AxisRow>,
    /// Cross-validated metrics of the final model without its unspecific terms (freed
    /// coefficients, generic terms), all folds pooled: what named mechanisms carry.
    /// Absent when the final model has no unspecific term.
    #[serde(default)]
    pub named_only: Option<Vec<AxisRow>>,
    /// Per fold, then pooled: before and after.
    pub folds: Vec<BeforeAfterRow>,
    /// On the reporting-only validation logs, when given: before and after.
    pub validation: Option<BeforeAfterRow>,
    /// Every step's ranked candidates.
    pub steps: Vec<StepRow>,
    /// One sentence per effect added, with what the data cannot separate it from.
    #[serde(default)]
    pub findings: Vec<String>,
    /// Named effects the data show that gain too little to be added, one sentence each.
    #[serde(default)]
    pub below_bar: Vec<String>,
    /// The search stopped at its effect limit with candidates left.
    #[serde(default)]
    pub stopped_at_limit: bool,
    /// What is left in each moment axis's residual: its correlation with the axis's
    /// rotor signals over lags (time series only).
    #[serde(default)]
    pub remainder: Vec<AxisRemainder>,
    /// Axes the adopted model predicts with the Eq. 22 model, because the final model
    /// predicted their held-out data (all folds pooled) worse (`Diagnosis::eq22`); absent
    /// when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub eq22_axes: Vec<Eq22AxisRow>,
    /// Axes on which the adopted model predicts the reporting-only validation logs worse
    /// than the Eq. 22 model (`Diagnosis::worse_on_validation`); absent when there are
    /// none or no validation log was given.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub worse_on_validation: Vec<Axis>,
}

/// An axis the adopted model predicts with the Eq. 22 model, with what the final model
/// reached there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Eq22AxisRow {
    /// The axis.
    pub axis: Axis,
    /// The final model's cross-validated metrics on it (all folds pooled).
    pub final_held_out: AxisRow,
    /// The final model's metrics on it on the validation logs, when given.
    pub final_validation: Option<AxisRow>,
}

/// An effect (candidate) with its estimates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectRow {
    /// Effect name, e.g. `weak rotor 3`.
    pub name: String,
    /// True for a completion of the Eq. 22 structure (a term its assumptions drop), false
    /// for an undeclared effect of the vehicle or log.
    pub model_completion: bool,
    /// True for a term of the generic pool: residual structure with no physical name.
    #[serde(default)]
    pub generic: bool,
    /// True for a hypothesis that names no mechanism: a generic term, or a moment
    /// coefficient freed from the forces.
    #[serde(default)]
    pub unspecific: bool,
    /// Axes it acts on.
    pub axes: Vec<Axis>,
    /// Its parameters.
    pub parameters: Vec<EffectParameterRow>,
    /// Relative validation-NRMSE reduction per axis, Fx…Mz (positive = better).
    pub validation_gain: Vec<f64>,
    /// P-value of the joint Wald test of its parameters.
    pub p: f64,
    /// Held-out likelihood-ratio statistic against the model before it.
    #[serde(default)]
    pub held_out_lr: f64,
    /// For an effect confined to part of the envelope, the relative validation-NRMSE
    /// reduction per axis where it acts, Fx…Mz.
    #[serde(default)]
    pub local_gain: Option<Vec<f64>>,
    /// Share of the held-out samples where it acts (1 when it acts everywhere).
    #[serde(default)]
    pub active_share: f64,
    /// Why it was not added (empty for an accepted candidate).
    pub rejected: String,
}

/// One estimated effect parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectParameterRow {
    /// Parameter name.
    pub name: String,
    /// Estimate.
    pub estimate: f64,
    /// Standard deviation.
    pub std: f64,
    /// Unit.
    pub unit: String,
    /// For an effect of the adopted model: its estimate there (after every later
    /// addition, withdrawal and the parsimony step), in the same unit; `estimate` is the
    /// one when it was added. `None` in the step rankings, and when parsimony left all
    /// its columns out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_estimate: Option<f64>,
    /// Standard deviation of `final_estimate`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_std: Option<f64>,
    /// How the estimate reads (a fraction is printed in %, a freed moment coefficient
    /// with its tie to the force). Not in the JSON, whose schema this does not change: a
    /// report read back from JSON prints every estimate as a plain value.
    #[serde(skip)]
    pub reading: Reading,
}

/// One step of the diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepRow {
    /// Effect added in this step.
    pub added: Option<String>,
    /// Other kinds the data cannot tell apart from it.
    pub look_alikes: Vec<String>,
    /// Findings of its own kind that fit the held-out data as well within noise.
    #[serde(default)]
    pub not_separable: Vec<String>,
    /// Earlier additions withdrawn after it, or replaced by another form of their family,
    /// with the reason.
    #[serde(default)]
    pub withdrawn: Vec<String>,
    /// Candidates, best first.
    pub ranking: Vec<EffectRow>,
}

impl From<&CandidateScore> for EffectRow {
    fn from(c: &CandidateScore) -> Self {
        Self {
            name: c.name.clone(),
            model_completion: c.role.is_model_completion(),
            generic: c.role == Role::Generic,
            unspecific: c.role.is_unspecific(),
            axes: c.axes.clone(),
            parameters: c
                .parameters
                .iter()
                .map(|p| EffectParameterRow {
                    name: p.name.clone(),
                    estimate: p.estimate,
                    std: p.std,
                    unit: p.unit.clone(),
                    final_estimate: None,
                    final_std: None,
                    reading: p.reading,
                })
                .collect(),
            validation_gain: c.validation_gain.to_vec(),
            p: c.p,
            held_out_lr: c.held_out_lr,
            local_gain: c.local_gain.map(|g| g.to_vec()),
            active_share: c.active_share,
            rejected: c
                .rejected
                .as_ref()
                .map(|r| r.to_string())
                .unwrap_or_default(),
        }
    }
}

impl EffectRow {
    /// The row of an effect of the adopted model `d`, with its parameters' estimates
    /// there.
    fn with_final_estimates(mut self, d: &Diagnosis) -> Self {
        for p in &mut self.parameters {
            if let Some(id) = d.structure.param_id(&p.name) {
                p.final_estimate = Some(d.theta[id.index()]);
                p.final_std = Some(d.std[id.index()]);
            }
        }
        self
    }
}

fn rows(m: &[AxisMetrics; 6]) -> Vec<AxisRow> {
    m.iter().map(AxisRow::from).collect()
}

fn before_after(name: &str, before: &[AxisMetrics; 6], after: &[AxisMetrics; 6]) -> BeforeAfterRow {
    BeforeAfterRow {
        name: name.to_string(),
        before: rows(before),
        after: rows(after),
    }
}

impl From<&Diagnosis> for DiagnosisReport {
    fn from(d: &Diagnosis) -> Self {
        let mut folds: Vec<BeforeAfterRow> = d
            .folds
            .iter()
            .zip(d.before_folds.iter().zip(&d.after_folds))
            .map(|(n, (b, a))| before_after(n, b, a))
            .collect();
        folds.push(before_after("pooled", &d.before, &d.after));
        Self {
            effects_added: d
                .effects_added
                .iter()
                .map(|e| EffectRow::from(e).with_final_estimates(d))
                .collect(),
            unsupported: d
                .unsupported
                .iter()
                .map(|u| UnsupportedRow {
                    name: u.name.clone(),
                    score_change: u.score_change,
                })
                .collect(),
            before: rows(&d.before),
            after: rows(&d.after),
            named_only: d.named_only.as_ref().map(rows),
            folds,
            validation: d
                .validation
                .as_ref()
                .map(|[b, a]| before_after("validation logs", b, a)),
            steps: d
                .steps
                .iter()
                .map(|s| StepRow {
                    added: s.added.map(|i| s.ranking[i].name.clone()),
                    look_alikes: s.look_alikes.clone(),
                    not_separable: s.not_separable.clone(),
                    withdrawn: s.withdrawn.clone(),
                    ranking: s.ranking.iter().map(EffectRow::from).collect(),
                })
                .collect(),
            findings: d.findings.clone(),
            below_bar: d.below_bar.clone(),
            stopped_at_limit: d.stopped_at_limit,
            remainder: d.remainder.clone(),
            eq22_axes: d.eq22.as_ref().map_or_else(Vec::new, |e| {
                (e.axes.iter().enumerate())
                    .map(|(i, &axis)| Eq22AxisRow {
                        axis,
                        final_held_out: AxisRow::from(&e.final_held_out[i]),
                        final_validation: (e.final_validation.as_ref())
                            .map(|v| AxisRow::from(&v[i])),
                    })
                    .collect()
            }),
            worse_on_validation: d.worse_on_validation(),
        }
    }
}

/// Vehicle identification in the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VehicleSummary {
    /// Name from the vehicle file.
    pub name: String,
    /// Configuration class (Definition 1).
    pub class: String,
    /// Rotor count.
    pub rotors: usize,
}

/// One row of seed Table 5.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterRow {
    /// Parameter name.
    pub name: String,
    /// Unit of the estimate ("-" for dimensionless).
    pub unit: String,
    /// θ̂.
    pub estimate: f64,
    /// σ(θ̂), white residuals.
    pub std: f64,
    /// t₀ = θ̂/σ.
    pub t: f64,
    /// Two-sided P-value.
    pub p: f64,
    /// σ(θ̂) corrected for coloured residuals (Morelli), when the second pass ran.
    pub std_coloured: Option<f64>,
}

/// A parameter the data could not identify.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DroppedRow {
    /// Which solve dropped it (`OLS Fx` … or `MMR`).
    pub problem: String,
    /// Dropped term.
    pub name: String,
    /// Other terms it could not be separated from.
    pub aliased_with: Vec<String>,
    /// Why, when it is aliased with nothing (its regressor is zero in every sample).
    #[serde(default)]
    pub cause: Option<String>,
}

/// One row of seed Table 4.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisRow {
    /// Axis name, `Fx` … `Mz`.
    pub axis: Axis,
    /// Centred R².
    pub r2: f64,
    /// RMSE / (max z − min z).
    pub nrmse: f64,
    /// Theil's inequality coefficient.
    pub tic: f64,
    /// Root-mean-square error, N or N m.
    pub rmse: f64,
}

impl From<&AxisMetrics> for AxisRow {
    fn from(m: &AxisMetrics) -> Self {
        Self {
            axis: m.axis,
            r2: m.r2,
            nrmse: m.nrmse,
            tic: m.tic,
            rmse: m.rmse,
        }
    }
}

/// FSOA table of one axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FsoaReport {
    /// Axis.
    pub axis: Axis,
    /// Candidate terms, `param (regressor)`.
    pub terms: Vec<String>,
    /// R² per iteration (rows) and candidate (columns); `null` once a term is in.
    pub r2: Vec<Vec<Option<f64>>>,
    /// Candidate added at each iteration (index into `terms`).
    pub order: Vec<usize>,
    /// Partial F of each added term.
    pub partial_f: Vec<f64>,
    /// Leading terms kept by the PSE rule.
    pub pse_terms: usize,
    /// Leading terms with partial F ≥ F_in.
    pub f_in_terms: usize,
    /// Residual variance σ̂² of the model with all terms, (N or N m)².
    pub residual_variance: f64,
}

/// Residual normality and whiteness of one axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NormalityRow {
    /// Axis.
    pub axis: Axis,
    /// Residual mean, N or N m.
    pub mean: f64,
    /// Residual standard deviation, N or N m.
    pub std: f64,
    /// Correlation of ordered residuals with normal quantiles (1 = Gaussian).
    pub normal_probability_correlation: f64,
    /// Lag-1 autocorrelation of the residuals (0 = white).
    pub lag1_autocorrelation: f64,
}

/// Conditioning of one solve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConditioningRow {
    /// `OLS Fx` … `OLS Mz`, or `MMR`.
    pub problem: String,
    /// Condition number of the equilibrated design.
    pub condition_number: f64,
    /// Largest variance-inflation factor and its term.
    pub max_vif: Option<(String, f64)>,
}

impl Report {
    /// Builds the report from a fit, its validation metrics and (optionally) the residual
    /// diagnostics of the second pass.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        vehicle: &Vehicle,
        structure: &ModelStructure,
        fit: &Fit,
        validation: &[AxisMetrics; 6],
        validation_samples: u64,
        validation_source: &str,
        cross_validation: (&[String], &CrossValidation),
        diagnostics: Option<&ResidualDiagnostics>,
        diagnosis: Option<&Diagnosis>,
    ) -> Self {
        let (fold_names, cv) = cross_validation;
        let mut folds: Vec<FoldRow> = fold_names
            .iter()
            .enumerate()
            .map(|(j, n)| FoldRow {
                name: n.clone(),
                axes: rows(&cv.fold_metrics(j)),
            })
            .collect();
        folds.push(FoldRow {
            name: "pooled".into(),
            axes: rows(&cv.pooled_metrics()),
        });
        let coloured = |name: &str| {
            diagnostics.and_then(|d| {
                d.std_errors
                    .iter()
                    .find(|s| s.name == name)
                    .map(|s| s.coloured)
                    .filter(|v| v.is_finite())
            })
        };
        Self {
            schema_version: REPORT_SCHEMA_VERSION,
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            samples: fit.samples,
            validation_samples,
            validation_source: validation_source.to_string(),
            vehicle: VehicleSummary {
                name: vehicle.name.clone(),
                class: vehicle.class().to_string(),
                rotors: vehicle.rotor_count(),
            },
            model: structure.options,
            airborne: Vec::new(),
            loads_low_pass_hz: None,
            loads_low_pass_scan: None,
            degrees_of_freedom: fit.mmr.dof,
            inference_withheld: fit.mmr.inference_withheld.clone(),
            parameters: fit
                .mmr
                .parameters
                .iter()
                .map(|p| ParameterRow {
                    name: p.name.clone(),
                    unit: p.unit.clone(),
                    estimate: p.estimate,
                    std: p.std_error,
                    t: p.t,
                    p: p.p_value,
                    std_coloured: coloured(&p.name),
                })
                .collect(),
            dropped_parameters: fit
                .identifiability
                .iter()
                .flat_map(|c| {
                    c.dropped.iter().map(|d| DroppedRow {
                        problem: c.problem.clone(),
                        name: d.name.clone(),
                        aliased_with: d.aliased_with.clone(),
                        cause: d.cause.clone(),
                    })
                })
                .collect(),
            axes: fit.metrics.iter().map(AxisRow::from).collect(),
            validation: validation.iter().map(AxisRow::from).collect(),
            cross_validation: folds,
            fsoa: fit
                .axes
                .iter()
                .map(|a| FsoaReport {
                    axis: a.fsoa.axis,
                    terms: a.fsoa.terms.clone(),
                    r2: a.fsoa.steps.iter().map(|s| s.r2.clone()).collect(),
                    order: a.fsoa.order(),
                    partial_f: a.fsoa.steps.iter().map(|s| s.partial_f).collect(),
                    pse_terms: a.fsoa.pse_terms,
                    f_in_terms: a.fsoa.f_in_terms,
                    residual_variance: a.ols.residual_variance,
                })
                .collect(),
            residual_covariance: fit.residual_covariance,
            normality: diagnostics
                .map(|d| {
                    d.axes
                        .iter()
                        .map(|a| NormalityRow {
                            axis: a.axis,
                            mean: a.mean,
                            std: a.std_dev,
                            normal_probability_correlation: a.normal_probability_correlation,
                            lag1_autocorrelation: a
                                .autocorrelation
                                .get(1)
                                .copied()
                                .unwrap_or(f64::NAN),
                        })
                        .collect()
                })
                .unwrap_or_default(),
            identifiability: fit
                .identifiability
                .iter()
                .map(|c| ConditioningRow {
                    problem: c.problem.clone(),
                    condition_number: c.condition_number,
                    max_vif: c.vif.iter().max_by(|a, b| a.1.total_cmp(&b.1)).cloned(),
                })
                .collect(),
            diagnosis: diagnosis.map(DiagnosisReport::from),
        }
    }
}
