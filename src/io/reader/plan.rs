//! What the reader derives and how much look-ahead it needs: the vehicle facts it uses,
//! the plan of each output signal, and the summary's words for it.

use super::super::derive::DeriveOptions;
use super::super::mapping::{ActuatorMap, Signal};
use super::super::slots::SlotLayout;
use super::super::validate::SPIKE_HALF_WINDOW;
use crate::vehicle::Vehicle;

/// What the reader differentiates when the log lacks it, and from what: the start of
/// its [`super::super::Summary::derived`] entry ("<what> from <source> by …").
pub(crate) const DIFFERENTIATED: [(&str, &str); 2] = [
    ("angular acceleration", "body rates"),
    ("rotor accelerations", "rotor speeds"),
];

/// Vehicle facts used by derivations and checks.
#[derive(Debug, Clone)]
pub(super) struct VehicleFacts {
    pub rotors: usize,
    pub mass: f64,
    pub inertia: [[f64; 3]; 3],
    pub rotor_inertia: f64,
    pub arm: f64,
    pub rotor_radius: f64,
    pub air_density: f64,
}

impl VehicleFacts {
    pub fn of(vehicle: &Vehicle) -> Self {
        Self {
            rotors: vehicle.rotor_count(),
            mass: vehicle.props.mass,
            inertia: vehicle.props.inertia,
            rotor_inertia: vehicle.props.rotor_inertia,
            arm: vehicle.arm_length(),
            rotor_radius: vehicle.props.rotor_radius,
            air_density: vehicle.props.air_density,
        }
    }
}

/// How each output signal is obtained.
#[derive(Debug, Clone, Copy)]
pub(super) struct Plan {
    /// ω̇ from a smoothing derivative of the rates (no logged ω̇ and needed).
    pub diff_rates: bool,
    /// Ω̇ from a smoothing derivative of Ω (not logged, J_z > 0).
    pub diff_omega: bool,
    /// Ω̇ emitted at all.
    pub has_omega_dot: bool,
    /// Look-ahead needed before a sample can be emitted.
    pub lookahead: usize,
}

impl Plan {
    /// The plan for a log of `layout` read with `derive` for a vehicle of `facts`.
    pub fn new(layout: &SlotLayout, derive: &DeriveOptions, facts: &VehicleFacts) -> Self {
        let needs_ang_acc = !layout.has(Signal::Moment) || derive.imu_lever_arm.is_some();
        let diff_rates = needs_ang_acc && !layout.has(Signal::AngularAcceleration);
        let diff_omega = !layout.has(Signal::RotorAccelerations) && facts.rotor_inertia > 0.0;
        let half = derive.sg_window / 2;
        Self {
            diff_rates,
            diff_omega,
            has_omega_dot: layout.has(Signal::RotorAccelerations) || diff_omega,
            lookahead: if diff_rates || diff_omega {
                half.max(SPIKE_HALF_WINDOW)
            } else {
                SPIKE_HALF_WINDOW
            },
        }
    }

    /// Which signals are derived and how, in words for [`super::super::Summary::derived`].
    pub fn describe(
        &self,
        layout: &SlotLayout,
        derive: &DeriveOptions,
        actuator: Option<&ActuatorMap>,
    ) -> Vec<String> {
        let mut derived = Vec::new();
        let sg = format!(
            "Savitzky-Golay derivative (window {}, order {})",
            derive.sg_window, derive.sg_order
        );
        for ((what, source), done) in DIFFERENTIATED
            .iter()
            .zip([self.diff_rates, self.diff_omega])
        {
            if done {
                derived.push(format!("{what} from {source} by {sg}"));
            }
        }
        if !layout.has(Signal::Moment) {
            derived.push("moment M = I w_dot + w x I w".into());
        }
        if !layout.has(Signal::Force) {
            derived.push(match derive.imu_lever_arm {
                Some(r) => {
                    format!("force F = m a, accelerometer carried to the CG from lever arm {r:?} m")
                }
                None => "force F = m a from the accelerometer".into(),
            });
        }
        if let Some(a) = actuator {
            derived.push(a.describe());
        }
        if !layout.has(Signal::VelocityBody) {
            derived.push("body velocity from world velocity and attitude".into());
        }
        derived
    }
}
