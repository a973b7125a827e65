//! The Eq. 22 model structure: named lumped parameters shared across the six axes, and
//! the regressor columns each parameter multiplies (seed §4.2).
//!
//! A [`ModelStructure`] is data: one parameter vector θ and, per axis, a sparse row of
//! [`Column`]s. Each column is a sum of [`Term`]s `coef · s1 · s2 · …`, products of
//! per-sample [`Signal`]s (states, virtual actuators, inflow sums) with constant
//! coefficients that carry ρπR², R, N, ν0, ℓ and h. Eq. 22 reads
//! `z_axis = Σ_columns θ[column.param] · column(sample)`.
//!
//! Terms with known coefficients (the J_z gyroscopic and motor-torque terms of
//! Eq. 16/22d–f) are either moved to the output side ([`RotorInertiaTerms::Known`]),
//! estimated as parameter `J_z`, or neglected.
//!
//! The inflow corrections Δν_z, Δν_ℒ, Δν_ℳ, Δν_𝒩, Δν_𝒩² come from per-rotor sums
//! ([`InflowCorrection::Derived`], default): with hub local vertical velocity
//! w_i = w + p y_i − q x_i (Eq. 18),
//!
//! - Δν_z = −Σ (w_i − w) Ω_i = p δa + q δe,
//! - Δν_ℒ = p Σ y_i² Ω_i − q Σ x_i y_i Ω_i,
//! - Δν_ℳ = q Σ x_i² Ω_i − p Σ x_i y_i Ω_i,
//! - Δν_𝒩 = p Σ σ_i y_i Ω_i − q Σ σ_i x_i Ω_i,
//! - N ℓ² Δν_𝒩² = −(p² Σ σ_i y_i² − 2pq Σ σ_i x_i y_i + q² Σ σ_i x_i²),
//!
//! and the M_z term of C_H_mub_muw is v(pΣx_iy_i − qΣx_i²) − u(pΣy_i² − qΣx_iy_i),
//! which equals the printed −½Nℓ²(up + vq) under Assumption 2.
//!
//! # General planar layouts
//!
//! Nothing above needs Assumption 2 beyond an even rotor count, balanced spins
//! (Σσ_i = 0) and coplanar, uncanted rotors: the virtual actuators use the actual hub
//! positions (M_ix rows 1/N, −y_i, x_i, −σ_i, Eq. 20) and the inflow corrections are the
//! per-rotor sums above. What Assumption 2's symmetry adds is that the first moments of
//! the layout vanish: Σx_i = Σy_i = 0 (rotor centroid at the CG) and Σσ_i x_i =
//! Σσ_i y_i = 0 (spins balanced on each side). For a layout that breaks Assumption 2
//! ([`ConfigurationClass::GeneralPlanar`]) these sums are kept and bring the terms that
//! symmetry cancels, all with the seed's lumped parameters except one:
//!
//! - F_x, F_y: Σ w_i = N w + p Σy_i − q Σx_i in the C_H_mub_muw column (and in the
//!   hub-force lever terms h F_y, −h F_x of M_x, M_y);
//! - M_x, M_y: the thrust's state-only part acts at the rotor centroid,
//!   −C_T_mu2 Σy_i V_h² (M_x) and +C_T_mu2 Σx_i V_h² (M_y); the hub rolling/pitching
//!   moments' inflow part adds ½ R {u, v} Σσ_i w_i to the C_T_muw column;
//! - M_z: (C_H_mub_mu0 ν0 + C_H_mub_mu V_h − C_H_mub_muw w)(u Σy_i − v Σx_i) from the
//!   H and S forces' lever arms; 2 w Σσ_i w_i in the C_Q_muw2 column; and
//!   −R (2 C_T_muw ν0 + C_Q_mu_muw V_h) Σσ_i w_i from the square of the inflow in the rotor
//!   torque, with Σσ_i w_i = p Σσ_i y_i − q Σσ_i x_i.
//!
//! `C_Q_mu_muw` = C_σ C_νμ (1 − C_νw) is the μ μ_w coefficient of Eq. 8f, which cancels
//! under Assumption 2: it is the product of the two inflow slopes, not a combination of
//! the other 15, so it is a parameter of its own (present only with the terms linear in
//! V_h). Only the printed case table of Eq. 22 (the ℓ² forms of the Δν terms, per
//! Definition 1) stops being exact; a general planar layout always uses the derived sums,
//! even with [`InflowCorrection::Paper`]. A vehicle that satisfies Assumption 2 within its
//! geometry tolerance keeps the seed's structure (first moments taken as zero).
//!
//! [`InflowCorrection::Paper`] reproduces the printed case table of Eq. 22 instead.
//! By the sums above, the printed table is not consistent with any single spin
//! assignment: for quadrotor× the printed Δν_ℒ, Δν_ℳ and Δν_𝒩² hold when rotor 1 at
//! (ℓ√2/2, ℓ√2/2) has σ = +1, while the printed Δν_𝒩 = −pδe − qδa holds for σ = −1 (the
//! sums give +pδe + qδa for σ = +1); for quadrotor+ the printed Δν_ℒ, Δν_ℳ and Δν_𝒩 hold
//! for σ = −1 at the front rotor while Δν_𝒩² holds for σ = +1. The multirotor≥6 forms
//! replace Σ y_i² Ω_i by (ℓ²/2) N δt and drop Σ x_i y_i Ω_i and Δν_𝒩, which is exact
//! only when all rotor speeds are equal.
//!
//! [`ConfigurationClass::GeneralPlanar`]: crate::vehicle::ConfigurationClass::GeneralPlanar

// One concept per file: `signals` (Signal, Term, Column, Parameter), `options`,
// `structure` (ModelStructure, ModelError, its edits), `eq22` (the builder: `forces`
// Eq. 22a-c, `moments` Eq. 22d-f), `evaluate` (values of the computed signals),
// `local_effects` (ground effect, wakes, vortex ring), `kernels` (the SIMD column
// kernels), `reuse` (columns from earlier columns), `assemble`, `predict`, `workspace`.
mod assemble;
mod attitude;
mod eq22;
mod evaluate;
mod kernels;
mod local_effects;
mod options;
mod predict;
mod reuse;
mod signals;
mod structure;
mod workspace;

pub use local_effects::ground_effect_factor;
pub use options::{InflowCorrection, ModelOptions, RotorInertiaTerms};
pub(crate) use reuse::Reuse;
pub use signals::{Column, ParamId, Parameter, Signal, Term, term};
pub use structure::{ModelError, ModelStructure, ParamOrigin};
pub use workspace::Workspace;
pub(crate) use workspace::row_ranges;

/// A quadrotor × (arm 0.25 m, R = 0.1 m, h = 0.05 m, 1 kg) for the model's unit tests.
#[cfg(test)]
pub(crate) fn test_quad() -> crate::vehicle::Vehicle {
    use crate::vehicle::{MassAndRotorProperties, Preset, Vehicle, test_props};
    let props = MassAndRotorProperties {
        air_density: 1.2,
        hub_height: 0.05,
        ..test_props()
    };
    Vehicle::preset("q", Preset::QuadX, 0.25, 1.0, props).unwrap()
}
