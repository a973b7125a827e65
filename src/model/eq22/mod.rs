//! The Eq. 22 structure of one vehicle, built from the vehicle's constants and rotor
//! layout: the force columns ([`forces`], Eq. 22a–c), the moment columns ([`moments`],
//! Eq. 22d–f), and the J_z terms of Eq. 16 as columns or known terms.

mod forces;
mod moments;

use super::evaluate::SignalConstants;
use super::{
    Column, InflowCorrection, ModelOptions, ModelStructure, ParamId, Parameter, RotorInertiaTerms,
    Signal, Term, term,
};
use crate::sample::Axis;
use crate::vehicle::{ConfigurationClass, Vehicle};
use forces::{in_plane_forces, vertical_force};
use moments::{roll_pitch_moments, yaw_moment};

/// Constants of one vehicle that the Eq. 22 coefficients use.
struct Consts {
    /// ρπR², kg/m.
    k: f64,
    /// Rotor radius R, m.
    r: f64,
    /// Rotor count N.
    n: f64,
    /// Hover induced velocity ν0, m/s.
    nu0: f64,
    /// Arm length squared ℓ², m².
    l2: f64,
    /// Height h of the rotor plane above the CG, m.
    h: f64,
    /// Smallest geometric coefficient kept, m² (smaller ones are rounding noise).
    tiny: f64,
}

/// Builds columns for one parameter, skipping terms whose coefficient is rounding noise.
struct Builder {
    params: Vec<Parameter>,
    columns: Vec<Column>,
}

impl Builder {
    /// The parameter `name`, added (with `unit`) at its first column.
    fn param(&mut self, name: &str, unit: &str) -> ParamId {
        if let Some(i) = self.params.iter().position(|p| p.name == name) {
            return ParamId::new(i);
        }
        self.params.push(Parameter {
            name: name.into(),
            unit: unit.into(),
        });
        ParamId::new(self.params.len() - 1)
    }

    fn col(&mut self, axis: Axis, param: &str, label: &str, terms: Vec<Term>) {
        let terms: Vec<Term> = terms.into_iter().filter(|t| t.coef != 0.0).collect();
        if terms.is_empty() {
            return;
        }
        let unit = if param == "J_z" { "kg m^2" } else { "-" };
        let param = self.param(param, unit);
        self.columns.push(Column {
            axis,
            param,
            label: label.into(),
            terms,
        });
    }
}

impl ModelStructure {
    /// The Eq. 22 structure for `vehicle` with `options`.
    pub fn eq22(vehicle: &Vehicle, options: ModelOptions) -> Self {
        let props = &vehicle.props;
        let r = props.rotor_radius;
        let l2 = vehicle.arm_length().powi(2);
        let n = vehicle.rotor_count() as f64;
        let c = Consts {
            k: props.air_density * std::f64::consts::PI * r * r,
            r,
            n,
            nu0: vehicle.hover_induced_velocity(),
            l2,
            h: props.hub_height,
            tiny: 1e-12 * n * l2,
        };
        let geometry = Geometry::of(vehicle, c.tiny, 1e-12 * n * vehicle.arm_length());
        let mut b = Builder {
            params: Vec::new(),
            columns: Vec::new(),
        };
        // The printed case table exists only for Definition 1's classes; a general
        // planar layout always uses the per-rotor sums.
        let mut o = options;
        if vehicle.class() == ConfigurationClass::GeneralPlanar {
            o.inflow = InflowCorrection::Derived;
        }
        in_plane_forces(&mut b, &c, o, &geometry);
        vertical_force(&mut b, &c, o);
        roll_pitch_moments(&mut b, &c, o, vehicle.class(), &geometry);
        yaw_moment(&mut b, &c, o, vehicle.class(), &geometry);
        let known = rotor_inertia_terms(&mut b, options, props.rotor_inertia);
        b.columns.sort_by_key(|col| col.axis);
        // Parameters in order of first appearance by axis, as in Table 5.
        let mut order: Vec<ParamId> = Vec::new();
        for col in &b.columns {
            if !order.contains(&col.param) {
                order.push(col.param);
            }
        }
        let params = order.iter().map(|&i| b.params[i.index()].clone()).collect();
        for col in &mut b.columns {
            let at = order.iter().position(|&i| i == col.param);
            col.param = ParamId::new(at.expect("present"));
        }
        let constants = SignalConstants::of(vehicle, c.tiny);
        Self::from_parts(
            params,
            b.columns,
            known,
            options,
            vehicle.rotor_count(),
            constants,
        )
    }
}

/// Geometric sums of the rotor layout: second moments (m²) and the first moments of a
/// general planar layout (m), which Assumption 2's symmetry makes zero.
struct Geometry {
    sxx: f64,
    syy: f64,
    sxy: f64,
    s_sigma_xx: f64,
    s_sigma_yy: f64,
    s_sigma_xy: f64,
    /// Σ x_i, Σ y_i: N times the rotor centroid's offset from the CG, m.
    sx: f64,
    sy: f64,
    /// Σ σ_i x_i, Σ σ_i y_i: the spin-weighted first moments, m.
    s_sigma_x: f64,
    s_sigma_y: f64,
}

impl Geometry {
    /// Sums of `vehicle`'s layout; second moments below `tiny` (m²) are rounding noise.
    /// The first moments are zero for a layout that satisfies Assumption 2 (within its
    /// tolerance, so an Assumption 2 vehicle keeps the seed's structure) and are taken
    /// exactly otherwise (rounding noise below `tiny_length`, m, dropped).
    fn of(vehicle: &Vehicle, tiny: f64, tiny_length: f64) -> Self {
        let sum = |f: &dyn Fn(&crate::vehicle::Rotor) -> f64, tiny: f64| {
            let s: f64 = vehicle.rotors().iter().map(f).sum();
            if s.abs() <= tiny { 0.0 } else { s }
        };
        let first = |f: &dyn Fn(&crate::vehicle::Rotor) -> f64| {
            if vehicle.satisfies_assumption2() {
                0.0
            } else {
                sum(f, tiny_length)
            }
        };
        Self {
            sxx: sum(&|r| r.x * r.x, tiny),
            syy: sum(&|r| r.y * r.y, tiny),
            sxy: sum(&|r| r.x * r.y, tiny),
            s_sigma_xx: sum(&|r| r.spin * r.x * r.x, tiny),
            s_sigma_yy: sum(&|r| r.spin * r.y * r.y, tiny),
            s_sigma_xy: sum(&|r| r.spin * r.x * r.y, tiny),
            sx: first(&|r| r.x),
            sy: first(&|r| r.y),
            s_sigma_x: first(&|r| r.spin * r.x),
            s_sigma_y: first(&|r| r.spin * r.y),
        }
    }
}

/// J_z q δr (M_x), −J_z p δr (M_y), J_z δ̇r (M_z): columns of `J_z` or known terms.
fn rotor_inertia_terms(b: &mut Builder, o: ModelOptions, jz: f64) -> [Vec<Term>; 6] {
    use Signal::*;
    let shapes = [
        (Axis::Mx, "q*dr", term(1.0, &[Q, Dr])),
        (Axis::My, "-p*dr", term(-1.0, &[P, Dr])),
        (Axis::Mz, "dr_dot", term(1.0, &[DrDot])),
    ];
    let mut known: [Vec<Term>; 6] = Default::default();
    for (axis, label, t) in shapes {
        match o.rotor_inertia {
            RotorInertiaTerms::Estimated => b.col(axis, "J_z", label, vec![t]),
            RotorInertiaTerms::Known if jz != 0.0 => known[axis as usize].push(Term {
                coef: jz * t.coef,
                factors: t.factors,
            }),
            _ => {}
        }
    }
    known
}
