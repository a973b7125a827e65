//! The ground-effect family (Cheeseman–Bennett, T_IGE = T/(1 − k (R/4z)²)) in three
//! forms: every rotor at the CG's rotor-plane height (level flight, or no attitude
//! logged); each rotor at its own height from the attitude (a tilted vehicle's low
//! rotors feel more of the ground, which also loads roll and pitch); and, with the
//! attitude, each rotor under the ground images of all the rotors, not only its own
//! (the multirotor's extra lift near the ground, which reaches higher than a single
//! rotor's: the neighbours' wakes meet below the airframe; the image picture of
//! Sanchez-Cuevas, Heredia and Ollero 2017, "Characterization of the aerodynamic ground
//! effect and its influence in multirotor control"). The data choose the form; one of
//! them enters a model. Needs the height above ground in the log.

use super::context::CandidateContext;
use crate::diagnose::candidate::{
    Activity, Candidate, CandidateParameter, EffectKind as Kind, Role,
};
use crate::model::{Signal, term};

const PHYSICS: &str = "Near the ground the wake is blocked and thrust rises as 1/(1 - k (R/4z)^2) (Cheeseman-Bennett), z the rotor height.";

const PHYSICS_MULTIROTOR: &str = "Near the ground every rotor's wake is blocked and, mirrored below the ground, pushes up on every rotor: thrust rises as 1/(1 - k s_i), s_i the upwash of all rotors' images at rotor i (its own alone is Cheeseman-Bennett's (R/4z)^2), so the lift reaches higher than a single rotor's.";

/// The uniform form, and the per-rotor and multirotor forms when the log has the
/// attitude; none without the height.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    if !ctx.has_height {
        return Vec::new();
    }
    let n = ctx.vehicle.rotor_count();
    let all: Vec<usize> = (0..n).collect();
    let uniform = |_: usize| vec![Signal::GroundEffect];
    let per_rotor = |i: usize| vec![Signal::RotorGroundEffect(i as u8)];
    let multirotor = |i: usize| vec![Signal::MultirotorGroundEffect(i as u8)];
    let form = |name: &str,
                physics: &'static str,
                param: &str,
                label: &str,
                signal: &dyn Fn(usize) -> Vec<Signal>| {
        // The scale of the Cheeseman–Bennett thrust gain g (1: the model itself).
        let scale =
            CandidateParameter::new(param, "-", ctx.thrust_change(label, &all, signal, 1.0))
                .within(0.0, 3.0)
                .fraction();
        Candidate::new(
            Kind::GroundEffect,
            Role::Mechanism,
            name,
            physics,
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
        PHYSICS,
        "ground_effect_scale",
        "g_IGE*T_i",
        &uniform,
    )];
    if ctx.has_attitude {
        out.push(form(
            "ground effect, per-rotor height",
            PHYSICS,
            "ground_effect_scale_per_rotor",
            "g_IGE,i*T_i",
            &per_rotor,
        ));
        out.push(form(
            "ground effect, multirotor",
            PHYSICS_MULTIROTOR,
            "ground_effect_scale_multirotor",
            "g_IGE,mr,i*T_i",
            &multirotor,
        ));
    }
    out
}
