//! Single-rotor aerodynamics in closed form (seed §3, Eq. 2–8).
//!
//! The blade-element coefficients of Eq. 5 with the plane approximation of the momentum
//! inflow (Eq. 6–7), and the map from blade and inflow constants to the lumped parameters
//! of Eq. 8 / Eq. 22. The seed cites this map ("full derivation found in \[26\]") without
//! printing it; it is derived here by expanding Eq. 5 with Eq. 7 and collecting terms:
//!
//! with C_σ = N_b c a / (2πR), K = C_σ(θ0/3 + θtw/4) and G = C_σ(θ0/2 + θtw/4),
//!
//! | parameter | value | | parameter | value |
//! |---|---|---|---|---|
//! | `C_H_mub` | C_σ c̄d / (2a) | | `C_T_muw` | C_σ (1 − C_νw) / 2 |
//! | `C_H_mub_mu0` | G | | `C_R_mub` | K |
//! | `C_H_mub_mu` | G C_νμ | | `C_Q0` | C_σ c̄d / (4a) |
//! | `C_H_mub_muw` | G (1 − C_νw) | | `C_Q_mu0` | K |
//! | `C_T0` | K | | `C_Q_mu` | K C_νμ |
//! | `C_T_mu0` | C_σ / 2 | | `C_Q_muw` | K (1 − C_νw) |
//! | `C_T_mu` | C_σ C_νμ / 2 | | `C_Q_muw2` | C_σ (1 − C_νw)² / 2 |
//! | `C_T_mu2` | G | | `C_Q_mu_muw` | C_σ C_νμ (1 − C_νw) |
//!
//! Differences from the printed seed, found by this derivation:
//! - Eq. 8e multiplies by μ_u; Eq. 5e (and Eq. 22e, which uses v δr) has μ_v. Eq. 5e is
//!   right: the pitching moment comes from lateral velocity.
//! - Eq. 8f lists `C_Q_mu_muw μ μ_w` twice; in the multirotor sum every term of C_Q that
//!   does not vary from rotor to rotor cancels (Σσ_i = 0), so only the μ_w-dependent
//!   terms reach Eq. 22f. Of those, the μ μ_w term (`C_Q_mu_muw`) also cancels under
//!   Assumption 2 (Σσ_i w_i = 0) and appears only for general planar layouts.
//! - The hub rolling and pitching moments of Eq. 5d–e, carried to the airframe by
//!   Eq. 11 as printed (σ(−ℛ, 𝒫)), have the wrong sign: for σ = +1 in forward flight the
//!   advancing blade is on the left and rolls the vehicle right (M_x > 0), where the
//!   printed form gives M_x < 0. Blade-element integration in the crate's simulator
//!   agrees with the physical sign to 0.1 %, and so does the seed's own Table 5, whose
//!   fitted C_Rμb (−1.12e-2) has the opposite sign to C_T0 (1.54e-2). The crate
//!   transmits σ(ℛ, −𝒫) (see [`crate::airframe`]), so C_R_mub = −K here; the Eq. 22
//!   regressors are unchanged.
//! - In Eq. 22, |C_R_mub|, C_T0 and C_Q_mu0 all equal K in this derivation; they stay
//!   separate parameters because the lumped model absorbs effects (airframe,
//!   Assumption 3) that break these equalities.

use std::f64::consts::PI;

/// Blade-element and inflow constants of one rotor (seed §3, Assumption 1, Eq. 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BladeConstants {
    /// Blade count N_b.
    pub blades: f64,
    /// Blade chord c, m.
    pub chord: f64,
    /// Lift-curve slope a, 1/rad.
    pub lift_slope: f64,
    /// Mean profile drag coefficient c̄d (at r = √2/2), dimensionless.
    pub mean_drag: f64,
    /// Collective pitch at the hub θ0, rad.
    pub theta0: f64,
    /// Linear twist θtw (θ(r) = θ0 + θtw r), rad.
    pub theta_tw: f64,
    /// Inflow-plane slope C_νμ with in-plane airspeed V_h (Eq. 6), dimensionless.
    pub c_nu_mu: f64,
    /// Inflow-plane slope C_νw with vertical velocity w (Eq. 6), dimensionless.
    pub c_nu_w: f64,
}

impl BladeConstants {
    /// C_σ = N_b c a / (2πR) for rotor radius `radius` (m), dimensionless (Eq. 5).
    pub fn c_sigma(&self, radius: f64) -> f64 {
        self.blades * self.chord * self.lift_slope / (2.0 * PI * radius)
    }

    /// Total inflow ratio λ of Eq. 7 from hover inflow ratio μ0, rotor-plane advance
    /// ratio μ and vertical advance ratio μ_w.
    pub fn inflow_ratio(&self, mu0: f64, mu: f64, mu_w: f64) -> f64 {
        mu0 + self.c_nu_mu * mu + (self.c_nu_w - 1.0) * mu_w
    }

    /// Rotor coefficients of Eq. 5 at body-axis advance ratios μ_u, μ_v (Eq. 2a),
    /// rotor-plane advance ratio μ (Eq. 2b) and total inflow ratio λ (Eq. 3).
    pub fn coefficients(
        &self,
        radius: f64,
        mu_u: f64,
        mu_v: f64,
        mu: f64,
        lambda: f64,
    ) -> RotorCoefficients {
        let cs = self.c_sigma(radius);
        let a = self.lift_slope;
        let cd = self.mean_drag;
        let th = self.theta0 / 2.0 + self.theta_tw / 4.0;
        let tk = self.theta0 / 3.0 + self.theta_tw / 4.0;
        let mu2 = mu * mu;
        RotorCoefficients {
            c_h: cs * (cd / (2.0 * a) * mu_u + th * lambda * mu_u),
            c_s: -cs * (cd / (2.0 * a) * mu_v + th * lambda * mu_v),
            c_t: cs
                * (self.theta0 / 3.0 * (1.0 + 1.5 * mu2) + self.theta_tw / 4.0 * (1.0 + mu2)
                    - lambda / 2.0),
            c_roll: cs * (tk - lambda / 4.0) * mu_u,
            c_pitch: -cs * (tk - lambda / 4.0) * mu_v,
            c_torque: cs * (cd / (4.0 * a) * (1.0 + mu2) + (tk - lambda / 2.0) * lambda),
        }
    }

    /// Dimensional loads of one rotor of radius `radius` (m) spinning at `omega`
    /// (rad/s, positive) in air of density `rho` (kg/m³), with hub velocity `v_hub` (body axes, m/s)
    /// and hover induced velocity `nu0` (m/s): Eq. 2, Eq. 7, Eq. 5 and Eq. 4.
    pub fn loads(
        &self,
        rho: f64,
        radius: f64,
        omega: f64,
        v_hub: [f64; 3],
        nu0: f64,
    ) -> RotorLoads {
        let tip = omega * radius;
        let [u, v, w] = v_hub;
        let (mu_u, mu_v, mu_w) = (u / tip, v / tip, w / tip);
        let mu = u.hypot(v) / tip;
        let lambda = self.inflow_ratio(nu0 / tip, mu, mu_w);
        let c = self.coefficients(radius, mu_u, mu_v, mu, lambda);
        let f = rho * PI * radius.powi(4) * omega * omega;
        let m = f * radius;
        RotorLoads {
            hub_force: f * c.c_h,
            side_force: f * c.c_s,
            thrust: f * c.c_t,
            rolling_moment: m * c.c_roll,
            pitching_moment: m * c.c_pitch,
            torque: m * c.c_torque,
        }
    }

    /// The lumped parameters of Eq. 8 / Eq. 22 implied by these constants (see the
    /// module documentation for the derivation).
    pub fn lumped_parameters(&self, radius: f64) -> LumpedParameters {
        let cs = self.c_sigma(radius);
        let k = cs * (self.theta0 / 3.0 + self.theta_tw / 4.0);
        let g = cs * (self.theta0 / 2.0 + self.theta_tw / 4.0);
        let one_minus_cw = 1.0 - self.c_nu_w;
        let drag = cs * self.mean_drag / self.lift_slope;
        LumpedParameters(vec![
            ("C_H_mub", drag / 2.0),
            ("C_H_mub_mu0", g),
            ("C_H_mub_mu", g * self.c_nu_mu),
            ("C_H_mub_muw", g * one_minus_cw),
            ("C_T0", k),
            ("C_T_mu0", cs / 2.0),
            ("C_T_mu", cs * self.c_nu_mu / 2.0),
            ("C_T_mu2", g),
            ("C_T_muw", cs * one_minus_cw / 2.0),
            // Negative: the hub rolling moment opposes the printed Eq. 11 sign (module docs).
            ("C_R_mub", -k),
            ("C_Q0", drag / 4.0),
            ("C_Q_mu0", k),
            ("C_Q_mu", k * self.c_nu_mu),
            ("C_Q_muw", k * one_minus_cw),
            ("C_Q_muw2", cs * one_minus_cw * one_minus_cw / 2.0),
            // Eq. 8f's μ μ_w term: reaches Eq. 22f only for a general planar layout.
            ("C_Q_mu_muw", cs * self.c_nu_mu * one_minus_cw),
        ])
    }
}

/// Dimensionless rotor force and moment coefficients of Eq. 4–5.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorCoefficients {
    /// Hub force coefficient C_H.
    pub c_h: f64,
    /// Side force coefficient C_S.
    pub c_s: f64,
    /// Thrust coefficient C_T.
    pub c_t: f64,
    /// Rolling moment coefficient C_ℛ.
    pub c_roll: f64,
    /// Pitching moment coefficient C_𝒫.
    pub c_pitch: f64,
    /// Torque coefficient C_𝒬.
    pub c_torque: f64,
}

/// Dimensional rotor loads in the rotor frame of seed Fig. 1 (r1 = −b1, r2 = b2,
/// r3 = −b3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorLoads {
    /// Hub force H, N.
    pub hub_force: f64,
    /// Side force S, N.
    pub side_force: f64,
    /// Thrust T, N.
    pub thrust: f64,
    /// Rolling moment ℛ, N m.
    pub rolling_moment: f64,
    /// Pitching moment 𝒫, N m.
    pub pitching_moment: f64,
    /// Aerodynamic torque 𝒬, N m.
    pub torque: f64,
}

/// Named lumped-parameter values (dimensionless), in the order of Eq. 22.
#[derive(Debug, Clone, PartialEq)]
pub struct LumpedParameters(pub Vec<(&'static str, f64)>);

impl LumpedParameters {
    /// The value of the parameter called `name`, if it exists.
    pub fn value(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hover_thrust_coefficient_matches_blade_element_theory() {
        // Hover, untwisted: C_T = C_σ (θ0/3 − λ/2) (Johnson ch. 2 with σa/2 = C_σ).
        let b = BladeConstants {
            blades: 2.0,
            chord: 0.02,
            lift_slope: 5.7,
            mean_drag: 0.01,
            theta0: 0.2,
            theta_tw: 0.0,
            c_nu_mu: 0.0,
            c_nu_w: 0.0,
        };
        let c = b.coefficients(0.1, 0.0, 0.0, 0.0, 0.05);
        let cs = 2.0 * 0.02 * 5.7 / (2.0 * PI * 0.1);
        assert!((c.c_t - cs * (0.2 / 3.0 - 0.025)).abs() < 1e-15);
        assert_eq!(c.c_h, 0.0);
        assert_eq!(c.c_roll, 0.0);
    }
}
