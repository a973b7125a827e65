//! Rotor loads transmitted to the airframe and summed (seed §4.1–4.2, Eq. 10–18).
//!
//! This is the per-rotor reference the Eq. 22 regressors are proven against: every rotor
//! is evaluated on its own at its local hub velocity (Eq. 18, Assumption 4), its force
//! (Eq. 13) and moment (Eq. 11–12) are carried to the CG and summed (Eq. 14–16). No
//! virtual actuator or lumped parameter is used here.
//!
//! One sign differs from the seed: the hub rolling and pitching moments enter as
//! σ(ℛ, −𝒫) where Eq. 11 prints σ(−ℛ, 𝒫). For σ = +1 (clockwise seen from above) in
//! forward flight the advancing blade is on the left, so its extra lift rolls the
//! vehicle right (M_x > 0), while Eq. 11 with Eq. 5d gives M_x < 0. The crate's
//! blade-element simulator confirms the corrected sign (`tests/sim_rotor.rs`).

use crate::rotor::BladeConstants;
use crate::util::cross;
use crate::vehicle::Vehicle;

/// Airframe force (N) and moment (N m) in body axes, `[F_x, F_y, F_z, M_x, M_y, M_z]`,
/// from the closed-form rotor model with blade constants `blade`, for body velocity
/// `velocity` (m/s), body rates `rates` (rad/s), rotor speeds `omega` (rad/s) and rotor
/// accelerations `omega_dot` (rad/s²).
///
/// Local hub velocity per Eq. 18 (yaw rate and hub height neglected, Assumption 4);
/// ν0 from [`Vehicle::hover_induced_velocity`]; gyroscopic and motor-torque terms of
/// Eq. 16 with J_z = `vehicle.props.rotor_inertia`.
pub fn closed_form_wrench(
    vehicle: &Vehicle,
    blade: &BladeConstants,
    velocity: [f64; 3],
    rates: [f64; 3],
    omega: &[f64],
    omega_dot: &[f64],
) -> [f64; 6] {
    let props = &vehicle.props;
    let nu0 = vehicle.hover_induced_velocity();
    let [u, v, w] = velocity;
    let [p, q, _r] = rates;
    let mut wrench = [0.0; 6];
    for (i, rotor) in vehicle.rotors().iter().enumerate() {
        let v_hub = [u, v, w + p * rotor.y - q * rotor.x];
        let l = blade.loads(props.air_density, props.rotor_radius, omega[i], v_hub, nu0);
        let force = [-l.hub_force, l.side_force, -l.thrust];
        let s = rotor.spin;
        // Eq. 11 prints σ(−ℛ, 𝒫, −𝒬); the hub rolling and pitching moments take the
        // opposite sign (see the `rotor` module docs), so σ(ℛ, −𝒫, −𝒬).
        let rotor_moment = [s * l.rolling_moment, -s * l.pitching_moment, -s * l.torque];
        let arm = cross(vehicle.hub_position(i), force);
        let jz = props.rotor_inertia;
        let motor = [
            -s * jz * q * omega[i],
            s * jz * p * omega[i],
            -s * jz * omega_dot[i],
        ];
        for k in 0..3 {
            wrench[k] += force[k];
            wrench[3 + k] += rotor_moment[k] + arm[k] + motor[k];
        }
    }
    wrench
}
