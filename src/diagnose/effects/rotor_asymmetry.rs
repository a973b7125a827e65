//! Rotor asymmetry: one rotor's thrust, in-plane force and torque each a fraction off
//! the others' at the same logged speed (a damaged propeller, a tired motor). One
//! candidate per rotor; a finding states it as "rotor 3 weaker by 9.8 %".

use super::context::{CandidateContext, column};
use crate::diagnose::candidate::{
    Candidate, CandidateParameter, EffectKind as Kind, Role, Statement,
};
use crate::model::Column;
use crate::sample::Axis;

const PHYSICS: &str = "A damaged propeller or tired motor makes one rotor's thrust, in-plane force and torque fractions off the others' at the same logged speed.";

/// One candidate per rotor.
pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate> {
    (0..ctx.vehicle.rotor_count())
        .map(|i| weak_rotor(ctx, i))
        .collect()
}

/// A fraction of the rotor's thrust, in-plane force or torque, plausible within ±60 %.
fn scale(name: String, columns: Vec<Column>) -> CandidateParameter {
    CandidateParameter::new(name, "-", columns)
        .within(-0.6, 0.6)
        .fraction()
}

fn weak_rotor(ctx: &CandidateContext, i: usize) -> Candidate {
    let rotor = ctx.vehicle.rotors()[i];
    let torque = ctx.rotor_torque(i, -rotor.spin, false);
    // Thrust, in-plane force and torque, each by its own fraction (a damaged blade
    // changes its lift and its drag differently); the in-plane force F_i acts with the
    // moments r_i × F_i of its hub at r_i = (x_i, y_i, −h).
    let h = ctx.vehicle.props.hub_height;
    let thrust = ctx.thrust_change(&format!("T_{}", i + 1), &[i], |_| Vec::new(), 1.0);
    let in_plane = |scale_x: f64, scale_y: f64| {
        let mut t = ctx.rotor_in_plane_force(i, true, scale_x);
        t.extend(ctx.rotor_in_plane_force(i, false, scale_y));
        t
    };
    let label = format!("H_{}", i + 1);
    let in_plane: Vec<Column> = [
        (Axis::Fx, in_plane(1.0, 0.0)),
        (Axis::Fy, in_plane(0.0, 1.0)),
        (Axis::Mx, in_plane(0.0, h)),
        (Axis::My, in_plane(-h, 0.0)),
        (Axis::Mz, in_plane(-rotor.y, rotor.x)),
    ]
    .into_iter()
    .filter(|(_, terms)| !terms.is_empty())
    .map(|(axis, terms)| column(axis, &label, terms))
    .collect();
    // The thrust fraction first: the finding states it.
    let mut parameters = vec![scale(format!("thrust_scale_{}", i + 1), thrust)];
    if !in_plane.is_empty() {
        parameters.push(scale(format!("in_plane_scale_{}", i + 1), in_plane));
    }
    if !torque.is_empty() {
        parameters.push(scale(
            format!("torque_scale_{}", i + 1),
            vec![column(Axis::Mz, &format!("-s{0}*Q_{0}", i + 1), torque)],
        ));
    }
    let name = format!("weak rotor {}", i + 1);
    Candidate::new(
        Kind::RotorAsymmetry,
        Role::Mechanism,
        name,
        PHYSICS,
        parameters,
    )
    .stated_as(Statement::Change {
        parameter: 0,
        less: format!("rotor {} weaker", i + 1),
        more: format!("rotor {} stronger", i + 1),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{ModelOptions, ModelStructure};
    use crate::vehicle::Vehicle;

    #[test]
    fn a_weak_rotor_is_stated_by_its_number_direction_and_thrust_fraction() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let v = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).unwrap();
        let base = ModelStructure::eq22(&v, ModelOptions::default());
        let theta = vec![1e-6; base.params.len()];
        let force_theta = vec![1e-6; base.columns.len()];
        let ctx = CandidateContext {
            vehicle: &v,
            structure: &base,
            theta: &theta,
            force_theta: &force_theta,
            has_height: false,
            has_omega_dot: false,
            has_omega_ddot: false,
            has_attitude: false,
            has_slow_thrust: false,
            hover_thrust_coefficient: None,
        };
        let third = &candidates(&ctx)[2];
        assert_eq!(third.parameters[0].name, "thrust_scale_3");
        // The thrust fraction is stated; the others do not change the sentence.
        assert_eq!(
            third.describe(&[-0.098, 0.3, 0.3]),
            "rotor 3 weaker by 9.8 %"
        );
        assert_eq!(
            third.describe(&[0.102, -0.3, 0.0]),
            "rotor 3 stronger by 10.2 %"
        );
    }
}
