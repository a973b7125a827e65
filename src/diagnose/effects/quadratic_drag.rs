//! Quadratic airframe drag: pressure drag −ρ/2 C_d A v|v| per body axis, beyond the
//! linear drag Eq. 22 lumps into the rotors.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "The airframe's pressure drag grows with the square of airspeed, -rho/2 CdA v|v| per axis, beyond the linear drag Eq. 22 lumps into the rotors.";

/// One drag area C_d A (m²) per axis.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let half_rho = 0.5 * ctx.vehicle.props.air_density;
    // Plausible from 0 to 2 m².
    let axis = |axis, s, a, label: &str| {
        CandidateParameter::new(
            label,
            "m^2",
            vec![column(
                axis,
                &format!("-rho/2*{0}|{0}|", s_name(s)),
                vec![term(-half_rho, &[s, a])],
            )],
        )
        .within(0.0, 2.0)
    };
    let parameters = vec![
        axis(Axis::Fx, U, AbsU, "drag_area_x"),
        axis(Axis::Fy, V, AbsV, "drag_area_y"),
        axis(Axis::Fz, W, AbsW, "drag_area_z"),
    ];
    vec![Candidate::new(
        Kind::QuadraticDrag,
        Role::Mechanism,
        "quadratic airframe drag",
        PHYSICS,
        parameters,
    )]
}

fn s_name(s: Signal) -> &'static str {
    match s {
        Signal::U => "u",
        Signal::V => "v",
        _ => "w",
    }
}
