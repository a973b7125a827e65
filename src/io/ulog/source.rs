//! [`UlogSource`]: the messages of a ULog file read in order, formats and subscriptions
//! kept, the mapped fields of each data message decoded and pushed to the [`Aligner`],
//! and logger dropouts recorded as epochs the alignment never bridges.

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use super::super::Dropout;
use super::super::align::{Aligner, Message, TopicSource, base_topic};
use super::super::error::{ErrorKind, IoError, Location, field};
use super::super::mapping::{Mapping, Signal};
use super::super::px4::{MISSING_ROTOR_SPEEDS, SLOW_TOPICS};
use super::super::slots::SlotLayout;
use super::format::{Formats, parse_format};
use super::messages::MessageReader;
use super::topics::{Located, Topic, mapped_topics};

/// Streaming ULog source; see the module docs.
pub struct UlogSource {
    file: String,
    reader: MessageReader,
    formats: Formats,
    /// Subscribed msg ids: the mapped topic they feed, if any.
    subscriptions: HashMap<u16, Option<usize>>,
    logged: BTreeSet<String>,
    /// `D` data messages read, of any topic.
    data_messages: u64,
    topics: Vec<Topic>,
    /// Which signal each slot of the topics feeds.
    layout: SlotLayout,
    align: Aligner,
    /// Dropouts read so far: the epoch of the messages read now.
    epoch: u32,
    dropouts: Vec<Dropout>,
    first_message: bool,
}

impl UlogSource {
    /// Opens `path` with `mapping` (topics and fields) for `rotors` rotors; asynchronous
    /// topics are interpolated between messages at most `align_gap` seconds apart.
    pub fn open(
        path: &Path,
        file: &str,
        mapping: &Mapping,
        rotors: usize,
        align_gap: f64,
    ) -> Result<(Self, SlotLayout), IoError> {
        let layout = SlotLayout::resolve(mapping, rotors, file, true)?;
        let topics = mapped_topics(mapping, &layout, file)?;
        let base = base_topic(mapping, topics.iter().map(|t| t.key.as_str()), file)?;
        let (reader, _) = MessageReader::open(path, file)?;
        let slots = topics
            .iter()
            .map(|t| {
                (
                    t.key.clone(),
                    t.fields.iter().map(|(slot, _)| *slot).collect(),
                )
            })
            .collect();
        let source = Self {
            file: file.to_string(),
            reader,
            formats: Formats::default(),
            subscriptions: HashMap::new(),
            logged: BTreeSet::new(),
            data_messages: 0,
            topics,
            layout: layout.clone(),
            align: Aligner::new(file, slots, base, align_gap)
                .with_quaternion(layout.start(Signal::Attitude))
                .with_rotor_speeds(layout.start(Signal::RotorSpeeds)),
            epoch: 0,
            dropouts: Vec::new(),
            first_message: true,
        };
        Ok((source, layout))
    }

    fn err(&self, offset: u64, field_label: Option<String>, text: String) -> IoError {
        IoError::new(
            &self.file,
            Location::Offset(offset),
            field_label,
            ErrorKind::Format(text),
        )
    }

    /// An `A` message: msg id → topic instance, locating the mapped fields.
    fn subscribe(&mut self, offset: u64) -> Result<(), IoError> {
        let b = &self.reader.buf;
        if b.len() < 4 {
            return Err(self.err(
                offset,
                None,
                format!(
                    "'A' subscription message has {} bytes, at least 4 expected",
                    b.len()
                ),
            ));
        }
        let multi_id = b[0];
        let msg_id = u16::from_le_bytes([b[1], b[2]]);
        let name = std::str::from_utf8(&b[3..])
            .map_err(|_| {
                self.err(
                    offset,
                    None,
                    "'A' subscription: topic name is not UTF-8".into(),
                )
            })?
            .to_string();
        if self.formats.get(&name).is_none() {
            return Err(self.err(
                offset,
                None,
                format!("'A' subscription of msg_id {msg_id} to {name:?}, which has no 'F' format definition"),
            ));
        }
        self.logged.insert(if multi_id == 0 {
            name.clone()
        } else {
            format!("{name}[{multi_id}]")
        });
        let topic = self
            .topics
            .iter()
            .position(|t| t.name == name && t.instance == multi_id);
        if let Some(j) = topic {
            let located = self.topics[j].locate(&self.formats, &name, &self.file, offset)?;
            self.topics[j].located = Some(located);
            self.topics[j].seen = true;
        }
        self.subscriptions.insert(msg_id, topic);
        Ok(())
    }

    /// A `D` message; true when it was queued for a mapped topic.
    fn data(&mut self, offset: u64) -> Result<bool, IoError> {
        let b = &self.reader.buf;
        if b.len() < 2 {
            return Err(self.err(
                offset,
                None,
                format!(
                    "'D' data message has {} bytes, at least 2 expected",
                    b.len()
                ),
            ));
        }
        let msg_id = u16::from_le_bytes([b[0], b[1]]);
        self.data_messages += 1;
        let j = match self.subscriptions.get(&msg_id) {
            Some(Some(j)) => *j,
            Some(None) => return Ok(false),
            None => {
                return Err(self.err(
                    offset,
                    None,
                    format!(
                        "'D' data message for msg_id {msg_id}, which no 'A' message subscribed"
                    ),
                ));
            }
        };
        let data = &b[2..];
        let topic = &self.topics[j];
        let Some(Located {
            time: (toff, tscalar),
            fields,
            need,
        }) = &topic.located
        else {
            return Ok(false);
        };
        if data.len() < *need {
            return Err(self.err(
                offset,
                field(&topic.key),
                format!(
                    "'D' data message of {:?} has {} data bytes, the mapped fields need {need}",
                    topic.key,
                    data.len()
                ),
            ));
        }
        let t = tscalar.read_le(&data[*toff..]) * topic.time.1;
        let values = fields.iter().map(|(o, s)| s.read_le(&data[*o..])).collect();
        self.topics[j].messages += 1;
        let message = Message {
            t,
            values,
            loc: Location::Offset(offset),
            epoch: self.epoch,
        };
        self.align.push(j, message);
        Ok(true)
    }
}

impl TopicSource for UlogSource {
    const GAP_WORDS: (&'static str, &'static str) = ("align_gap", SLOW_TOPICS);

    fn aligner(&mut self) -> &mut Aligner {
        &mut self.align
    }

    fn read_message(&mut self) -> Result<bool, IoError> {
        while let Some(offset) = self.reader.next_message()? {
            let kind = self.reader.kind;
            if std::mem::take(&mut self.first_message) && kind == b'B' {
                self.reader.flag_bits(offset)?;
                continue;
            }
            match kind {
                b'B' => {
                    return Err(self.err(
                        offset,
                        None,
                        "'B' flag-bits message after the first message".into(),
                    ));
                }
                b'F' => {
                    let text = std::str::from_utf8(&self.reader.buf).map_err(|_| {
                        self.err(offset, None, "'F' format message is not UTF-8 text".into())
                    })?;
                    let (name, fields) = parse_format(text)
                        .map_err(|m| self.err(offset, None, format!("'F' format message: {m}")))?;
                    self.formats.insert(name, fields);
                }
                b'A' => self.subscribe(offset)?,
                b'R' => {
                    let b = &self.reader.buf;
                    if b.len() < 2 {
                        return Err(self.err(
                            offset,
                            None,
                            format!("'R' message has {} bytes, 2 expected", b.len()),
                        ));
                    }
                    self.subscriptions.remove(&u16::from_le_bytes([b[0], b[1]]));
                }
                b'D' if self.data(offset)? => return Ok(true),
                b'O' => {
                    let b = &self.reader.buf;
                    if b.len() < 2 {
                        return Err(self.err(
                            offset,
                            None,
                            format!("'O' dropout message has {} bytes, 2 expected", b.len()),
                        ));
                    }
                    let ms = u16::from_le_bytes([b[0], b[1]]);
                    self.epoch += 1;
                    if self.dropouts.len() < 1000 {
                        self.dropouts.push(Dropout {
                            offset,
                            after: self.align.latest_time(),
                            duration: ms as f64 * 1e-3,
                        });
                    }
                }
                _ => {}
            }
        }
        Ok(false)
    }

    fn missing_topic(&self) -> Option<IoError> {
        let t = self.topics.iter().find(|t| t.messages == 0)?;
        let logged: Vec<&str> = self.logged.iter().map(String::as_str).collect();
        let text = if self.data_messages == 0 {
            let subscribed = if logged.is_empty() {
                "no topic is subscribed".to_string()
            } else {
                format!("subscribed topics: {}", logged.join(", "))
            };
            format!("the log has no data messages ({subscribed})")
        } else if t.seen {
            "topic is subscribed but has no data messages in the log".to_string()
        } else {
            format!(
                "topic not in the log (logged topics: {})",
                logged.join(", ")
            )
        };
        let feeds_rotors = t
            .fields
            .iter()
            .any(|(slot, _)| self.layout.signal_of_slot(*slot) == Signal::RotorSpeeds);
        let text = if feeds_rotors {
            format!("{text}; {MISSING_ROTOR_SPEEDS}")
        } else {
            text
        };
        Some(IoError::new(
            &self.file,
            Location::File,
            field(&t.key),
            ErrorKind::MissingSignal(text),
        ))
    }

    fn dropouts(&self) -> &[Dropout] {
        &self.dropouts
    }

    fn cut_off(&self) -> Option<&str> {
        self.reader.cut_off.note()
    }

    fn bytes_read(&self) -> u64 {
        self.reader.position()
    }
}
