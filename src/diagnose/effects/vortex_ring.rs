//! Vortex-ring state: descending near the hover inflow speed, a rotor re-ingests its own
//! wake and loses the fraction θ vrs_i of its thrust, vrs_i its onset signal. Confined to
//! where the onset is a tenth of the full one or more, summed over the rotors.

use super::context::CandidateContext;
use crate::diagnose::candidate::{
    Activity, Candidate, CandidateParameter, EffectKind as Kind, Role,
};
use crate::model::{Signal, term};

const PHYSICS: &str = "Descending near the hover inflow speed, a rotor re-ingests its own wake and loses thrust unsteadily; forward speed clears it.";

/// The thrust loss of every rotor in the state.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let n = ctx.vehicle.rotor_count();
    let all: Vec<usize> = (0..n).collect();
    let columns = ctx.thrust_change(
        "-vrs_i*T_i",
        &all,
        |i| vec![Signal::VortexRing(i as u8)],
        -1.0,
    );
    // Measured vortex-ring thrust losses are tens of percent; a fitted loss beyond
    // 60 % is a bump shape fitting inflow-model error, not the state itself.
    let loss = CandidateParameter::new("vortex_ring_thrust_loss", "-", columns)
        .within(0.0, 0.6)
        .fraction();
    vec![
        Candidate::new(
            Kind::VortexRing,
            Role::Mechanism,
            "vortex-ring state",
            PHYSICS,
            vec![loss],
        )
        // A tenth of the full onset or more, summed over rotors.
        .acting_where(Activity {
            terms: (0..n)
                .map(|i| term(1.0, &[Signal::VortexRing(i as u8)]))
                .collect(),
            threshold: 0.1,
        }),
    ]
}
