//! [`ModelStructure`]: the parameters, the regressor columns per axis and the known terms
//! of one vehicle's model, what a chunk must carry to be assembled ([`ModelError`]), and
//! the structure's edits (candidate parameters added, parameters or columns kept).

use super::evaluate::SignalConstants;
use super::{Column, ModelOptions, ParamId, Parameter, Signal, Term};
use crate::sample::{Axis, SampleChunk};

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
    /// The model has a trim-moment term but the data has no slow rotor thrust.
    #[error(
        "the model needs the slow part of the rotor thrust (a trim-moment term) but the data has none; it is derived from the rotor speeds of a whole log by the fit pipeline, so it cannot be predicted sample by sample"
    )]
    MissingSlowThrust,
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

/// Where a parameter of [`ModelStructure::with_axes_of`]'s result takes its value from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamOrigin {
    /// This parameter of the structure `with_axes_of` was called on.
    Own(ParamId),
    /// This parameter of the other structure (copied to one axis).
    Other(ParamId),
}

impl ParamOrigin {
    /// The value of the parameter: from `own` (θ of the structure `with_axes_of` was
    /// called on) or `other` (θ of the other structure).
    pub fn value(self, own: &[f64], other: &[f64]) -> f64 {
        match self {
            Self::Own(p) => own[p.index()],
            Self::Other(p) => other[p.index()],
        }
    }
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
    pub(super) required: Vec<Signal>,
    /// The vehicle constants the computed signals use.
    pub(super) constants: SignalConstants,
}

impl ModelStructure {
    /// A structure of `params` and `columns` (whose `param` ids point into `params`)
    /// with `known` terms, for a vehicle of `rotor_count` rotors whose signals use
    /// `constants`.
    pub(super) fn from_parts(
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

    /// The parameter called `name`.
    pub fn param_id(&self, name: &str) -> Option<ParamId> {
        self.params
            .iter()
            .position(|p| p.name == name)
            .map(ParamId::new)
    }

    /// Every parameter, in [`ModelStructure::params`] order.
    pub fn param_ids(&self) -> impl Iterator<Item = ParamId> + use<> {
        (0..self.params.len()).map(ParamId::new)
    }

    /// The parameter `id`.
    pub fn param(&self, id: ParamId) -> &Parameter {
        &self.params[id.index()]
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

    /// Appends a parameter with its columns (e.g. a candidate effect); returns it.
    /// Columns' `param` fields are overwritten with the new parameter.
    pub fn add_parameter(&mut self, param: Parameter, mut columns: Vec<Column>) -> ParamId {
        let id = ParamId::new(self.params.len());
        self.params.push(param);
        for c in &mut columns {
            c.param = id;
        }
        self.columns.extend(columns);
        self.columns.sort_by_key(|c| c.axis);
        self.required = self.collect_required_signals();
        id
    }

    /// The structure restricted to parameters `keep` (in the order given) and their
    /// columns; also returns, for each kept column, its index in `self.columns`.
    pub fn subset(&self, keep: &[ParamId]) -> (ModelStructure, Vec<usize>) {
        let cols: Vec<usize> = (0..self.columns.len())
            .filter(|&j| keep.contains(&self.columns[j].param))
            .collect();
        let columns = cols
            .iter()
            .map(|&j| {
                let mut c = self.columns[j].clone();
                let at = keep.iter().position(|&p| p == c.param);
                c.param = ParamId::new(at.expect("kept parameter"));
                c
            })
            .collect();
        let params = keep.iter().map(|&p| self.param(p).clone()).collect();
        (self.with_columns(params, columns), cols)
    }

    /// This structure's vehicle, options and known terms with `params` and `columns`
    /// (whose `param` ids point into `params`) instead of its own.
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
        let mut used: Vec<ParamId> = cols.iter().map(|&j| self.columns[j].param).collect();
        used.sort_unstable();
        used.dedup();
        let columns = cols
            .iter()
            .map(|&j| {
                let mut c = self.columns[j].clone();
                let at = used.binary_search(&c.param);
                c.param = ParamId::new(at.expect("kept parameter"));
                c
            })
            .collect();
        let params = used.iter().map(|&p| self.param(p).clone()).collect();
        self.with_columns(params, columns)
    }

    /// This structure with its columns on `axes` replaced by `other`'s columns there:
    /// each parameter of `other` with a column on one of `axes` becomes a parameter of its
    /// own on that axis, named `name(parameter name, axis)`, so that with the values the
    /// returned origins point to the result predicts `axes` as `other` and every other
    /// axis as this structure. Parameters left with no column are dropped; the rest keep
    /// this structure's order, the copies follow in `axes` order. `other` must be built
    /// for the same vehicle and options (the known terms are this structure's).
    pub fn with_axes_of(
        &self,
        other: &ModelStructure,
        axes: &[Axis],
        name: impl Fn(&str, Axis) -> String,
    ) -> (ModelStructure, Vec<ParamOrigin>) {
        let own: Vec<usize> = (0..self.columns.len())
            .filter(|&j| !axes.contains(&self.columns[j].axis))
            .collect();
        let mut used: Vec<ParamId> = own.iter().map(|&j| self.columns[j].param).collect();
        used.sort_unstable();
        used.dedup();
        let mut structure = self.select_columns(&own);
        let mut origins: Vec<ParamOrigin> = used.into_iter().map(ParamOrigin::Own).collect();
        for &axis in axes {
            for p in other.param_ids() {
                let columns: Vec<Column> = (other.columns.iter())
                    .filter(|c| c.axis == axis && c.param == p)
                    .cloned()
                    .collect();
                if columns.is_empty() {
                    continue;
                }
                let param = Parameter {
                    name: name(&other.param(p).name, axis),
                    unit: other.param(p).unit.clone(),
                };
                structure.add_parameter(param, columns);
                origins.push(ParamOrigin::Other(p));
            }
        }
        (structure, origins)
    }

    /// True when a column needs the slow rotor thrusts (a trim-moment term), which only
    /// a whole log's time series gives.
    pub fn needs_slow_thrust(&self) -> bool {
        self.required
            .iter()
            .any(|s| matches!(s, Signal::SlowSquaredActuator(..)))
    }

    /// Checks that `chunk` can be assembled with this structure.
    pub fn check_chunk(&self, chunk: &SampleChunk) -> Result<(), ModelError> {
        chunk.check_lengths().map_err(|e| ModelError::ChunkShape {
            signal: e.signal,
            problem: e.problem,
        })?;
        if chunk.rotor_count() != self.rotor_count {
            return Err(ModelError::RotorCountMismatch {
                expected: self.rotor_count,
                found: chunk.rotor_count(),
            });
        }
        if self.needs_omega_dot() && chunk.omega_dot.is_none() {
            return Err(ModelError::MissingRotorAcceleration);
        }
        if self.required.contains(&Signal::DrDDot) && chunk.omega_ddot.is_none() {
            return Err(ModelError::MissingRotorAccelerationRate);
        }
        if self.needs_slow_thrust() && chunk.omega_squared_slow.is_none() {
            return Err(ModelError::MissingSlowThrust);
        }
        let per_rotor_ground = self.required.iter().any(|s| {
            matches!(
                s,
                Signal::RotorGroundEffect(_) | Signal::MultirotorGroundEffect(_)
            )
        });
        let needs_height = per_rotor_ground || self.required.contains(&Signal::GroundEffect);
        if needs_height && chunk.height.is_none() {
            return Err(ModelError::MissingHeight);
        }
        let needs_attitude = per_rotor_ground
            || self
                .required
                .iter()
                .any(|s| matches!(s, Signal::NedToBody(_)));
        if needs_attitude && chunk.attitude.is_none() {
            return Err(ModelError::MissingAttitude);
        }
        Ok(())
    }
}
