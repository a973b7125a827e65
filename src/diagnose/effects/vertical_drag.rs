//! Linear vertical airframe drag, F_z = −D_z w: a completion of Assumption 3.
//!
//! Assumption 3 lumps the airframe's loads into the rotor terms. In-plane the lumping
//! holds: Eq. 22a–b carry a drag linear in u, v that does not scale with rotor speed
//! (C_H_mub_mu0 ν0 u, the isolated airframe drag the seed's §5 reads into it). Eq. 22c
//! has no such term: its only w column, C_T_muw w δt, scales with rotor speed and is
//! shared with the moments through Δν_z, so a drag −D_z w on the airframe moves the
//! moments' rate damping when it is fitted there. This column gives the vertical
//! airframe drag the term the in-plane forces already have.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "The airframe drags linearly in vertical flight, -Dz w, independent of rotor speed: Eq. 22 holds such a drag in-plane (C_H_mub_mu0 nu0 u) but on F_z only inside the rotor-speed-scaled C_T_muw column it shares with the moments.";

/// One vertical drag coefficient D_z, N s/m, plausible when not negative.
pub(super) fn candidates(_: &CandidateContext) -> Vec<Candidate> {
    let drag = CandidateParameter::new(
        "linear_drag_z",
        "N s/m",
        vec![column(Axis::Fz, "-w", vec![term(-1.0, &[Signal::W])])],
    )
    .within(0.0, f64::INFINITY);
    vec![Candidate::new(
        Kind::VerticalLinearDrag,
        Role::Completion,
        "linear vertical airframe drag",
        PHYSICS,
        vec![drag],
    )]
}
