//! Eq. 22a–c: the force columns F_x, F_y (rotor H and S forces) and F_z (thrust with its
//! inflow correction Δν_z).

use super::{Builder, Consts, Geometry};
use crate::model::{ModelOptions, Signal, term};
use crate::sample::Axis;

/// Eq. 22a–b: F_x, F_y = ρπR² N {u, v} (−C_H_mub R δt − C_H_mub_mu0 ν0 −
/// C_H_mub_mu V_h + C_H_mub_muw w), where N w is Σ w_i = N w + p Σy_i − q Σx_i (Eq. 18)
/// for a general planar layout.
pub(super) fn in_plane_forces(b: &mut Builder, c: &Consts, o: ModelOptions, g: &Geometry) {
    use Signal::*;
    let kn = c.k * c.n;
    for (axis, s, name) in [(Axis::Fx, U, "u"), (Axis::Fy, V, "v")] {
        b.col(
            axis,
            "C_H_mub",
            &format!("{name}*dt"),
            vec![term(-kn * c.r, &[s, Dt])],
        );
        b.col(
            axis,
            "C_H_mub_mu0",
            &format!("{name}*nu0"),
            vec![term(-kn * c.nu0, &[s])],
        );
        if o.linear_vh_terms {
            b.col(
                axis,
                "C_H_mub_mu",
                &format!("{name}*Vh"),
                vec![term(-kn, &[s, Vh])],
            );
        }
        b.col(
            axis,
            "C_H_mub_muw",
            &format!("{name}*w"),
            vec![
                term(kn, &[s, W]),
                term(c.k * g.sy, &[s, P]),
                term(-c.k * g.sx, &[s, Q]),
            ],
        );
    }
}

/// Eq. 22c: F_z.
pub(super) fn vertical_force(b: &mut Builder, c: &Consts, o: ModelOptions) {
    use Signal::*;
    let (k, r, n) = (c.k, c.r, c.n);
    b.col(Axis::Fz, "C_T0", "d2t", vec![term(-k * r * r * n, &[D2t])]);
    b.col(
        Axis::Fz,
        "C_T_mu0",
        "nu0*dt",
        vec![term(k * r * n * c.nu0, &[Dt])],
    );
    if o.linear_vh_terms {
        b.col(
            Axis::Fz,
            "C_T_mu",
            "Vh*dt",
            vec![term(k * r * n, &[Vh, Dt])],
        );
    }
    b.col(Axis::Fz, "C_T_mu2", "Vh^2", vec![term(-k * n, &[Vh, Vh])]);
    // −C_T_muw R (N w δt − Δν_z), Δν_z = p δa + q δe.
    b.col(
        Axis::Fz,
        "C_T_muw",
        "N*w*dt - dnu_z",
        vec![
            term(-k * r * n, &[W, Dt]),
            term(k * r, &[P, Da]),
            term(k * r, &[Q, De]),
        ],
    );
}
