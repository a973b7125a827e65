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
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use mcap::records::{MessageHeader, Record};
use mcap::sans_io::indexed_reader::{IndexedReadEvent, IndexedReader, IndexedReaderOptions};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
use serde_json::Value;

use super::align::{Aligner, Message, TopicSource, base_topic, topic_time};
use super::error::{ErrorKind, IoError, Location, field};
use super::field_path::{self, Step, Style};
use super::mapping::{Mapping, Signal};
use super::slots::SlotLayout;

/// Largest MCAP record (or chunk) accepted, bytes: a corrupt length field is an error,
/// not an allocation of that size.
pub const MAX_RECORD_BYTES: usize = 256 << 20;

/// Parses a JSON field path `a.b[2].c`.
fn parse_path(path: &str) -> Result<Vec<Step>, String> {
    field_path::parse(path, Style::Json)
}

fn lookup<'v>(value: &'v Value, steps: &[Step]) -> Option<&'v Value> {
    steps.iter().try_fold(value, |v, s| match s {
        Step::Key(k) => v.get(k),
        Step::Index(i) => v.get(*i),
    })
}

/// What `value` has where the path `steps` leaves it, e.g. `gyro has 3 elements`, `the
/// message has fields f, gyro, vel`; empty when the path is in it.
fn what_is_there(value: &Value, steps: &[Step]) -> String {
    let mut v = value;
    let mut path = String::new();
    for step in steps {
        let next = match step {
            Step::Key(k) => v.get(k),
            Step::Index(i) => v.get(*i),
        };
        let Some(next) = next else {
            let here = if path.is_empty() {
                "the message".to_string()
            } else {
                path
            };
            return match v {
                Value::Object(map) => {
                    let keys: Vec<&str> = map.keys().map(String::as_str).collect();
                    format!("{here} has fields {}", keys.join(", "))
                }
                Value::Array(items) => format!("{here} has {} elements", items.len()),
                other => format!("{here} is {other}, not an object or array"),
            };
        };
        match step {
            Step::Key(k) if path.is_empty() => path = k.clone(),
            Step::Key(k) => path = format!("{path}.{k}"),
            Step::Index(i) => path = format!("{path}[{i}]"),
        }
        v = next;
    }
    String::new()
}

/// A number, or a ROS time `{sec, nanosec}` / `{secs, nsecs}` in seconds.
fn as_number(v: &Value) -> Option<f64> {
    if let Some(x) = v.as_f64() {
        return Some(x);
    }
    let sec = v.get("sec").or_else(|| v.get("secs"))?.as_f64()?;
    let ns = v.get("nanosec").or_else(|| v.get("nsecs"))?.as_f64()?;
    Some(sec + ns * 1e-9)
}

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

/// How messages are read: log-time order through chunk indexes, or file order.
enum Order {
    /// Through the summary's chunk indexes; `buffer` holds one compressed chunk.
    LogTime {
        reader: Box<IndexedReader>,
        buffer: Vec<u8>,
    },
    /// Record by record in file order (no summary or no chunk index).
    File(Box<LinearReader>),
}

/// The file's summary (channels, schemas, chunk indexes) when it has one that is
/// readable, has chunk indexes and names every topic in `topics`; `None` otherwise (read
/// in file order then). The file position is left at the start.
fn indexed_summary(handle: &mut File, topics: &[Topic]) -> Result<Option<mcap::Summary>, String> {
    let size = handle.metadata().map_err(|e| e.to_string())?.len();
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(size)
            .with_record_length_limit(MAX_RECORD_BYTES),
    );
    let mut readable = true;
    while let Some(event) = reader.next_event() {
        let done = match event {
            Ok(SummaryReadEvent::ReadRequest(need)) => match handle.read(reader.insert(need)) {
                Ok(n) => {
                    reader.notify_read(n);
                    false
                }
                Err(_) => true,
            },
            Ok(SummaryReadEvent::SeekRequest(to)) => match handle.seek(to) {
                Ok(pos) => {
                    reader.notify_seeked(pos);
                    false
                }
                Err(_) => true,
            },
            // A damaged summary: the file-order reader reports what is wrong.
            Err(_) => true,
        };
        if done {
            readable = false;
            break;
        }
    }
    handle.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    let summary = if readable { reader.finish() } else { None };
    Ok(summary.filter(|s| {
        !s.chunk_indexes.is_empty()
            && topics
                .iter()
                .all(|t| s.channels.values().any(|c| c.topic == t.name))
    }))
}

/// Checks the start of the file (magic and header record) with the linear reader, as a
/// file-order read would: reading through the index skips it.
fn check_start(handle: &mut File) -> Result<(), String> {
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES),
    );
    let result = loop {
        match reader.next_event() {
            None => break Ok(()),
            Some(Err(e)) => break Err(format!("MCAP: {e}")),
            Some(Ok(LinearReadEvent::Record { .. })) => break Ok(()),
            Some(Ok(LinearReadEvent::ReadRequest(need))) => {
                match handle.read(reader.insert(need)) {
                    Ok(n) => reader.notify_read(n),
                    Err(e) => break Err(e.to_string()),
                }
            }
        }
    };
    handle.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    result
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
            let steps = parse_path(&field_name).map_err(|m| {
                IoError::new(
                    file,
                    Location::File,
                    field(&format!("{name}.{field_name}")),
                    ErrorKind::Mapping(m),
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
                        ErrorKind::Mapping(e),
                    )
                })?;
                Some((steps, mapping.factor(Signal::Time)))
            }
            _ => None,
        };
        for topic in &mut topics {
            topic.time = topic_time(mapping, &topic.name, file, parse_path)?.or(time_field.clone());
        }
        let read_error = |m: String| IoError::new(file, Location::File, None, ErrorKind::Read(m));
        let summary = indexed_summary(&mut handle, &topics).map_err(read_error)?;
        let order = match &summary {
            Some(summary) => {
                check_start(&mut handle).map_err(|m| {
                    IoError::new(file, Location::Record(0), None, ErrorKind::Format(m))
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
            align: Aligner::new(file, slots, base, max_gap),
            message_index: 0,
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

    fn read_error(&self, e: std::io::Error) -> IoError {
        self.err(Location::File, None, ErrorKind::Read(e.to_string()))
    }

    /// The next mapped message in log-time order, through the chunk indexes.
    fn read_indexed(&mut self) -> Result<bool, IoError> {
        loop {
            let Order::LogTime { reader, buffer } = &mut self.order else {
                return Ok(false);
            };
            let (header, data) = match reader.next_event() {
                None => return Ok(false),
                Some(Err(e)) => {
                    let index = self.message_index;
                    return Err(self.err(
                        Location::Record(index),
                        None,
                        ErrorKind::Format(format!("MCAP: {e}")),
                    ));
                }
                Some(Ok(IndexedReadEvent::Message { header, data })) => (header, data.to_vec()),
                Some(Ok(IndexedReadEvent::ReadChunkRequest { offset, length })) => {
                    buffer.resize(length, 0);
                    let read = self
                        .handle
                        .seek(SeekFrom::Start(offset))
                        .and_then(|_| self.handle.read_exact(buffer));
                    if let Err(e) = read {
                        return Err(self.read_error(e));
                    }
                    if let Err(e) = reader.insert_chunk_record_data(offset, buffer) {
                        let index = self.message_index;
                        return Err(self.err(
                            Location::Record(index),
                            None,
                            ErrorKind::Format(format!("MCAP chunk at byte {offset}: {e}")),
                        ));
                    }
                    continue;
                }
            };
            if self.on_message(&header, &data)? {
                return Ok(true);
            }
        }
    }

    /// The next mapped message in file order.
    fn read_linear(&mut self) -> Result<bool, IoError> {
        loop {
            let Order::File(reader) = &mut self.order else {
                return Ok(false);
            };
            let event = match reader.next_event() {
                None => return Ok(false),
                Some(Err(e)) => {
                    let index = self.message_index;
                    // A file that ends before its first message (the magic bytes alone,
                    // a cut header) has no message to name: the byte it ends at is.
                    let ended = self.handle.stream_position().ok().filter(|&at| {
                        index == 0 && self.handle.metadata().is_ok_and(|m| m.len() == at)
                    });
                    return Err(match ended {
                        Some(at) => self.err(
                            Location::Offset(at),
                            None,
                            ErrorKind::Format(format!(
                                "MCAP: {e}: the file ends at byte {at}, before any message"
                            )),
                        ),
                        None => self.err(
                            Location::Record(index),
                            None,
                            ErrorKind::Format(format!("MCAP: {e}")),
                        ),
                    });
                }
                Some(Ok(ev)) => ev,
            };
            let (opcode, data) = match event {
                LinearReadEvent::ReadRequest(need) => {
                    match self.handle.read(reader.insert(need)) {
                        Ok(n) => reader.notify_read(n),
                        Err(e) => return Err(self.read_error(e)),
                    }
                    continue;
                }
                LinearReadEvent::Record { opcode, data } => (opcode, data.to_vec()),
            };
            let record = mcap::parse_record(opcode, &data).map_err(|e| {
                IoError::new(
                    &self.file,
                    Location::Record(self.message_index),
                    None,
                    ErrorKind::Format(format!("MCAP record: {e}")),
                )
            })?;
            match record {
                Record::Schema { header, data } => {
                    self.schemas
                        .insert(header.id, (header.name, header.encoding, data.into_owned()));
                }
                Record::Channel(ch) => {
                    self.add_channel(ch.id, &ch.topic, &ch.message_encoding, ch.schema_id)?;
                }
                Record::Message { header, data } if self.on_message(&header, &data)? => {
                    return Ok(true);
                }
                _ => {}
            }
        }
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
                    .map_err(|m| fail(format!("schema {name}: {m}")))?;
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
            Decoder::Cdr(schema) => super::cdr::decode(schema, data).map_err(|m| {
                self.err(
                    loc,
                    field(&name),
                    ErrorKind::Format(format!("invalid CDR: {m}")),
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
}
