//! MCAP writer for sample streams (simulator output, tests): three topics with the
//! sample time as a field, JSON-encoded, plus the [`Mapping`] that reads them back.
//!
//! Topics: `/mrsysid/state` {t, velocity{x,y,z}, rates{x,y,z}[, height][, attitude{w,x,y,z}]},
//! `/mrsysid/rotors` {t, omega[N][, omega_dot[N]]}, `/mrsysid/wrench` {t, force{x,y,z},
//! moment{x,y,z}}; SI units, body FRD, attitude body→NED. Message log time is t in ns.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use serde_json::json;

use super::mapping::{Mapping, McapOptions, SignalMap};
use crate::sample::SampleChunk;
use crate::vehicle::Vehicle;

/// Message encoding of a written MCAP file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// JSON messages with a JSON-Schema-less channel (`message_encoding = "json"`).
    Json,
}

/// Topic of body velocity, rates, height and attitude.
pub const STATE_TOPIC: &str = "/mrsysid/state";
/// Topic of rotor speeds and accelerations.
pub const ROTORS_TOPIC: &str = "/mrsysid/rotors";
/// Topic of force and moment.
pub const WRENCH_TOPIC: &str = "/mrsysid/wrench";

/// Errors of the writer.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// File or MCAP error.
    #[error("{0}")]
    Mcap(#[from] mcap::McapError),
    /// A chunk does not match the vehicle.
    #[error("chunk has {chunk} rotors, vehicle {vehicle}")]
    Rotors {
        /// Rotors in the chunk.
        chunk: usize,
        /// Rotors of the vehicle.
        vehicle: usize,
    },
    /// A time is negative or not finite, so it has no MCAP log time.
    #[error("sample time {0} s cannot be an MCAP log time")]
    Time(f64),
}

/// Writes `chunks` to `path` as MCAP in `encoding`.
pub fn write_samples<'a>(
    path: &Path,
    vehicle: &Vehicle,
    chunks: impl IntoIterator<Item = &'a SampleChunk>,
    encoding: Encoding,
) -> Result<(), WriteError> {
    let Encoding::Json = encoding;
    let file = File::create(path).map_err(mcap::McapError::from)?;
    let mut w = mcap::Writer::new(BufWriter::new(file))?;
    let meta = BTreeMap::from([("vehicle".to_string(), vehicle.name.clone())]);
    let mut ids = [0u16; 3];
    for (id, topic) in ids
        .iter_mut()
        .zip([STATE_TOPIC, ROTORS_TOPIC, WRENCH_TOPIC])
    {
        *id = w.add_channel(0, topic, "json", &meta)?;
    }
    let mut sequence = 0u32;
    for c in chunks {
        if c.rotor_count() != vehicle.rotor_count() {
            return Err(WriteError::Rotors {
                chunk: c.rotor_count(),
                vehicle: vehicle.rotor_count(),
            });
        }
        for k in 0..c.len() {
            let t = c.t[k];
            if !(t.is_finite() && t >= 0.0) {
                return Err(WriteError::Time(t));
            }
            let log_time = (t * 1e9).round() as u64;
            let v = |a: &[Vec<f64>; 3]| json!({"x": a[0][k], "y": a[1][k], "z": a[2][k]});
            let mut state = json!({"t": t, "velocity": v(&c.velocity), "rates": v(&c.rates)});
            if !c.height.is_empty() {
                state["height"] = json!(c.height[k]);
            }
            if !c.attitude[0].is_empty() {
                let q = &c.attitude;
                state["attitude"] = json!({"w": q[0][k], "x": q[1][k], "y": q[2][k], "z": q[3][k]});
            }
            let mut rotors =
                json!({"t": t, "omega": c.omega.iter().map(|o| o[k]).collect::<Vec<_>>()});
            if c.has_omega_dot() {
                rotors["omega_dot"] = json!(c.omega_dot.iter().map(|o| o[k]).collect::<Vec<_>>());
            }
            let f = &c.wrench;
            let wrench = json!({"t": t, "force": {"x": f[0][k], "y": f[1][k], "z": f[2][k]},
                "moment": {"x": f[3][k], "y": f[4][k], "z": f[5][k]}});
            for (id, msg) in ids.iter().zip([state, rotors, wrench]) {
                let header = mcap::records::MessageHeader {
                    channel_id: *id,
                    sequence,
                    log_time,
                    publish_time: log_time,
                };
                w.write_to_known_channel(&header, msg.to_string().as_bytes())?;
                sequence = sequence.wrapping_add(1);
            }
        }
    }
    w.finish()?;
    Ok(())
}

/// The mapping that reads a file of [`write_samples`] back: time from the `t` field,
/// `/mrsysid/state` as time base, optional signals included as given.
pub fn written_mapping(rotors: usize, omega_dot: bool, height: bool, attitude: bool) -> Mapping {
    let map = |topic: &str, fields: Vec<String>| SignalMap {
        topic: Some(topic.to_string()),
        fields,
        ..SignalMap::default()
    };
    let xyz = |p: &str| ["x", "y", "z"].map(|a| format!("{p}.{a}")).to_vec();
    let mut m = Mapping {
        time: Some(SignalMap {
            fields: vec!["t".into()],
            ..SignalMap::default()
        }),
        mcap: McapOptions {
            time_base: Some(STATE_TOPIC.into()),
        },
        ..Mapping::default()
    };
    m.signals.velocity_body = Some(map(STATE_TOPIC, xyz("velocity")));
    m.signals.rates = Some(map(STATE_TOPIC, xyz("rates")));
    m.signals.rotor_speeds = Some(map(
        ROTORS_TOPIC,
        (0..rotors).map(|i| format!("omega[{i}]")).collect(),
    ));
    if omega_dot {
        m.signals.rotor_accelerations = Some(map(
            ROTORS_TOPIC,
            (0..rotors).map(|i| format!("omega_dot[{i}]")).collect(),
        ));
    }
    m.signals.force = Some(map(WRENCH_TOPIC, xyz("force")));
    m.signals.moment = Some(map(WRENCH_TOPIC, xyz("moment")));
    if height {
        m.signals.height = Some(map(STATE_TOPIC, vec!["height".into()]));
    }
    if attitude {
        m.signals.attitude = Some(map(
            STATE_TOPIC,
            ["w", "x", "y", "z"]
                .map(|a| format!("attitude.{a}"))
                .to_vec(),
        ));
    }
    m
}
