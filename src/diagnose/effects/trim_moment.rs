//! The trim moment: a slow moment the model lacks, held by the attitude controller.
//!
//! A flying multirotor's attitude loop balances any slow moment on the airframe (a
//! fuselage or payload moment, a CG that shifts in flight) with differential rotor
//! thrust and torque. Below the loop's bandwidth the rotor signals then carry that trim,
//! while the logged moment (the airframe's angular acceleration) carries almost nothing:
//! M ≈ 0 where the model sees M̂ = the slow control moment. The candidate takes the slow
//! part of the modelled control moment of each axis back out,
//!
//!   ΔM_x = −k_x c_T δ²a_slow,  ΔM_y = −k_y c_T δ²e_slow,  ΔM_z = −k_z c_Q δ²r_slow,
//!
//! with δ²_slow the zero-phase low-pass of δ² = M_ix Ω² (Eq. 19–20) at one cut-off of
//! [`crate::TRIM_BANDS_HZ`] (filled by `crate::slow`), c_T the thrust per Ω² that carries the
//! weight on average ([`super::hover_thrust_coefficient`]: the scale is the vehicle's,
//! not the base fit's) and c_Q = ρπR⁵ Ĉ_Q0 the base fit's drag-torque coefficient (no
//! yaw part when Ĉ_Q0 ≤ 0): k = 1 is a slow control moment wholly balancing a moment
//! the model lacks, k = 0 none. Each cut-off is one form; the data
//! choose one. The low-pass is centred on each sample: it is the trim around it, not a
//! response to rotor speeds later than the load (the fast band keeps the Eq. 22 gains).
//! Only for time series (flights): a sweep's points have no slow part of their own.

use super::context::{CandidateContext, column};
use crate::TRIM_BANDS_HZ;
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "Below the attitude loop's bandwidth the rotor commands hold the trim against a slow moment the model lacks (a fuselage or payload moment, a shifting CG), so that band of the control moment produces no angular acceleration: M loses k times the slow part of the modelled control moment.";

/// One form per cut-off; none without the slow rotor thrusts of a time series.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    let Some(thrust) = ctx.hover_thrust_coefficient.filter(|_| ctx.has_slow_thrust) else {
        return Vec::new();
    };
    let torque = ctx.k() * ctx.theta("C_Q0") * ctx.vehicle.props.rotor_radius.powi(3);
    TRIM_BANDS_HZ
        .iter()
        .enumerate()
        .map(|(band, hz)| {
            let slow = |row: u8| Signal::SlowSquaredActuator(band as u8, row);
            // A fraction of the slow control moment, never negative (that would add slow
            // moment, not trim it away): for roll and pitch plausible up to a little more
            // than all of it (a real vehicle's moment coefficients differ from the weight's
            // c_T by tens of percent); for yaw without an upper bound, as c_Q is the base
            // fit's, which a yaw axis its model hardly explains shrinks.
            let axis = |axis: Axis, name: &str, label: &str, coef: f64, row: u8, hi: f64| {
                let columns = vec![column(axis, label, vec![term(-coef, &[slow(row)])])];
                CandidateParameter::new(name, "-", columns).within(0.0, hi)
            };
            let mut parameters = vec![
                axis(Axis::Mx, "trim_roll", "-cT*da2_slow", thrust, 1, 2.0),
                axis(Axis::My, "trim_pitch", "-cT*de2_slow", thrust, 2, 2.0),
            ];
            if torque > 0.0 {
                let unbounded = f64::INFINITY;
                parameters.push(axis(
                    Axis::Mz,
                    "trim_yaw",
                    "-cQ*dr2_slow",
                    torque,
                    3,
                    unbounded,
                ));
            }
            Candidate::new(
                Kind::TrimMoment,
                Role::Mechanism,
                format!("trim moment, {hz} Hz"),
                PHYSICS,
                parameters,
            )
            .form_of(Kind::TrimMoment)
        })
        .collect()
}
