//! Closing the loop (beyond the seed): trace the residual of a fitted Eq. 22 model to a
//! physical effect the model lacks, add it, and report the error before and after on
//! data not used to fit.

pub mod candidates;
pub mod generic;
pub mod local;
pub mod procedure;

pub use candidates::{Candidate, CandidateContext, CandidateParameter, EffectKind, library};
pub use generic::{SCREENING_SAMPLES, Thinned};
pub use procedure::{
    CandidateScore, CandidateStatistics, DiagnoseError, DiagnoseOptions, Diagnosis, DiagnosisStep,
    EffectParameter, Rejection, diagnose, diagnose_chunks, diagnose_on_threads,
};

use crate::model::{ModelError, ModelStructure, Parameter};
use crate::sample::SampleChunk;

/// Every candidate of one diagnosis, added to the base structure.
pub struct CandidateSet {
    /// Base structure followed by every candidate's parameters.
    pub extended: ModelStructure,
    /// Named candidates first, then the generic-pool survivors.
    pub candidates: Vec<Candidate>,
    /// Parameter indices in `extended` of each candidate.
    pub params: Vec<Vec<usize>>,
    /// The candidates confined to part of the envelope, and where they act.
    pub regions: local::LocalRegions,
}

/// The named library for `ctx` plus the generic-pool monomials that survive screening
/// on `screening_data` (a thinned sample of the fit data; no screening when `None`).
pub fn candidate_set(
    ctx: &CandidateContext,
    screening_data: Option<&SampleChunk>,
    options: &DiagnoseOptions,
) -> Result<CandidateSet, ModelError> {
    candidate_set_on_threads(ctx, screening_data, options, 1)
}

/// [`candidate_set`] with the screening's axes on up to `threads` threads (the set does
/// not depend on `threads`).
pub fn candidate_set_on_threads(
    ctx: &CandidateContext,
    screening_data: Option<&SampleChunk>,
    options: &DiagnoseOptions,
    threads: usize,
) -> Result<CandidateSet, ModelError> {
    let mut candidates = library(ctx);
    let mut extended = ctx.structure.clone();
    let mut params: Vec<Vec<usize>> = candidates.iter().map(|c| c.add_to(&mut extended)).collect();
    let screened = match screening_data {
        Some(data) if !data.is_empty() => generic::screen(
            ctx.structure,
            data,
            &generic::ScreeningOptions {
                alpha: options.alpha,
                min_drop: options.min_gain,
                threads,
                ..Default::default()
            },
        )?,
        _ => Vec::new(),
    };
    for s in &screened {
        let c = s.candidate();
        params.push(c.add_to(&mut extended));
        candidates.push(c);
    }
    let regions = local::LocalRegions::new(ctx.structure, &candidates);
    Ok(CandidateSet {
        extended,
        candidates,
        params,
        regions,
    })
}

impl Candidate {
    /// Adds the candidate's parameters and columns to `structure`; returns the new
    /// parameter indices.
    pub fn add_to(&self, structure: &mut ModelStructure) -> Vec<usize> {
        self.parameters
            .iter()
            .map(|p| {
                structure.add_parameter(
                    Parameter {
                        name: p.name.clone(),
                        unit: p.unit.clone(),
                    },
                    p.columns.clone(),
                )
            })
            .collect()
    }
}
