//! Eq. 22d–f: the moment columns M_x, M_y (rotor moments, thrust and hub-force lever
//! arms, the inflow corrections Δν_ℒ, Δν_ℳ) and M_z (rotor torque, Δν_𝒩, Δν_𝒩², the H
//! and S forces' lever arms), in the derived or the printed inflow form.

use super::{Builder, Consts, Geometry};
use crate::model::{InflowCorrection, ModelOptions, Signal, Term, term};
use crate::sample::Axis;
use crate::vehicle::ConfigurationClass;

/// Eq. 22d–e: M_x and M_y. A general planar layout adds, from the first moments
/// Σx_i, Σy_i, Σσ_i x_i, Σσ_i y_i: −C_T_mu2 V_h² Σy_i (M_x) and +C_T_mu2 V_h² Σx_i (M_y)
/// from the thrust's lever arm; ½ C_T_muw R {u, v} Σσ_i w_i in the C_T_muw column from
/// the hub rolling/pitching moments' inflow term; Σ w_i in the hub-force lever term.
pub(super) fn roll_pitch_moments(
    b: &mut Builder,
    c: &Consts,
    o: ModelOptions,
    class: ConfigurationClass,
    g: &Geometry,
) {
    use Signal::*;
    let (k, r, n, h) = (c.k, c.r, c.n, c.h);
    // (axis, rotor-moment velocity, virtual actuator δ, δ², hub-force velocity, sign of
    // the hub-force moment: M_x gets +h ΣS = h F_y, M_y gets +h ΣH = −h F_x).
    let axes = [
        (Axis::Mx, U, Da, D2a, V, 1.0, "a", "u", "v"),
        (Axis::My, V, De, D2e, U, -1.0, "e", "v", "u"),
    ];
    for (axis, vr, d, d2, vh, sign, dn, vrn, vhn) in axes {
        b.col(
            axis,
            "C_R_mub",
            &format!("{vrn}*dr"),
            vec![term(k * r * r, &[vr, Dr])],
        );
        b.col(
            axis,
            "C_T0",
            &format!("d2{dn}"),
            vec![term(k * r * r, &[d2])],
        );
        b.col(
            axis,
            "C_T_mu0",
            &format!("nu0*d{dn}"),
            vec![term(-k * r * c.nu0, &[d])],
        );
        if o.linear_vh_terms {
            b.col(
                axis,
                "C_T_mu",
                &format!("Vh*d{dn}"),
                vec![term(-k * r, &[Vh, d])],
            );
        }
        let mut muw = vec![term(k * r, &[W, d])];
        muw.extend(inflow_roll_pitch(axis, c, o.inflow, class));
        // ½ R {u, v} Σσ_i w_i, Σσ_i w_i = p Σσ_i y_i − q Σσ_i x_i (balanced spins).
        muw.extend([
            term(0.5 * k * r * g.s_sigma_y, &[vr, P]),
            term(-0.5 * k * r * g.s_sigma_x, &[vr, Q]),
        ]);
        let label = if axis == Axis::Mx {
            "w*da - dnu_L"
        } else {
            "w*de - dnu_M"
        };
        b.col(axis, "C_T_muw", label, muw);
        // Thrust lever arm of the rotor centroid: −Σy_i T_i (M_x), +Σx_i T_i (M_y).
        let centroid = if axis == Axis::Mx { -g.sy } else { g.sx };
        let vh2_label = if axis == Axis::Mx {
            "-Sy*Vh^2"
        } else {
            "Sx*Vh^2"
        };
        b.col(
            axis,
            "C_T_mu2",
            vh2_label,
            vec![term(k * centroid, &[Vh, Vh])],
        );
        let khn = sign * k * h * n;
        b.col(
            axis,
            "C_H_mub",
            &format!("h*{vhn}*dt"),
            vec![term(-khn * r, &[vh, Dt])],
        );
        b.col(
            axis,
            "C_H_mub_mu0",
            &format!("h*{vhn}*nu0"),
            vec![term(-khn * c.nu0, &[vh])],
        );
        if o.linear_vh_terms {
            b.col(
                axis,
                "C_H_mub_mu",
                &format!("h*{vhn}*Vh"),
                vec![term(-khn, &[vh, Vh])],
            );
        }
        b.col(
            axis,
            "C_H_mub_muw",
            &format!("h*{vhn}*w"),
            vec![
                term(khn, &[vh, W]),
                term(sign * k * h * g.sy, &[vh, P]),
                term(-sign * k * h * g.sx, &[vh, Q]),
            ],
        );
    }
}

/// The −ρπR² C_T_muw R Δν_ℒ (M_x) or Δν_ℳ (M_y) terms.
fn inflow_roll_pitch(
    axis: Axis,
    c: &Consts,
    form: InflowCorrection,
    class: ConfigurationClass,
) -> Vec<Term> {
    use Signal::*;
    let kr = c.k * c.r;
    let half = kr * c.l2 / 2.0;
    let roll = axis == Axis::Mx;
    match (form, roll) {
        (InflowCorrection::Derived, true) => {
            vec![term(-kr, &[P, SumY2Omega]), term(kr, &[Q, SumXYOmega])]
        }
        (InflowCorrection::Derived, false) => {
            vec![term(-kr, &[Q, SumX2Omega]), term(kr, &[P, SumXYOmega])]
        }
        (InflowCorrection::Paper, _) => {
            let (rate, other) = if roll { (P, Q) } else { (Q, P) };
            let mut t = vec![term(-half * c.n, &[rate, Dt])];
            match class {
                // Δν_ℒ = ℓ²/2 p (N δt − δr); Δν_ℳ = ℓ²/2 q (N δt + δr).
                ConfigurationClass::QuadPlus => {
                    t.push(term(if roll { half } else { -half }, &[rate, Dr]))
                }
                // Δν_ℒ = ℓ²/2 (N p δt + q δr); Δν_ℳ = ℓ²/2 (N q δt + p δr).
                ConfigurationClass::QuadX => t.push(term(-half, &[other, Dr])),
                // (A general planar layout never takes the printed table: see `eq22`.)
                ConfigurationClass::Multirotor6Plus | ConfigurationClass::GeneralPlanar => {}
            }
            t
        }
    }
}

/// Eq. 22f: M_z.
pub(super) fn yaw_moment(
    b: &mut Builder,
    c: &Consts,
    o: ModelOptions,
    class: ConfigurationClass,
    g: &Geometry,
) {
    use Signal::*;
    let (k, r) = (c.k, c.r);
    let kr2 = k * r * r;
    b.col(Axis::Mz, "C_Q0", "d2r", vec![term(kr2 * r, &[D2r])]);
    b.col(
        Axis::Mz,
        "C_Q_mu0",
        "nu0*dr",
        vec![term(kr2 * c.nu0, &[Dr])],
    );
    if o.linear_vh_terms {
        b.col(Axis::Mz, "C_Q_mu", "Vh*dr", vec![term(kr2, &[Vh, Dr])]);
    }
    // −C_Q_muw R² (w δr − Δν_𝒩).
    let mut muw = vec![term(-kr2, &[W, Dr])];
    // −C_Q_muw2 R N ℓ² Δν_𝒩².
    let mut muw2;
    // C_H_mub_muw: v(pΣxy − qΣx²) − u(pΣy² − qΣxy), printed −½Nℓ²(up + vq).
    let mut hw;
    match o.inflow {
        InflowCorrection::Derived => {
            muw.extend([
                term(kr2, &[P, SumSigmaYOmega]),
                term(-kr2, &[Q, SumSigmaXOmega]),
            ]);
            muw2 = vec![
                term(k * r * g.s_sigma_yy, &[P, P]),
                term(-2.0 * k * r * g.s_sigma_xy, &[P, Q]),
                term(k * r * g.s_sigma_xx, &[Q, Q]),
            ];
            hw = vec![
                term(k * g.sxy, &[V, P]),
                term(-k * g.sxx, &[V, Q]),
                term(-k * g.syy, &[U, P]),
                term(k * g.sxy, &[U, Q]),
            ];
        }
        InflowCorrection::Paper => {
            let knl2 = k * r * c.n * c.l2;
            match class {
                ConfigurationClass::QuadPlus => {
                    muw.extend([term(kr2, &[Q, De]), term(-kr2, &[P, Da])]);
                    muw2 = vec![term(-knl2 / 2.0, &[P, P]), term(knl2 / 2.0, &[Q, Q])];
                }
                ConfigurationClass::QuadX => {
                    muw.extend([term(-kr2, &[P, De]), term(-kr2, &[Q, Da])]);
                    muw2 = vec![term(-knl2, &[P, Q])];
                }
                ConfigurationClass::Multirotor6Plus | ConfigurationClass::GeneralPlanar => {
                    muw2 = Vec::new()
                }
            }
            let half = 0.5 * k * c.n * c.l2;
            hw = vec![term(-half, &[U, P]), term(-half, &[V, Q])];
        }
    }
    // General planar layout: Σσ_i w_i² gains 2w Σσ_i w_i; the H and S forces' lever arms
    // gain Σy_i u − Σx_i v times their state-only part.
    muw2.extend([
        term(2.0 * k * r * g.s_sigma_y, &[W, P]),
        term(-2.0 * k * r * g.s_sigma_x, &[W, Q]),
    ]);
    hw.extend([term(-k * g.sy, &[U, W]), term(k * g.sx, &[V, W])]);
    b.col(Axis::Mz, "C_Q_muw", "w*dr - dnu_N", muw);
    b.col(Axis::Mz, "C_Q_muw2", "N*l^2*dnu_N2", muw2);
    b.col(
        Axis::Mz,
        "C_H_mub",
        "u*da + v*de",
        vec![term(-k * r, &[U, Da]), term(-k * r, &[V, De])],
    );
    b.col(Axis::Mz, "C_H_mub_muw", "l^2*(u*p + v*q)", hw);
    // The rest of a general planar layout's M_z: −σ_i 𝒬_i's inflow-squared part
    // R (C_σ/2) Σσ_i Λ_i², Λ_i = ν0 + C_νμ V_h − (1 − C_νw) w_i, gives
    // −R (2 C_T_muw ν0 + C_Q_mu_muw V_h) Σσ_i w_i; Σ(y_i H_i + x_i S_i) gives
    // (C_H_mub_mu0 ν0 + C_H_mub_mu V_h)(u Σy_i − v Σx_i).
    b.col(
        Axis::Mz,
        "C_T_muw",
        "-2*nu0*(p*Ssy - q*Ssx)",
        vec![
            term(-2.0 * k * r * c.nu0 * g.s_sigma_y, &[P]),
            term(2.0 * k * r * c.nu0 * g.s_sigma_x, &[Q]),
        ],
    );
    b.col(
        Axis::Mz,
        "C_H_mub_mu0",
        "nu0*(u*Sy - v*Sx)",
        vec![term(k * c.nu0 * g.sy, &[U]), term(-k * c.nu0 * g.sx, &[V])],
    );
    if o.linear_vh_terms {
        b.col(
            Axis::Mz,
            "C_H_mub_mu",
            "Vh*(u*Sy - v*Sx)",
            vec![term(k * g.sy, &[U, Vh]), term(-k * g.sx, &[V, Vh])],
        );
        b.col(
            Axis::Mz,
            "C_Q_mu_muw",
            "-Vh*(p*Ssy - q*Ssx)",
            vec![
                term(-k * r * g.s_sigma_y, &[Vh, P]),
                term(k * r * g.s_sigma_x, &[Vh, Q]),
            ],
        );
    }
}
