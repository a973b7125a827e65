//! Quadratic airframe drag: pressure drag beyond the linear drag Eq. 22 lumps into the
//! rotors, in two forms the data choose between: −ρ/2 C_d A v_k|v_k| per body axis (each
//! axis's own flow, as on a box-shaped body), or −ρ/2 C_d A v_k |V| (the drag along the
//! airflow, its magnitude from the whole airspeed, as on a blunt body in oblique flow).

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{Candidate, CandidateParameter, EffectKind as Kind, Role};
use crate::model::{Signal, term};
use crate::sample::Axis;

const PHYSICS: &str = "The airframe's pressure drag grows with the square of airspeed, -rho/2 CdA v|v| per axis, beyond the linear drag Eq. 22 lumps into the rotors.";

/// One drag area C_d A (m²) per axis, in each form.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    use Signal::*;
    let half_rho = 0.5 * ctx.vehicle.props.air_density;
    // Plausible from 0 to 2 m².
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
        .within(0.0, 2.0)
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
    ]
}

const PHYSICS_ALONG: &str = "The airframe's pressure drag acts along the airflow and grows with the square of airspeed, -rho/2 CdA v|V| per axis, beyond the linear drag Eq. 22 lumps into the rotors.";

fn s_name(s: Signal) -> &'static str {
    match s {
        Signal::U => "u",
        Signal::V => "v",
        _ => "w",
    }
}
