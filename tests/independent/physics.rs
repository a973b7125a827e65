//! Loads of the independent model: a closed-form rotor of its own (thrust and drag
//! torque from Ω² with corrections in the climb and edgewise advance ratios, an in-plane
//! H-force ∝ Ω·V plus a profile term ∝ |V|·V, a hub moment from edgewise flow), rotor
//! gyroscopic and reaction torques, and the hidden effects of [`Hidden`].
//!
//! Every rotor sees its own hub velocity v + ω × r (yaw rate and hub height included),
//! with λ = −w_hub/(Ω R) (climb positive) and μ = |v_hub,in-plane|/(Ω R):
//!
//! - thrust T = k_T Ω² (1 − a λ − c λ|λ| + b μ²), along −z;
//! - drag torque Q = k_Q Ω² (1 − a_Q λ + b_Q μ²), on the airframe −σ Q about z;
//! - H-force −(k_H Ω + k_H2 |v_ip|) v_ip in the rotor plane;
//! - hub moment k_R σ Ω (u_hub, v_hub, 0) (the advancing blade's extra lift);
//! - −σ J_z (q Ω, −p Ω, Ω̇) from the rotor's angular momentum.
//!
//! The wrench returned is the data contract's: force and moment about the true CG in
//! body axes, gravity excluded, i.e. what I ω̇ + ω × I ω and m a measure.

use mrsysid::Vehicle;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::effects::Hidden;

/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.80665;

/// Rotor coefficients of the independent model (by default a 5-inch propeller turning
/// ~1800 rad/s in hover on the 1.2 kg quadrotor; [`RotorCoefficients::scaled`] for
/// other sizes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorCoefficients {
    /// Static thrust coefficient k_T, N s².
    pub k_t: f64,
    /// Thrust loss per unit climb inflow ratio a (-).
    pub climb: f64,
    /// Thrust curvature in the climb inflow ratio c (-).
    pub climb_curvature: f64,
    /// Thrust gain per squared edgewise advance ratio b (-).
    pub edgewise: f64,
    /// Static torque coefficient k_Q, N m s².
    pub k_q: f64,
    /// Torque change per unit climb inflow ratio a_Q (-).
    pub torque_climb: f64,
    /// Torque gain per squared edgewise advance ratio b_Q (-).
    pub torque_edgewise: f64,
    /// H-force coefficient k_H, N s / (rad m/s).
    pub k_h: f64,
    /// Profile H-force coefficient k_H2, N s²/m².
    pub k_h2: f64,
    /// Hub moment coefficient k_R, N m s / (rad m/s).
    pub k_r: f64,
    /// Motor time constant, s.
    pub motor_tau: f64,
}

/// How a vehicle's size compares with the shipped quadrotor × the harness was written for
/// (1.2 kg, R = 63.5 mm, inertia diag(0.011, 0.012, 0.021) kg m², four rotors, air at
/// 1.225 kg/m³): every ratio is exactly 1 for that vehicle, so its data are the same to
/// the bit whichever way they are scaled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// Rotor radius over 63.5 mm (-).
    pub length: f64,
    /// Air density over 1.225 kg/m³ (-).
    pub density: f64,
    /// Mass over 1.2 kg (-).
    pub mass: f64,
    /// Principal inertias over (0.011, 0.012, 0.021) kg m² (-).
    pub inertia: [f64; 3],
    /// The sum of the principal inertias over 0.044 kg m² (-).
    pub inertia_sum: f64,
    /// Hover induced velocity over the reference's, √(m g / (2 ρ n π R²)) (-).
    pub induced: f64,
}

impl Scale {
    /// `vehicle` against the reference quadrotor.
    pub fn of(vehicle: &Vehicle) -> Self {
        let p = &vehicle.props;
        let (radius, density, mass, rotors) = (0.0635, 1.225, 1.2, 4.0);
        let inertia = [0.011, 0.012, 0.021];
        let length = p.rotor_radius / radius;
        let density_ratio = p.air_density / density;
        let mass_ratio = p.mass / mass;
        let n = vehicle.rotors().len() as f64;
        Self {
            length,
            density: density_ratio,
            mass: mass_ratio,
            inertia: std::array::from_fn(|k| p.inertia[k][k] / inertia[k]),
            inertia_sum: (p.inertia[0][0] + p.inertia[1][1] + p.inertia[2][2])
                / (inertia[0] + inertia[1] + inertia[2]),
            induced: (mass_ratio * (rotors / n) / (density_ratio * length * length)).sqrt(),
        }
    }
}

impl RotorCoefficients {
    /// The default rotor grown to `scale` by similarity: the same thrust, torque,
    /// H-force and hub-moment coefficients in ρ, Ω and R (k_T and k_R ∝ ρR⁴, k_Q ∝ ρR⁵,
    /// k_H ∝ ρR³, the profile term ∝ ρR²), the same dimensionless climb and edgewise
    /// corrections, and a motor time constant ∝ √R.
    pub fn scaled(scale: &Scale) -> Self {
        let d = Self::default();
        let (r, rho) = (scale.length, scale.density);
        Self {
            k_t: d.k_t * rho * r.powi(4),
            k_q: d.k_q * rho * r.powi(5),
            k_h: d.k_h * rho * r.powi(3),
            k_h2: d.k_h2 * rho * r.powi(2),
            k_r: d.k_r * rho * r.powi(4),
            motor_tau: d.motor_tau * r.sqrt(),
            ..d
        }
    }
}

impl Default for RotorCoefficients {
    fn default() -> Self {
        Self {
            k_t: 9.0e-7,
            climb: 2.5,
            climb_curvature: 2.0,
            edgewise: 1.5,
            k_q: 1.5e-8,
            torque_climb: 1.2,
            torque_edgewise: 0.8,
            k_h: 1.2e-5,
            k_h2: 4.0e-4,
            k_r: 2.5e-7,
            motor_tau: 0.025,
        }
    }
}

/// The instantaneous state the loads depend on.
#[derive(Debug, Clone)]
pub struct LoadState<'a> {
    /// Air-relative velocity of the CG, body axes, m/s.
    pub velocity: Vector3<f64>,
    /// Body rates p, q, r, rad/s.
    pub rates: Vector3<f64>,
    /// Rotor speeds, rad/s.
    pub omega: &'a [f64],
    /// Rotor accelerations, rad/s².
    pub omega_dot: &'a [f64],
    /// CG height above ground, m (up).
    pub height: f64,
    /// Attitude body→NED.
    pub attitude: UnitQuaternion<f64>,
}

/// The airframe: mass properties and rotor sites of the vehicle file, this model's rotor
/// coefficients, and at most one hidden effect.
#[derive(Debug, Clone)]
pub struct Airframe {
    /// Mass, kg.
    pub mass: f64,
    /// Inertia about the CG, body axes, kg m².
    pub inertia: Matrix3<f64>,
    /// Rotor radius, m.
    pub radius: f64,
    /// Air density, kg/m³.
    pub rho: f64,
    /// Rotor inertia J_z, kg m².
    pub rotor_inertia: f64,
    /// Hub positions relative to the true CG, body axes, m.
    pub hubs: Vec<Vector3<f64>>,
    /// Hub positions as the vehicle file gives them (what the controller knows), m.
    pub nominal_hubs: Vec<Vector3<f64>>,
    /// Spin directions σ_i (+1: angular velocity along +z).
    pub spins: Vec<f64>,
    /// Rotor coefficients.
    pub rotor: RotorCoefficients,
    /// The hidden effect, if any.
    pub hidden: Option<Hidden>,
    /// The vehicle's size against the reference quadrotor (controller, excitation,
    /// envelope and noise scale with it).
    pub scale: Scale,
}

impl Airframe {
    /// The vehicle's airframe with this model's rotors and `hidden`.
    pub fn new(vehicle: &Vehicle, hidden: Option<Hidden>) -> Self {
        let p = &vehicle.props;
        let nominal_hubs: Vec<Vector3<f64>> = vehicle
            .rotors()
            .iter()
            .map(|r| Vector3::new(r.x, r.y, -p.hub_height))
            .collect();
        let cg = match hidden {
            Some(Hidden::CgOffset { offset }) => Vector3::from(offset),
            _ => Vector3::zeros(),
        };
        let scale = Scale::of(vehicle);
        Self {
            mass: p.mass,
            inertia: Matrix3::from_fn(|i, j| p.inertia[i][j]),
            radius: p.rotor_radius,
            rho: p.air_density,
            rotor_inertia: p.rotor_inertia,
            hubs: nominal_hubs.iter().map(|h| h - cg).collect(),
            nominal_hubs,
            spins: vehicle.rotors().iter().map(|r| r.spin).collect(),
            rotor: RotorCoefficients::scaled(&scale),
            hidden,
            scale,
        }
    }

    /// Rotor speed at which the rotors carry the weight in still air, rad/s.
    pub fn hover_omega(&self) -> f64 {
        (self.mass * GRAVITY / (self.hubs.len() as f64 * self.rotor.k_t)).sqrt()
    }

    /// Force (N) and moment about the CG (N m), body axes, gravity excluded, in the
    /// data contract's order.
    pub fn wrench(&self, s: &LoadState) -> [f64; 6] {
        let c = &self.rotor;
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        for (i, hub) in self.hubs.iter().enumerate() {
            let omega = s.omega[i].max(1.0);
            let sigma = self.spins[i];
            let tip = omega * self.radius;
            let v_hub = s.velocity + s.rates.cross(hub);
            let in_plane = Vector3::new(v_hub.x, v_hub.y, 0.0);
            let speed = in_plane.norm();
            let lambda = -v_hub.z / tip;
            let mu = speed / tip;
            let w2 = omega * omega;
            let mut thrust = c.k_t
                * w2
                * (1.0 - c.climb * lambda - c.climb_curvature * lambda * lambda.abs()
                    + c.edgewise * mu * mu);
            let mut torque =
                c.k_q * w2 * (1.0 - c.torque_climb * lambda + c.torque_edgewise * mu * mu);
            let (t_scale, q_scale) = self.hidden_rotor_scales(i, s, omega);
            thrust *= t_scale;
            torque *= q_scale;
            let h_force = -(c.k_h * omega + c.k_h2 * speed) * in_plane;
            let f = Vector3::new(h_force.x, h_force.y, -thrust);
            force += f;
            moment += hub.cross(&f);
            moment += c.k_r * sigma * omega * in_plane;
            moment.z -= sigma * torque;
            let j = self.rotor_inertia * sigma;
            moment -= j * Vector3::new(s.rates.y * omega, -s.rates.x * omega, s.omega_dot[i]);
        }
        if let Some(Hidden::QuadraticDrag { area, centre }) = self.hidden {
            let v = s.velocity;
            let drag = -0.5 * self.rho * v.norm() * v.component_mul(&Vector3::from(area));
            force += drag;
            moment += Vector3::from(centre).cross(&drag);
        }
        [force.x, force.y, force.z, moment.x, moment.y, moment.z]
    }

    /// Thrust and torque factors of rotor `i` from the hidden effect.
    fn hidden_rotor_scales(&self, i: usize, s: &LoadState, omega: f64) -> (f64, f64) {
        match self.hidden {
            Some(Hidden::RearWake { loss }) if self.nominal_hubs[i].x < 0.0 => {
                let mu_forward = s.velocity.x.max(0.0) / (omega * self.radius);
                (1.0 - loss * mu_forward, 1.0)
            }
            Some(Hidden::WeakRotor {
                rotor,
                thrust,
                torque,
            }) if rotor == i + 1 => (thrust, torque),
            Some(Hidden::GroundEffect { gain, decay }) => {
                let hub_ned = s.attitude * self.hubs[i];
                let z = (s.height - hub_ned.z).max(0.01);
                let diameter = 2.0 * self.radius;
                (1.0 + gain * (-z / (decay * diameter)).exp(), 1.0)
            }
            _ => (1.0, 1.0),
        }
    }
}
