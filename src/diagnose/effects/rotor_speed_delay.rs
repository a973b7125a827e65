//! The family of loads leading the logged rotor speeds, in two forms that agree to first
//! order where Ω varies little, one of which enters a model:
//!
//! - the rotor-speed delay: loads follow Ω(t + τ) while the log holds Ω(t), so
//!   ΔF ≈ τ dF/dΩ Ω̇ (yaw torque and the gyroscopic moments included);
//! - thrust from rotor acceleration: ΔT_i = c Ω̇_i (the induced flow lags a change of
//!   rotor speed, or the logged speed lags the true one through a first-order filter), so
//!   F_z = −c Σ Ω̇_i, M_x = −c Σ y_i Ω̇_i, M_y = c Σ x_i Ω̇_i.
//!
//! Each physics text names the other's mechanism. Both need the rotor accelerations in
//! the log.

use super::context::{CandidateContext, THRUST_LOADS, column, rotor_signals};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{RotorInertiaTerms, Signal, Term, term};
use crate::sample::Axis;

/// The delay form; none without rotor accelerations.
pub(super) fn delay(ctx: &CandidateContext) -> Vec<Candidate> {
    if !ctx.has_omega_dot {
        return Vec::new();
    }
    let n = ctx.vehicle.rotor_count();
    let rotors = ctx.vehicle.rotors();
    let thrust = |scale: &dyn Fn(usize) -> f64| -> Vec<Term> {
        (0..n)
            .flat_map(|i| ctx.rotor_thrust(i, &[], scale(i), true))
            .collect()
    };
    let torque: Vec<Term> = (0..n)
        .flat_map(|i| ctx.rotor_torque(i, -rotors[i].spin, true))
        .collect();
    // The gyroscopic moments J_z (q δr, −p δr) follow the true speeds too.
    let jz = match ctx.structure.options.rotor_inertia {
        RotorInertiaTerms::Known => ctx.vehicle.props.rotor_inertia,
        _ => 0.0,
    };
    let mut roll = thrust(&|i| -rotors[i].y);
    let mut pitch = thrust(&|i| rotors[i].x);
    let mut yaw = torque;
    if jz != 0.0 {
        roll.push(term(jz, &[Signal::Q, Signal::DrDot]));
        pitch.push(term(-jz, &[Signal::P, Signal::DrDot]));
        // The reaction torque J_z δ̇r leads the log too; with a motor time constant of
        // tens of ms its rate J_z δ̈r is most of the delay's yaw moment.
        if ctx.has_omega_ddot {
            yaw.push(term(jz, &[Signal::DrDDot]));
        }
    }
    let yaw_label = if ctx.has_omega_ddot && jz != 0.0 {
        "-Sum s_i dQ_i/dt + Jz dr_ddot"
    } else {
        "-Sum s_i dQ_i/dt"
    };
    let columns = vec![
        column(Axis::Fz, "-Sum dT_i/dt", thrust(&|_| -1.0)),
        column(Axis::Mx, "-Sum y_i dT_i/dt + Jz q dr_dot", roll),
        column(Axis::My, "Sum x_i dT_i/dt - Jz p dr_dot", pitch),
        column(Axis::Mz, yaw_label, yaw),
    ];
    let columns = columns
        .into_iter()
        .filter(|c| !c.terms.is_empty())
        .collect();
    // Plausible within ±50 ms. Positive: the logged speed lags the true one (ESC
    // telemetry latency and filtering: milliseconds to a few tens of them). Negative:
    // the loads lag the rotors (the induced flow building up). Beyond 50 ms a "delay"
    // is no sensor: loads would follow rotor speeds logged that much later, which the
    // attitude controller makes from the loads' own motion (it drives the rotors from
    // the measured rates), so the form would predict through the feedback loop, not
    // through physics.
    let tau = CandidateParameter::new("rotor_speed_delay", "s", columns).within(-0.05, 0.05);
    vec![
        Candidate::new(
            Kind::RotorSpeedDelay,
            Role::Mechanism,
            "rotor-speed delay",
            "When logged rotor speeds lag the true ones by tau (a pure delay, or a first-order filter of time constant tau: the two agree to first order in tau), the loads lead the log: dF = tau dF/dOmega dOmega/dt.",
            vec![tau],
        )
        .form_of(Kind::RotorSpeedDelay),
    ]
}

/// The rotor-acceleration form; none without rotor accelerations.
pub(super) fn acceleration_thrust(ctx: &CandidateContext) -> Vec<Candidate> {
    if !ctx.has_omega_dot {
        return Vec::new();
    }
    let n = ctx.vehicle.rotor_count();
    let rotors = ctx.vehicle.rotors();
    let axis_terms = |weight: &dyn Fn(usize) -> f64| -> Vec<Term> {
        (0..n)
            .filter(|&i| weight(i) != 0.0)
            .map(|i| term(weight(i), &[rotor_signals(i).2]))
            .collect()
    };
    let columns = THRUST_LOADS
        .iter()
        .map(|&(axis, lever, label)| {
            column(
                axis,
                &format!("{label}dOmega_i"),
                axis_terms(&|i| lever(&rotors[i])),
            )
        })
        .collect();
    vec![
        Candidate::new(
            Kind::RotorAccelerationThrust,
            Role::Mechanism,
            "thrust from rotor acceleration",
            "When a rotor speeds up, its thrust changes in proportion to the rotor acceleration as well as the speed: the induced flow takes time to build (dynamic inflow), or the logged speed lags the true one through a filter.",
            vec![CandidateParameter::new(
                "thrust_per_rotor_acceleration",
                "N s^2/rad",
                columns,
            )],
        )
        .form_of(Kind::RotorSpeedDelay),
    ]
}
