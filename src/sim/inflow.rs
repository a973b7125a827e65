//! Induced inflow of one rotor from momentum theory (seed §3, the implicit form before
//! Eq. 6), coupled to the blade-element thrust.
//!
//! Glauert's momentum relation for a rotor of disc area A with thrust T, in-plane airspeed
//! V_h and axial velocity w (positive down) reads
//!
//! ν · √(V_h² + (ν − w)²) = T / (2ρA),
//!
//! which is the seed's ν = ν0² / √(V_h² + (ν − w)²) with ν0² = T / (2ρA). The seed fixes
//! ν0 at the vehicle's hover value; here T is the rotor's own blade-element thrust at the
//! inflow ν, so the pair (ν, T) is solved together (a secant iteration on
//! r(ν) = ν − N(T(ν)), N the momentum root below). At hover trim both forms coincide.
//!
//! Branch choice and vortex-ring guard: the relation has up to three roots in descent.
//! The normal working state (largest root, flow down through the disc) is used while it
//! is an increasing branch, i.e. while w·V_h < T/(2ρA); otherwise (fast descent with
//! forward speed, windmill side) a root in (0, w) is found by bisection. In purely axial
//! descent faster than 2ν_h the normal-working-state root is kept, which is outside the
//! simulator's domain (sweeps stop at 0.45 ν0, or 1.6 ν0 with `vortex_ring`). Both are bracketed, so the
//! solver never diverges or returns NaN; near the vortex-ring state (descent at
//! 0.5–1.5 ν_h) momentum theory itself is unreliable and the thrust loss observed there is
//! modelled by the `vortex_ring` effect ([`super::effects`]).

/// How a rotor's induced velocity is obtained.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InflowModel {
    /// Implicit momentum theory coupled to the blade-element thrust (the truth model).
    Momentum,
    /// The plane of Eq. 6: ν = ν0 + C_νμ V_h + C_νw w (for comparison with Eq. 5).
    Plane {
        /// Hover induced velocity ν0, m/s.
        nu0: f64,
        /// Slope C_νμ with in-plane airspeed, dimensionless.
        c_nu_mu: f64,
        /// Slope C_νw with axial velocity, dimensionless.
        c_nu_w: f64,
    },
}

/// The previous solution of one rotor, used as the starting guess of the next.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InflowState {
    /// Last induced velocity, m/s, if any.
    pub nu: Option<f64>,
}

/// Relative tolerance of the inflow iteration (on ν, relative to max(ν, 0.1 m/s)).
pub const INFLOW_TOLERANCE: f64 = 1e-10;

/// Induced velocity ν (m/s) under `model` of a rotor with disc area `disk_area` (m²) in
/// air of density `air_density` (kg/m³), whose hub moves at `hub_velocity` (m/s, body
/// axes, relative to the air) and whose thrust at inflow ν is `thrust(ν)` (N; the
/// simulator's rotors pass their blade-element thrust).
pub fn solve(
    hub_velocity: [f64; 3],
    air_density: f64,
    disk_area: f64,
    thrust: impl Fn(f64) -> f64,
    model: &InflowModel,
    state: &mut InflowState,
) -> f64 {
    let [vx, vy, w] = hub_velocity;
    let vh = vx.hypot(vy);
    let nu = match *model {
        InflowModel::Plane {
            nu0,
            c_nu_mu,
            c_nu_w,
        } => nu0 + c_nu_mu * vh + c_nu_w * w,
        InflowModel::Momentum => {
            let k = 1.0 / (2.0 * air_density * disk_area);
            let fixed_point = |nu: f64| momentum_root(k * thrust(nu), vh, w);
            let mut a = state.nu.unwrap_or_else(|| fixed_point(0.0) * 0.6);
            let mut ra = a - fixed_point(a);
            let mut b = a - ra;
            for _ in 0..40 {
                let rb = b - fixed_point(b);
                let scale = b.abs().max(0.1);
                if rb.abs() < INFLOW_TOLERANCE * scale {
                    break;
                }
                let denom = rb - ra;
                let next = if denom.abs() > f64::EPSILON * rb.abs().max(1.0) {
                    b - rb * (b - a) / denom
                } else {
                    b - rb
                };
                a = b;
                ra = rb;
                b = next;
            }
            b
        }
    };
    state.nu = Some(nu);
    nu
}

/// The root ν of ν · √(V_h² + (ν − w)²) = c (c = T/(2ρA), m²/s²) on the branch described
/// in the module documentation. Negative thrust mirrors the problem (ν < 0).
pub fn momentum_root(c: f64, vh: f64, w: f64) -> f64 {
    if c == 0.0 || !c.is_finite() {
        return 0.0;
    }
    if c < 0.0 {
        return -momentum_root(-c, vh, -w);
    }
    let g = |nu: f64| nu * (vh * vh + (nu - w) * (nu - w)).sqrt() - c;
    if w > 0.0 && g(w) >= 0.0 {
        // Windmill side: a root in (0, w], bracketed.
        let (mut lo, mut hi) = (0.0, w);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if g(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo < 1e-14 * w {
                break;
            }
        }
        return 0.5 * (lo + hi);
    }
    // Normal working state: g is increasing and convex on ν ≥ max(w, 0) up to the root;
    // ν1 = w/2 + √(w²/4 + c) bounds the root from above, so Newton from ν1 decreases
    // monotonically onto it.
    let mut nu = 0.5 * w + (0.25 * w * w + c).sqrt();
    nu = nu
        .min(if vh > 0.0 { c / vh } else { f64::INFINITY })
        .max(0.0);
    for _ in 0..100 {
        let s = (vh * vh + (nu - w) * (nu - w)).sqrt();
        let val = nu * s - c;
        let d = s + if s > 0.0 { nu * (nu - w) / s } else { 0.0 };
        if d <= 0.0 {
            break;
        }
        let step = val / d;
        nu -= step;
        if step.abs() < 1e-14 * nu.abs().max(1e-3) {
            break;
        }
    }
    nu
}

/// Least-squares plane ν ≈ ν0 + C_νμ V_h + C_νw w (Eq. 6) through the momentum surface
/// ν = ν0² / √(V_h² + (ν − w)²) at fixed ν0 (m/s), over a grid of V_h ∈ [0, `vh_max`] and
/// w ∈ [`w_min`, `w_max`] (m/s). Returns (C_νμ, C_νw); ν0 is held at its hover value as in
/// the seed.
pub fn fit_plane(nu0: f64, vh_max: f64, w_min: f64, w_max: f64) -> (f64, f64) {
    // Normal equations of the 2-parameter fit of ν − ν0 on (V_h, w).
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let n = 41;
    for i in 0..n {
        let vh = vh_max * i as f64 / (n - 1) as f64;
        for j in 0..n {
            let w = w_min + (w_max - w_min) * j as f64 / (n - 1) as f64;
            let y = momentum_root(nu0 * nu0, vh, w) - nu0;
            a11 += vh * vh;
            a12 += vh * w;
            a22 += w * w;
            b1 += vh * y;
            b2 += w * y;
        }
    }
    let det = a11 * a22 - a12 * a12;
    ((b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn momentum_root_satisfies_glauert_and_limits() {
        // Hover: ν = ν_h exactly.
        assert!((momentum_root(25.0, 0.0, 0.0) - 5.0).abs() < 1e-12);
        // Axial climb at w = −4 m/s: ν = −w/2... closed form ν = w/2 + √(w²/4 + ν_h²).
        let nu = momentum_root(25.0, 0.0, -4.0);
        assert!((nu - (-2.0 + (4.0f64 + 25.0).sqrt())).abs() < 1e-12);
        // High speed: ν → ν_h² / V_h.
        let nu = momentum_root(25.0, 40.0, 0.0);
        assert!((nu - 25.0 / 40.0).abs() < 0.01 * 25.0 / 40.0);
        // Every branch satisfies the relation to round-off.
        for &(vh, w) in &[(3.0, 2.0), (0.0, 12.0), (1.0, 6.0), (10.0, -8.0)] {
            let nu = momentum_root(25.0, vh, w);
            let lhs = nu * (vh * vh + (nu - w) * (nu - w)).sqrt();
            assert!((lhs - 25.0).abs() < 1e-9, "vh {vh} w {w}: {lhs}");
        }
    }
}
