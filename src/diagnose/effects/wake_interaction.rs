//! The rotor-wake family: rotors downstream in the wakes of rotors upstream lose the
//! fraction θ f_i of their thrust, f_i their wake overlap (capped at 1) times the
//! overlap-area form's wake strength V_h²/(V_h² + ν0²) (saturating with speed), or the
//! advance-ratio form's μ_i = V_h/(Ω_i R) (growing with speed), in any direction of
//! flight; or, in one direction of flight along the body x axis only, the rotors behind
//! the CG (forward flight, u > 0) or ahead of it (backward flight) lose θ μ_i with
//! μ_i = |u|/(Ω_i R) and nothing otherwise (a fuselage or a camera that shields, or
//! spreads, the wake in the other direction; rotors where they sit in the flow). The data
//! choose the form; one of them enters a model.

use super::context::CandidateContext;
use crate::diagnose::candidate::{
    Activity, Candidate, CandidateParameter, EffectKind as Kind, Role,
};
use crate::model::{Signal, term};

const PHYSICS: &str = "In forward flight rotors downstream fly in the wakes of rotors upstream and lose thrust, more so as the wake is swept back.";

/// The overlap-area form and the advance-ratio form.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let n = ctx.vehicle.rotor_count();
    let all: Vec<usize> = (0..n).collect();
    // `most`: the largest plausible loss per unit of the form's signal, on `rotors`.
    let form = |name: &str,
                param: &str,
                label: &str,
                signal: &dyn Fn(u8) -> Signal,
                most: f64,
                rotors: &[usize]| {
        let columns = ctx.thrust_change(label, rotors, |i| vec![signal(i as u8)], -1.0);
        let loss = CandidateParameter::new(param, "-", columns)
            .within(0.0, most)
            .fraction();
        Candidate::new(
            Kind::WakeInteraction,
            Role::Mechanism,
            name,
            PHYSICS,
            vec![loss],
        )
        .form_of(Kind::WakeInteraction)
        // A tenth of a rotor's thrust or more at θ = 1, summed over rotors.
        .acting_where(Activity {
            terms: rotors
                .iter()
                .map(|&i| term(1.0, &[signal(i as u8)]))
                .collect(),
            threshold: 0.1,
        })
    };
    let hubs = ctx.vehicle.rotors();
    let behind: Vec<usize> = (0..n).filter(|&i| hubs[i].x < 0.0).collect();
    let ahead: Vec<usize> = (0..n).filter(|&i| hubs[i].x > 0.0).collect();
    vec![
        // At most the whole thrust of a rotor fully in a wake.
        form(
            "rotor-wake interaction",
            "wake_thrust_loss",
            "-wake_i*T_i",
            &Signal::WakeImmersion,
            1.0,
            &all,
        ),
        // Per unit advance ratio: a full loss at μ ≈ 0.3 is k ≈ 3.
        form(
            "rotor-wake interaction, advance ratio",
            "wake_thrust_loss_advance",
            "-overlap_i*mu_i*T_i",
            &Signal::WakeAdvance,
            5.0,
            &all,
        ),
        form(
            "rotor-wake interaction, forward flight",
            "wake_thrust_loss_forward",
            "-mu_fwd_i*T_i",
            &|i| Signal::DownstreamAdvance(i, 0),
            5.0,
            &behind,
        ),
        form(
            "rotor-wake interaction, backward flight",
            "wake_thrust_loss_backward",
            "-mu_back_i*T_i",
            &|i| Signal::DownstreamAdvance(i, 1),
            5.0,
            &ahead,
        ),
    ]
}
