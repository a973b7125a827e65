//! One sample from raw slot values to a [`Row`]: actuator map, units to SI, finite and
//! physical-range checks, then axes to body FRD and world NED.

use super::super::MAX_ROTORS;
use super::super::derive::{body_velocity, matrix_to_quat};
use super::super::error::{self, ErrorKind, IoError, Location};
use super::super::mapping::{ActuatorMap, AxisMap, Mapping, Signal};
use super::super::slots::SlotLayout;
use super::super::validate::{QUATERNION_NORM_TOLERANCE, physical_range};
use super::plan::VehicleFacts;
use crate::util::quat_to_matrix;

/// One converted sample (SI, FRD/NED) inside the look-ahead window.
#[derive(Debug, Clone, Copy)]
pub(super) struct Row {
    pub loc: Location,
    pub t: f64,
    pub velocity: [f64; 3],
    pub rates: [f64; 3],
    pub ang_acc: [f64; 3],
    pub omega: [f64; MAX_ROTORS],
    pub omega_dot: [f64; MAX_ROTORS],
    /// Commanded rotor speeds (actuator map), before the motor lag.
    pub command: [f64; MAX_ROTORS],
    pub force: [f64; 3],
    pub moment: [f64; 3],
    pub specific_force: [f64; 3],
    pub height: f64,
    pub attitude: [f64; 4],
}

impl Default for Row {
    fn default() -> Self {
        Self {
            loc: Location::File,
            t: 0.0,
            velocity: [0.0; 3],
            rates: [0.0; 3],
            ang_acc: [0.0; 3],
            omega: [0.0; MAX_ROTORS],
            omega_dot: [0.0; MAX_ROTORS],
            command: [0.0; MAX_ROTORS],
            force: [0.0; 3],
            moment: [0.0; 3],
            specific_force: [0.0; 3],
            height: 0.0,
            attitude: [1.0, 0.0, 0.0, 0.0],
        }
    }
}

/// Turns the raw slot values of a sample into a [`Row`].
pub(super) struct Converter {
    /// Where each signal sits among the slots, with its unit factor.
    pub layout: SlotLayout,
    /// The log's body axes → FRD.
    body: AxisMap,
    /// The log's world axes → NED.
    world: AxisMap,
    /// Physical range of each slot (SI), with its text for errors.
    ranges: Vec<Option<(f64, f64, String)>>,
    /// The raw values of the sample being converted, one per slot.
    pub raw: Vec<f64>,
    /// Actuator outputs mapped to rotor speeds, when the mapping says so.
    pub actuator: Option<ActuatorMap>,
    rotors: usize,
    /// Fields are labelled `topic.field` (MCAP, ULog) rather than CSV columns.
    topics: bool,
}

impl Converter {
    /// The converter of a log of `layout` read with `mapping` for a vehicle of `facts`;
    /// `topics` when fields are named by topic (MCAP, ULog).
    pub fn new(layout: SlotLayout, mapping: &Mapping, facts: &VehicleFacts, topics: bool) -> Self {
        let actuator = mapping
            .get(Signal::RotorSpeeds)
            .and_then(|m| m.actuator)
            .filter(|_| layout.has(Signal::RotorSpeeds));
        let ranges = (0..layout.len())
            .map(|s| physical_range(layout.signal_of_slot(s), facts.mass, facts.arm))
            .collect();
        Self {
            raw: vec![0.0; layout.len()],
            body: mapping.frames.body.to_frd(),
            world: mapping.frames.world.to_ned(),
            layout,
            ranges,
            actuator,
            rotors: facts.rotors,
            topics,
        }
    }

    /// The label of slot `slot` in errors: its column, or `topic.field`.
    pub fn label(&self, slot: usize) -> Option<String> {
        let name = self.layout.source_name(slot);
        if self.topics {
            error::field(&format!(
                "{}.{}",
                self.layout.topic(slot).unwrap_or(""),
                name
            ))
        } else {
            error::column(name)
        }
    }

    /// The label of the log's time in errors.
    pub fn time_label(&self) -> Option<String> {
        match self.layout.start(Signal::Time) {
            Some(slot) => self.label(slot),
            None => error::field("log time"),
        }
    }

    /// Converts and checks the values in `raw` (sample at `loc` of `file`, at
    /// `source_time` when the source gives it) into `row`.
    pub fn row(
        &mut self,
        file: &str,
        loc: Location,
        source_time: Option<f64>,
        row: &mut Row,
    ) -> Result<(), IoError> {
        if let (Some(a), Some(start)) = (&self.actuator, self.layout.start(Signal::RotorSpeeds)) {
            for v in &mut self.raw[start..start + self.rotors] {
                if v.is_finite() {
                    *v = a.speed(*v);
                }
            }
        }
        for slot in 0..self.raw.len() {
            let v = self.raw[slot] * self.layout.factor(slot);
            if !v.is_finite() {
                return Err(IoError::new(
                    file,
                    loc,
                    self.label(slot),
                    ErrorKind::NotFinite(self.raw[slot]),
                ));
            }
            self.raw[slot] = v;
            if let Some((lo, hi, text)) = &self.ranges[slot]
                && !(*lo..=*hi).contains(&v)
            {
                return Err(IoError::new(
                    file,
                    loc,
                    self.label(slot),
                    ErrorKind::OutOfRange {
                        value: v,
                        range: text.clone(),
                    },
                ));
            }
        }
        *row = Row {
            loc,
            t: source_time.unwrap_or(0.0),
            ..Row::default()
        };
        self.convert(row)
            .map_err(|(slot, kind)| IoError::new(file, loc, self.label(slot), kind))
    }

    /// Slot values (already SI) → row in FRD/NED.
    fn convert(&self, row: &mut Row) -> Result<(), (usize, ErrorKind)> {
        let l = &self.layout;
        let raw = &self.raw;
        let vec3 = |s: Signal| l.start(s).map(|i| [raw[i], raw[i + 1], raw[i + 2]]);
        row.t = match l.start(Signal::Time) {
            Some(i) => raw[i],
            None => row.t,
        };
        if let Some(i) = l.start(Signal::Attitude) {
            let q = [raw[i], raw[i + 1], raw[i + 2], raw[i + 3]];
            let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
                return Err((
                    i,
                    ErrorKind::OutOfRange {
                        value: norm,
                        range: format!(
                            "1 ± {QUATERNION_NORM_TOLERANCE} (norm of the attitude quaternion)"
                        ),
                    },
                ));
            }
            row.attitude = self.attitude_to_ned(q);
        }
        if let Some(v) = vec3(Signal::VelocityBody) {
            row.velocity = self.body.apply(v);
        } else if let Some(v) = vec3(Signal::VelocityWorld) {
            row.velocity = body_velocity(row.attitude, self.world.apply(v));
        }
        let body = |s: Signal, dst: &mut [f64; 3]| {
            if let Some(v) = vec3(s) {
                *dst = self.body.apply(v);
            }
        };
        body(Signal::Rates, &mut row.rates);
        body(Signal::AngularAcceleration, &mut row.ang_acc);
        body(Signal::Force, &mut row.force);
        body(Signal::Moment, &mut row.moment);
        body(Signal::SpecificForce, &mut row.specific_force);
        let n = self.rotors;
        if let Some(i) = l.start(Signal::RotorSpeeds) {
            row.omega[..n].copy_from_slice(&raw[i..i + n]);
            row.command = row.omega;
        }
        if let Some(i) = l.start(Signal::RotorAccelerations) {
            row.omega_dot[..n].copy_from_slice(&raw[i..i + n]);
        }
        if let Some(i) = l.start(Signal::Height) {
            row.height = raw[i];
        }
        Ok(())
    }

    /// Attitude body→world of the log → body FRD → world NED: R' = W R Bᵀ.
    fn attitude_to_ned(&self, q: [f64; 4]) -> [f64; 4] {
        let identity = AxisMap {
            perm: [0, 1, 2],
            sign: [1.0; 3],
        };
        if self.body == identity && self.world == identity {
            return if q[0] < 0.0 { q.map(|c| -c) } else { q };
        }
        let r = quat_to_matrix(q);
        let w = self.world.matrix();
        let b = self.body.matrix();
        let mut out = [[0.0; 3]; 3];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                let mut s = 0.0;
                for k in 0..3 {
                    for m in 0..3 {
                        s += w[i][k] * r[k][m] * b[j][m];
                    }
                }
                *v = s;
            }
        }
        matrix_to_quat(&out)
    }
}
