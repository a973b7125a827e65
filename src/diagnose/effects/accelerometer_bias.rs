//! Forces derived as F = m a from an accelerometer with a constant bias b carry m b.
//! Only the in-plane components: a constant on F_z cannot be told from the thrust
//! terms (δt² and ν0 δt are nearly constant near hover), while Eq. 22's in-plane forces
//! have no constant term.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::term;
use crate::sample::Axis;

const PHYSICS: &str = "Forces derived as m a from an accelerometer with a constant bias b (or logged with a constant offset) carry m b on every sample.";

/// The bias along body x and y.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let m = ctx.vehicle.props.mass;
    // Consumer MEMS accelerometers stay within ~1 m/s² of zero bias.
    let axis = |axis: Axis, name: &str| {
        CandidateParameter::new(name, "m/s^2", vec![column(axis, "m", vec![term(m, &[])])])
            .within(-2.0, 2.0)
    };
    vec![Candidate::new(
        Kind::AccelerometerBias,
        Role::Mechanism,
        "accelerometer bias",
        PHYSICS,
        vec![
            axis(Axis::Fx, "accel_bias_x"),
            axis(Axis::Fy, "accel_bias_y"),
        ],
    )]
}
