//! The candidate-effect library: named physical hypotheses that the Eq. 22 model lacks.
//!
//! Each effect (or family of forms of one effect) lives in a file of its own and builds
//! its [`Candidate`]s from the [`CandidateContext`]: the regressor columns it adds, its
//! parameters with unit, plausible range and reading, its sentence of physics, its role
//! in the search (mechanism, completion of Eq. 22, unspecific), the family of forms it
//! belongs to, where it acts and how a finding states it. An effect that does not apply
//! to the vehicle, model or data (no height logged for the ground effect) builds none.
//!
//! To add an effect: write its file here with a
//! `pub(super) fn candidates(ctx: &CandidateContext) -> Vec<Candidate>`, name a new
//! [`super::EffectKind`] for it, and add one line to the list `LIBRARY` below. Nothing
//! else in the diagnosis knows effects by name.

mod accelerometer_bias;
mod cg_height;
mod cg_offset;
mod context;
mod decoupled_moments;
mod ground_effect;
mod linear_vh;
mod quadratic_drag;
mod roll_pitch_rate_drag;
mod rotor_asymmetry;
mod rotor_flapping;
mod rotor_rate_damping;
mod rotor_speed_delay;
mod second_order_inflow;
mod steady_wind;
mod trim_moment;
mod vertical_drag;
mod vortex_ring;
mod wake_interaction;
mod yaw_rate_drag;
mod yaw_rate_hub_airspeed;

pub use context::{CandidateContext, hover_thrust_coefficient};

use super::candidate::Candidate;

/// Builds an effect's candidates (none when it does not apply).
type Effect = fn(&CandidateContext) -> Vec<Candidate>;

/// Every effect of the library, in the order its candidates are offered (the order
/// breaks ties in the search).
const LIBRARY: [Effect; 21] = [
    ground_effect::candidates,
    rotor_asymmetry::candidates,
    cg_offset::candidates,
    cg_height::candidates,
    wake_interaction::candidates,
    quadratic_drag::candidates,
    vortex_ring::candidates,
    linear_vh::candidates,
    rotor_speed_delay::delay,
    steady_wind::candidates,
    yaw_rate_drag::candidates,
    yaw_rate_hub_airspeed::candidates,
    roll_pitch_rate_drag::candidates,
    decoupled_moments::candidates,
    rotor_flapping::candidates,
    rotor_rate_damping::candidates,
    second_order_inflow::candidates,
    vertical_drag::candidates,
    rotor_speed_delay::acceleration_thrust,
    accelerometer_bias::candidates,
    trim_moment::candidates,
];

/// Every candidate that applies to this vehicle, model and data.
pub fn library(ctx: &CandidateContext) -> Vec<Candidate> {
    LIBRARY.iter().flat_map(|effect| effect(ctx)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::{EffectKind, Reading, Role};
    use crate::model::{ModelOptions, ModelStructure};
    use crate::vehicle::Vehicle;

    /// The whole library for the shipped quadrotor× (hubs above the CG) with every signal
    /// logged and a model without the terms linear in V_h: every effect applies.
    fn full_library() -> Vec<Candidate> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let v = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).unwrap();
        let options = ModelOptions {
            linear_vh_terms: false,
            ..ModelOptions::default()
        };
        let base = ModelStructure::eq22(&v, options);
        let theta = vec![1e-6; base.params.len()];
        let force_theta = vec![1e-6; base.columns.len()];
        library(&CandidateContext {
            vehicle: &v,
            structure: &base,
            theta: &theta,
            force_theta: &force_theta,
            has_height: true,
            has_omega_dot: true,
            has_omega_ddot: true,
            has_attitude: true,
            has_slow_thrust: true,
            hover_thrust_coefficient: Some(1e-6),
        })
    }

    /// The order of the candidates is part of the search's behaviour (ties keep it).
    #[test]
    fn every_effect_is_offered_in_library_order() {
        let names: Vec<String> = full_library()
            .into_iter()
            .filter(|c| c.kind != EffectKind::DecoupledMoments)
            .map(|c| c.name)
            .collect();
        let expected = [
            "ground effect",
            "ground effect, per-rotor height",
            "ground effect, multirotor",
            "weak rotor 1",
            "weak rotor 2",
            "weak rotor 3",
            "weak rotor 4",
            "CG offset",
            "CG offset, joint lever force",
            "in-plane force lever arm",
            "rotor-wake interaction",
            "rotor-wake interaction, advance ratio",
            "rotor-wake interaction, forward flight",
            "rotor-wake interaction, backward flight",
            "quadratic airframe drag",
            "quadratic airframe drag, along the airflow",
            "quadratic airframe drag, off the CG",
            "vortex-ring state",
            "terms linear in Vh",
            "rotor-speed delay",
            "steady wind",
            "yaw-rate rotor drag",
            "yaw-rate hub airspeed",
            "roll/pitch-rate rotor drag",
            "rotor flapping moment",
            "rotor rate damping",
            "second-order inflow",
            "linear vertical airframe drag",
            "thrust from rotor acceleration",
            "accelerometer bias",
            "trim moment, 0.5 Hz",
            "trim moment, 1 Hz",
            "trim moment, 2 Hz",
        ];
        assert_eq!(names, expected);
    }

    /// Each parameter's physical range, as the procedure judged it by name before the
    /// ranges moved into the effects (one range per name prefix, any finite value
    /// otherwise); and its reading, as the report chose it by name (a fraction for
    /// `*scale*` and `*loss*`, a freed coefficient for `name@axis`).
    #[test]
    fn parameters_carry_their_range_and_reading() {
        let ranges: [(&str, f64, f64); 19] = [
            ("thrust_scale_", -0.6, 0.6),
            ("in_plane_scale_", -0.6, 0.6),
            ("torque_scale_", -0.6, 0.6),
            ("cg_d", -0.2, 0.2),
            ("ground_effect_scale", 0.0, 3.0),
            ("wake_thrust_loss_advance", 0.0, 5.0),
            // Added with the directional wake forms (never in the old table).
            ("wake_thrust_loss_forward", 0.0, 5.0),
            ("wake_thrust_loss_backward", 0.0, 5.0),
            ("wake_thrust_loss", 0.0, 1.0),
            ("vortex_ring_thrust_loss", 0.0, 0.6),
            ("drag_area_", 0.0, 2.0),
            // Added with the drag off the CG (never in the old table): a centre of
            // pressure within 0.5 m of the CG times an area of at most 2 m².
            ("drag_moment_area_", -1.0, 1.0),
            // Narrowed with the closed-loop guard (was −0.05..0.2).
            ("rotor_speed_delay", -0.05, 0.05),
            ("wind_", -30.0, 30.0),
            ("accel_bias_", -2.0, 2.0),
            // Added with the trim moment (never in the old table).
            ("trim_roll", 0.0, 2.0),
            ("trim_pitch", 0.0, 2.0),
            ("trim_yaw", 0.0, f64::INFINITY),
            // Added with the linear vertical airframe drag (never in the old table).
            ("linear_drag_z", 0.0, f64::INFINITY),
        ];
        let library = full_library();
        let mut ranged = 0;
        for c in &library {
            for p in &c.parameters {
                let expected = ranges
                    .iter()
                    .find(|(prefix, _, _)| p.name.starts_with(prefix))
                    .map(|&(_, lo, hi)| lo..=hi);
                assert_eq!(p.range, expected, "{}", p.name);
                ranged += usize::from(expected.is_some());
                let reading = if p.name.contains("scale") || p.name.contains("loss") {
                    Reading::Fraction
                } else if p.name.contains('@') {
                    Reading::MomentMinusForce
                } else {
                    Reading::Value
                };
                assert_eq!(p.reading, reading, "{}", p.name);
            }
        }
        // 4 rotors × 3 scales, 5 CG (the in-plane offset in two forms, the height),
        // 3 ground, 4 wake, vortex ring, 2 × 3 + 5 drag, delay, 3 wind, 2 bias, 3 bands
        // × 3 trim fractions, vertical linear drag.
        assert_eq!(ranged, 52);
        let freed = library
            .iter()
            .filter(|c| c.kind == EffectKind::DecoupledMoments)
            .inspect(|c| assert_eq!(c.role, Role::Unspecific))
            .count();
        assert!(freed > 0);
    }
}
