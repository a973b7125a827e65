//! Quadratic airframe drag: pressure drag beyond the linear drag Eq. 22 lumps into the
//! rotors, in three forms the data choose between: −ρ/2 C_d A v_k|v_k| per body axis
//! (each axis's own flow, as on a box-shaped body), −ρ/2 C_d A v_k |V| (the drag along
//! the airflow, its magnitude from the whole airspeed, as on a blunt body in oblique
//! flow), or that drag acting at a centre of pressure above or below the CG, which also
//! rolls and pitches the vehicle.

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{
    Candidate, CandidateParameter, EffectKind as Kind, Role, Statement,
};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "The airframe's pressure drag grows with the square of airspeed, -rho/2 CdA v|v| per axis, beyond the linear drag Eq. 22 lumps into the rotors.";

/// One drag area C_d A (m²) per axis, in each form.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let half_rho = 0.5 * ctx.vehicle.props.air_density;
    // Plausible from 0 to AREA_MAX.
    let axis = |axis, s, magnitude: Signal, label: &str| {
        let shown = match magnitude {
            Airspeed => "|V|".to_string(),
            _ => format!("|{}|", s_name(s)),
        };
        CandidateParameter::new(
            label,
            "m^2",
            vec![column(
                axis,
                &format!("-rho/2*{}{shown}", s_name(s)),
                vec![term(-half_rho, &[s, magnitude])],
            )],
        )
        .within(0.0, AREA_MAX)
    };
    let per_axis = vec![
        axis(Axis::Fx, U, AbsU, "drag_area_x"),
        axis(Axis::Fy, V, AbsV, "drag_area_y"),
        axis(Axis::Fz, W, AbsW, "drag_area_z"),
    ];
    let along_flow = vec![
        axis(Axis::Fx, U, Airspeed, "drag_area_x"),
        axis(Axis::Fy, V, Airspeed, "drag_area_y"),
        axis(Axis::Fz, W, Airspeed, "drag_area_z"),
    ];
    // The along-the-airflow drag acting at a centre of pressure z_cp below the CG (body
    // z): its moment r × F is M_x = −z_cp F_y = z_cp A_y ρ/2 v|V| and
    // M_y = z_cp F_x = −z_cp A_x ρ/2 u|V|, linear in the moment areas z_cp A (m³).
    let moment = |axis, s, sign: f64, label: &str| {
        CandidateParameter::new(
            label,
            "m^3",
            vec![column(
                axis,
                &format!(
                    "{}rho/2*{}|V|",
                    if sign < 0.0 { "-" } else { "" },
                    s_name(s)
                ),
                vec![term(sign * half_rho, &[s, Airspeed])],
            )],
        )
        .within(
            -CENTRE_OF_PRESSURE_MAX * AREA_MAX,
            CENTRE_OF_PRESSURE_MAX * AREA_MAX,
        )
    };
    let mut off_centre = along_flow.clone();
    off_centre.push(moment(Axis::Mx, V, 1.0, "drag_moment_area_x"));
    off_centre.push(moment(Axis::My, U, -1.0, "drag_moment_area_y"));
    vec![
        Candidate::new(
            Kind::QuadraticDrag,
            Role::Mechanism,
            "quadratic airframe drag",
            PHYSICS,
            per_axis,
        )
        .form_of(Kind::QuadraticDrag),
        Candidate::new(
            Kind::QuadraticDrag,
            Role::Mechanism,
            "quadratic airframe drag, along the airflow",
            PHYSICS_ALONG,
            along_flow,
        )
        .form_of(Kind::QuadraticDrag),
        Candidate::new(
            Kind::QuadraticDrag,
            Role::Mechanism,
            "quadratic airframe drag, off the CG",
            PHYSICS_OFF_CENTRE,
            off_centre,
        )
        .form_of(Kind::QuadraticDrag)
        .stated_as(Statement::CentreOfPressure {
            areas: [1, 0],
            moments: [3, 4],
            max: CENTRE_OF_PRESSURE_MAX,
        }),
    ]
}

/// Largest plausible drag area C_d A, m².
const AREA_MAX: f64 = 2.0;

/// Largest plausible distance of the drag's centre of pressure from the CG, m (with
/// [`AREA_MAX`] it bounds the moment areas).
const CENTRE_OF_PRESSURE_MAX: f64 = 0.5;

const PHYSICS_OFF_CENTRE: &str = "The airframe's pressure drag acts along the airflow, -rho/2 CdA v|V| per axis, at a centre of pressure above or below the CG, so it also rolls and pitches the vehicle (moment areas z_cp CdA).";

const PHYSICS_ALONG: &str = "The airframe's pressure drag acts along the airflow and grows with the square of airspeed, -rho/2 CdA v|V| per axis, beyond the linear drag Eq. 22 lumps into the rotors.";

fn s_name(s: Signal) -> &'static str {
    match s {
        Signal::U => "u",
        Signal::V => "v",
        _ => "w",
    }
}
