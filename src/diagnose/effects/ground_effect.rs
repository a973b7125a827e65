//! The ground-effect family (Cheeseman–Bennett, T_IGE = T/(1 − k (R/4z)²)) in two
//! forms: every rotor at the CG's rotor-plane height (level flight, or no attitude
//! logged), and each rotor at its own height from the attitude (a tilted vehicle's low
//! rotors feel more of the ground, which also loads roll and pitch). The data choose the
//! form; one of them enters a model. Needs the height above ground in the log.

use super::context::CandidateContext;
use crate::diagnose::candidate::{
    Activity, Candidate, CandidateParameter, EffectKind as Kind, Role,
};
use crate::model::{Signal, term};

const PHYSICS: &str = "Near the ground the wake is blocked and thrust rises as 1/(1 - k (R/4z)^2) (Cheeseman-Bennett), z the rotor height.";

/// The uniform form, and the per-rotor form when the log has the attitude; none without
/// the height.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    if !ctx.has_height {
        return Vec::new();
    }
    let n = ctx.vehicle.rotor_count();
    let all: Vec<usize> = (0..n).collect();
    let uniform = |_: usize| vec![Signal::GroundEffect];
    let per_rotor = |i: usize| vec![Signal::RotorGroundEffect(i as u8)];
    let form = |name: &str, param: &str, label: &str, signal: &dyn Fn(usize) -> Vec<Signal>| {
        // The scale of the Cheeseman–Bennett thrust gain g (1: the model itself).
        let scale =
            CandidateParameter::new(param, "-", ctx.thrust_change(label, &all, signal, 1.0))
                .within(0.0, 3.0)
                .fraction();
        Candidate::new(
            Kind::GroundEffect,
            Role::Mechanism,
            name,
            PHYSICS,
            vec![scale],
        )
        .form_of(Kind::GroundEffect)
        // Thrust 1 % or more above its value out of ground effect (rotors within ~1.2
        // diameters of the ground), on average over the rotors.
        .acting_where(Activity {
            terms: (0..n).map(|i| term(1.0 / n as f64, &signal(i))).collect(),
            threshold: 0.01,
        })
    };
    let mut out = vec![form(
        "ground effect",
        "ground_effect_scale",
        "g_IGE*T_i",
        &uniform,
    )];
    if ctx.has_attitude {
        out.push(form(
            "ground effect, per-rotor height",
            "ground_effect_scale_per_rotor",
            "g_IGE,i*T_i",
            &per_rotor,
        ));
    }
    out
}
