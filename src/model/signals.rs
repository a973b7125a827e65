//! The vocabulary of Eq. 22 as data: the per-sample [`Signal`]s, the products ([`Term`])
//! and regressor columns ([`Column`]) built from them, and the lumped [`Parameter`]s the
//! columns multiply.

use crate::sample::Axis;

/// A per-sample quantity that regressor terms multiply.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub enum Signal {
    /// Body velocity u, m/s.
    U,
    /// Body velocity v, m/s.
    V,
    /// Body velocity w, m/s.
    W,
    /// Roll rate p, rad/s.
    P,
    /// Pitch rate q, rad/s.
    Q,
    /// Yaw rate r, rad/s.
    R,
    /// Rotor-plane airspeed V_h = √(u² + v²), m/s (Eq. 2b).
    Vh,
    /// Virtual thrust δt (Eq. 21), rad/s.
    Dt,
    /// Virtual aileron δa (Eq. 21), m rad/s.
    Da,
    /// Virtual elevator δe (Eq. 21), m rad/s.
    De,
    /// Virtual rudder δr (Eq. 21), rad/s.
    Dr,
    /// δ²t (Eq. 19), rad²/s².
    D2t,
    /// δ²a (Eq. 19), m rad²/s².
    D2a,
    /// δ²e (Eq. 19), m rad²/s².
    D2e,
    /// δ²r (Eq. 19), rad²/s².
    D2r,
    /// Rate of the virtual rudder δ̇r = M_ix,r Ω̇, rad/s².
    DrDot,
    /// Second rate of the virtual rudder δ̈r = M_ix,r Ω̈, rad/s³ (Ω̈ derived by the fit
    /// pipeline, `io`'s `rotor_jerk`).
    DrDDot,
    /// Rate δ̇ = M_ix,row Ω̇ of the virtual actuator of one row of Eq. 20 (0 δt, 1 δa,
    /// 2 δe, 3 δr): a rotor-local sum Σ w_i Ω̇_i, in that actuator's unit per second.
    ActuatorRate(u8),
    /// Σ y_i² Ω_i, m² rad/s.
    SumY2Omega,
    /// Σ x_i y_i Ω_i, m² rad/s.
    SumXYOmega,
    /// Σ x_i² Ω_i, m² rad/s.
    SumX2Omega,
    /// Σ σ_i y_i Ω_i, m rad/s.
    SumSigmaYOmega,
    /// Σ σ_i x_i Ω_i, m rad/s.
    SumSigmaXOmega,
    /// |u|, m/s.
    AbsU,
    /// |v|, m/s.
    AbsV,
    /// |w|, m/s.
    AbsW,
    /// Speed Ω_i of rotor `i` (0-based), rad/s.
    RotorSpeed(u8),
    /// Ω_i² of rotor `i` (0-based), rad²/s².
    RotorSpeedSquared(u8),
    /// Ω̇_i of rotor `i` (0-based), rad/s².
    RotorAcceleration(u8),
    /// Rate of change of δ² = M_ix Ω² for one row of Eq. 20: M_ix,row (2 Ω ∘ Ω̇), in the
    /// unit of that δ² per second.
    SquaredActuatorRate(u8),
    /// Ground-effect factor g = s/(1 − s), s = (R/(4 z_r))², z_r = CG height + h the
    /// rotor-plane height above ground (Cheeseman–Bennett: T_IGE = T (1 + g)); z_r is
    /// held at ≥ R/2 (s ≤ 1/4). Dimensionless; needs the `height` signal.
    GroundEffect,
    /// Ground-effect factor g of rotor `i` (0-based) at its own rotor-plane height: the
    /// CG height less the down (NED) component of the hub's offset (x_i, y_i, −h), so a
    /// tilted vehicle's low rotors feel more of the ground; as [`Signal::GroundEffect`]
    /// otherwise. Dimensionless; needs the `height` and attitude signals.
    RotorGroundEffect(u8),
    /// Wake immersion of rotor `i` (0-based) in forward flight, dimensionless in [0, 1]:
    /// the summed overlap (1 − miss/2R, ≥ 0) of the rotor with the wakes of rotors
    /// upstream of it along the in-plane airflow, capped at 1, times the wake strength
    /// V_h²/(V_h² + ν0²).
    WakeImmersion(u8),
    /// Wake overlap of rotor `i` (0-based) as in [`Signal::WakeImmersion`], times its
    /// advance ratio μ_i = V_h/(Ω_i R) instead of the wake strength: a loss that keeps
    /// growing with speed. Dimensionless (0 at Ω_i = 0).
    WakeAdvance(u8),
    /// Advance ratio of rotor `i` (0-based) when it sits downstream of the CG for one
    /// direction of flight along the body x axis (second index: 0 forward, 1 backward),
    /// dimensionless: max(±u, 0)/(Ω_i R) for a rotor behind the CG in forward flight
    /// (x_i < 0) or ahead of it in backward flight (x_i > 0), 0 otherwise (and at
    /// Ω_i = 0): the rotors in the others' wake when flying that way, and only then.
    DownstreamAdvance(u8, u8),
    /// Airspeed |V| = √(u² + v² + w²), m/s.
    Airspeed,
    /// Vortex-ring-state onset of rotor `i` (0-based), dimensionless in [0, 1]:
    /// exp(−((w_i/ν0 − 1)/0.5)²) exp(−(V_h/ν0)²), w_i = w + p y_i − q x_i the hub's
    /// descent speed (Eq. 18): a bump centred on descent at the hover inflow speed, the
    /// classical vortex-ring region, fading with forward speed.
    VortexRing(u8),
    /// ∂V_h/∂u = u/V_h, dimensionless (0 at V_h = 0).
    UOverVh,
    /// ∂V_h/∂v = v/V_h, dimensionless (0 at V_h = 0).
    VOverVh,
    /// Slow part of δ² = M_ix Ω² for one row of Eq. 20 (second index: 0 δt, 1 δa, 2 δe,
    /// 3 δr): M_ix,row times the rotors' slow Ω² in band `band` (first index) of
    /// [`crate::TRIM_BANDS_HZ`] (derived by the fit pipeline), in the unit of that δ².
    SlowSquaredActuator(u8, u8),
    /// Element (k, j) of the NED→body rotation, index 3k + j (body axis k, NED axis j),
    /// dimensionless; needs the attitude signals.
    NedToBody(u8),
    /// Ground-effect factor g_i = s_i/(1 − s_i) of rotor `i` (0-based) under the images
    /// of every rotor, not only its own: each rotor's wake is a point source of strength
    /// πR²ν mirrored below the ground, and s_i = Σ_j (R²/4) Δz_ij/|Δ_ij|³ is the upwash
    /// (per unit ν) that the image of rotor j puts on hub i, with Δ_ij the vector from
    /// that image to hub i and Δz_ij = z_i + z_j its vertical part (z the rotor-plane
    /// heights above ground, each held at ≥ R/2, from the attitude as in
    /// [`Signal::RotorGroundEffect`]). The own image alone (j = i) gives
    /// Cheeseman–Bennett's (R/(4 z_i))²; the neighbours' images add the multirotor's
    /// extra lift, which reaches higher. Dimensionless; needs the `height` and attitude
    /// signals.
    MultirotorGroundEffect(u8),
}

impl Signal {
    /// True when the signal is read straight from the chunk (no computation).
    pub(super) fn is_direct(self) -> bool {
        use Signal::*;
        matches!(
            self,
            U | V | W | P | Q | R | RotorSpeed(_) | RotorAcceleration(_)
        )
    }
}

/// One product `coef · Π factors` inside a regressor column.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Term {
    /// Constant coefficient (carries ρπR², R, N, ν0, ℓ, h as the column needs).
    pub coef: f64,
    /// Signals multiplied together (empty: the constant `coef`).
    pub factors: Vec<Signal>,
}

/// `coef · Π factors`.
pub fn term(coef: f64, factors: &[Signal]) -> Term {
    Term {
        coef,
        factors: factors.to_vec(),
    }
}

/// A parameter of a [`super::ModelStructure`]: its position in
/// [`super::ModelStructure::params`], and of its value in θ. Written as that position in
/// model files.
#[derive(
    Debug,
    Clone,
    Copy,
    Default,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(transparent)]
pub struct ParamId(usize);

impl ParamId {
    /// The parameter at `index` of a structure's parameter list.
    pub(crate) fn new(index: usize) -> Self {
        Self(index)
    }

    /// Its position in the structure's parameter list and in θ.
    pub fn index(self) -> usize {
        self.0
    }
}

/// A regressor column: which axis, which parameter it multiplies, and its terms.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Column {
    /// Output axis.
    pub axis: Axis,
    /// The parameter the column multiplies (set by
    /// [`super::ModelStructure::add_parameter`] for a column added with a parameter).
    pub param: ParamId,
    /// ASCII description of the regressor, after Eq. 22 (e.g. `u*dt`).
    pub label: String,
    /// Terms summed into the column.
    pub terms: Vec<Term>,
}

/// A named lumped parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// ASCII name after the seed, e.g. `C_H_mub_mu0`.
    pub name: String,
    /// Unit of the estimate ("-" for the dimensionless coefficients of Eq. 8).
    pub unit: String,
}

/// In-plane airspeed V_h = √(u² + v²), m/s. Plain square root of the sum rather than
/// `hypot` (several times slower, guarding against overflow that body velocities in m/s
/// cannot reach).
pub(super) fn in_plane_speed(u: f64, v: f64) -> f64 {
    (u * u + v * v).sqrt()
}
