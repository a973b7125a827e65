//! Hub in-plane velocity from the yaw rate, r × r_i (Assumption 4 drops it): rotor
//! drag gains −r y_i, r x_i components (Eq. 17). A completion.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "Yawing moves each hub sideways (r x r_i); the rotors' H-force on that velocity damps yaw and couples yaw rate into Fx and Fy.";

/// The H-force coefficients of the yaw rate's share of the hub velocity.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let k = ctx.k();
    let r = ctx.vehicle.props.rotor_radius;
    let n = ctx.vehicle.rotor_count() as f64;
    let l2 = ctx.vehicle.arm_length().powi(2);
    let nu0 = ctx.vehicle.hover_induced_velocity();
    let parameters = vec![
        CandidateParameter::new(
            "C_H_mub_r",
            "-",
            vec![
                column(Axis::Fx, "-r*da", vec![term(-k * r, &[R, Da])]),
                column(Axis::Fy, "-r*de", vec![term(-k * r, &[R, De])]),
                column(
                    Axis::Mz,
                    "-l^2*N*r*dt",
                    vec![term(-k * r * l2 * n, &[R, Dt])],
                ),
            ],
        ),
        CandidateParameter::new(
            "C_H_mub_mu0_r",
            "-",
            vec![column(
                Axis::Mz,
                "-nu0*l^2*N*r",
                vec![term(-k * nu0 * l2 * n, &[R])],
            )],
        ),
    ];
    vec![Candidate::new(
        Kind::YawRateDrag,
        Role::Completion,
        "yaw-rate rotor drag",
        PHYSICS,
        parameters,
    )]
}
