//! Hub in-plane velocity from the roll and pitch rates at hub height h (Eq. 18 with the
//! hubs at z = −h: u_i = u − q h, v_i = v + p h): the Eq. 22a–b H-force terms gain
//! q h, −p h and, through the hub-force lever arm h, roll and pitch damping −h² p, −h² q.
//! A completion, offered when the vehicle's hubs sit above the CG.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "Rolling and pitching move the hubs, which sit h above the CG, sideways at p h and q h; the rotors' H-force on that velocity couples the rates into Fx and Fy and damps roll and pitch through the same lever arm.";

/// The H-force coefficients of the rates' share of the hub velocity; none with the hubs
/// at the CG's height.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let h = ctx.vehicle.props.hub_height;
    if h == 0.0 {
        return Vec::new();
    }
    let kn = ctx.k() * ctx.vehicle.rotor_count() as f64;
    let r = ctx.vehicle.props.rotor_radius;
    let nu0 = ctx.vehicle.hover_induced_velocity();
    // Coefficient of (Fx, Fy, Mx, My) per unit of the lumped parameter and its signal.
    let columns = |scale: f64, with: &[Signal], label: &str| {
        let with_q: Vec<Signal> = [&[Q][..], with].concat();
        let with_p: Vec<Signal> = [&[P][..], with].concat();
        vec![
            column(
                Axis::Fx,
                &format!("h*q*{label}"),
                vec![term(kn * scale * h, &with_q)],
            ),
            column(
                Axis::Fy,
                &format!("-h*p*{label}"),
                vec![term(-kn * scale * h, &with_p)],
            ),
            column(
                Axis::Mx,
                &format!("-h^2*p*{label}"),
                vec![term(-kn * scale * h * h, &with_p)],
            ),
            column(
                Axis::My,
                &format!("-h^2*q*{label}"),
                vec![term(-kn * scale * h * h, &with_q)],
            ),
        ]
    };
    vec![Candidate::new(
        Kind::RollPitchRateDrag,
        Role::Completion,
        "roll/pitch-rate rotor drag",
        PHYSICS,
        vec![
            CandidateParameter::new("C_H_mub_pq", "-", columns(r, &[Dt], "dt")),
            CandidateParameter::new("C_H_mub_mu0_pq", "-", columns(nu0, &[], "nu0")),
        ],
    )]
}
