//! Roll and pitch damping with a coefficient of its own: rotor i's thrust changes by
//! c Ω_i w_i with its hub's vertical velocity w_i = p y_i − q x_i (Eq. 18), so
//! M_x = −c (p Σ y_i² Ω_i − q Σ x_i y_i Ω_i), M_y = −c (q Σ x_i² Ω_i − p Σ x_i y_i Ω_i).
//! Eq. 22 has these terms only inside the C_T_muw column, tied to w δa and to F_z: a
//! completion.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "Rolling and pitching move each hub up or down (w_i = p y_i - q x_i), changing its rotor's angle of attack and thrust in proportion to rotor speed: a damping moment, here with its own coefficient instead of the one Eq. 22 shares with the vertical force.";

/// One damping coefficient on roll and pitch.
pub(super) fn candidates(_: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let damping = CandidateParameter::new(
        "rate_damping",
        "N s^2/(rad m)",
        vec![
            column(
                Axis::Mx,
                "-(p*SumY2Omega - q*SumXYOmega)",
                vec![term(-1.0, &[P, SumY2Omega]), term(1.0, &[Q, SumXYOmega])],
            ),
            column(
                Axis::My,
                "-(q*SumX2Omega - p*SumXYOmega)",
                vec![term(-1.0, &[Q, SumX2Omega]), term(1.0, &[P, SumXYOmega])],
            ),
        ],
    );
    vec![Candidate::new(
        Kind::RotorRateDamping,
        Role::Completion,
        "rotor rate damping",
        PHYSICS,
        vec![damping],
    )]
}
