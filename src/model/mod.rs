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

use crate::sample::{Axis, Sample, SampleChunk};
use crate::util::range_of_slice;

mod eq22;
mod evaluate;
mod kernels;
mod local_effects;
mod options;
mod reuse;
mod signals;
mod workspace;

use evaluate::{SignalConstants, signal_slice};
use kernels::{AssembleColumns, apply_term};
pub use local_effects::ground_effect_factor;
pub use options::{InflowCorrection, ModelOptions, RotorInertiaTerms};
pub(crate) use reuse::Reuse;
pub use signals::{Column, Parameter, Signal, Term, term};
pub use workspace::Workspace;

/// Why a chunk could not be assembled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// The chunk has a different rotor count from the vehicle.
    #[error("the data has {found} rotor speed columns but the vehicle has {expected} rotors")]
    RotorCountMismatch {
        /// Vehicle rotor count.
        expected: usize,
        /// Rotor series in the data.
        found: usize,
    },
    /// The model needs the CG height (ground-effect term) and the data has none.
    #[error(
        "the model needs the CG height above ground (ground-effect term) but the data has no `height`"
    )]
    MissingHeight,
    /// The model needs the attitude (wind term) and the data has none.
    #[error("the model needs the attitude (steady-wind term) but the data has no `qw, qx, qy, qz`")]
    MissingAttitude,
    /// The model needs rotor accelerations (J_z δ̇r term) and the data has none.
    #[error(
        "the model needs rotor accelerations (the J_z * dr_dot term of Eq. 22f) but the data has none; derive them, or neglect the J_z terms"
    )]
    MissingRotorAcceleration,
    /// The model needs rates of the rotor accelerations (a rotor-speed delay's J_z δ̈r
    /// term) and the data has none.
    #[error(
        "the model needs rates of the rotor accelerations (the J_z * dr_ddot term of a rotor-speed delay) but the data has none; they are derived from omega_dot by the fit pipeline"
    )]
    MissingRotorAccelerationRate,
    /// A chunk whose signal vectors do not all hold one value per time stamp.
    #[error("malformed sample chunk: signal {signal:?}: {problem}")]
    ChunkShape {
        /// The signal concerned.
        signal: String,
        /// What is wrong.
        problem: String,
    },
    /// θ has another length than the structure's parameter list.
    #[error("{found} parameter values for a model of {expected} parameters")]
    ParameterCount {
        /// Parameters of the structure.
        expected: usize,
        /// Values given.
        found: usize,
    },
}

/// The Eq. 22 model of one vehicle: parameters, columns per axis and known terms.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelStructure {
    /// Parameters, in estimation order.
    pub params: Vec<Parameter>,
    /// All regressor columns, grouped by axis in [`Axis`] order.
    pub columns: Vec<Column>,
    /// Known-coefficient terms per axis, subtracted from the measured outputs.
    pub known: [Vec<Term>; 6],
    /// The options the structure was built with.
    pub options: ModelOptions,
    rotor_count: usize,
    /// Signals any column or known term uses (kept in step with the columns).
    required: Vec<Signal>,
    /// The vehicle constants the computed signals use.
    constants: SignalConstants,
}

impl ModelStructure {
    /// A structure of `params` and `columns` (whose `param` indices point into `params`)
    /// with `known` terms, for a vehicle of `rotor_count` rotors whose signals use
    /// `constants`.
    fn from_parts(
        params: Vec<Parameter>,
        columns: Vec<Column>,
        known: [Vec<Term>; 6],
        options: ModelOptions,
        rotor_count: usize,
        constants: SignalConstants,
    ) -> Self {
        let mut s = Self {
            params,
            columns,
            known,
            options,
            rotor_count,
            required: Vec::new(),
            constants,
        };
        s.required = s.collect_required_signals();
        s
    }

    /// Index of the parameter called `name`.
    pub fn param_index(&self, name: &str) -> Option<usize> {
        self.params.iter().position(|p| p.name == name)
    }

    /// Indices (into [`ModelStructure::columns`]) of the columns of `axis`.
    pub fn axis_columns(&self, axis: Axis) -> impl Iterator<Item = usize> + '_ {
        self.columns
            .iter()
            .enumerate()
            .filter(move |(_, c)| c.axis == axis)
            .map(|(j, _)| j)
    }

    /// Rotor count the structure was built for.
    pub fn rotor_count(&self) -> usize {
        self.rotor_count
    }

    /// True when assembling needs rotor accelerations.
    pub fn needs_omega_dot(&self) -> bool {
        self.required.iter().any(|s| {
            matches!(
                s,
                Signal::DrDot
                    | Signal::ActuatorRate(_)
                    | Signal::RotorAcceleration(_)
                    | Signal::SquaredActuatorRate(_)
            )
        })
    }

    fn all_terms(&self) -> impl Iterator<Item = &Term> {
        self.columns
            .iter()
            .flat_map(|c| c.terms.iter())
            .chain(self.known.iter().flatten())
    }

    /// The signals any column or known term uses, sorted.
    pub fn required_signals(&self) -> &[Signal] {
        &self.required
    }

    fn collect_required_signals(&self) -> Vec<Signal> {
        let mut s: Vec<Signal> = self
            .all_terms()
            .flat_map(|t| t.factors.iter().copied())
            .collect();
        s.sort();
        s.dedup();
        s
    }

    /// Appends a parameter with its columns (e.g. a candidate effect); returns its index.
    /// Columns' `param` fields are overwritten with the new index.
    pub fn add_parameter(&mut self, param: Parameter, mut columns: Vec<Column>) -> usize {
        let idx = self.params.len();
        self.params.push(param);
        for c in &mut columns {
            c.param = idx;
        }
        self.columns.extend(columns);
        self.columns.sort_by_key(|c| c.axis);
        self.required = self.collect_required_signals();
        idx
    }

    /// The structure restricted to parameters `keep` (indices, in the order given) and
    /// their columns; also returns, for each kept column, its index in `self.columns`.
    pub fn subset(&self, keep: &[usize]) -> (ModelStructure, Vec<usize>) {
        let cols: Vec<usize> = (0..self.columns.len())
            .filter(|&j| keep.contains(&self.columns[j].param))
            .collect();
        let columns = cols
            .iter()
            .map(|&j| {
                let mut c = self.columns[j].clone();
                c.param = keep
                    .iter()
                    .position(|&p| p == c.param)
                    .expect("kept parameter");
                c
            })
            .collect();
        let params = keep.iter().map(|&p| self.params[p].clone()).collect();
        (self.with_columns(params, columns), cols)
    }

    /// This structure's vehicle, options and known terms with `params` and `columns`
    /// (whose `param` indices point into `params`) instead of its own.
    fn with_columns(&self, params: Vec<Parameter>, columns: Vec<Column>) -> ModelStructure {
        Self::from_parts(
            params,
            columns,
            self.known.clone(),
            self.options,
            self.rotor_count,
            self.constants.clone(),
        )
    }

    /// True for a control-effectiveness column: state-independent and quadratic in the
    /// rotor speeds, a multiple of one δ² (Eq. 19) — C_T0 δ²t, δ²a, δ²e and C_Q0 δ²r,
    /// the terms through which the virtual actuators act.
    pub fn is_control_effectiveness(&self, j: usize) -> bool {
        use Signal::*;
        self.columns[j]
            .terms
            .iter()
            .all(|t| matches!(t.factors[..], [D2t | D2a | D2e | D2r]))
    }

    /// The structure restricted to columns `cols` (indices into `self.columns`,
    /// ascending) and the parameters they use, in this structure's parameter order.
    pub fn select_columns(&self, cols: &[usize]) -> ModelStructure {
        let mut used: Vec<usize> = cols.iter().map(|&j| self.columns[j].param).collect();
        used.sort_unstable();
        used.dedup();
        let columns = cols
            .iter()
            .map(|&j| {
                let mut c = self.columns[j].clone();
                c.param = used.binary_search(&c.param).expect("kept parameter");
                c
            })
            .collect();
        let params = used.iter().map(|&p| self.params[p].clone()).collect();
        self.with_columns(params, columns)
    }

    /// Checks that `chunk` can be assembled with this structure.
    pub fn check_chunk(&self, chunk: &SampleChunk) -> Result<(), ModelError> {
        crate::source::check_lengths(chunk)
            .map_err(|(signal, problem)| ModelError::ChunkShape { signal, problem })?;
        if chunk.rotor_count() != self.rotor_count {
            return Err(ModelError::RotorCountMismatch {
                expected: self.rotor_count,
                found: chunk.rotor_count(),
            });
        }
        if self.needs_omega_dot() && !chunk.has_omega_dot() {
            return Err(ModelError::MissingRotorAcceleration);
        }
        if self.required.contains(&Signal::DrDDot) && !chunk.has_omega_ddot() {
            return Err(ModelError::MissingRotorAccelerationRate);
        }
        let per_rotor_ground = self
            .required
            .iter()
            .any(|s| matches!(s, Signal::RotorGroundEffect(_)));
        let needs_height = per_rotor_ground || self.required.contains(&Signal::GroundEffect);
        if needs_height && chunk.height.len() != chunk.len() {
            return Err(ModelError::MissingHeight);
        }
        let needs_attitude = per_rotor_ground
            || self
                .required
                .iter()
                .any(|s| matches!(s, Signal::NedToBody(_)));
        if needs_attitude && chunk.attitude[0].len() != chunk.len() {
            return Err(ModelError::MissingAttitude);
        }
        Ok(())
    }

    /// Assembles all regressor columns and the known-term-corrected outputs of `chunk`
    /// into `ws` (column-major, reused across chunks; allocates only when a chunk is
    /// longer than any before).
    pub fn assemble(&self, chunk: &SampleChunk, ws: &mut Workspace) -> Result<(), ModelError> {
        self.assemble_columns(chunk, ws, None, &[])
    }

    /// [`Self::assemble`] of the columns j with `wanted[j]` only (and all outputs); the
    /// other columns of `ws` are left unspecified. For an accumulator, which reads one
    /// column of each shape (`wanted` shorter than the columns assembles them all).
    pub(crate) fn assemble_wanted(
        &self,
        chunk: &SampleChunk,
        ws: &mut Workspace,
        wanted: &[bool],
    ) -> Result<(), ModelError> {
        let wanted = (wanted.len() == self.columns.len()).then_some(wanted);
        self.assemble_columns(chunk, ws, wanted, &[])
    }

    /// How [`Self::assemble_reusing`] computes the columns j with `wanted[j]` (one entry
    /// per column): runs of terms that are an earlier wanted column's terms, as they are
    /// or times one more signal (a rotor's thrust terms times its wake factor), as one
    /// product each.
    pub(crate) fn reuse_plan(&self, wanted: &[bool]) -> Vec<Option<Reuse>> {
        reuse::plan(&self.columns, wanted)
    }

    /// [`Self::assemble_wanted`] by `plan` ([`Self::reuse_plan`] of the same `wanted`):
    /// the same columns to rounding, with fewer products.
    pub(crate) fn assemble_reusing(
        &self,
        chunk: &SampleChunk,
        ws: &mut Workspace,
        wanted: &[bool],
        plan: &[Option<Reuse>],
    ) -> Result<(), ModelError> {
        assert!(
            wanted.len() == self.columns.len() && plan.len() == wanted.len(),
            "a reuse plan of this structure"
        );
        self.assemble_columns(chunk, ws, Some(wanted), plan)
    }

    fn assemble_columns(
        &self,
        chunk: &SampleChunk,
        ws: &mut Workspace,
        wanted: Option<&[bool]>,
        plan: &[Option<Reuse>],
    ) -> Result<(), ModelError> {
        self.check_chunk(chunk)?;
        let n = chunk.len();
        ws.prepare(n, self.columns.len(), self.required.len());
        let cap = ws.capacity;
        for (slot, &s) in self.required.iter().enumerate() {
            if !s.is_direct() {
                let dst = &mut ws.signals[slot * cap..slot * cap + n];
                self.constants.compute(s, chunk, dst);
            }
        }
        let Workspace {
            signals,
            columns,
            outputs,
            measured,
            motion,
            ..
        } = ws;
        let range = |v: &[f64]| range_of_slice(&v[..n.min(v.len())]);
        for k in 0..3 {
            motion[k] = range(&chunk.velocity[k]);
            motion[3 + k] = range(&chunk.rates[k]);
        }
        let required = &self.required;
        let lookup = |s: Signal| {
            let slot = required.binary_search(&s).expect("required signal");
            signal_slice(s, chunk, signals, slot * cap, n)
        };
        crate::util::vectorized(AssembleColumns {
            columns: &self.columns,
            wanted,
            plan,
            dst: columns,
            cap,
            n,
            lookup: &lookup,
        });
        for axis in Axis::ALL {
            let a = axis as usize;
            let dst = &mut outputs[a * cap..a * cap + n];
            // A chunk without measured outputs (prediction only) counts them as zero.
            match chunk.wrench[a].get(..n) {
                Some(z) => dst.copy_from_slice(z),
                None => dst.fill(0.0),
            }
            measured[a] = range_of_slice(dst);
            for t in &self.known[a] {
                apply_term(dst, t, false, -1.0, &lookup);
            }
        }
        Ok(())
    }

    /// Model output ŷ = Σ `θ[param]` · column for one sample, plus the known terms:
    /// `[F_x, F_y, F_z, M_x, M_y, M_z]` in N and N m.
    pub fn predict(&self, theta: &[f64], sample: &Sample) -> Result<[f64; 6], ModelError> {
        let mut chunk =
            SampleChunk::with_capacity(sample.omega.len(), 1, !sample.omega_dot.is_empty());
        chunk.push(sample);
        let mut ws = Workspace::default();
        let y = self.predict_chunk(theta, &chunk, &mut ws)?;
        Ok(y.map(|v| v[0]))
    }

    /// Model output of every sample of `chunk` per axis (N, N m), `ws` as scratch space.
    pub fn predict_chunk(
        &self,
        theta: &[f64],
        chunk: &SampleChunk,
        ws: &mut Workspace,
    ) -> Result<[Vec<f64>; 6], ModelError> {
        self.check_theta(theta)?;
        self.assemble(chunk, ws)?;
        Ok(self.predict_assembled(theta, chunk, ws))
    }

    /// Model output of every sample of `chunk` whose regressors `ws` holds (assembled by
    /// this structure): Σ θ x over the axis' columns plus the known terms (the measured
    /// output less the known-term-corrected one). The one prediction routine of the
    /// crate.
    pub fn predict_assembled(
        &self,
        theta: &[f64],
        chunk: &SampleChunk,
        ws: &Workspace,
    ) -> [Vec<f64>; 6] {
        Axis::ALL.map(|axis| {
            let a = axis as usize;
            let mut y: Vec<f64> = chunk.wrench[a]
                .iter()
                .zip(ws.output(axis))
                .map(|(z, c)| z - c)
                .collect();
            for j in self.axis_columns(axis) {
                let th = theta[self.columns[j].param];
                y.iter_mut()
                    .zip(ws.column(j))
                    .for_each(|(o, x)| *o += th * x);
            }
            y
        })
    }

    /// θ holds one value per parameter.
    fn check_theta(&self, theta: &[f64]) -> Result<(), ModelError> {
        if theta.len() == self.params.len() {
            Ok(())
        } else {
            Err(ModelError::ParameterCount {
                expected: self.params.len(),
                found: theta.len(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::{MassAndRotorProperties, Preset, Vehicle};

    fn quad() -> Vehicle {
        let props = MassAndRotorProperties {
            mass: 1.0,
            inertia: [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.02]],
            air_density: 1.2,
            rotor_radius: 0.1,
            hub_height: 0.05,
            rotor_inertia: 0.0,
        };
        Vehicle::preset("q", Preset::QuadX, 0.25, 1.0, props).unwrap()
    }

    #[test]
    fn candidate_signals_evaluate_as_documented() {
        use Signal::*;
        let v = quad();
        let mut s = ModelStructure::eq22(&v, ModelOptions::default());
        let extra = |axis, label: &str, terms| Column {
            axis,
            param: 0,
            label: label.into(),
            terms,
        };
        let x = s.add_parameter(
            Parameter {
                name: "x".into(),
                unit: "-".into(),
            },
            vec![
                extra(Axis::Fx, "u|u|", vec![term(1.0, &[U, AbsU])]),
                extra(Axis::Fz, "W3^2", vec![term(2.0, &[RotorSpeedSquared(2)])]),
                extra(
                    Axis::My,
                    "d2e_dot",
                    vec![term(1.0, &[SquaredActuatorRate(2)])],
                ),
                extra(
                    Axis::Mz,
                    "g*W1_dot",
                    vec![term(1.0, &[GroundEffect, RotorAcceleration(0)])],
                ),
            ],
        );
        let sample = Sample {
            velocity: [-3.0, 1.0, 0.5],
            omega: vec![100.0, 200.0, 300.0, 400.0],
            omega_dot: vec![10.0, 20.0, 30.0, 40.0],
            height: Some(0.1),
            ..Sample::default()
        };
        let mut chunk = SampleChunk::with_capacity(4, 1, true);
        chunk.push(&sample);
        let mut ws = Workspace::default();
        s.assemble(&chunk, &mut ws).unwrap();
        let value = |label: &str| {
            let j = (0..s.columns.len())
                .find(|&j| s.columns[j].param == x && s.columns[j].label == label)
                .unwrap();
            ws.column(j)[0]
        };
        assert_eq!(value("u|u|"), -9.0);
        assert_eq!(value("W3^2"), 2.0 * 300.0 * 300.0);
        // δ̇²e = Σ x_i 2 Ω_i Ω̇_i, x = ℓ/√2 (1, −1, −1, 1).
        let arm = 0.25 / 2f64.sqrt();
        let expect = arm * 2.0 * (100.0 * 10.0 - 200.0 * 20.0 - 300.0 * 30.0 + 400.0 * 40.0);
        assert!((value("d2e_dot") - expect).abs() < 1e-9 * expect.abs());
        // Rotor plane 0.15 m up, R = 0.1: s = (0.1/0.6)² = 1/36, g = s/(1 − s) = 1/35.
        assert!((value("g*W1_dot") - 10.0 / 35.0).abs() < 1e-12);
        // Wake and vortex-ring onset: rear rotors sit in the front rotors' wakes in
        // forward flight; descent at ν0 in hover is the centre of the vortex-ring bump.
        let nu0 = v.hover_induced_velocity();
        let fwd = Sample {
            velocity: [10.0, 0.0, nu0],
            omega: vec![100.0; 4],
            omega_dot: vec![0.0; 4],
            height: Some(1.0),
            ..Sample::default()
        };
        let mut c2 = SampleChunk::with_capacity(4, 1, true);
        c2.push(&fwd);
        let y = s.add_parameter(
            Parameter {
                name: "y".into(),
                unit: "-".into(),
            },
            vec![
                extra(Axis::Fz, "wake1", vec![term(1.0, &[WakeImmersion(0)])]),
                extra(Axis::Fz, "wake2", vec![term(1.0, &[WakeImmersion(1)])]),
                extra(Axis::Fz, "vrs1", vec![term(1.0, &[VortexRing(0)])]),
            ],
        );
        s.assemble(&c2, &mut ws).unwrap();
        let col = |label: &str| {
            let j = (0..s.columns.len())
                .find(|&j| s.columns[j].param == y && s.columns[j].label == label)
                .unwrap();
            ws.column(j)[0]
        };
        assert_eq!(col("wake1"), 0.0, "front-right rotor is upstream");
        assert!((col("wake2") - 100.0 / (100.0 + nu0 * nu0)).abs() < 1e-12);
        let vrs = (-(10.0 / nu0).powi(2)).exp();
        assert!((col("vrs1") - vrs).abs() < 1e-12);
        // Without a height signal the ground-effect column cannot be built.
        let mut no_height = chunk.clone();
        no_height.height.clear();
        assert_eq!(
            s.assemble(&no_height, &mut ws),
            Err(ModelError::MissingHeight)
        );
    }

    /// Three-factor terms are summed in one pass with the products of the pairwise fold
    /// ((c·x)·y)·z, bit for bit; an assembly of the wanted columns gives the same bits in
    /// those columns and the same outputs.
    /// A column made of an earlier column's terms times a signal (a rotor's thrust times
    /// its wake factor), or of an earlier column's terms as they are (M_z from the F_x and
    /// F_y in-plane force columns), is assembled from that column, with the same values to
    /// rounding; a run whose coefficients are not proportional, or an earlier column not
    /// assembled, is not reused.
    #[test]
    fn columns_reusing_earlier_columns_assemble_to_rounding() {
        use Signal::*;
        let v = quad();
        let mut s = ModelStructure::eq22(&v, ModelOptions::default());
        let column = |label: &str, terms: Vec<Term>| Column {
            axis: Axis::Fz,
            param: 0,
            label: label.into(),
            terms,
        };
        let a = vec![term(2.0, &[U, W]), term(3.0, &[V])];
        let times_p = vec![term(4.0, &[U, W, P]), term(6.0, &[V, P]), term(1.5, &[Q])];
        let scaled = vec![term(0.7, &[R]), term(-1.0, &[U, W]), term(-1.5, &[V])];
        let not_proportional = vec![term(4.0, &[U, W, P]), term(7.0, &[V, P])];
        let param = s.add_parameter(
            Parameter {
                name: "x".into(),
                unit: "-".into(),
            },
            vec![
                column("a", a),
                column("a*p + q", times_p),
                column("r - a/2", scaled),
                column("not a*p", not_proportional),
            ],
        );
        let first = (0..s.columns.len())
            .find(|&j| s.columns[j].param == param)
            .expect("the added columns");
        let all = vec![true; s.columns.len()];
        let plan = s.reuse_plan(&all);
        let run = |signal, ratio| reuse::Run {
            column: first,
            signal,
            ratio,
        };
        let reuse = |runs, terms| {
            Some(Reuse {
                runs: vec![runs],
                terms,
            })
        };
        assert_eq!(plan[first + 1], reuse(run(Some(P), 2.0), vec![2]));
        assert_eq!(plan[first + 2], reuse(run(None, -0.5), vec![0]));
        assert_eq!(plan[first + 3], None);
        let mut without_a = all.clone();
        without_a[first] = false;
        assert_eq!(s.reuse_plan(&without_a)[first + 1], None);

        let mut chunk = SampleChunk::with_capacity(4, 64, true);
        for k in 0..64 {
            let f = k as f64;
            chunk.push(&Sample {
                velocity: [0.3 * f - 7.1, 1.0 / (f + 3.0), (0.1 * f).sin()],
                rates: [0.01 * f - 0.2, (0.2 * f).cos(), -0.5],
                omega: vec![400.0 + 3.7 * f; 4],
                omega_dot: vec![1.0; 4],
                ..Sample::default()
            });
        }
        let (mut terms, mut reused) = (Workspace::default(), Workspace::default());
        s.assemble(&chunk, &mut terms).unwrap();
        s.assemble_reusing(&chunk, &mut reused, &all, &plan)
            .unwrap();
        for (j, how) in plan.iter().enumerate() {
            let (x, y) = (terms.column(j), reused.column(j));
            // The same terms summed in another order: a few roundings of the largest.
            let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..64 {
                assert!(
                    (x[k] - y[k]).abs() <= 8.0 * f64::EPSILON * scale,
                    "column {j}, sample {k}"
                );
            }
            if how.is_none() {
                assert_eq!(x, y, "column {j} is assembled term by term");
            }
        }
    }

    #[test]
    fn three_factor_terms_and_wanted_columns_assemble_exactly() {
        use Signal::*;
        let v = quad();
        let mut s = ModelStructure::eq22(&v, ModelOptions::default());
        let param = s.add_parameter(
            Parameter {
                name: "x".into(),
                unit: "-".into(),
            },
            vec![Column {
                axis: Axis::Fz,
                param: 0,
                label: "u*v*w + 3 p*q*W1".into(),
                terms: vec![term(0.7, &[U, V, W]), term(3.0, &[P, Q, RotorSpeed(0)])],
            }],
        );
        let p = (0..s.columns.len())
            .find(|&j| s.columns[j].param == param)
            .expect("the added column");
        let mut chunk = SampleChunk::with_capacity(4, 64, true);
        for k in 0..64 {
            let f = k as f64;
            chunk.push(&Sample {
                velocity: [0.3 * f - 7.1, 1.0 / (f + 3.0), (0.1 * f).sin()],
                rates: [0.01 * f, (0.2 * f).cos(), -0.5],
                omega: vec![400.0 + 3.7 * f; 4],
                omega_dot: vec![1.0; 4],
                ..Sample::default()
            });
        }
        let mut ws = Workspace::default();
        s.assemble(&chunk, &mut ws).unwrap();
        for k in 0..64 {
            let u: [f64; 3] = std::array::from_fn(|a| chunk.velocity[a][k]);
            let r: [f64; 3] = std::array::from_fn(|a| chunk.rates[a][k]);
            let first = 0.7 * u[0] * u[1] * u[2];
            let expected = first + 3.0 * r[0] * r[1] * chunk.omega[0][k];
            assert_eq!(ws.column(p)[k].to_bits(), expected.to_bits(), "sample {k}");
        }
        let wanted: Vec<bool> = (0..s.columns.len()).map(|j| j % 3 != 1).collect();
        let mut part = Workspace::default();
        s.assemble_wanted(&chunk, &mut part, &wanted).unwrap();
        for (j, _) in wanted.iter().enumerate().filter(|(_, w)| **w) {
            assert_eq!(part.column(j), ws.column(j), "column {j}");
        }
        for axis in Axis::ALL {
            assert_eq!(part.output(axis), ws.output(axis));
        }
    }
}
