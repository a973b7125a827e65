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

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Column, Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "Yawing moves each hub sideways (r x r_i), so each rotor meets its own in-plane airspeed: the thrust's edgewise term rolls the vehicle with u*r and pitches it with v*r.";

/// The edgewise thrust coefficient at the yaw rate's share of each hub's in-plane
/// velocity.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let thrust = CandidateParameter::new("C_T_mu2_r", "-", edgewise_thrust_columns(ctx));
    vec![Candidate::new(
        Kind::YawRateHubAirspeed,
        Role::Completion,
        "yaw-rate hub airspeed",
        PHYSICS,
        vec![thrust],
    )]
}

/// One term of a column as a sum over the layout: its coefficient (a layout sum), its
/// signals and the sum's power of length (its scale is ℓ to that power).
type LayoutTerm = (f64, Vec<Signal>, i32);

/// The columns of `axes` (axis, label, terms), each term's coefficient times ρπR²: a
/// term whose layout sum is below 1e-9 of its scale is the rounding of a symmetric
/// layout's zero and is dropped, and so is a column left without terms.
fn layout_columns(
    ctx: &CandidateContext,
    axes: Vec<(Axis, String, Vec<LayoutTerm>)>,
) -> Vec<Column> {
    let k = ctx.k();
    let l = ctx.vehicle.arm_length();
    axes.into_iter()
        .filter_map(|(axis, label, parts)| {
            let terms: Vec<_> = parts
                .into_iter()
                .filter(|(c, _, power)| c.abs() > 1e-9 * l.powi(*power))
                .map(|(c, signals, _)| term(k * c, &signals))
                .collect();
            (!terms.is_empty()).then(|| column(axis, &label, terms))
        })
        .collect()
}

/// The layout sum Σ f(x_i, y_i) over the vehicle's rotors, m to the power of f.
fn layout_sum(ctx: &CandidateContext, f: impl Fn(f64, f64) -> f64) -> f64 {
    ctx.vehicle.rotors().iter().map(|p| f(p.x, p.y)).sum()
}

/// Columns of the thrust change ΔT_i = ρπR² [2 r (v x_i − u y_i) + r² (x_i² + y_i²)] per
/// unit C_T_mu2 (module docs): F_z = −ΣΔT_i, M_x = −Σ y_i ΔT_i, M_y = Σ x_i ΔT_i
/// (Eq. 13–15), as sums over the layout.
fn edgewise_thrust_columns(ctx: &CandidateContext) -> Vec<Column> {
    use Signal::*;
    // Rotor (x, y)'s lever arm on each axis (Eq. 13–15); below, with its power of length.
    let lever = |axis: Axis, x: f64, y: f64| match axis {
        Axis::Fz => -1.0,
        Axis::Mx => -y,
        _ => x,
    };
    let axes = [
        (Axis::Fz, "-dT", 0),
        (Axis::Mx, "-y*dT", 1),
        (Axis::My, "x*dT", 1),
    ]
    .into_iter()
    .map(|(axis, label, power)| {
        let sum = |f: fn(f64, f64) -> f64| layout_sum(ctx, |x, y| lever(axis, x, y) * f(x, y));
        let terms = vec![
            (sum(|_, y| -2.0 * y), vec![U, R], power + 1),
            (sum(|x, _| 2.0 * x), vec![V, R], power + 1),
            (sum(|x, y| x * x + y * y), vec![R, R], power + 2),
        ];
        (axis, format!("C_T_mu2*{label}(r)"), terms)
    })
    .collect();
    layout_columns(ctx, axes)
}
