//! The variants of the Eq. 22 structure: inflow-correction form, terms linear in V_h,
//! and the treatment of the J_z terms (Eq. 16).

/// How the inflow-correction terms are built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "snake_case")]
pub enum InflowCorrection {
    /// From per-rotor sums over the vehicle's positions and spins (exact for any
    /// supported planar layout and spin assignment, Assumption 2 or not).
    #[default]
    Derived,
    /// The printed case table of Eq. 22, to reproduce the seed (Definition 1 classes
    /// only: a general planar layout always uses the derived form).
    Paper,
}

/// Treatment of the J_z gyroscopic and motor-torque terms (Eq. 16).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "snake_case")]
pub enum RotorInertiaTerms {
    /// J_z from the vehicle file; the terms are subtracted from the measured moments.
    #[default]
    Known,
    /// J_z is estimated as a parameter (unit kg m²).
    Estimated,
    /// The terms are left out.
    Neglected,
}

/// Variant of the Eq. 22 structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelOptions {
    /// Inflow-correction form.
    pub inflow: InflowCorrection,
    /// Keep the terms linear in V_h (C_H_mub_mu, C_T_mu, C_Q_mu). The seed's simulation
    /// study removed them (constant-inflow simulator).
    pub linear_vh_terms: bool,
    /// J_z term treatment.
    pub rotor_inertia: RotorInertiaTerms,
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self {
            inflow: InflowCorrection::Derived,
            linear_vh_terms: true,
            rotor_inertia: RotorInertiaTerms::Known,
        }
    }
}

impl ModelOptions {
    /// The variant of the seed's simulation study (§5): printed inflow table, no terms
    /// linear in V_h.
    pub fn paper_simulation_study() -> Self {
        Self {
            inflow: InflowCorrection::Paper,
            linear_vh_terms: false,
            rotor_inertia: RotorInertiaTerms::Known,
        }
    }
}
