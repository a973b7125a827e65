//! Blade flapping: each rotor's disc tilts away from the in-plane airflow at its hub by
//! an angle ∝ μ_i = V_i/(Ω_i R), so its thrust (∝ Ω_i²) gains an in-plane component, and
//! a hingeless hub a moment, ∝ Ω_i V_i. Acting above the CG both give M_x = −a Σ Ω_i v_i
//! and M_y = a Σ Ω_i u_i, the same sign for either spin direction. (The spin-weighted
//! lateral part, Σ σ_i Ω_i u_i on M_x, is Eq. 22's moment-only C_R_mub term.)

use super::context::{CandidateContext, column, rotor_signals};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, Term, term};
use crate::sample::Axis;

const PHYSICS: &str = "Each rotor's disc flaps back from the in-plane airflow at its hub (angle proportional to the advance ratio), tilting its thrust and loading a stiff hub: a rolling moment against the hub's sideways speed and a pitching moment against its forward speed, proportional to rotor speed times hub speed.";

/// One flapping-moment coefficient on roll and pitch.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let n = ctx.vehicle.rotor_count();
    let axis_terms = |component: usize, sign: f64| -> Vec<Term> {
        (0..n)
            .flat_map(|i| {
                let (w, _, _) = rotor_signals(i);
                hub_in_plane_velocity(ctx, i)[component]
                    .clone()
                    .into_iter()
                    .filter(|(c, _)| *c != 0.0)
                    .map(move |(c, s)| term(sign * c, &[s, w]))
            })
            .collect()
    };
    let moment = CandidateParameter::new(
        "flapping_moment",
        "N s^2/rad",
        vec![
            column(Axis::Mx, "-Sum Omega_i v_i", axis_terms(1, -1.0)),
            column(Axis::My, "Sum Omega_i u_i", axis_terms(0, 1.0)),
        ],
    );
    vec![Candidate::new(
        Kind::RotorFlapping,
        Role::Mechanism,
        "rotor flapping moment",
        PHYSICS,
        vec![moment],
    )]
}

/// In-plane velocity (u_i, v_i) of hub `i` at (x_i, y_i, −h) from body velocity and
/// rates (Eq. 18 with the hub height): u_i = u − q h − r y_i, v_i = v + p h + r x_i; as
/// (coefficient, factors) pairs of each component.
fn hub_in_plane_velocity(ctx: &CandidateContext, i: usize) -> [Vec<(f64, Signal)>; 2] {
    use Signal::*;
    let rotor = ctx.vehicle.rotors()[i];
    let h = ctx.vehicle.props.hub_height;
    [
        vec![(1.0, U), (-h, Q), (-rotor.y, R)],
        vec![(1.0, V), (h, P), (rotor.x, R)],
    ]
}
