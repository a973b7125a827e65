//! The closing-the-loop procedure: score every candidate effect on the residual of the
//! current model, add the best one that is significant, plausible and pays on
//! validation data, refit, repeat.
//!
//! All candidates' columns are accumulated once, next to the base columns, for the fit
//! and the validation data; every trial model is then a column subset of those
//! statistics ([`Accumulator::select`]), so no trial re-reads the data.
//!
//! A candidate is accepted when
//! 1. its MMR estimates are significant: the smallest P-value of its parameters is below
//!    α / (number of named candidates scored in the step) (Bonferroni);
//! 2. it is plausible: every estimate lies in the physical range of its parameter;
//! 3. it pays on validation data: on some axis validation NRMSE falls by at least
//!    [`DiagnoseOptions::min_gain`] (relative), so does the sum over all axes, and no
//!    axis gets worse by more than [`DiagnoseOptions::max_loss`]. All axes count: the
//!    MMR couples them through shared parameters, so a candidate can pay on an axis it
//!    has no column on.
//!
//! Among accepted candidates, completions of the Eq. 22 structure (terms its own
//! assumptions drop, [`EffectKind::is_model_completion`]) are added before undeclared
//! effects; within each group the largest validation gain summed over the axes wins.
//! Terms of the
//! generic pool ([`super::generic`]: residual structure with no name, whose Bonferroni
//! divisor is the whole pool it was screened from) compete with named effects, but a
//! named effect's gain counts 1 + [`DiagnoseOptions::look_alike`] times: named effects
//! are preferred when they explain about as much. Candidates of other kinds in the same
//! group whose gain is within [`DiagnoseOptions::look_alike`] of the winner's are
//! reported as look-alikes the data cannot tell apart.

use serde::Serialize;

use super::candidates::{Candidate, EffectKind};
use crate::estimate::{self, AxisMetrics, FitOptions};
use crate::model::ModelStructure;
use crate::sample::Axis;
use crate::stats::Accumulator;

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
    /// Smallest P-value of its parameters.
    pub min_p: f64,
    /// Why it was not accepted (empty when it was acceptable).
    pub rejected: String,
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

/// Result of the procedure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// Steps in order; the last one adds nothing (or the effect limit was reached).
    pub steps: Vec<DiagnosisStep>,
    /// Effects added, in order.
    pub effects_added: Vec<CandidateScore>,
    /// Validation metrics of the base model.
    pub before: [AxisMetrics; 6],
    /// Validation metrics of the final model.
    pub after: [AxisMetrics; 6],
    /// θ̂ of the final model over `structure.params`.
    pub theta: Vec<f64>,
    /// Standard deviations of `theta` (0 for parameters dropped as unidentifiable).
    pub std: Vec<f64>,
    /// Structure of the final model.
    #[serde(skip)]
    pub structure: ModelStructure,
}

/// Why the procedure could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    /// The base model itself could not be fitted from the statistics.
    #[error("diagnosis: {0}")]
    Fit(String),
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
    /// Fit-data statistics over `extended`.
    pub fit: &'a Accumulator,
    /// Validation-data statistics over `extended`.
    pub validation: &'a Accumulator,
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

/// Sub-model of `stats.extended` with the base parameters plus `params`: the structure
/// and the column indices into `extended`.
fn submodel(stats: &CandidateStatistics, params: &[usize]) -> (ModelStructure, Vec<usize>) {
    let mut keep: Vec<usize> = (0..stats.base_params).collect();
    keep.extend_from_slice(params);
    stats.extended.subset(&keep)
}

/// Fit of a sub-model: (θ over its params, std, P-values, validation metrics).
struct Trial {
    theta: Vec<f64>,
    std: Vec<f64>,
    p: Vec<f64>,
    validation: [AxisMetrics; 6],
    structure: ModelStructure,
}

fn trial(
    stats: &CandidateStatistics,
    params: &[usize],
    options: &FitOptions,
    inflation: f64,
) -> Result<Trial, String> {
    let (structure, cols) = submodel(stats, params);
    let fit_acc = stats.fit.select(&cols);
    let val_acc = stats.validation.select(&cols);
    let fit = estimate::fit(&structure, &fit_acc, options).map_err(|e| e.to_string())?;
    let validation =
        estimate::evaluate(&structure, &fit.mmr.theta, &val_acc).map_err(|e| e.to_string())?;
    let mut std = vec![0.0; structure.params.len()];
    let mut p = vec![1.0; structure.params.len()];
    let inflation = inflation.max(1.0).sqrt();
    for (est, &i) in fit.mmr.parameters.iter().zip(&fit.mmr.param_index) {
        std[i] = est.std_error * inflation;
        p[i] = crate::estimate::inference::t_test(est.estimate / std[i], fit.mmr.dof).0;
    }
    Ok(Trial {
        theta: fit.mmr.theta.clone(),
        std,
        p,
        validation,
        structure,
    })
}

fn gains(before: &[AxisMetrics; 6], after: &[AxisMetrics; 6]) -> [f64; 6] {
    std::array::from_fn(|a| {
        let b = before[a].nrmse;
        if b > 0.0 {
            (b - after[a].nrmse) / b
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
    let mut added: Vec<usize> = Vec::new();
    let mut current =
        trial(stats, &[], fit_options, options.variance_inflation).map_err(DiagnoseError::Fit)?;
    let before = current.validation;
    let mut steps = Vec::new();
    let mut effects_added = Vec::new();
    while added.len() < options.max_effects {
        let remaining: Vec<usize> = (0..stats.candidates.len())
            .filter(|c| !added.contains(c))
            .collect();
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
            .map(|&c| score(stats, &added, c, &current, fit_options, options, level(c)))
            .collect();
        // Accepted first; among them completions of the Eq. 22 structure before
        // undeclared effects (so an effect is judged against a model that already has
        // the terms its own assumptions drop), and named effects before generic terms;
        // then by validation gain.
        let look_alike = options.look_alike;
        scored.sort_by(|a, b| {
            let key = |s: &CandidateScore| {
                let ok = s.rejected.is_empty();
                (ok, ok && s.kind.is_model_completion())
            };
            key(&a.0)
                .cmp(&key(&b.0))
                .then(preference(&a.0, look_alike).total_cmp(&preference(&b.0, look_alike)))
                .reverse()
        });
        let best_ok = scored
            .first()
            .filter(|s| s.0.rejected.is_empty())
            .map(|s| s.0.clone());
        let look_alikes = best_ok
            .as_ref()
            .map(|best| {
                scored[1..]
                    .iter()
                    .filter(|s| {
                        s.0.rejected.is_empty()
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
            if i == 0 && s.rejected.is_empty() {
                winner = Some((c, t.expect("accepted trials exist")));
            }
            ranking.push(s);
        }
        match winner {
            Some((c, t)) => {
                added.push(c);
                current = t;
                effects_added.push(ranking[0].clone());
                steps.push(DiagnosisStep {
                    ranking,
                    added: Some(0),
                    look_alikes,
                });
            }
            None => {
                steps.push(DiagnosisStep {
                    ranking,
                    added: None,
                    look_alikes,
                });
                break;
            }
        }
    }
    Ok(Diagnosis {
        steps,
        effects_added,
        before,
        after: current.validation,
        theta: current.theta,
        std: current.std,
        structure: current.structure,
    })
}

/// Validation gain used to rank accepted candidates of one group: a named effect's gain
/// counts `1 + look_alike` times, so it is preferred over a generic term that explains
/// about as much, but not over one that explains clearly more.
fn preference(s: &CandidateScore, look_alike: f64) -> f64 {
    match s.kind {
        EffectKind::Generic => s.total_gain,
        _ => s.total_gain * (1.0 + look_alike),
    }
}

/// Scores candidate `c` added to the model with candidates `added`.
fn score(
    stats: &CandidateStatistics,
    added: &[usize],
    c: usize,
    current: &Trial,
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
    level: f64,
) -> (CandidateScore, usize, Option<Trial>) {
    let cand = &stats.candidates[c];
    let mut params: Vec<usize> = added
        .iter()
        .flat_map(|&a| stats.candidate_params[a].clone())
        .collect();
    params.extend_from_slice(&stats.candidate_params[c]);
    let axes = cand.axes();
    let mut s = CandidateScore {
        name: cand.name.clone(),
        kind: cand.kind,
        axes: axes.clone(),
        parameters: Vec::new(),
        validation_gain: [0.0; 6],
        total_gain: 0.0,
        min_p: 1.0,
        rejected: String::new(),
    };
    let t = match trial(stats, &params, fit_options, options.variance_inflation) {
        Ok(t) => t,
        Err(e) => {
            s.rejected = format!("cannot be estimated: {e}");
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
            estimate: t.theta[i],
            std: t.std[i],
            unit: t.structure.params[i].unit.clone(),
            p: t.p[i],
        })
        .collect();
    s.min_p = s.parameters.iter().map(|p| p.p).fold(1.0, f64::min);
    s.validation_gain = gains(&current.validation, &t.validation);
    // The MMR couples the axes through shared parameters, so a candidate can pay on an
    // axis it has no column on (freeing a moment coefficient lets F_z fit itself):
    // gains count on every axis, losses too.
    s.total_gain = s.validation_gain.iter().sum();
    let worst = s.validation_gain.iter().fold(0.0_f64, |m, &g| m.min(g));
    let best_axis = s
        .validation_gain
        .iter()
        .fold(f64::NEG_INFINITY, |m, &g| m.max(g));
    s.rejected = if s.min_p >= level {
        format!("not significant (P = {:.2e} >= {level:.2e})", s.min_p)
    } else if let Some(p) = s
        .parameters
        .iter()
        .find(|p| !plausible(&p.name, p.estimate))
    {
        format!("implausible {} = {:.4e} {}", p.name, p.estimate, p.unit)
    } else if best_axis < options.min_gain {
        format!(
            "validation gain {:.1} % below {:.1} %",
            100.0 * best_axis,
            100.0 * options.min_gain
        )
    } else if s.total_gain < options.min_gain {
        format!(
            "net validation gain over all axes {:.1} % below {:.1} %",
            100.0 * s.total_gain,
            100.0 * options.min_gain
        )
    } else if worst < -options.max_loss {
        format!("validation worse by {:.1} % on an axis", -100.0 * worst)
    } else {
        String::new()
    };
    (s, c, Some(t))
}

/// The whole procedure on in-memory data: fits `base` on `fit_data`, builds the
/// candidates from its estimates, accumulates them over both parts and runs
/// [`diagnose`]. (The `fit` pipeline does the same while streaming files.)
pub fn diagnose_chunks(
    vehicle: &crate::vehicle::Vehicle,
    base: &ModelStructure,
    fit_data: &[crate::sample::SampleChunk],
    validation_data: &[crate::sample::SampleChunk],
    fit_options: &FitOptions,
    options: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let err = |e: &dyn std::fmt::Display| DiagnoseError::Fit(e.to_string());
    let mut ws = crate::model::Workspace::default();
    let mut acc = Accumulator::new(base);
    for c in fit_data {
        acc.push(base, c, &mut ws).map_err(|e| err(&e))?;
    }
    let fit = estimate::fit(base, &acc, fit_options).map_err(|e| err(&e))?;
    let first = fit_data.first();
    let ctx = super::CandidateContext {
        vehicle,
        structure: base,
        theta: &fit.mmr.theta,
        has_height: first.is_some_and(|c| c.height.len() == c.len() && !c.is_empty()),
        has_omega_dot: first.is_some_and(|c| c.has_omega_dot()),
        has_attitude: first.is_some_and(|c| c.attitude[0].len() == c.len() && !c.is_empty()),
    };
    let mut thinned = super::Thinned::new(super::SCREENING_SAMPLES);
    fit_data.iter().for_each(|c| thinned.push(c));
    let set = super::candidate_set(&ctx, Some(thinned.samples()), options).map_err(|e| err(&e))?;
    let extended = set.extended;
    let (mut fa, mut va) = (Accumulator::new(&extended), Accumulator::new(&extended));
    for (acc, data) in [(&mut fa, fit_data), (&mut va, validation_data)] {
        for c in data {
            acc.push(&extended, c, &mut ws).map_err(|e| err(&e))?;
        }
    }
    let stats = CandidateStatistics {
        extended: &extended,
        candidates: &set.candidates,
        candidate_params: &set.params,
        base_params: base.params.len(),
        fit: &fa,
        validation: &va,
    };
    diagnose(&stats, fit_options, options)
}
