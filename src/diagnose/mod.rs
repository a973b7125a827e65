//! Closing the loop (beyond the seed): trace the residual of a fitted Eq. 22 model to a
//! physical effect the model lacks, add it, and report the error before and after on
//! data not used to fit.

pub mod candidates;
pub mod procedure;

pub use candidates::{Candidate, CandidateContext, CandidateParameter, EffectKind, library};
pub use procedure::{
    CandidateScore, CandidateStatistics, DiagnoseError, DiagnoseOptions, Diagnosis, DiagnosisStep,
    EffectParameter, diagnose, diagnose_chunks,
};

use crate::model::{ModelStructure, Parameter};

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
