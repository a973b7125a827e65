//! CG offset in the rotor plane: ΔM = F̂ × d for a CG at d = (dx, dy) from the reference
//! point (moments about the true CG), F̂ the base model's force.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::Column;
use crate::sample::Axis;

const PHYSICS: &str = "With the CG at (dx, dy) from the reference point, the thrust acts on a lever arm: M gains F x d.";

/// The offset's two components.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let dx = vec![
        column(Axis::My, "Fz_model", ctx.model_force(Axis::Fz, 1.0)),
        column(Axis::Mz, "-Fy_model", ctx.model_force(Axis::Fy, -1.0)),
    ];
    let dy = vec![
        column(Axis::Mx, "-Fz_model", ctx.model_force(Axis::Fz, -1.0)),
        column(Axis::Mz, "Fx_model", ctx.model_force(Axis::Fx, 1.0)),
    ];
    let parameters = vec![displacement("cg_dx", dx), displacement("cg_dy", dy)];
    vec![Candidate::new(
        Kind::CgOffset,
        Role::Mechanism,
        "CG offset",
        PHYSICS,
        parameters,
    )]
}

/// A CG displacement (m), plausible within ±0.2 m, with those of `columns` that have
/// terms.
fn displacement(name: &str, columns: Vec<Column>) -> CandidateParameter {
    let columns = columns
        .into_iter()
        .filter(|c| !c.terms.is_empty())
        .collect();
    CandidateParameter::new(name, "m", columns).within(-0.2, 0.2)
}
