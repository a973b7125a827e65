//! The mapping file (TOML): which column (CSV) or topic and field (MCAP) holds each
//! signal, its unit, the log's body and world axis conventions and the rotor numbering.
//!
//! ```toml
//! [frames]
//! body = "flu"          # frd | flu
//! world = "nwu"         # ned | enu | nwu (z-up, x forward)
//! [time]
//! columns = ["t"]
//! unit = "s"
//! [signals.rates]
//! columns = ["ang vel x", "ang vel y", "ang vel z"]
//! unit = "rad/s"
//! [signals.rotor_speeds]          # listed in vehicle rotor order 1..N
//! columns = ["mot 1", "mot 2", "mot 3", "mot 4"]
//! unit = "rad/s"
//! ```
//!
//! The format is documented in `docs/mapping.md`. Without a mapping file the contract
//! header (`docs/data-contract.md`) is mapped by [`contract_mapping`].

use std::path::Path;

use serde::Deserialize;

use super::derive::DeriveOptions;
use super::error::{ErrorKind, IoError, Location, display_name, key};
use super::units::{Dimension, UnitError, unit_for};

/// Body axis convention of a log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum BodyFrame {
    /// Front-right-down (the product's convention).
    #[default]
    Frd,
    /// Front-left-up: y and z flip to reach FRD.
    Flu,
}

/// World axis convention of a log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum WorldFrame {
    /// North-east-down (the product's convention).
    #[default]
    Ned,
    /// East-north-up: x and y swap, z flips.
    Enu,
    /// x forward/north, y left/west, z up: y and z flip.
    Nwu,
}

/// A proper rotation that only permutes and flips axes, so conversion is exact:
/// `out[k] = sign[k] * in[perm[k]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisMap {
    /// Source component of each output component.
    pub perm: [usize; 3],
    /// Sign of each output component.
    pub sign: [f64; 3],
}

impl AxisMap {
    /// Applies the map to a vector.
    pub fn apply(&self, v: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|k| self.sign[k] * v[self.perm[k]])
    }

    /// The rotation matrix (row k has `sign[k]` in column `perm[k]`).
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        let mut m = [[0.0; 3]; 3];
        for k in 0..3 {
            m[k][self.perm[k]] = self.sign[k];
        }
        m
    }
}

impl BodyFrame {
    /// Map from this frame's components to FRD components.
    pub(crate) fn to_frd(self) -> AxisMap {
        match self {
            Self::Frd => AxisMap {
                perm: [0, 1, 2],
                sign: [1.0, 1.0, 1.0],
            },
            Self::Flu => AxisMap {
                perm: [0, 1, 2],
                sign: [1.0, -1.0, -1.0],
            },
        }
    }
}

impl WorldFrame {
    /// Map from this frame's components to NED components.
    pub(crate) fn to_ned(self) -> AxisMap {
        match self {
            Self::Ned => AxisMap {
                perm: [0, 1, 2],
                sign: [1.0, 1.0, 1.0],
            },
            Self::Enu => AxisMap {
                perm: [1, 0, 2],
                sign: [1.0, 1.0, -1.0],
            },
            Self::Nwu => AxisMap {
                perm: [0, 1, 2],
                sign: [1.0, -1.0, -1.0],
            },
        }
    }
}

/// Axis conventions of the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Frames {
    /// Body axes of every body vector in the log.
    #[serde(default)]
    pub body: BodyFrame,
    /// World axes of world vectors and of the attitude quaternion (body→world).
    #[serde(default)]
    pub world: WorldFrame,
}

/// Where one signal is in the log.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SignalMap {
    /// CSV column names, one per component, in component order.
    #[serde(default)]
    pub columns: Vec<String>,
    /// MCAP or ULog topic holding the signal; a ULog multi-instance topic is named with
    /// its instance, `actuator_outputs[1]` (instance 0 when absent).
    pub topic: Option<String>,
    /// MCAP or ULog field paths inside the message (`angular_velocity.x`,
    /// `esc[2].esc_rpm`), one per component.
    #[serde(default)]
    pub fields: Vec<String>,
    /// Unit of the logged values (the names of `docs/mapping.md`); SI when absent.
    pub unit: Option<String>,
    /// Motor pole pairs, for unit `erpm`.
    pub pole_pairs: Option<f64>,
    /// Rotor speeds only: the mapped fields are commanded actuator outputs (PWM or
    /// normalised), turned into rotor speeds by this map. The model is then identified on
    /// commanded, not measured, rotor speeds.
    pub actuator: Option<ActuatorMap>,
}

/// How commanded actuator outputs become rotor speeds when a log has no rotor-speed
/// telemetry: command u = (x − pwm_min)/(pwm_max − pwm_min) clamped to [0, 1] (x itself
/// when no PWM range is given), thrust fraction (1 − f) u + f u² with PX4's thrust-curve
/// factor f = `THR_MDL_FAC`, rotor speed Ω = `max_speed` · √(thrust fraction), optionally
/// lagged by a first-order motor model with time constant τ.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActuatorMap {
    /// Output at zero command (PWM, µs, e.g. 1000); absent for outputs normalised to 0..1.
    pub pwm_min: Option<f64>,
    /// Output at full command (PWM, µs, e.g. 2000).
    pub pwm_max: Option<f64>,
    /// Rotor speed at full command, in the signal's `unit` (rad/s when absent).
    pub max_speed: f64,
    /// PX4's `THR_MDL_FAC` f in [0, 1] (0: thrust linear in the command, rotor speed ∝ √u;
    /// 1: thrust quadratic, rotor speed ∝ u). Default 0.
    #[serde(default)]
    pub thr_mdl_fac: f64,
    /// First-order motor time constant τ, s: the rotor speed follows the command with
    /// Ω̇ = (Ω_cmd − Ω)/τ, restarted at the command at each segment start.
    pub time_constant: Option<f64>,
}

impl ActuatorMap {
    /// Checks the ranges; the error names the offending key.
    pub(crate) fn check(&self) -> Result<(), SignalMapError> {
        match (self.pwm_min, self.pwm_max) {
            (Some(lo), Some(hi)) if lo.is_finite() && hi.is_finite() && lo < hi => {}
            (None, None) => {}
            (pwm_min, pwm_max) => return Err(SignalMapError::PwmRange { pwm_min, pwm_max }),
        }
        if !(self.max_speed.is_finite() && self.max_speed > 0.0) {
            return Err(SignalMapError::MaxSpeed {
                max_speed: self.max_speed,
            });
        }
        if !(0.0..=1.0).contains(&self.thr_mdl_fac) {
            return Err(SignalMapError::ThrMdlFac {
                thr_mdl_fac: self.thr_mdl_fac,
            });
        }
        if let Some(tau) = self.time_constant
            && !(tau.is_finite() && tau > 0.0)
        {
            return Err(SignalMapError::TimeConstant { time_constant: tau });
        }
        Ok(())
    }

    /// Commanded rotor speed of actuator output `x`, in the signal's unit.
    pub(crate) fn speed(&self, x: f64) -> f64 {
        let u = match (self.pwm_min, self.pwm_max) {
            (Some(lo), Some(hi)) => (x - lo) / (hi - lo),
            _ => x,
        }
        .clamp(0.0, 1.0);
        let f = self.thr_mdl_fac;
        self.max_speed * ((1.0 - f) * u + f * u * u).sqrt()
    }

    /// In words, for the reader's summary.
    pub(crate) fn describe(&self) -> String {
        let range = match (self.pwm_min, self.pwm_max) {
            (Some(lo), Some(hi)) => format!("PWM {lo}..{hi}"),
            _ => "normalised 0..1".into(),
        };
        let lag = self
            .time_constant
            .map_or(String::new(), |t| format!(", first-order lag {t} s"));
        format!(
            "rotor speeds from COMMANDED actuator outputs ({range}, max speed {}, THR_MDL_FAC {}{lag}): \
             the model is identified on commanded, not measured, rotor speeds",
            self.max_speed, self.thr_mdl_fac
        )
    }
}

/// The signals a log may carry; each optional, the reader says which are missing.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Signals {
    /// Air-relative velocity in body axes (3).
    pub velocity_body: Option<SignalMap>,
    /// Velocity in world axes (3), rotated to body with the attitude.
    pub velocity_world: Option<SignalMap>,
    /// Body rates p, q, r (3).
    pub rates: Option<SignalMap>,
    /// Body angular acceleration (3), used for M = I ω̇ + ω × I ω.
    pub angular_acceleration: Option<SignalMap>,
    /// Rotor speeds, in vehicle rotor order (N).
    pub rotor_speeds: Option<SignalMap>,
    /// Rotor accelerations, in vehicle rotor order (N).
    pub rotor_accelerations: Option<SignalMap>,
    /// Force on the airframe, gravity excluded (3).
    pub force: Option<SignalMap>,
    /// Moment on the airframe (3).
    pub moment: Option<SignalMap>,
    /// Accelerometer specific force (3), for F = m a.
    pub specific_force: Option<SignalMap>,
    /// Height above ground, up (1).
    pub height: Option<SignalMap>,
    /// Attitude quaternion body→world, components listed w, x, y, z (4).
    pub attitude: Option<SignalMap>,
}

/// Options of topic-based logs (the `[mcap]` table serves MCAP and ULog alike).
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct McapOptions {
    /// Topic whose message times form the common time base (default: the rates topic).
    pub time_base: Option<String>,
    /// Per-topic time field overriding `[time]` (e.g. px4 `timestamp` in µs), by topic.
    #[serde(default)]
    pub topic_time: std::collections::BTreeMap<String, TopicTime>,
    /// Largest spacing of the two messages of an asynchronous topic that a time-base
    /// sample is interpolated between, s (default: the reader's `max_gap`). Raise it for
    /// slow topics (a 10 Hz position estimate); logger dropouts are never bridged.
    pub align_gap: Option<f64>,
}

/// The time field of one topic's messages.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TopicTime {
    /// Field path of the time (a number, or a ROS time `{sec, nanosec}`).
    pub field: String,
    /// Unit of a numeric time field (default s).
    pub unit: Option<String>,
}

/// How a log's forces and moments were processed when the log was made, so that the
/// regressors can see the same processing (`[loads]` in a mapping file).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadsProcessing {
    /// The loads were low-passed at this −3 dB cut-off, Hz (> 0): forces and moments from
    /// accelerations through a zero-phase low-pass, or a smoothing spline of about this
    /// bandwidth. The velocity, rates, rotor speeds and rotor accelerations then pass
    /// through the crate's zero-phase low-pass at the same cut-off before the regressors
    /// are built from them (consistent filtering).
    pub low_pass_hz: f64,
}

/// A parsed mapping file.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Mapping {
    /// Axis conventions.
    #[serde(default)]
    pub frames: Frames,
    /// Time column (CSV; MCAP uses message log time when absent).
    pub time: Option<SignalMap>,
    /// Signal locations.
    #[serde(default)]
    pub signals: Signals,
    /// Derivation options, overriding those of the read options.
    pub derive: Option<DeriveOptions>,
    /// How the log's loads were processed when it was made (e.g. smoothed).
    pub loads: Option<LoadsProcessing>,
    /// Options of topic-based logs (MCAP and ULog).
    #[serde(default)]
    pub mcap: McapOptions,
}

/// A signal kind of the sample contract before derivation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Signal {
    /// Time.
    Time,
    /// Body velocity.
    VelocityBody,
    /// World velocity.
    VelocityWorld,
    /// Body rates.
    Rates,
    /// Body angular acceleration.
    AngularAcceleration,
    /// Rotor speeds.
    RotorSpeeds,
    /// Rotor accelerations.
    RotorAccelerations,
    /// Force.
    Force,
    /// Moment.
    Moment,
    /// Specific force.
    SpecificForce,
    /// Height.
    Height,
    /// Attitude quaternion.
    Attitude,
}

impl Signal {
    /// Every signal, in slot order.
    pub const ALL: [Signal; 12] = [
        Self::Time,
        Self::VelocityBody,
        Self::VelocityWorld,
        Self::Rates,
        Self::AngularAcceleration,
        Self::RotorSpeeds,
        Self::RotorAccelerations,
        Self::Force,
        Self::Moment,
        Self::SpecificForce,
        Self::Height,
        Self::Attitude,
    ];

    /// Key in the mapping file.
    pub fn key(self) -> &'static str {
        match self {
            Self::Time => "time",
            Self::VelocityBody => "velocity_body",
            Self::VelocityWorld => "velocity_world",
            Self::Rates => "rates",
            Self::AngularAcceleration => "angular_acceleration",
            Self::RotorSpeeds => "rotor_speeds",
            Self::RotorAccelerations => "rotor_accelerations",
            Self::Force => "force",
            Self::Moment => "moment",
            Self::SpecificForce => "specific_force",
            Self::Height => "height",
            Self::Attitude => "attitude",
        }
    }

    /// Physical dimension.
    pub fn dimension(self) -> Dimension {
        match self {
            Self::Time => Dimension::Time,
            Self::VelocityBody | Self::VelocityWorld => Dimension::Speed,
            Self::Rates | Self::RotorSpeeds => Dimension::AngularRate,
            Self::AngularAcceleration | Self::RotorAccelerations => Dimension::AngularAcceleration,
            Self::Force => Dimension::Force,
            Self::Moment => Dimension::Moment,
            Self::SpecificForce => Dimension::Acceleration,
            Self::Height => Dimension::Length,
            Self::Attitude => Dimension::Dimensionless,
        }
    }

    /// Number of components for a vehicle with `rotors` rotors.
    pub fn components(self, rotors: usize) -> usize {
        match self {
            Self::Time | Self::Height => 1,
            Self::RotorSpeeds | Self::RotorAccelerations => rotors,
            Self::Attitude => 4,
            _ => 3,
        }
    }
}

impl Mapping {
    /// Reads a mapping file; errors name the file and the TOML position.
    pub fn from_toml_file(path: &Path) -> Result<Self, IoError> {
        let name = display_name(path);
        let text = std::fs::read_to_string(path).map_err(|e| {
            IoError::new(&name, Location::File, None, ErrorKind::Read(e.to_string()))
        })?;
        Self::from_toml_str(&text, &name)
    }

    /// Parses mapping TOML text; `name` is the file name used in errors.
    pub fn from_toml_str(text: &str, name: &str) -> Result<Self, IoError> {
        let mapping: Mapping = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| {
                1 + text.as_bytes()[..s.start.min(text.len())]
                    .iter()
                    .filter(|&&b| b == b'\n')
                    .count()
            });
            let loc = line.map_or(Location::File, |l| Location::Line(l as u64));
            IoError::new(
                name,
                loc,
                None,
                ErrorKind::Format(e.message().trim().to_string()),
            )
        })?;
        if let Some(l) = mapping.loads
            && !(l.low_pass_hz.is_finite() && l.low_pass_hz > 0.0)
        {
            return Err(IoError::new(
                name,
                Location::File,
                key("loads.low_pass_hz"),
                ErrorKind::Mapping(format!(
                    "the loads' low-pass cut-off must be a positive number of Hz, not {}",
                    l.low_pass_hz
                )),
            ));
        }
        for signal in Signal::ALL {
            if let Some(map) = mapping.get(signal) {
                check_signal_map(signal, map).map_err(|e| {
                    IoError::new(
                        name,
                        Location::File,
                        key(&key_path(signal)),
                        ErrorKind::Mapping(e.to_string()),
                    )
                })?;
            }
        }
        Ok(mapping)
    }

    /// The location of `signal`, if mapped.
    pub(crate) fn get(&self, signal: Signal) -> Option<&SignalMap> {
        let s = &self.signals;
        match signal {
            Signal::Time => self.time.as_ref(),
            Signal::VelocityBody => s.velocity_body.as_ref(),
            Signal::VelocityWorld => s.velocity_world.as_ref(),
            Signal::Rates => s.rates.as_ref(),
            Signal::AngularAcceleration => s.angular_acceleration.as_ref(),
            Signal::RotorSpeeds => s.rotor_speeds.as_ref(),
            Signal::RotorAccelerations => s.rotor_accelerations.as_ref(),
            Signal::Force => s.force.as_ref(),
            Signal::Moment => s.moment.as_ref(),
            Signal::SpecificForce => s.specific_force.as_ref(),
            Signal::Height => s.height.as_ref(),
            Signal::Attitude => s.attitude.as_ref(),
        }
    }

    fn slot(&mut self, signal: Signal) -> &mut Option<SignalMap> {
        let s = &mut self.signals;
        match signal {
            Signal::Time => &mut self.time,
            Signal::VelocityBody => &mut s.velocity_body,
            Signal::VelocityWorld => &mut s.velocity_world,
            Signal::Rates => &mut s.rates,
            Signal::AngularAcceleration => &mut s.angular_acceleration,
            Signal::RotorSpeeds => &mut s.rotor_speeds,
            Signal::RotorAccelerations => &mut s.rotor_accelerations,
            Signal::Force => &mut s.force,
            Signal::Moment => &mut s.moment,
            Signal::SpecificForce => &mut s.specific_force,
            Signal::Height => &mut s.height,
            Signal::Attitude => &mut s.attitude,
        }
    }

    /// Sets the columns of `signal` (SI units).
    pub(crate) fn set_columns(&mut self, signal: Signal, columns: Vec<String>) {
        *self.slot(signal) = Some(SignalMap {
            columns,
            ..SignalMap::default()
        });
    }

    /// Conversion factor to SI of `signal`'s unit (1 when no unit is given).
    pub(crate) fn factor(&self, signal: Signal) -> f64 {
        self.get(signal)
            .and_then(|m| {
                m.unit
                    .as_ref()
                    .map(|u| unit_for(u, m.pole_pairs, signal.dimension(), signal.key()))
            })
            .and_then(Result::ok)
            .map_or(1.0, |u| u.to_si)
    }
}

fn key_path(signal: Signal) -> String {
    if signal == Signal::Time {
        "time".into()
    } else {
        format!("signals.{}", signal.key())
    }
}

/// Why a signal's table in a mapping file was refused (the error names its key).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SignalMapError {
    /// An `actuator` table on another signal than `rotor_speeds`.
    #[error("`actuator` is only for rotor_speeds")]
    ActuatorNotRotorSpeeds,
    /// One PWM bound without the other, or bounds not finite and increasing.
    #[error(
        "actuator: give both `pwm_min` < `pwm_max` (finite), or neither (got {pwm_min:?}, {pwm_max:?})"
    )]
    PwmRange {
        /// `pwm_min` given.
        pwm_min: Option<f64>,
        /// `pwm_max` given.
        pwm_max: Option<f64>,
    },
    /// A `max_speed` that is not a positive number.
    #[error("actuator: `max_speed` = {max_speed} must be positive")]
    MaxSpeed {
        /// The value given.
        max_speed: f64,
    },
    /// A `thr_mdl_fac` outside [0, 1].
    #[error("actuator: `thr_mdl_fac` = {thr_mdl_fac} must be in [0, 1]")]
    ThrMdlFac {
        /// The value given.
        thr_mdl_fac: f64,
    },
    /// A `time_constant` that is not a positive number of seconds.
    #[error("actuator: `time_constant` = {time_constant} s must be positive")]
    TimeConstant {
        /// The value given, s.
        time_constant: f64,
    },
    /// A unit that is unknown or of another dimension.
    #[error(transparent)]
    Unit(#[from] UnitError),
    /// Neither `columns` nor `fields`.
    #[error("give `columns` (CSV) or `topic` and `fields` (MCAP)")]
    NoColumnsOrFields,
    /// `fields` without a `topic` (only `[time]` may omit it).
    #[error("`fields` needs a `topic`")]
    FieldsWithoutTopic,
    /// A list of names whose length is not the signal's component count.
    #[error("`{list}` lists {listed} names, {signal} needs {needs}")]
    WrongCount {
        /// `columns` or `fields`.
        list: &'static str,
        /// Names listed.
        listed: usize,
        /// The signal's mapping key.
        signal: &'static str,
        /// Components the signal has.
        needs: usize,
    },
}

fn check_signal_map(signal: Signal, map: &SignalMap) -> Result<(), SignalMapError> {
    if let Some(a) = &map.actuator {
        if signal != Signal::RotorSpeeds {
            return Err(SignalMapError::ActuatorNotRotorSpeeds);
        }
        a.check()?;
    }
    if let Some(unit) = &map.unit {
        unit_for(unit, map.pole_pairs, signal.dimension(), signal.key())?;
    }
    if map.columns.is_empty() && map.fields.is_empty() {
        return Err(SignalMapError::NoColumnsOrFields);
    }
    if !map.fields.is_empty() && map.topic.is_none() && signal != Signal::Time {
        return Err(SignalMapError::FieldsWithoutTopic);
    }
    let fixed = signal.components(0);
    for (what, list) in [("columns", &map.columns), ("fields", &map.fields)] {
        if !list.is_empty()
            && !matches!(signal, Signal::RotorSpeeds | Signal::RotorAccelerations)
            && list.len() != fixed
        {
            return Err(SignalMapError::WrongCount {
                list: what,
                listed: list.len(),
                signal: signal.key(),
                needs: fixed,
            });
        }
    }
    Ok(())
}
