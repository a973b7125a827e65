//! CG offset in the rotor plane, to first order in the offset d = (dx, dy) of the CG from
//! the reference point the rotor positions are given from:
//!
//! - the lever arms: moments about the true CG gain ΔM = F̂ × d, F̂ the base model's
//!   force (two forms: see [`candidates`]);
//! - the rotors' inflow: every hub sits at r_i − d from the true CG, so its climb
//!   velocity w + p y_i − q x_i (Eq. 18) differs from the model's by q dx − p dy, the
//!   same for every rotor, and every load changes by (∂F̂/∂w)(q dx − p dy), ∂F̂/∂w the
//!   base model's gradient in w. (The hubs' in-plane velocities would change by
//!   (r dy, −r dx) too, but Eq. 22 takes every rotor's in-plane velocity as the CG's.)
//!
//! The forces are linear in the hub positions, so their columns are exact; the moments
//! leave the force change times d, second order (`tests/candidates_exact.rs`).

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Column, Signal, Term};
use crate::sample::Axis;

const PHYSICS: &str = "With the CG at (dx, dy) from the reference point, the thrust acts on a lever arm (M gains F x d), and each rotor climbs with the body rates about the true CG, by q dx - p dy more than about the reference point, which changes its inflow and thrust.";

/// The offset's two components, in two forms that differ in the force on the lever
/// arm: each force axis's own OLS ([`CandidateContext::lever_force`]), or the joint
/// estimates ([`CandidateContext::model_force`]). The joint fit shares the thrust
/// coefficients between F_z and the moments, so a large offset pulls them and the
/// lever force with them (RotorPy's hummingbird with 17 mm: Ĉ_T0 −0.0135 against
/// 0.0139, the offset 7.6 % short); but F_z alone may split its thrust among collinear
/// terms that extrapolate worse (a PX4 log's future M_x R² 48 against 82). The
/// held-out data choose.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    vec![
        form(ctx, "CG offset", &|a, s| ctx.lever_force(a, s)),
        form(ctx, "CG offset, joint lever force", &|a, s| {
            ctx.model_force(a, s)
        }),
    ]
}

/// One form, with the lever arm's force `force(axis, scale)`.
fn form(ctx: &CandidateContext, name: &str, force: &dyn Fn(Axis, f64) -> Vec<Term>) -> Candidate {
    // Per unit dx: ΔM_y = F̂_z, ΔM_z = −F̂_y; the climb velocity gains q.
    let dx = with_inflow(
        ctx,
        vec![
            column(Axis::My, "Fz_model", force(Axis::Fz, 1.0)),
            column(Axis::Mz, "-Fy_model", force(Axis::Fy, -1.0)),
        ],
        1.0,
        Signal::Q,
    );
    // Per unit dy: ΔM_x = −F̂_z, ΔM_z = F̂_x; the climb velocity gains −p.
    let dy = with_inflow(
        ctx,
        vec![
            column(Axis::Mx, "-Fz_model", force(Axis::Fz, -1.0)),
            column(Axis::Mz, "Fx_model", force(Axis::Fx, 1.0)),
        ],
        -1.0,
        Signal::P,
    );
    let parameters = vec![displacement("cg_dx", dx), displacement("cg_dy", dy)];
    Candidate::new(Kind::CgOffset, Role::Mechanism, name, PHYSICS, parameters)
        .form_of(Kind::CgOffset)
}

/// The lever-arm columns `lever` of one offset component with, on every axis, the base
/// model's gradient in w times the climb velocity change per unit offset, `sign` ·
/// `rate`.
fn with_inflow(ctx: &CandidateContext, lever: Vec<Column>, sign: f64, rate: Signal) -> Vec<Column> {
    Axis::ALL
        .iter()
        .map(|&axis| {
            let mut c = lever
                .iter()
                .find(|c| c.axis == axis)
                .cloned()
                .unwrap_or_else(|| column(axis, "dF/dw*dw", Vec::new()));
            c.terms.extend(
                ctx.model_velocity_gradient(axis, 2)
                    .into_iter()
                    .map(|t| Term {
                        coef: sign * t.coef,
                        factors: t.factors.iter().copied().chain([rate]).collect(),
                    }),
            );
            c
        })
        .collect()
}

/// A CG displacement (m), plausible within ±0.2 m, with those of `columns` that have
/// terms.
fn displacement(name: &str, columns: Vec<Column>) -> CandidateParameter {
    let columns = columns
        .into_iter()
        .filter(|c| !c.terms.is_empty())
        .collect();
    CandidateParameter::new(name, "m", columns).within(-0.2, 0.2)
}
