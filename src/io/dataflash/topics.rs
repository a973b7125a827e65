//! The mapped messages of a DataFlash log: which message instance (`IMU`, `ESC[2]`)
//! feeds which slots through which field labels, with which time field; and, once the
//! message's format is known, where those fields sit in its body, their value factors
//! and the log's unit conversions.

use super::super::align::{split_instance, topic_time};
use super::super::error::{ErrorKind, IoError, Location, field, key};
use super::super::mapping::{Mapping, Signal};
use super::super::scalar::Scalar;
use super::super::slots::SlotLayout;
use super::super::units::{UnitError, unit_for};
use super::format::{Format, Kind, UnitTables};

/// A numeric field located in a message body: offset, type and factor to the value
/// (multiplier or implied scale, times the log unit's factor to SI when used).
pub(super) type Spot = (usize, Scalar, f64);

/// Where a mapped message's time, instance and fields sit.
pub(super) struct Located {
    pub time: Spot,
    /// The instance field, when the message has one.
    pub instance: Option<(usize, Scalar)>,
    pub fields: Vec<Spot>,
}

/// A mapped message instance.
pub(super) struct Topic {
    /// Key as the mapping names it, `IMU` or `ESC[2]`.
    pub key: String,
    pub name: String,
    /// Instance wanted (0 when the key names none).
    pub instance: u8,
    /// (slot, field label) of every mapped field.
    pub fields: Vec<(usize, String)>,
    /// Time field label and its factor to seconds.
    pub time: (String, f64),
    pub located: Option<Located>,
    /// Messages of the name seen (any instance), and of this instance.
    pub seen: u64,
    pub messages: u64,
}

/// The messages `mapping` maps onto the slots of `layout`. A field is a label of the
/// signal's `topic` (`GyrX`), or names its own message instance, `ESC[2].RPM` (labels
/// hold no dot). A message's time
/// is its `[mcap.topic_time]` field, else the `[time]` field, else `TimeUS` (µs).
pub(super) fn mapped_topics(
    mapping: &Mapping,
    layout: &SlotLayout,
    file: &str,
) -> Result<Vec<Topic>, IoError> {
    let default_time = match mapping.get(Signal::Time) {
        Some(m) if !m.fields.is_empty() => (m.fields[0].clone(), mapping.factor(Signal::Time)),
        _ => ("TimeUS".to_string(), 1e-6),
    };
    let mut topics: Vec<Topic> = Vec::new();
    for slot in 0..layout.len() {
        let signal = layout.signal_of_slot(slot);
        let name = layout.source_name(slot);
        let (topic_key, label) = match name.split_once('.') {
            Some((t, l)) => (t.to_string(), l.to_string()),
            None => match layout.topic(slot) {
                Some(t) => (t.to_string(), name.to_string()),
                None => {
                    return Err(IoError::new(
                        file,
                        Location::File,
                        key(&format!("signals.{}", signal.key())),
                        ErrorKind::Mapping(format!(
                            "field {name:?} names no message: give `topic` or write it as MSG.{name} (e.g. \"ESC[0].RPM\")"
                        )),
                    ));
                }
            },
        };
        let idx = match topics.iter().position(|t| t.key == topic_key) {
            Some(i) => i,
            None => {
                let (msg, instance) = split_instance(&topic_key, "message").map_err(|e| {
                    IoError::new(
                        file,
                        Location::File,
                        key(&format!("signals.{}", signal.key())),
                        ErrorKind::Mapping(e.to_string()),
                    )
                })?;
                let time = topic_time(mapping, &topic_key, file, |p| Ok(p.to_string()))?
                    .unwrap_or_else(|| default_time.clone());
                topics.push(Topic {
                    key: topic_key.clone(),
                    name: msg.to_string(),
                    instance,
                    fields: Vec::new(),
                    time,
                    located: None,
                    seen: 0,
                    messages: 0,
                });
                topics.len() - 1
            }
        };
        topics[idx].fields.push((slot, label));
    }
    Ok(topics)
}

impl Topic {
    /// Locates the time, instance and mapped fields in `format`. A field the mapping
    /// gives no unit for (and no actuator map) takes the log's `FMTU` unit when that is
    /// a unit of the signal's dimension; one of another dimension is an error. Errors
    /// name the field and the message at byte `offset`.
    pub fn locate(
        &self,
        format: &Format,
        tables: &UnitTables,
        mapping: &Mapping,
        layout: &SlotLayout,
        file: &str,
        offset: u64,
    ) -> Result<Located, IoError> {
        let err = |label: &str, m: String| {
            IoError::new(
                file,
                Location::Offset(offset),
                field(&format!("{}.{label}", self.key)),
                ErrorKind::Mapping(m),
            )
        };
        let find = |label: &str| -> Result<(usize, Scalar, f64), IoError> {
            let (k, f) = format.field(label).ok_or_else(|| {
                let labels: Vec<&str> = format.fields.iter().map(|f| f.label.as_str()).collect();
                err(
                    label,
                    format!(
                        "field not in message {} (fields: {})",
                        format.name,
                        labels.join(", ")
                    ),
                )
            })?;
            match f.kind {
                Kind::Number(s, _) => Ok((k, s, format.factor(k, tables))),
                Kind::Bytes(_) => Err(err(
                    label,
                    format!("field of format {:?} is not a number", f.code as char),
                )),
            }
        };
        let (k, s, _) = find(&self.time.0)?;
        let time = (format.fields[k].offset, s, self.time.1);
        let instance = match format.instance_field() {
            Some(f) => match f.kind {
                Kind::Number(s, _) => Some((f.offset, s)),
                Kind::Bytes(_) => None,
            },
            None if self.instance != 0 => {
                return Err(err(
                    "",
                    format!(
                        "message {} has no instance field (FMTU unit '#', or a field I, Instance or C): map it as {:?}",
                        format.name, format.name
                    ),
                ));
            }
            None => None,
        };
        let mut fields = Vec::with_capacity(self.fields.len());
        for (slot, label) in &self.fields {
            let (k, s, factor) = find(label)?;
            let signal = layout.signal_of_slot(*slot);
            let map = mapping.get(signal);
            let own_unit = map.is_some_and(|m| m.unit.is_some() || m.actuator.is_some());
            let log_factor = match format.unit(k, tables) {
                Some(u) if !own_unit => log_unit_factor(u, signal)
                    .map_err(|e| err(label, format!("the log's unit of this field: {e}")))?,
                _ => 1.0,
            };
            fields.push((format.fields[k].offset, s, factor * log_factor));
        }
        Ok(Located {
            time,
            instance,
            fields,
        })
    }
}

/// The factor to SI of a log unit name (`UNIT` text: `rpm`, `deg/s`, `m/s/s`) for
/// `signal`: 1 for names that are no unit of the crate (`instance`, `UNKNOWN`, ``); an
/// error for a unit of another dimension.
fn log_unit_factor(unit: &str, signal: Signal) -> Result<f64, UnitError> {
    if unit.is_empty() {
        return Ok(1.0);
    }
    let name = unit.replace("/s/s", "/s^2");
    match unit_for(&name, None, signal.dimension(), signal.key()) {
        Ok(u) => Ok(u.to_si),
        Err(UnitError::Unknown { .. }) => Ok(1.0),
        Err(e) => Err(e),
    }
}
