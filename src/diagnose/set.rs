//! The candidate set of one diagnosis: the named library for the vehicle, model and data,
//! plus the generic-pool terms that survive screening, added to the base structure.

use super::candidate::Candidate;
use super::effects::{CandidateContext, library};
use super::generic;
use super::local::LocalRegions;
use super::options::DiagnoseOptions;
use crate::model::{ModelError, ModelStructure, ParamId};
use crate::sample::SampleChunk;

/// Every candidate of one diagnosis, added to the base structure.
pub struct CandidateSet {
    /// Base structure followed by every candidate's parameters.
    pub extended: ModelStructure,
    /// Named candidates first, then the generic-pool survivors.
    pub candidates: Vec<Candidate>,
    /// The parameters in `extended` of each candidate.
    pub params: Vec<Vec<ParamId>>,
    /// The candidates confined to part of the envelope, and where they act.
    pub regions: LocalRegions,
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
    let mut params: Vec<Vec<ParamId>> =
        candidates.iter().map(|c| c.add_to(&mut extended)).collect();
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
    let regions = LocalRegions::new(ctx.structure, &candidates);
    Ok(CandidateSet {
        extended,
        candidates,
        params,
        regions,
    })
}
