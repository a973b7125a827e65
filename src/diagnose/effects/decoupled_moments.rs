//! Freed moment coefficients. Eq. 22 shares each lumped coefficient between the forces
//! and the moments, the moments' columns carrying the vehicle file's rotor positions and
//! hub height. Wrong lever arms, effective thrust and drag centres away from the hubs, or
//! moment physics the model lacks that correlates with a term (hub moments, flapping)
//! break that tie. One candidate per coefficient that acts on both and per moment axis:
//! it gives that axis a second value of the coefficient (the estimate is the moment value
//! minus the force value, so its t-statistic tests the tie). Unspecific: it names a
//! term's shape, not a mechanism.

use super::context::CandidateContext;
use crate::diagnose::candidate::{
    Candidate, CandidateParameter, EffectKind as Kind, Reading, Role,
};
use crate::model::Column;
use crate::sample::Axis;

const PHYSICS: &str = "Eq. 22 ties this coefficient's moment terms to its force terms through the vehicle file's lever arms; wrong arms, thrust and drag centres away from the hubs, or moment physics the model lacks that follows the same term give the moment a value of its own.";

/// One candidate per base coefficient acting on a force and per moment axis it acts on.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let s = ctx.structure;
    let is_moment = |a: Axis| (a as usize) >= 3;
    let mut out = Vec::new();
    for p in s.param_ids() {
        let columns: Vec<&Column> = s.columns.iter().filter(|c| c.param == p).collect();
        if !columns.iter().any(|c| !is_moment(c.axis)) {
            continue;
        }
        let name = &s.param(p).name;
        for axis in [Axis::Mx, Axis::My, Axis::Mz] {
            let cols: Vec<Column> = columns
                .iter()
                .filter(|c| c.axis == axis)
                .map(|&c| c.clone())
                .collect();
            if cols.is_empty() {
                continue;
            }
            let freed =
                CandidateParameter::new(format!("{name}@{}", axis.name()), &s.param(p).unit, cols)
                    .read_as(Reading::MomentMinusForce);
            out.push(Candidate::new(
                Kind::DecoupledMoments,
                Role::Unspecific,
                format!("decoupled {name} on {axis}"),
                PHYSICS,
                vec![freed],
            ));
        }
    }
    out
}
