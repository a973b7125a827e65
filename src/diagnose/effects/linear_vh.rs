//! The Eq. 22 terms linear in V_h, taken from the full structure: a completion offered
//! when the model left them out (a constant-inflow model).

use super::context::CandidateContext;
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{ModelOptions, ModelStructure};

const PHYSICS: &str = "The inflow varies with in-plane airspeed (Eq. 6, C_nu_mu); a constant-inflow model leaves out the terms linear in Vh.";

/// The terms' coefficients with their Eq. 22 columns; none when the model has them.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    if ctx.structure.options.linear_vh_terms {
        return Vec::new();
    }
    let full = ModelStructure::eq22(
        ctx.vehicle,
        ModelOptions {
            linear_vh_terms: true,
            ..ctx.structure.options
        },
    );
    let parameters = ["C_H_mub_mu", "C_T_mu", "C_Q_mu"]
        .iter()
        .filter_map(|name| {
            let p = full.param_id(name)?;
            let cols = full
                .columns
                .iter()
                .filter(|c| c.param == p)
                .cloned()
                .collect();
            Some(CandidateParameter::new(*name, "-", cols))
        })
        .collect();
    vec![Candidate::new(
        Kind::LinearVh,
        Role::Completion,
        "terms linear in Vh",
        PHYSICS,
        parameters,
    )]
}
