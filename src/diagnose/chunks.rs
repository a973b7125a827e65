//! The diagnosis alone on in-memory data (sweeps), without the pipeline.

use super::effects::{CandidateContext, hover_thrust_coefficient};
use super::generic::{SCREENING_SAMPLES, Thinned};
use super::local::{ActivityParts, LocalFolds};
use super::options::DiagnoseOptions;
use super::procedure::{CandidateStatistics, DiagnoseError, Diagnosis, diagnose};
use super::set::candidate_set;
use crate::estimate::{self, FitOptions, Folds};
use crate::model::ModelStructure;
use crate::stats::{AccumulateError, Accumulator};

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
    let force_theta = fit.own_axis_estimates(base.columns.len());
    let ctx = CandidateContext {
        vehicle,
        structure: base,
        theta: &fit.mmr.theta,
        force_theta: &force_theta,
        has_height: first.is_some_and(|c| !c.is_empty() && c.height.is_some()),
        has_omega_dot: first.is_some_and(|c| c.omega_dot.is_some()),
        has_omega_ddot: first.is_some_and(|c| c.omega_ddot.is_some()),
        has_attitude: first.is_some_and(|c| !c.is_empty() && c.attitude.is_some()),
        has_slow_thrust: first.is_some_and(|c| c.omega_squared_slow.is_some()),
        hover_thrust_coefficient: hover_thrust_coefficient(
            vehicle,
            &fit_data.iter().collect::<Vec<_>>(),
        ),
    };
    let mut thinned = Thinned::new(SCREENING_SAMPLES);
    fit_data.iter().for_each(|c| thinned.push(c));
    let set =
        candidate_set(&ctx, Some(thinned.samples()), options).map_err(AccumulateError::from)?;
    let extended = set.extended;
    let (mut fa, mut va) = (Accumulator::new(&extended), Accumulator::new(&extended));
    for (acc, data) in [(&mut fa, fit_data), (&mut va, validation_data)] {
        for c in data {
            acc.push(&extended, c, &mut ws)?;
        }
    }
    let mut local_parts = ActivityParts::default();
    let mut active_ws = Default::default();
    for c in validation_data {
        extended
            .assemble(c, &mut ws)
            .map_err(AccumulateError::from)?;
        let parts = &mut local_parts;
        set.regions.push(c, &ws, &extended, parts, &mut active_ws)?;
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
