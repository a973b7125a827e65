//! MCAP source: messages read in log-time order, JSON or ROS 2 CDR payloads decoded by
//! field path, asynchronous topics aligned on the time base topic by linear
//! interpolation when the bracketing messages are at most `max_gap` apart. A base sample
//! that cannot be aligned is reported as a sample-level error (dropped and counted,
//! never bridged), so the time step it leaves splits the log into segments.
//!
//! MCAP does not require messages to be stored in log-time order (a recorder may write
//! topics in blocks; merged files interleave chunks). When the file's summary has chunk
//! indexes, messages are read in log-time order through them with the `mcap` crate's
//! sans-I/O indexed reader, which holds only the chunks overlapping in time at once (as
//! the mcap tooling and Foxglove read). Without an index the file is read in file order
//! by the streaming linear reader, and a message more than `max_gap` earlier than one
//! already read is an error saying the file must be indexed or sorted.

use std::collections::{BTreeSet, HashMap};
use std::fs::File;
use std::path::Path;

use mcap::records::MessageHeader;
use mcap::sans_io::indexed_reader::{IndexedReader, IndexedReaderOptions};
use mcap::sans_io::linear_reader::{LinearReader, LinearReaderOptions};
use serde_json::Value;

use super::align::{Aligner, Message, TopicSource, base_topic, topic_time};
use super::error::{ErrorKind, IoError, Location, field};
use super::field_path::Step;
use super::mapping::{Mapping, Signal};
use super::slots::SlotLayout;
use json::{as_number, lookup, parse_path, what_is_there};
use order::{Order, check_start, indexed_summary};

mod json;
mod order;

/// Largest MCAP record (or chunk) accepted, bytes: a corrupt length field is an error,
/// not an allocation of that size.
pub const MAX_RECORD_BYTES: usize = 256 << 20;

/// How a topic's messages are decoded.
enum Decoder {
    /// Not known yet (no channel record seen).
    Unknown,
    /// JSON text.
    Json,
    /// ROS 2 CDR with its parsed schema.
    Cdr(Box<super::ros2msg::Schema>),
}

/// A mapped topic and its messages waiting for alignment.
struct Topic {
    decoder: Decoder,
    /// Time field and its factor to seconds; message log time when `None`.
    time: Option<(Vec<Step>, f64)>,
    name: String,
    /// (slot, path) of every mapped field of this topic.
    fields: Vec<(usize, String, Vec<Step>)>,
    seen: bool,
}

/// Streaming MCAP source; see the module docs.
pub struct McapSource {
    file: String,
    handle: File,
    order: Order,
    channel_topic: HashMap<u16, Option<usize>>,
    /// Schemas by id: (name, encoding, text).
    schemas: HashMap<u16, (String, String, Vec<u8>)>,
    topics: Vec<Topic>,
    /// Every channel topic of the file seen so far.
    file_topics: BTreeSet<String>,
    align: Aligner,
    message_index: u64,
    /// Bytes of records read from the file (the indexed reader reads only the chunks of
    /// mapped topics).
    bytes_read: u64,
}

impl McapSource {
    /// Opens `path` with `mapping` (topics and fields) for `rotors` rotors.
    pub fn open(
        path: &Path,
        file: &str,
        mapping: &Mapping,
        rotors: usize,
        max_gap: f64,
    ) -> Result<(Self, SlotLayout), IoError> {
        let layout = SlotLayout::resolve(mapping, rotors, file, true)?;
        let mut handle = File::open(path).map_err(|e| {
            IoError::new(file, Location::File, None, ErrorKind::Read(e.to_string()))
        })?;
        let mut topics: Vec<Topic> = Vec::new();
        for slot in 0..layout.len() {
            let name = layout.topic(slot).unwrap_or_default().to_string();
            let field_name = layout.source_name(slot).to_string();
            let steps = parse_path(&field_name).map_err(|e| {
                IoError::new(
                    file,
                    Location::File,
                    field(&format!("{name}.{field_name}")),
                    ErrorKind::Mapping(e.to_string()),
                )
            })?;
            let idx = match topics.iter().position(|t| t.name == name) {
                Some(i) => i,
                None => {
                    topics.push(Topic {
                        decoder: Decoder::Unknown,
                        time: None,
                        name: name.clone(),
                        fields: Vec::new(),
                        seen: false,
                    });
                    topics.len() - 1
                }
            };
            topics[idx].fields.push((slot, field_name, steps));
        }
        let base = base_topic(mapping, topics.iter().map(|t| t.name.as_str()), file)?;
        let time_field = match mapping.get(Signal::Time) {
            Some(m) if !m.fields.is_empty() => {
                let steps = parse_path(&m.fields[0]).map_err(|e| {
                    IoError::new(
                        file,
                        Location::File,
                        super::error::key("time"),
                        ErrorKind::Mapping(e.to_string()),
                    )
                })?;
                Some((steps, mapping.factor(Signal::Time)))
            }
            _ => None,
        };
        for topic in &mut topics {
            topic.time = topic_time(mapping, &topic.name, file, parse_path)?.or(time_field.clone());
        }
        let summary = indexed_summary(&mut handle, &topics).map_err(|e| {
            IoError::new(file, Location::File, None, ErrorKind::Read(e.to_string()))
        })?;
        let order = match &summary {
            Some(summary) => {
                check_start(&mut handle).map_err(|e| {
                    IoError::new(
                        file,
                        Location::Record(0),
                        None,
                        ErrorKind::Format(e.to_string()),
                    )
                })?;
                let options = IndexedReaderOptions::new()
                    .include_topics(topics.iter().map(|t| t.name.clone()))
                    .with_record_length_limit(MAX_RECORD_BYTES);
                let reader = IndexedReader::new_with_options(summary, options).map_err(|e| {
                    IoError::new(
                        file,
                        Location::File,
                        None,
                        ErrorKind::Format(format!("MCAP chunk index: {e}")),
                    )
                })?;
                Order::LogTime {
                    reader: Box::new(reader),
                    buffer: Vec::new(),
                }
            }
            None => Order::File(Box::new(LinearReader::new_with_options(
                LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES),
            ))),
        };
        let slots = topics
            .iter()
            .map(|t| {
                let slots = t.fields.iter().map(|(slot, _, _)| *slot).collect();
                (t.name.clone(), slots)
            })
            .collect();
        let mut source = Self {
            file: file.to_string(),
            handle,
            order,
            channel_topic: HashMap::new(),
            schemas: HashMap::new(),
            topics,
            file_topics: BTreeSet::new(),
            align: Aligner::new(file, slots, base, max_gap)
                .with_quaternion(layout.start(Signal::Attitude))
                .with_rotor_speeds(layout.start(Signal::RotorSpeeds)),
            message_index: 0,
            bytes_read: 0,
        };
        if let Some(summary) = summary {
            for (id, schema) in &summary.schemas {
                source.schemas.insert(
                    *id,
                    (
                        schema.name.clone(),
                        schema.encoding.clone(),
                        schema.data.to_vec(),
                    ),
                );
            }
            let mut channels: Vec<_> = summary.channels.values().collect();
            channels.sort_by_key(|c| c.id);
            for ch in channels {
                source.add_channel(
                    ch.id,
                    &ch.topic,
                    &ch.message_encoding,
                    ch.schema.as_ref().map_or(0, |s| s.id),
                )?;
            }
        }
        Ok((source, layout))
    }

    /// Registers channel `id` on `topic`, with its decoder when the topic is mapped.
    fn add_channel(
        &mut self,
        id: u16,
        topic: &str,
        encoding: &str,
        schema_id: u16,
    ) -> Result<(), IoError> {
        self.file_topics.insert(topic.to_string());
        let mapped = self.topics.iter().position(|t| t.name == topic);
        if let Some(t) = mapped {
            let decoder = self.decoder_for(topic, encoding, schema_id)?;
            self.topics[t].decoder = decoder;
            self.topics[t].seen = true;
        }
        self.channel_topic.insert(id, mapped);
        Ok(())
    }

    fn err(&self, loc: Location, field_path: Option<String>, kind: ErrorKind) -> IoError {
        IoError::new(&self.file, loc, field_path, kind)
    }

    /// Decodes a message into its topic's queue: true when its channel is mapped.
    fn on_message(&mut self, header: &MessageHeader, data: &[u8]) -> Result<bool, IoError> {
        let index = self.message_index;
        self.message_index += 1;
        let topic = match self.channel_topic.get(&header.channel_id) {
            Some(Some(t)) => *t,
            Some(None) => return Ok(false),
            None => {
                return Err(self.err(
                    Location::Record(index),
                    None,
                    ErrorKind::Format(format!("message on unknown channel {}", header.channel_id)),
                ));
            }
        };
        self.decode(topic, index, header.log_time, data)?;
        Ok(true)
    }

    fn decoder_for(&self, topic: &str, encoding: &str, schema_id: u16) -> Result<Decoder, IoError> {
        let fail = |m: String| self.err(Location::File, field(topic), ErrorKind::Format(m));
        match encoding {
            "json" => Ok(Decoder::Json),
            "cdr" => {
                let (name, encoding, text) = self.schemas.get(&schema_id).ok_or_else(|| {
                    fail(format!(
                        "CDR channel without schema (schema id {schema_id})"
                    ))
                })?;
                if encoding != "ros2msg" {
                    return Err(fail(format!(
                        "CDR schema encoding {encoding:?} is not supported (supported: \"ros2msg\")"
                    )));
                }
                let text = std::str::from_utf8(text)
                    .map_err(|_| fail("schema text is not UTF-8".into()))?;
                let schema = super::ros2msg::parse_schema(name, text)
                    .map_err(|e| fail(format!("schema {name}: {e}")))?;
                Ok(Decoder::Cdr(Box::new(schema)))
            }
            other => Err(fail(format!(
                "message encoding {other:?} is not supported (supported: \"json\", \"cdr\")"
            ))),
        }
    }

    fn decode(
        &mut self,
        topic: usize,
        index: u64,
        log_time: u64,
        data: &[u8],
    ) -> Result<(), IoError> {
        let loc = Location::Record(index);
        let name = self.topics[topic].name.clone();
        let value: Value = match &self.topics[topic].decoder {
            Decoder::Cdr(schema) => super::cdr::decode(schema, data).map_err(|e| {
                self.err(
                    loc,
                    field(&name),
                    ErrorKind::Format(format!("invalid CDR: {e}")),
                )
            })?,
            _ => serde_json::from_slice(data).map_err(|e| {
                let (path, text) = super::json_error::describe(data, &e);
                let label = if path.is_empty() {
                    name.clone()
                } else {
                    format!("{name}.{path}")
                };
                self.err(loc, field(&label), ErrorKind::Format(text))
            })?,
        };
        let t = match &self.topics[topic].time {
            Some((steps, factor)) => {
                let v = lookup(&value, steps).and_then(as_number).ok_or_else(|| {
                    self.err(
                        loc,
                        field(&name),
                        ErrorKind::MissingSignal("time field missing or not a number".into()),
                    )
                })?;
                v * factor
            }
            None => log_time as f64 * 1e-9,
        };
        let mut values = Vec::with_capacity(self.topics[topic].fields.len());
        for (_, path, steps) in &self.topics[topic].fields {
            let v = lookup(&value, steps).ok_or_else(|| {
                self.err(
                    loc,
                    field(&format!("{name}.{path}")),
                    ErrorKind::MissingSignal(format!(
                        "field not in the message ({})",
                        what_is_there(&value, steps)
                    )),
                )
            })?;
            values.push(v.as_f64().ok_or_else(|| {
                self.err(
                    loc,
                    field(&format!("{name}.{path}")),
                    ErrorKind::NotANumber(v.to_string()),
                )
            })?);
        }
        let (max_gap, latest) = (self.align.gap(), self.align.latest_time());
        if t < latest - max_gap {
            let why = match self.order {
                Order::LogTime { .. } => format!(
                    "time t = {t} s is more than max_gap = {max_gap} s before t = {latest} s of a message \
                     read earlier in log-time order: this topic's time field disagrees with \
                     the message log times"
                ),
                Order::File(_) => format!(
                    "time t = {t} s is more than max_gap = {max_gap} s before t = {latest} s of a message \
                     earlier in the file: the messages are not stored in log-time order and \
                     the file has no chunk index to read them in order (write it with chunk \
                     indexes, as the mcap and ROS 2 writers do by default, or in log-time \
                     order)"
                ),
            };
            return Err(self.err(loc, field(&name), ErrorKind::Format(why)));
        }
        let message = Message {
            t,
            values,
            loc,
            epoch: 0,
        };
        self.align.push(topic, message);
        Ok(())
    }
}

impl TopicSource for McapSource {
    const GAP_WORDS: (&'static str, &'static str) = ("max_gap", "");

    fn aligner(&mut self) -> &mut Aligner {
        &mut self.align
    }

    fn read_message(&mut self) -> Result<bool, IoError> {
        match self.order {
            Order::LogTime { .. } => self.read_indexed(),
            Order::File(_) => self.read_linear(),
        }
    }

    fn missing_topic(&self) -> Option<IoError> {
        let t = self.topics.iter().find(|t| !t.seen)?;
        let has = if self.file_topics.is_empty() {
            "the file has no channels".to_string()
        } else {
            let names: Vec<&str> = self.file_topics.iter().map(String::as_str).collect();
            format!("topics in the file: {}", names.join(", "))
        };
        Some(self.err(
            Location::File,
            field(&t.name),
            ErrorKind::MissingSignal(format!("topic not in the file ({has})")),
        ))
    }

    fn bytes_read(&self) -> u64 {
        self.bytes_read
    }
}
