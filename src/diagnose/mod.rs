//! Closing the loop (beyond the seed): trace the residual of a fitted Eq. 22 model to a
//! physical effect the model lacks, add it, and report the error before and after on
//! data not used to fit.
//!
//! The layers, each using only those above it: [`Candidate`] (what a candidate effect
//! is) and [`DiagnoseOptions`]; the named library ([`effects`], one file per effect),
//! the [`generic`] pool and the [`local`] regions where an effect acts; the candidate set
//! of one diagnosis ([`candidate_set`]); the [`procedure`] that searches it; and
//! [`diagnose_chunks`], the whole diagnosis on in-memory data.

mod candidate;
mod chunks;
pub mod effects;
pub mod generic;
pub mod local;
mod options;
pub mod procedure;
mod set;

pub use candidate::{
    Activity, Candidate, CandidateParameter, EffectKind, Reading, Role, Statement,
};
pub use chunks::diagnose_chunks;
pub use effects::{CandidateContext, hover_thrust_coefficient, library};
pub use generic::{SCREENING_SAMPLES, Thinned};
pub use options::DiagnoseOptions;
pub use procedure::{
    CandidateScore, CandidateStatistics, DiagnoseError, Diagnosis, DiagnosisStep, EffectParameter,
    Eq22Axes, Rejection, Unsupported, diagnose, diagnose_on_threads,
};
pub use set::{CandidateSet, candidate_set, candidate_set_on_threads};
