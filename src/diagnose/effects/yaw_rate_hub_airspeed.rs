//! Eq. 22's edgewise thrust at each yawing hub's own in-plane airspeed (Assumption 4
//! drops the hub velocity r × r_i): each hub moves at (u − r y_i, v + r x_i) in the
//! rotor plane (Eq. 17), so Eq. 22c's C_T_mu2 V_h² takes a different speed at each hub
//! and changes rotor i's thrust by
//!
//!   ΔT_i = ρπR² C_T_mu2 [(u − r y_i)² + (v + r x_i)² − u² − v²]
//!        = ρπR² C_T_mu2 [2 r (v x_i − u y_i) + r² (x_i² + y_i²)],
//!
//! whose lever arms give M_x = −Σ y_i ΔT_i ∋ 2 ρπR² C_T_mu2 Σy_i² u r: a roll moment from
//! yaw rate times forward speed (and a pitch moment from yaw rate times side speed). Its
//! share of the thrust is (arm / tip speed)² times the advance ratio, so it matters most
//! on large, slow rotors. A completion beside the yaw-rate rotor drag (the H-force's
//! terms in Ω and ν0 at the same velocity). Eq. 8's derivation gives C_T_mu2 = G, the
//! coefficient Eq. 22 also fits as C_H_mub_mu0, so the estimate can be read against it.

use super::context::CandidateContext;
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::Signal;

const PHYSICS: &str = "Yawing moves each hub sideways (r x r_i), so each rotor meets its own in-plane airspeed: the thrust's edgewise term rolls the vehicle with u*r and pitches it with v*r.";

/// The edgewise thrust coefficient at the yaw rate's share of each hub's in-plane
/// velocity.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let rotors = ctx.vehicle.rotors();
    let per_rotor = |c: fn(f64, f64) -> f64| rotors.iter().map(|p| c(p.x, p.y)).collect();
    // ΔT_i/(ρπR² C_T_mu2) = 2 u r (−y_i) + 2 v r x_i + r² (x_i² + y_i²).
    let columns = ctx.thrust_polynomial(
        "dVh_i^2(r)",
        &[
            (vec![U, R], per_rotor(|_, y| -2.0 * y)),
            (vec![V, R], per_rotor(|x, _| 2.0 * x)),
            (vec![R, R], per_rotor(|x, y| x * x + y * y)),
        ],
    );
    vec![Candidate::new(
        Kind::YawRateHubAirspeed,
        Role::Completion,
        "yaw-rate hub airspeed",
        PHYSICS,
        vec![CandidateParameter::new("C_T_mu2_r", "-", columns)],
    )]
}
