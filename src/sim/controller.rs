//! Cascaded flight controller: position PD with acceleration feed-forward → thrust vector
//! and attitude (Lee et al. geometric form) → body-rate loop → moments → rotor speeds by
//! pseudo-inverse allocation of the hover-linearised rotor map T_i = k_T Ω_i²,
//! Q_i = k_Q Ω_i². It sees the true state (the flight log's sensors are separate); its
//! job is to keep the vehicle on an aggressive reference, not to be identified.

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, Vector3};

use crate::vehicle::{STANDARD_GRAVITY, Vehicle};

/// Gains in SI units; positions scale with the Froude time scale of the vehicle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gains {
    /// Position stiffness, 1/s².
    pub position: f64,
    /// Velocity damping, 1/s.
    pub velocity: f64,
    /// Roll/pitch attitude stiffness, 1/s².
    pub attitude: f64,
    /// Roll/pitch rate damping, 1/s.
    pub rate: f64,
    /// Yaw attitude stiffness, 1/s².
    pub yaw: f64,
    /// Yaw rate damping, 1/s.
    pub yaw_rate: f64,
    /// Largest commanded tilt of the thrust vector, rad.
    pub max_tilt: f64,
}

impl Gains {
    /// Gains for a vehicle whose Froude time scale is `time_scale` (√(ℓ/ℓ_ref)): attitude
    /// loop ω_n = 10 rad/s, ζ = 0.9 (below the motor bandwidth 1/τ_m ≈ 33 rad/s); position
    /// loop ω_n = 2.5/time_scale rad/s, ζ = 1.
    pub fn for_time_scale(time_scale: f64) -> Self {
        let wp = 2.5 / time_scale;
        Self {
            position: wp * wp,
            velocity: 2.0 * wp,
            attitude: 100.0,
            rate: 18.0,
            yaw: 25.0,
            yaw_rate: 10.0,
            max_tilt: 1.0,
        }
    }
}

/// The reference the controller tracks at one instant (NED).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reference {
    /// Position, m.
    pub position: Vector3<f64>,
    /// Velocity, m/s.
    pub velocity: Vector3<f64>,
    /// Acceleration, m/s².
    pub acceleration: Vector3<f64>,
    /// Heading ψ, rad.
    pub yaw: f64,
    /// Heading rate, rad/s.
    pub yaw_rate: f64,
    /// Roll and pitch excitation added to the attitude command, rad.
    pub excitation: [f64; 2],
}

/// The controller with its allocation matrix.
#[derive(Debug, Clone)]
pub struct Controller {
    gains: Gains,
    mass: f64,
    inertia: Matrix3<f64>,
    /// Pseudo-inverse of the allocation map [T, Mx, My, Mz] = A Ω² (N × 4).
    allocation_pinv: DMatrix<f64>,
    omega_min: f64,
    omega_max: f64,
}

impl Controller {
    /// Controller for `vehicle` with hover speed `hover_omega` (rad/s), hover rotor torque
    /// `hover_torque` (N m), and rotor-speed limits 0.3 and 1.7 × hover.
    pub fn new(vehicle: &Vehicle, hover_omega: f64, hover_torque: f64, gains: Gains) -> Self {
        let n = vehicle.rotor_count();
        let w2 = hover_omega * hover_omega;
        let k_t = vehicle.props.mass * STANDARD_GRAVITY / (n as f64 * w2);
        let k_q = hover_torque / w2;
        let a = DMatrix::from_fn(4, n, |row, i| {
            let r = vehicle.rotors()[i];
            match row {
                0 => k_t,
                1 => -r.y * k_t,
                2 => r.x * k_t,
                _ => -r.spin * k_q,
            }
        });
        let allocation_pinv = a
            .pseudo_inverse(1e-12)
            .unwrap_or_else(|_| DMatrix::zeros(n, 4));
        Self {
            gains,
            mass: vehicle.props.mass,
            inertia: Matrix3::from_fn(|r, c| vehicle.props.inertia[r][c]),
            allocation_pinv,
            omega_min: 0.3 * hover_omega,
            omega_max: 1.7 * hover_omega,
        }
    }

    /// Rotor-speed commands (rad/s) for the state: NED position `pos` (m), NED velocity
    /// `vel` (m/s), attitude `att` (body → NED), body rates `rates` (rad/s).
    pub fn command(
        &self,
        reference: &Reference,
        pos: &Vector3<f64>,
        vel: &Vector3<f64>,
        att: &Rotation3<f64>,
        rates: &Vector3<f64>,
        out: &mut [f64],
    ) {
        let g = &self.gains;
        let e3 = Vector3::z();
        let acc = reference.acceleration
            + g.position * (reference.position - pos)
            + g.velocity * (reference.velocity - vel);
        // Force the rotors must supply (NED): m (a − g e3).
        let mut f = self.mass * (acc - STANDARD_GRAVITY * e3);
        // Limit the tilt of the thrust vector from vertical.
        let up = -f.z.min(-0.2 * self.mass * STANDARD_GRAVITY);
        let horizontal = Vector3::new(f.x, f.y, 0.0);
        let limit = up * g.max_tilt.tan();
        let h = horizontal.norm();
        let horizontal = if h > limit {
            horizontal * (limit / h)
        } else {
            horizontal
        };
        f = horizontal - up * e3;
        let b3 = -f.normalize();
        let heading = Vector3::new(reference.yaw.cos(), reference.yaw.sin(), 0.0);
        let b2 = b3.cross(&heading).normalize();
        let b1 = b2.cross(&b3);
        let desired = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[b1, b2, b3]))
            * Rotation3::from_euler_angles(reference.excitation[0], reference.excitation[1], 0.0);
        let r = att.matrix();
        let rd = desired.matrix();
        let e = 0.5 * (rd.transpose() * r - r.transpose() * rd);
        let e_r = Vector3::new(e[(2, 1)], e[(0, 2)], e[(1, 0)]);
        let rate_ff = Vector3::new(0.0, 0.0, reference.yaw_rate);
        let de = rates - rate_ff;
        let alpha = Vector3::new(
            -g.attitude * e_r.x - g.rate * de.x,
            -g.attitude * e_r.y - g.rate * de.y,
            -g.yaw * e_r.z - g.yaw_rate * de.z,
        );
        let moment = self.inertia * alpha + rates.cross(&(self.inertia * rates));
        let thrust = -f.dot(&(r * e3));
        let demand = DVector::from_column_slice(&[thrust, moment.x, moment.y, moment.z]);
        let w2 = &self.allocation_pinv * demand;
        for (o, w) in out.iter_mut().zip(w2.iter()) {
            *o = w
                .max(self.omega_min * self.omega_min)
                .min(self.omega_max * self.omega_max)
                .sqrt();
        }
    }
}
