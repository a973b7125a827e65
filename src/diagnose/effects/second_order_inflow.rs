//! Second-order inflow: ΔT_i = ρπR² (C_T_muvw V_h w_i + C_T_w2 w_i²), w_i = w + p y_i −
//! q x_i the hub's axial velocity (Eq. 18), so F_z = −Σ ΔT_i, M_x = −Σ y_i ΔT_i,
//! M_y = Σ x_i ΔT_i. Eq. 6's inflow plane ν = ν0 + C_νμ V_h + C_νw w is first order; in
//! momentum theory ν = ν0 F(V_h/ν0, w/ν0) with ν0 ∝ Ω, so the inflow's second-order terms
//! enter the thrust −ρπR² R Ω ν as Ω-free V_h w, w² and V_h² terms. Eq. 22 keeps V_h²
//! (C_T_mu2); these are the other two: a completion. V_h w is the growth of the heave
//! damping with forward speed (the induced flow follows the climb speed less in forward
//! flight).

use super::context::CandidateContext;
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::Signal;

const PHYSICS: &str = "In forward flight a rotor's induced flow follows the climb speed less than in hover, so its thrust changes more with axial speed as in-plane speed grows, and in hover the inflow bends with the axial speed: the V_h w and w^2 terms of momentum-theory inflow that the first-order inflow plane of Eq. 6 drops.";

/// The V_h w_i and w_i² coefficients.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let rotors = ctx.vehicle.rotors();
    let (xs, ys): (Vec<f64>, Vec<f64>) = rotors.iter().map(|r| (r.x, r.y)).unzip();
    let one = vec![1.0; rotors.len()];
    let neg_x: Vec<f64> = xs.iter().map(|x| -x).collect();
    // w_i V_h = (w + p y_i − q x_i) V_h.
    let cross = ctx.thrust_polynomial(
        "Vh*w_i",
        &[
            (vec![W, Vh], one.clone()),
            (vec![P, Vh], ys.clone()),
            (vec![Q, Vh], neg_x.clone()),
        ],
    );
    // w_i² = w² + 2 w p y_i − 2 w q x_i + p² y_i² − 2 p q x_i y_i + q² x_i².
    let prod = |a: &[f64], b: &[f64], f: f64| a.iter().zip(b).map(|(a, b)| f * a * b).collect();
    let square = ctx.thrust_polynomial(
        "w_i^2",
        &[
            (vec![W, W], one.clone()),
            (vec![W, P], prod(&one, &ys, 2.0)),
            (vec![W, Q], prod(&one, &neg_x, 2.0)),
            (vec![P, P], prod(&ys, &ys, 1.0)),
            (vec![P, Q], prod(&ys, &neg_x, 2.0)),
            (vec![Q, Q], prod(&xs, &xs, 1.0)),
        ],
    );
    vec![Candidate::new(
        Kind::SecondOrderInflow,
        Role::Completion,
        "second-order inflow",
        PHYSICS,
        vec![
            CandidateParameter::new("C_T_muvw", "-", cross),
            CandidateParameter::new("C_T_w2", "-", square),
        ],
    )]
}
