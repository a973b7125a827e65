//! The flat "slot" layout a source fills per sample: every mapped component of every
//! signal, in [`Signal::ALL`] order, with its SI conversion factor and source name.

use super::error::{ErrorKind, IoError, Location, key};
use super::mapping::{Mapping, Signal};
use super::units::unit_for;

/// Slot positions, factors and names of a resolved mapping.
#[derive(Debug, Clone)]
pub struct SlotLayout {
    start: [Option<usize>; 12],
    signal: Vec<Signal>,
    factor: Vec<f64>,
    names: Vec<String>,
    topics: Vec<Option<String>>,
}

impl SlotLayout {
    /// Resolves `mapping` for `rotors` rotors. `mcap` selects topic/field names (else CSV
    /// columns). Checks rotor counts, units and that the required signals are present.
    pub fn resolve(
        mapping: &Mapping,
        rotors: usize,
        file: &str,
        mcap: bool,
    ) -> Result<Self, IoError> {
        let mut s = Self {
            start: [None; 12],
            signal: Vec::new(),
            factor: Vec::new(),
            names: Vec::new(),
            topics: Vec::new(),
        };
        for (idx, signal) in Signal::ALL.into_iter().enumerate() {
            let Some(map) = mapping.get(signal) else {
                continue;
            };
            if signal == Signal::Time && mcap {
                continue; // the MCAP source supplies the (aligned) time itself
            }
            let mapping_err = |m: String| {
                IoError::new(
                    file,
                    Location::File,
                    key(&format!("signals.{}", signal.key())),
                    ErrorKind::Mapping(m),
                )
            };
            let list = if mcap { &map.fields } else { &map.columns };
            if list.is_empty() {
                if signal == Signal::Time && mcap {
                    continue;
                }
                return Err(mapping_err(format!(
                    "no {} given for this {} file",
                    if mcap { "`fields`" } else { "`columns`" },
                    if mcap { "MCAP" } else { "CSV" }
                )));
            }
            let want = signal.components(rotors);
            if list.len() != want {
                return Err(mapping_err(format!(
                    "lists {} names but {} needs {want}{}",
                    list.len(),
                    signal.key(),
                    if matches!(signal, Signal::RotorSpeeds | Signal::RotorAccelerations) {
                        format!(" (the vehicle has {rotors} rotors)")
                    } else {
                        String::new()
                    }
                )));
            }
            let factor = match &map.unit {
                Some(u) => {
                    unit_for(u, map.pole_pairs, signal.dimension(), signal.key())
                        .map_err(|e| mapping_err(e.to_string()))?
                        .to_si
                }
                None => 1.0,
            };
            s.start[idx] = Some(s.signal.len());
            for name in list {
                s.signal.push(signal);
                s.factor.push(factor);
                s.names.push(name.clone());
                s.topics.push(map.topic.clone());
            }
        }
        s.check_required(file, mcap)?;
        Ok(s)
    }

    fn check_required(&self, file: &str, mcap: bool) -> Result<(), IoError> {
        let missing = |m: &str| {
            Err(IoError::new(
                file,
                Location::File,
                None,
                ErrorKind::MissingSignal(m.into()),
            ))
        };
        if !mcap && !self.has(Signal::Time) {
            return missing("no time: map `time` (contract column \"t\")");
        }
        if !self.has(Signal::Rates) {
            return missing("no body rates: map `rates` (contract columns \"p\",\"q\",\"r\")");
        }
        if !self.has(Signal::RotorSpeeds) {
            return missing("no rotor speeds: map `rotor_speeds` (contract columns \"omega_1\"..)");
        }
        let world_velocity = self.has(Signal::VelocityWorld) && self.has(Signal::Attitude);
        if !(self.has(Signal::VelocityBody) || world_velocity) {
            return missing(
                "no body velocity: map `velocity_body` (contract columns \"u\",\"v\",\"w\"), or \
                 `velocity_world` together with `attitude`",
            );
        }
        if !self.has(Signal::Force) && !self.has(Signal::SpecificForce) {
            return missing(
                "no force: map `force` (contract columns \"fx\",\"fy\",\"fz\"), or `specific_force` \
                 (contract columns \"ax\",\"ay\",\"az\") to derive F = m a",
            );
        }
        Ok(())
    }

    /// Number of slots.
    pub fn len(&self) -> usize {
        self.signal.len()
    }

    /// True when `signal` is mapped.
    pub fn has(&self, signal: Signal) -> bool {
        self.start[signal_index(signal)].is_some()
    }

    /// First slot of `signal`.
    pub fn start(&self, signal: Signal) -> Option<usize> {
        self.start[signal_index(signal)]
    }

    /// Signal of a slot.
    pub fn signal_of_slot(&self, slot: usize) -> Signal {
        self.signal[slot]
    }

    /// SI factor of a slot.
    pub fn factor(&self, slot: usize) -> f64 {
        self.factor[slot]
    }

    /// Column name (CSV) or field path (MCAP) of a slot.
    pub fn source_name(&self, slot: usize) -> &str {
        &self.names[slot]
    }

    /// MCAP topic of a slot.
    pub fn topic(&self, slot: usize) -> Option<&str> {
        self.topics[slot].as_deref()
    }
}

fn signal_index(signal: Signal) -> usize {
    Signal::ALL.iter().position(|&s| s == signal).unwrap_or(0)
}
