//! Rotor aerodynamics by blade-element integration (the truth counterpart of seed §3).
//!
//! Each rotor is integrated numerically over radius (Gauss–Legendre on
//! [root cutout, 1]·R) and azimuth (uniform, time average over one revolution) with the
//! exact element kinematics: the element velocity is the hub velocity plus
//! ω × r_element plus the blade's own rotation, the inflow angle is
//! φ = atan2(U_P, U_T) (no small-angle approximation, reverse flow included), and the
//! section has a lift-curve slope, a quadratic drag polar and a stall limit
//! ([`Airfoil`]). The uniform induced inflow ν comes from [`super::inflow`].
//!
//! Unlike Eq. 5 nothing here assumes small angles, μ ≪ 1, or a constant drag
//! coefficient; with the plane inflow of Eq. 6–7, no stall, zero root cutout and small
//! advance ratios the integrals reduce to Eq. 5 (tested in `tests/sim_rotor.rs`).
//!
//! Sign conventions: body FRD axes; the rotor of spin σ turns with angular velocity
//! σΩ b₃ relative to the airframe; the induced velocity ν is positive down through the
//! disc; loads are those the air exerts on the rotor, at the hub.

use std::f64::consts::PI;

use crate::rotor::BladeConstants;
use crate::vehicle::{STANDARD_GRAVITY, Vehicle};

/// Section aerodynamics of the blade (two-dimensional airfoil polar).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Airfoil {
    /// Lift-curve slope a, 1/rad (c_l = a α below stall).
    pub lift_slope: f64,
    /// Zero-lift profile drag coefficient c_d0.
    pub cd0: f64,
    /// Quadratic drag-polar coefficient c_d2 (c_d = c_d0 + c_d2 α² below stall), 1/rad².
    pub cd2: f64,
    /// Stall angle α_s, rad: beyond it lift follows a flat plate, c_l = a α_s sin 2α / sin 2α_s,
    /// and drag rises towards `cd_flat_plate` at 90°.
    pub stall_angle: f64,
    /// Drag coefficient of the section broadside to the flow (α = 90°).
    pub cd_flat_plate: f64,
}

impl Airfoil {
    /// Lift and drag coefficients at angle of attack `alpha` (rad, any value).
    #[inline]
    pub fn coefficients(&self, alpha: f64) -> (f64, f64) {
        let a_s = self.stall_angle;
        if alpha.abs() <= a_s {
            (self.lift_slope * alpha, self.cd0 + self.cd2 * alpha * alpha)
        } else {
            let cl = self.lift_slope * a_s * (2.0 * alpha).sin() / (2.0 * a_s).sin();
            let cd_s = self.cd0 + self.cd2 * a_s * a_s;
            let s2 = alpha.sin().powi(2);
            let s2s = a_s.sin().powi(2);
            let cd = cd_s + (self.cd_flat_plate - cd_s) * (s2 - s2s) / (1.0 - s2s);
            (cl, cd)
        }
    }
}

/// Blade geometry and section of one rotor; every rotor of a vehicle shares it.
#[derive(Debug, Clone, PartialEq)]
pub struct BladeDescription {
    /// Blade count N_b.
    pub blades: u32,
    /// Chord c (constant along the span), m.
    pub chord: f64,
    /// Collective pitch at the hub θ0 (θ(r̄) = θ0 + θ_tw r̄), rad.
    pub theta0: f64,
    /// Linear twist θ_tw from hub to tip, rad (negative = washout).
    pub theta_tw: f64,
    /// Root cutout as a fraction of R (no lift inboard of it).
    pub root_cutout: f64,
    /// Section polar.
    pub airfoil: Airfoil,
}

/// A blade that cannot be used: a value out of range, or no hover trim.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BladeError {
    /// A rotor-file value out of its range.
    #[error("field `{field}`{}: {requirement}", value.map(|v| format!(" = {v}")).unwrap_or_default())]
    Field {
        /// The rotor-file key.
        field: &'static str,
        /// Its value, when the message names it.
        value: Option<f64>,
        /// What it must satisfy, e.g. `must be finite`.
        requirement: &'static str,
    },
    /// A negative drag-polar coefficient.
    #[error("fields `cd0`, `cd2`: must be >= 0")]
    DragPolar,
    /// No collective pitch up to 0.8 rad gives the hover thrust.
    #[error(
        "cannot trim the rotor for hover: thrust {thrust:.3} N needs more than 0.8 rad of pitch at {omega:.1} rad/s"
    )]
    Trim {
        /// Hover thrust of one rotor, N.
        thrust: f64,
        /// Rotor speed, rad/s.
        omega: f64,
    },
    /// The blade does not give the hover thrust below a 400 m/s tip speed.
    #[error(
        "the rotor cannot lift {thrust:.3} N below a tip speed of 400 m/s; increase `theta0` or `chord`"
    )]
    NoHoverSpeed {
        /// Hover thrust of one rotor, N.
        thrust: f64,
    },
}

/// Default solidity N_b c / (πR) of the sized rotor.
pub const DEFAULT_SOLIDITY: f64 = 0.1;
/// Default hover blade loading C_T/σ (C_T = T / (ρπR²(ΩR)²)); 0.1 is a typical
/// design value, leaving a stall margin for manoeuvres at ±40 % rotor speed.
pub const DEFAULT_HOVER_BLADE_LOADING: f64 = 0.1;

/// Values of an optional `--rotor` TOML file; every field is optional and falls back to
/// the sizing of [`BladeDescription::sized_for`].
#[derive(Debug, Clone, Default)]
pub struct BladeOverrides {
    /// Blade count.
    pub blades: Option<u32>,
    /// Chord, m.
    pub chord: Option<f64>,
    /// Hub pitch θ0, rad (default: trimmed so hover thrust = m g / N).
    pub theta0: Option<f64>,
    /// Linear twist, rad.
    pub theta_tw: Option<f64>,
    /// Root cutout, fraction of R.
    pub root_cutout: Option<f64>,
    /// Lift-curve slope, 1/rad.
    pub lift_slope: Option<f64>,
    /// Zero-lift drag coefficient.
    pub cd0: Option<f64>,
    /// Quadratic drag-polar coefficient, 1/rad².
    pub cd2: Option<f64>,
    /// Stall angle, rad.
    pub stall_angle: Option<f64>,
    /// Broadside drag coefficient.
    pub cd_flat_plate: Option<f64>,
    /// Hover tip speed ΩR the trim aims for, m/s (default from C_T/σ = 0.1).
    pub hover_tip_speed: Option<f64>,
}

impl BladeDescription {
    /// A blade sized for `vehicle`: two blades, solidity 0.1, washout −0.3 rad,
    /// NACA-0012-like section (a = 5.7 /rad, c_d0 = 0.011, c_d2 = 0.9, stall at 0.26 rad),
    /// root cutout 0.1 R, and θ0 trimmed so that the hover thrust of each rotor equals
    /// m g / N at the tip speed giving C_T/σ = 0.1. `overrides` replace any value.
    /// Returns the blade and its hover rotor speed (rad/s).
    pub fn sized_for(
        vehicle: &Vehicle,
        overrides: &BladeOverrides,
    ) -> Result<(Self, f64), BladeError> {
        let p = &vehicle.props;
        let r = p.rotor_radius;
        let blades = overrides.blades.unwrap_or(2);
        if blades == 0 {
            return Err(BladeError::Field {
                field: "blades",
                value: None,
                requirement: "must be at least 1",
            });
        }
        let chord = overrides
            .chord
            .unwrap_or(DEFAULT_SOLIDITY * PI * r / blades as f64);
        let mut blade = Self {
            blades,
            chord,
            theta0: 0.0,
            theta_tw: overrides.theta_tw.unwrap_or(-0.3),
            root_cutout: overrides.root_cutout.unwrap_or(0.1),
            airfoil: Airfoil {
                lift_slope: overrides.lift_slope.unwrap_or(5.7),
                cd0: overrides.cd0.unwrap_or(0.011),
                cd2: overrides.cd2.unwrap_or(0.9),
                stall_angle: overrides.stall_angle.unwrap_or(0.26),
                cd_flat_plate: overrides.cd_flat_plate.unwrap_or(1.8),
            },
        };
        blade.check()?;
        let thrust = p.mass * STANDARD_GRAVITY / vehicle.rotor_count() as f64;
        let solidity = blade.blades as f64 * blade.chord / (PI * r);
        let tip = match overrides.hover_tip_speed {
            Some(v) if v.is_finite() && v > 0.0 => v,
            Some(v) => {
                return Err(BladeError::Field {
                    field: "hover_tip_speed",
                    value: Some(v),
                    requirement: "must be > 0",
                });
            }
            None => (thrust
                / (p.air_density * PI * r * r * solidity * DEFAULT_HOVER_BLADE_LOADING))
                .sqrt(),
        };
        let omega = tip / r;
        match overrides.theta0 {
            Some(t) if t.is_finite() => blade.theta0 = t,
            Some(t) => {
                return Err(BladeError::Field {
                    field: "theta0",
                    value: Some(t),
                    requirement: "must be finite",
                });
            }
            None => blade.theta0 = blade.trim_theta0(vehicle, omega, thrust)?,
        }
        let hover_omega = if overrides.theta0.is_some() {
            blade.hover_speed(vehicle, thrust)?
        } else {
            omega
        };
        Ok((blade, hover_omega))
    }

    fn check(&self) -> Result<(), BladeError> {
        let field = |field, value, requirement| BladeError::Field {
            field,
            value,
            requirement,
        };
        let pos = |name, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(field(name, Some(v), "must be a finite number > 0"))
            }
        };
        pos("chord", self.chord)?;
        pos("lift_slope", self.airfoil.lift_slope)?;
        pos("stall_angle", self.airfoil.stall_angle)?;
        pos("cd_flat_plate", self.airfoil.cd_flat_plate)?;
        if self.airfoil.stall_angle >= PI / 4.0 {
            return Err(field(
                "stall_angle",
                Some(self.airfoil.stall_angle),
                "must be below pi/4 rad",
            ));
        }
        if !(self.airfoil.cd0 >= 0.0 && self.airfoil.cd2 >= 0.0) {
            return Err(BladeError::DragPolar);
        }
        if !(0.0..0.9).contains(&self.root_cutout) {
            return Err(field(
                "root_cutout",
                Some(self.root_cutout),
                "must be in [0, 0.9)",
            ));
        }
        if !self.theta_tw.is_finite() {
            return Err(field("theta_tw", None, "must be finite"));
        }
        Ok(())
    }

    /// θ0 that gives hover thrust `thrust` (N) at rotor speed `omega` (rad/s), by bisection
    /// on the blade-element thrust with momentum inflow.
    fn trim_theta0(&self, vehicle: &Vehicle, omega: f64, thrust: f64) -> Result<f64, BladeError> {
        let (mut lo, mut hi) = (-0.2, 0.8);
        let mut b = self.clone();
        for _ in 0..80 {
            b.theta0 = 0.5 * (lo + hi);
            if hover_thrust(&b, vehicle, omega) < thrust {
                lo = b.theta0;
            } else {
                hi = b.theta0;
            }
        }
        b.theta0 = 0.5 * (lo + hi);
        if (hover_thrust(&b, vehicle, omega) - thrust).abs() > 1e-6 * thrust {
            return Err(BladeError::Trim { thrust, omega });
        }
        Ok(b.theta0)
    }

    /// Rotor speed (rad/s) at which hover thrust equals `thrust` (N), by bisection.
    fn hover_speed(&self, vehicle: &Vehicle, thrust: f64) -> Result<f64, BladeError> {
        let r = vehicle.props.rotor_radius;
        let (mut lo, mut hi) = (1.0 / r, 400.0 / r);
        if hover_thrust(self, vehicle, hi) < thrust {
            return Err(BladeError::NoHoverSpeed { thrust });
        }
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if hover_thrust(self, vehicle, mid) < thrust {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(0.5 * (lo + hi))
    }

    /// Mean drag coefficient c̄_d of Eq. 5 (at r̄ = √2/2) for the hover inflow ratio
    /// `lambda` (so α = θ(√2/2) − λ/(√2/2)).
    pub fn mean_drag(&self, lambda: f64) -> f64 {
        let r = std::f64::consts::FRAC_1_SQRT_2;
        let alpha = self.theta0 + self.theta_tw * r - (lambda / r).atan();
        self.airfoil.coefficients(alpha).1
    }

    /// The closed-form constants of Eq. 5–7 that describe this blade: same N_b, c, a,
    /// θ0, θ_tw, c̄_d at hover inflow ratio `hover_lambda`, and the inflow-plane slopes
    /// `c_nu_mu`, `c_nu_w` (Eq. 6; see [`super::inflow::fit_plane`]).
    pub fn blade_constants(&self, hover_lambda: f64, c_nu_mu: f64, c_nu_w: f64) -> BladeConstants {
        BladeConstants {
            blades: self.blades as f64,
            chord: self.chord,
            lift_slope: self.airfoil.lift_slope,
            mean_drag: self.mean_drag(hover_lambda),
            theta0: self.theta0,
            theta_tw: self.theta_tw,
            c_nu_mu,
            c_nu_w,
        }
    }
}

/// Blade-element thrust (N) in still-air hover at `omega` with momentum inflow.
fn hover_thrust(blade: &BladeDescription, vehicle: &Vehicle, omega: f64) -> f64 {
    let rotor = BladeElementRotor::new(blade.clone(), vehicle, 8, 12);
    let mut inflow = super::inflow::InflowState::default();
    let kin = RotorKinematics {
        omega,
        spin: 1.0,
        hub_velocity: [0.0; 3],
        body_rates: [0.0; 3],
    };
    rotor
        .loads(&kin, &super::inflow::InflowModel::Momentum, &mut inflow)
        .force[2]
        .abs()
}

/// Gauss–Legendre nodes and weights on [a, b] (`n` points; exact for polynomials of
/// degree 2n − 1).
pub fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Newton iteration on P_n from the Chebyshev-like initial guess.
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { x } else { p1 };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pn1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w));
    }
    out
}

/// Motion of one rotor relative to the air.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorKinematics {
    /// Rotor speed Ω relative to the airframe, rad/s (≥ 0).
    pub omega: f64,
    /// Spin σ = ±1 (angular velocity σΩ b₃).
    pub spin: f64,
    /// Hub velocity relative to the air in body axes, m/s (v_air + ω × r_hub, Eq. 17).
    pub hub_velocity: [f64; 3],
    /// Body angular velocity (p, q, r), rad/s; adds ω × r_element along the blade.
    pub body_rates: [f64; 3],
}

/// Aerodynamic loads on one rotor at its hub, body axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HubLoads {
    /// Force on the rotor, N, body axes.
    pub force: [f64; 3],
    /// Moment on the rotor about its hub, N m, body axes (includes the drag torque).
    pub moment: [f64; 3],
    /// Induced velocity ν used, m/s (positive down through the disc).
    pub induced_velocity: f64,
}

/// One radial station of the quadrature.
#[derive(Debug, Clone, Copy)]
struct Station {
    /// Radius r̄ R, m.
    radius: f64,
    /// Quadrature weight × R (dr in metres).
    weight: f64,
    /// Local pitch θ(r̄), rad.
    pitch: f64,
}

/// A blade-element rotor ready to evaluate: quadrature tables precomputed.
#[derive(Debug, Clone)]
pub struct BladeElementRotor {
    /// The blade.
    pub blade: BladeDescription,
    /// Rotor radius R, m.
    pub radius: f64,
    /// Air density ρ, kg/m³.
    pub air_density: f64,
    stations: Vec<Station>,
    /// (cos ψ, sin ψ) of the azimuth stations.
    azimuths: Vec<(f64, f64)>,
}

impl BladeElementRotor {
    /// Precomputes `radial` Gauss points and `azimuthal` uniform azimuth stations.
    pub fn new(
        blade: BladeDescription,
        vehicle: &Vehicle,
        radial: usize,
        azimuthal: usize,
    ) -> Self {
        let radius = vehicle.props.rotor_radius;
        let stations = gauss_legendre(radial.max(1), blade.root_cutout, 1.0)
            .into_iter()
            .map(|(x, w)| Station {
                radius: x * radius,
                weight: w * radius,
                pitch: blade.theta0 + blade.theta_tw * x,
            })
            .collect();
        let azimuths = (0..azimuthal.max(1))
            .map(|k| {
                let psi = 2.0 * PI * (k as f64 + 0.5) / azimuthal.max(1) as f64;
                (psi.cos(), psi.sin())
            })
            .collect();
        Self {
            blade,
            radius,
            air_density: vehicle.props.air_density,
            stations,
            azimuths,
        }
    }

    /// Disc area πR², m².
    pub fn disk_area(&self) -> f64 {
        PI * self.radius * self.radius
    }

    /// Loads at a given uniform induced velocity `nu` (m/s): the revolution-averaged sum
    /// over blades, azimuth and radius. With `thrust_only`, only the thrust −F_z is
    /// accumulated (cheaper, used while solving for ν).
    pub fn loads_at_inflow(&self, kin: &RotorKinematics, nu: f64, thrust_only: bool) -> HubLoads {
        let [vx, vy, vz] = kin.hub_velocity;
        let [p, q, r] = kin.body_rates;
        let s = kin.spin;
        let half_rho_c = 0.5 * self.air_density * self.blade.chord;
        let airfoil = self.blade.airfoil;
        let mut f = [0.0; 3];
        let mut m = [0.0; 3];
        for &(c, sn) in &self.azimuths {
            // Blade direction e_r = (c, s, 0); direction of blade motion e_t = σ(−s, c, 0).
            let (etx, ety) = (-s * sn, s * c);
            for st in &self.stations {
                let x = st.radius * c;
                let y = st.radius * sn;
                // Element velocity through the air: hub + ω × r_el + σΩ b₃ × r_el.
                let ex = vx - r * y;
                let ey = vy + r * x;
                let ez = vz + p * y - q * x;
                let ut = kin.omega * st.radius + ex * etx + ey * ety;
                let up = nu - ez;
                let u2 = ut * ut + up * up;
                if u2 == 0.0 {
                    continue;
                }
                let phi = up.atan2(ut);
                let (cl, cd) = airfoil.coefficients(st.pitch - phi);
                let ql = half_rho_c * st.weight * u2.sqrt();
                let (l, d) = (ql * cl, ql * cd);
                // Element force (per U): lift (−U_P e_t − U_T b₃), drag (−U_T e_t + U_P b₃).
                let ft = -l * up - d * ut;
                let fz = -l * ut + d * up;
                f[2] += fz;
                if !thrust_only {
                    let fx = ft * etx;
                    let fy = ft * ety;
                    f[0] += fx;
                    f[1] += fy;
                    m[0] += y * fz;
                    m[1] -= x * fz;
                    m[2] += x * fy - y * fx;
                }
            }
        }
        let scale = self.blade.blades as f64 / self.azimuths.len() as f64;
        HubLoads {
            force: f.map(|v| v * scale),
            moment: m.map(|v| v * scale),
            induced_velocity: nu,
        }
    }

    /// Loads with the inflow given by `model`; `state` carries the previous solution as
    /// the starting guess (warm start in time-domain simulation).
    pub fn loads(
        &self,
        kin: &RotorKinematics,
        model: &super::inflow::InflowModel,
        state: &mut super::inflow::InflowState,
    ) -> HubLoads {
        let nu = self.solve_inflow(kin, model, state);
        self.loads_at_inflow(kin, nu, false)
    }

    /// The induced velocity ν (m/s) that `model` gives this rotor at `kin` (the thrust
    /// at each trial inflow from blade elements); `state` warm-starts the solve.
    pub fn solve_inflow(
        &self,
        kin: &RotorKinematics,
        model: &super::inflow::InflowModel,
        state: &mut super::inflow::InflowState,
    ) -> f64 {
        let thrust = |nu: f64| -self.loads_at_inflow(kin, nu, true).force[2];
        let (rho, area) = (self.air_density, self.disk_area());
        super::inflow::solve(kin.hub_velocity, rho, area, thrust, model, state)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        // 8 points are exact to degree 15: ∫_0.1^1 r^15 dr = (1 − 0.1^16)/16.
        let nodes = gauss_legendre(8, 0.1, 1.0);
        let integral: f64 = nodes.iter().map(|(x, w)| w * x.powi(15)).sum();
        assert!((integral - (1.0 - 0.1f64.powi(16)) / 16.0).abs() < 1e-14);
        let total: f64 = nodes.iter().map(|(_, w)| w).sum();
        assert!((total - 0.9).abs() < 1e-14);
    }

    #[test]
    fn airfoil_polar_is_continuous_at_stall_and_flat_plate_at_90_degrees() {
        let a = Airfoil {
            lift_slope: 5.7,
            cd0: 0.011,
            cd2: 0.9,
            stall_angle: 0.26,
            cd_flat_plate: 1.8,
        };
        let (below, above) = (a.coefficients(0.26 - 1e-9), a.coefficients(0.26 + 1e-9));
        assert!((below.0 - above.0).abs() < 1e-7 && (below.1 - above.1).abs() < 1e-7);
        let (cl90, cd90) = a.coefficients(std::f64::consts::FRAC_PI_2);
        assert!(cl90.abs() < 1e-12 && (cd90 - 1.8).abs() < 1e-12);
        // Odd lift, even drag.
        let (p, m) = (a.coefficients(0.4), a.coefficients(-0.4));
        assert!((p.0 + m.0).abs() < 1e-12 && (p.1 - m.1).abs() < 1e-12);
    }
}
