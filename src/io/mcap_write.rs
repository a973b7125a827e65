//! MCAP writer for sample streams (simulator output, tests): three topics with the
//! sample time as a field, JSON- or ROS 2 CDR-encoded, plus the [`Mapping`] that reads them back.
//!
//! Topics: `/mrsysid/state` {t, velocity{x,y,z}, rates{x,y,z}[, height][, attitude{w,x,y,z}]},
//! `/mrsysid/rotors` `{t, omega[N][, omega_dot[N]]}`, `/mrsysid/wrench` {t, force{x,y,z},
//! moment{x,y,z}}; SI units, body FRD, attitude body→NED. Message log time is t in ns.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use serde_json::json;

use super::cdr::Encoder;
use super::mapping::{Mapping, McapOptions, SignalMap};
use crate::sample::SampleChunk;
use crate::vehicle::Vehicle;

/// Message encoding of a written MCAP file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// JSON messages (`message_encoding = "json"`).
    Json,
    /// ROS 2 CDR messages with `ros2msg` schemas (`message_encoding = "cdr"`).
    Cdr,
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
    /// A chunk carries other optional signals than the first one.
    #[error("a chunk carries other optional signals (height, attitude, omega_dot) than the first")]
    Shape,
    /// A time is negative or not finite, so it has no MCAP log time.
    #[error("sample time {0} s cannot be an MCAP log time")]
    Time(f64),
}

/// Which optional signals the written messages carry (decided by the first chunk).
#[derive(Debug, Clone, Copy)]
struct Shape {
    height: bool,
    attitude: bool,
    omega_dot: bool,
}

const VECTOR3: &str = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str =
    "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";
const SEPARATOR: &str =
    "================================================================================\n";

/// `ros2msg` schema texts of the three topics.
fn schemas(shape: Shape) -> [(String, String); 3] {
    let mut state =
        String::from("float64 t\ngeometry_msgs/Vector3 velocity\ngeometry_msgs/Vector3 rates\n");
    if shape.height {
        state += "float64 height\n";
    }
    if shape.attitude {
        state += "geometry_msgs/Quaternion attitude\n";
    }
    state += &format!("{SEPARATOR}{VECTOR3}");
    if shape.attitude {
        state += &format!("{SEPARATOR}{QUATERNION}");
    }
    let mut rotors = String::from("float64 t\nfloat64[] omega\n");
    if shape.omega_dot {
        rotors += "float64[] omega_dot\n";
    }
    let wrench = format!(
        "float64 t\ngeometry_msgs/Vector3 force\ngeometry_msgs/Vector3 moment\n{SEPARATOR}{VECTOR3}"
    );
    [
        ("mrsysid_msgs/msg/State".into(), state),
        ("mrsysid_msgs/msg/Rotors".into(), rotors),
        ("mrsysid_msgs/msg/Wrench".into(), wrench),
    ]
}

/// The three messages of sample `k`, JSON-encoded.
fn json_messages(c: &SampleChunk, k: usize) -> [Vec<u8>; 3] {
    let t = c.t[k];
    let v = |a: &[Vec<f64>; 3]| json!({"x": a[0][k], "y": a[1][k], "z": a[2][k]});
    let mut state = json!({"t": t, "velocity": v(&c.velocity), "rates": v(&c.rates)});
    if c.has_height() {
        state["height"] = json!(c.height[k]);
    }
    if c.has_attitude() {
        let q = &c.attitude;
        state["attitude"] = json!({"w": q[0][k], "x": q[1][k], "y": q[2][k], "z": q[3][k]});
    }
    let mut rotors = json!({"t": t, "omega": c.omega.iter().map(|o| o[k]).collect::<Vec<_>>()});
    if c.has_omega_dot() {
        rotors["omega_dot"] = json!(c.omega_dot.iter().map(|o| o[k]).collect::<Vec<_>>());
    }
    let f = &c.wrench;
    let wrench = json!({"t": t, "force": {"x": f[0][k], "y": f[1][k], "z": f[2][k]},
        "moment": {"x": f[3][k], "y": f[4][k], "z": f[5][k]}});
    [state, rotors, wrench].map(|m| m.to_string().into_bytes())
}

/// The three messages of sample `k`, CDR-encoded per [`schemas`].
fn cdr_messages(c: &SampleChunk, k: usize, shape: Shape) -> [Vec<u8>; 3] {
    let mut state = Encoder::new();
    state.f64(c.t[k]);
    c.velocity
        .iter()
        .chain(&c.rates)
        .for_each(|v| state.f64(v[k]));
    if shape.height {
        state.f64(c.height[k]);
    }
    if shape.attitude {
        // geometry_msgs/Quaternion is x, y, z, w.
        [1, 2, 3, 0]
            .iter()
            .for_each(|&a| state.f64(c.attitude[a][k]));
    }
    let mut rotors = Encoder::new();
    rotors.f64(c.t[k]);
    rotors.f64_seq(&c.omega.iter().map(|o| o[k]).collect::<Vec<_>>());
    if shape.omega_dot {
        rotors.f64_seq(&c.omega_dot.iter().map(|o| o[k]).collect::<Vec<_>>());
    }
    let mut wrench = Encoder::new();
    wrench.f64(c.t[k]);
    c.wrench.iter().for_each(|v| wrench.f64(v[k]));
    [state.finish(), rotors.finish(), wrench.finish()]
}

/// How the messages are laid out in a written file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Each topic's messages as one block after the previous topic's (state, rotors,
    /// wrench): valid MCAP, but not stored in log-time order, as a recorder that writes
    /// topics in blocks leaves it. False: interleaved in log-time order.
    pub topic_blocks: bool,
    /// Messages in compressed chunks with chunk and message indexes in the summary (the
    /// default of MCAP writers). False: unchunked messages, no index.
    pub indexed: bool,
    /// Uncompressed chunk size, bytes: small values give many chunks, overlapping in
    /// time when `topic_blocks` is set.
    pub chunk_size: u64,
}

impl Default for Layout {
    /// Log-time order, indexed, the mcap crate's default chunk size.
    fn default() -> Self {
        Self {
            topic_blocks: false,
            indexed: true,
            chunk_size: mcap::WriteOptions::DEFAULT_CHUNK_SIZE,
        }
    }
}

/// Writes `chunks` to `path` as MCAP in `encoding`, in log-time order with indexes.
/// Optional signals (height, attitude, rotor accelerations) are written when the first
/// chunk carries them; every chunk must then carry them too.
pub fn write_samples<'a>(
    path: &Path,
    vehicle: &Vehicle,
    chunks: impl IntoIterator<Item = &'a SampleChunk>,
    encoding: Encoding,
) -> Result<(), WriteError> {
    write_samples_laid_out(path, vehicle, chunks, encoding, Layout::default())
}

/// [`write_samples`] with the messages laid out as `layout` says.
pub fn write_samples_laid_out<'a>(
    path: &Path,
    vehicle: &Vehicle,
    chunks: impl IntoIterator<Item = &'a SampleChunk>,
    encoding: Encoding,
    layout: Layout,
) -> Result<(), WriteError> {
    let file = File::create(path).map_err(mcap::McapError::from)?;
    let options = mcap::WriteOptions::new()
        .use_chunks(layout.indexed)
        .chunk_size(Some(layout.chunk_size));
    let mut w = options.create(BufWriter::new(file))?;
    let meta = BTreeMap::from([("vehicle".to_string(), vehicle.name.clone())]);
    let mut chunks = chunks.into_iter().peekable();
    let shape = chunks.peek().map_or(
        Shape {
            height: false,
            attitude: false,
            omega_dot: false,
        },
        |c| Shape {
            height: c.has_height(),
            attitude: c.has_attitude(),
            omega_dot: c.has_omega_dot(),
        },
    );
    let mut ids = [0u16; 3];
    for ((id, topic), (name, text)) in ids
        .iter_mut()
        .zip([STATE_TOPIC, ROTORS_TOPIC, WRENCH_TOPIC])
        .zip(schemas(shape))
    {
        *id = match encoding {
            Encoding::Json => w.add_channel(0, topic, "json", &meta)?,
            Encoding::Cdr => {
                let schema = w.add_schema(&name, "ros2msg", text.as_bytes())?;
                w.add_channel(schema, topic, "cdr", &meta)?
            }
        };
    }
    let mut sequence = 0u32;
    // With topic blocks, the rotor and wrench messages wait here until the state block
    // is written.
    let mut held: [Vec<(mcap::records::MessageHeader, Vec<u8>)>; 2] = Default::default();
    for c in chunks {
        if c.rotor_count() != vehicle.rotor_count() {
            return Err(WriteError::Rotors {
                chunk: c.rotor_count(),
                vehicle: vehicle.rotor_count(),
            });
        }
        let same_shape = shape.height != c.height.is_empty()
            && shape.attitude != c.attitude[0].is_empty()
            && shape.omega_dot == c.has_omega_dot();
        if !same_shape {
            return Err(WriteError::Shape);
        }
        for k in 0..c.len() {
            let t = c.t[k];
            if !(t.is_finite() && t >= 0.0) {
                return Err(WriteError::Time(t));
            }
            let log_time = (t * 1e9).round() as u64;
            let messages = match encoding {
                Encoding::Json => json_messages(c, k),
                Encoding::Cdr => cdr_messages(c, k, shape),
            };
            for (k, (id, msg)) in ids.iter().zip(messages).enumerate() {
                let header = mcap::records::MessageHeader {
                    channel_id: *id,
                    sequence,
                    log_time,
                    publish_time: log_time,
                };
                if layout.topic_blocks && k > 0 {
                    held[k - 1].push((header, msg));
                } else {
                    w.write_to_known_channel(&header, &msg)?;
                }
                sequence = sequence.wrapping_add(1);
            }
        }
    }
    for (header, msg) in held.iter().flatten() {
        w.write_to_known_channel(header, msg)?;
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
            ..McapOptions::default()
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
