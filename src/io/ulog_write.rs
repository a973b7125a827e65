//! ULog writer for tests and examples: a message-level builder ([`UlogWriter`]) that can
//! also write malformed files on purpose, and [`write_samples`], which writes sample
//! chunks as ULog topics, plus the [`Mapping`] that reads them back ([`written_mapping`]).
//!
//! Topics of [`write_samples`]: `mrsysid_state` {timestamp (µs), `double[3]` velocity,
//! rates, force, moment, `double` height, `double[4]` q (w, x, y, z)} and `mrsysid_rotors`
//! {timestamp, `uint8_t` count, padding, `mrsysid_rotor[N]` rotor {`double` omega,
//! `double` omega_dot}} logged as instance 0 (a decoy with every value halved) and
//! instance 1 (the true values); SI units, body FRD, attitude body→NED.

use std::path::Path;

use super::mapping::{Mapping, McapOptions, SignalMap};
use crate::sample::SampleChunk;

/// Builds a ULog file in memory, message by message.
#[derive(Debug, Clone)]
pub struct UlogWriter {
    bytes: Vec<u8>,
}

impl UlogWriter {
    /// A file with the ULog header (version 1) and logging start time `start_us`, µs.
    pub fn new(start_us: u64) -> Self {
        let mut bytes = super::ulog::MAGIC.to_vec();
        bytes.push(1);
        bytes.extend_from_slice(&start_us.to_le_bytes());
        Self { bytes }
    }

    /// Appends a message of type `kind` with `payload` (at most 65535 bytes; longer
    /// payloads are cut, which is a malformed file on purpose).
    pub fn message(&mut self, kind: u8, payload: &[u8]) -> &mut Self {
        let n = payload.len().min(u16::MAX as usize);
        self.bytes.extend_from_slice(&(n as u16).to_le_bytes());
        self.bytes.push(kind);
        self.bytes.extend_from_slice(&payload[..n]);
        self
    }

    /// A `B` flag-bits message.
    pub fn flag_bits(
        &mut self,
        compat: [u8; 8],
        incompat: [u8; 8],
        appended: [u64; 3],
    ) -> &mut Self {
        let mut p = compat.to_vec();
        p.extend_from_slice(&incompat);
        for o in appended {
            p.extend_from_slice(&o.to_le_bytes());
        }
        self.message(b'B', &p)
    }

    /// An `F` format message, `name:type field;…`.
    pub fn format(&mut self, text: &str) -> &mut Self {
        self.message(b'F', text.as_bytes())
    }

    /// An `I` info message with a string value (`char[n] key`).
    pub fn info(&mut self, key: &str, value: &str) -> &mut Self {
        let k = format!("char[{}] {key}", value.len());
        let mut p = vec![k.len() as u8];
        p.extend_from_slice(k.as_bytes());
        p.extend_from_slice(value.as_bytes());
        self.message(b'I', &p)
    }

    /// A `P` parameter message of type `int32_t`.
    pub fn param_i32(&mut self, name: &str, value: i32) -> &mut Self {
        self.param("int32_t", name, &value.to_le_bytes())
    }

    /// A `P` parameter message of type `float`.
    pub fn param_f32(&mut self, name: &str, value: f32) -> &mut Self {
        self.param("float", name, &value.to_le_bytes())
    }

    fn param(&mut self, ty: &str, name: &str, value: &[u8]) -> &mut Self {
        let k = format!("{ty} {name}");
        let mut p = vec![k.len() as u8];
        p.extend_from_slice(k.as_bytes());
        p.extend_from_slice(value);
        self.message(b'P', &p)
    }

    /// An `A` subscription of `msg_id` to topic `name`, instance `multi_id`.
    pub fn add(&mut self, multi_id: u8, msg_id: u16, name: &str) -> &mut Self {
        let mut p = vec![multi_id];
        p.extend_from_slice(&msg_id.to_le_bytes());
        p.extend_from_slice(name.as_bytes());
        self.message(b'A', &p)
    }

    /// A `D` data message of `msg_id` with the message's bytes.
    pub fn data(&mut self, msg_id: u16, data: &[u8]) -> &mut Self {
        let mut p = msg_id.to_le_bytes().to_vec();
        p.extend_from_slice(data);
        self.message(b'D', &p)
    }

    /// An `O` dropout message of `ms` milliseconds.
    pub fn dropout(&mut self, ms: u16) -> &mut Self {
        self.message(b'O', &ms.to_le_bytes())
    }

    /// Bytes written so far (the byte offset of the next message).
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// True when nothing was written (never: the header is written by [`UlogWriter::new`]).
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// The file's bytes, to edit them (e.g. to corrupt them on purpose).
    pub fn bytes_mut(&mut self) -> &mut Vec<u8> {
        &mut self.bytes
    }

    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// Name of the state topic of [`write_samples`].
pub const STATE_TOPIC: &str = "mrsysid_state";
/// Name of the rotor topic of [`write_samples`].
pub const ROTORS_TOPIC: &str = "mrsysid_rotors";

/// Time of a sample in whole µs (ULog timestamps are integers).
pub fn micros(t: f64) -> u64 {
    (t * 1e6).round().max(0.0) as u64
}

/// Writes `chunks` (rotor count of the first chunk; all chunks must have it) as a ULog
/// file; see the module docs. Times are rounded to whole µs; a chunk without height or
/// attitude is written with height 0 and the identity attitude.
pub fn write_samples<'a>(
    path: &Path,
    chunks: impl IntoIterator<Item = &'a SampleChunk>,
) -> std::io::Result<()> {
    let mut chunks = chunks.into_iter().peekable();
    let rotors = chunks.peek().map_or(0, |c| c.omega.len());
    if rotors > u8::MAX as usize {
        return Err(std::io::Error::other(format!(
            "{rotors} rotors: at most 255"
        )));
    }
    let mut w = UlogWriter::new(0);
    w.flag_bits([0; 8], [0; 8], [0; 3]);
    w.info("sys_name", "mrsysid");
    w.format(&format!(
        "{STATE_TOPIC}:uint64_t timestamp;double[3] velocity;double[3] rates;double[3] force;\
         double[3] moment;double height;double[4] q;"
    ));
    w.format("mrsysid_rotor:double omega;double omega_dot;");
    w.format(&format!(
        "{ROTORS_TOPIC}:uint64_t timestamp;uint8_t count;uint8_t[7] _padding0;mrsysid_rotor[{rotors}] rotor;"
    ));
    w.add(0, 0, STATE_TOPIC);
    w.add(0, 1, ROTORS_TOPIC);
    w.add(1, 2, ROTORS_TOPIC);
    for c in chunks {
        for k in 0..c.len() {
            let ts = micros(c.t[k]);
            let mut state = ts.to_le_bytes().to_vec();
            let mut put = |v: f64| state.extend_from_slice(&v.to_le_bytes());
            for v in c.velocity.iter().chain(&c.rates).chain(&c.wrench) {
                put(v[k]);
            }
            put(c.height.get(k).copied().unwrap_or(0.0));
            for (q, identity) in c.attitude.iter().zip([1.0, 0.0, 0.0, 0.0]) {
                put(q.get(k).copied().unwrap_or(identity));
            }
            w.data(0, &state);
            for (msg_id, scale) in [(1u16, 0.5), (2, 1.0)] {
                let mut r = ts.to_le_bytes().to_vec();
                r.push(rotors as u8);
                r.extend_from_slice(&[0; 7]);
                for (i, omega) in c.omega.iter().enumerate() {
                    r.extend_from_slice(&(scale * omega[k]).to_le_bytes());
                    let od = c
                        .omega_dot
                        .get(i)
                        .and_then(|v| v.get(k))
                        .copied()
                        .unwrap_or(0.0);
                    r.extend_from_slice(&(scale * od).to_le_bytes());
                }
                w.data(msg_id, &r);
            }
        }
    }
    std::fs::write(path, w.bytes())
}

/// The mapping that reads a [`write_samples`] file back: body velocity, rates, force,
/// moment from `mrsysid_state`, rotor speeds (and accelerations when `omega_dot`) from
/// instance 1 of `mrsysid_rotors`, height and attitude when asked.
pub fn written_mapping(rotors: usize, omega_dot: bool, height: bool, attitude: bool) -> Mapping {
    let map = |topic: &str, fields: Vec<String>| SignalMap {
        topic: Some(topic.to_string()),
        fields,
        ..SignalMap::default()
    };
    let xyz = |p: &str| (0..3).map(|a| format!("{p}[{a}]")).collect::<Vec<_>>();
    let rotor_topic = format!("{ROTORS_TOPIC}[1]");
    let mut m = Mapping {
        mcap: McapOptions {
            time_base: Some(STATE_TOPIC.into()),
            ..McapOptions::default()
        },
        ..Mapping::default()
    };
    m.signals.velocity_body = Some(map(STATE_TOPIC, xyz("velocity")));
    m.signals.rates = Some(map(STATE_TOPIC, xyz("rates")));
    m.signals.force = Some(map(STATE_TOPIC, xyz("force")));
    m.signals.moment = Some(map(STATE_TOPIC, xyz("moment")));
    m.signals.rotor_speeds = Some(map(
        &rotor_topic,
        (0..rotors).map(|i| format!("rotor[{i}].omega")).collect(),
    ));
    if omega_dot {
        m.signals.rotor_accelerations = Some(map(
            &rotor_topic,
            (0..rotors)
                .map(|i| format!("rotor[{i}].omega_dot"))
                .collect(),
        ));
    }
    if height {
        m.signals.height = Some(map(STATE_TOPIC, vec!["height".into()]));
    }
    if attitude {
        m.signals.attitude = Some(map(
            STATE_TOPIC,
            (0..4).map(|i| format!("q[{i}]")).collect(),
        ));
    }
    m
}
