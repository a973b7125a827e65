//! The in-plane forces' lever arm: the CG dz away from the height Eq. 22 assumes (the
//! hubs), or airframe drag acting nearer the CG. A completion: Assumption 3 lumps the
//! airframe drag into the rotors.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::sample::Axis;

const PHYSICS: &str = "In-plane forces act dz below the height Eq. 22 assumes (the hubs): the CG is not where assumed, or airframe drag, which Assumption 3 lumps into the rotors, acts nearer the CG.";

/// ΔM_x = F̂_y dz, ΔM_y = −F̂_x dz.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let dz = vec![
        column(Axis::Mx, "Fy_model", ctx.lever_force(Axis::Fy, 1.0)),
        column(Axis::My, "-Fx_model", ctx.lever_force(Axis::Fx, -1.0)),
    ];
    let dz = dz.into_iter().filter(|c| !c.terms.is_empty()).collect();
    // Plausible within ±0.2 m.
    let dz = CandidateParameter::new("cg_dz", "m", dz).within(-0.2, 0.2);
    vec![Candidate::new(
        Kind::CgHeight,
        Role::Completion,
        "in-plane force lever arm",
        PHYSICS,
        vec![dz],
    )]
}
