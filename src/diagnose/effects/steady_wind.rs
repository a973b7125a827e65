//! Unmeasured steady wind W (NED): the model sees the logged velocity v where the rotors
//! feel v − C W (C the NED→body rotation), so to first order the loads change by
//! −(∂F/∂v) C W. ∂F/∂v is the base model's velocity gradient with the base estimates
//! (terms in u, v, w, V_h; ∂V_h/∂u = u/V_h). Needs the attitude in the log.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::Signal;
use crate::sample::Axis;

const PHYSICS: &str = "A steady wind makes the airspeed differ from the logged (ground-relative) velocity by the wind rotated into body axes, which changes the rotor loads through their velocity dependence.";

/// The wind's three NED components; none without the attitude.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    if !ctx.has_attitude {
        return Vec::new();
    }
    let parameters = ["wind_north", "wind_east", "wind_down"]
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let columns = Axis::ALL
                .iter()
                .map(|&axis| {
                    let terms = (0..3)
                        .flat_map(|k| {
                            let c = Signal::NedToBody((3 * k + j) as u8);
                            ctx.model_velocity_gradient(axis, k)
                                .into_iter()
                                .map(move |mut t| {
                                    t.coef = -t.coef;
                                    t.factors.push(c);
                                    t
                                })
                        })
                        .collect();
                    column(axis, &format!("-dF/dv*C[:,{j}]"), terms)
                })
                .filter(|c| !c.terms.is_empty())
                .collect();
            // Plausible within ±30 m/s.
            CandidateParameter::new(*name, "m/s", columns).within(-30.0, 30.0)
        })
        .collect();
    vec![Candidate::new(
        Kind::SteadyWind,
        Role::Mechanism,
        "steady wind",
        PHYSICS,
        parameters,
    )]
}
