//! [`DataflashSource`]: the messages of a DataFlash log read in order, each mapped
//! message's fields located once its format is known, the mapped fields of each message
//! of the wanted instance decoded and pushed to the [`Aligner`].

use std::collections::BTreeSet;
use std::path::Path;

use super::super::align::{Aligner, Message, TopicSource, base_topic};
use super::super::ardupilot::{MISSING_ROTOR_SPEEDS, SLOW_MESSAGES};
use super::super::error::{ErrorKind, IoError, Location, field};
use super::super::mapping::{Mapping, Signal};
use super::super::slots::SlotLayout;
use super::FMT_TYPE;
use super::messages::MessageReader;
use super::topics::{Located, Topic, mapped_topics};

/// Streaming DataFlash source; see the module docs.
pub struct DataflashSource {
    file: String,
    reader: MessageReader,
    mapping: Mapping,
    layout: SlotLayout,
    topics: Vec<Topic>,
    /// Mapped topics by message type, filled as the formats are defined.
    by_type: Vec<Vec<usize>>,
    /// The message types with data in the log.
    logged: [bool; 256],
    /// Data messages read, of any type.
    data_messages: u64,
    align: Aligner,
}

impl DataflashSource {
    /// Opens `path` with `mapping` (messages and fields) for `rotors` rotors; messages of
    /// other rates are interpolated between messages at most `align_gap` seconds apart.
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
        let reader = MessageReader::open(path, file)?;
        let slots = topics
            .iter()
            .map(|t| (t.key.clone(), t.fields.iter().map(|(s, _)| *s).collect()))
            .collect();
        let source = Self {
            file: file.to_string(),
            reader,
            mapping: mapping.clone(),
            layout: layout.clone(),
            topics,
            by_type: vec![Vec::new(); 256],
            logged: [false; 256],
            data_messages: 0,
            align: Aligner::new(file, slots, base, align_gap)
                .with_quaternion(layout.start(Signal::Attitude))
                .with_rotor_speeds(layout.start(Signal::RotorSpeeds)),
        };
        Ok((source, layout))
    }

    /// The message just read, of type `ty` at `offset`: true when it was queued for a
    /// mapped topic.
    fn data(&mut self, ty: u8, offset: u64) -> Result<bool, IoError> {
        self.data_messages += 1;
        let Some(format) = self.reader.formats[ty as usize].as_ref() else {
            return Ok(false);
        };
        self.logged[ty as usize] = true;
        let js = &self.by_type[ty as usize];
        let body = &self.reader.body;
        let mut queued = false;
        for &j in js {
            let topic = &mut self.topics[j];
            topic.seen += 1;
            if topic.located.is_none() {
                let located = topic.locate(
                    format,
                    &self.reader.tables,
                    &self.mapping,
                    &self.layout,
                    &self.file,
                    offset,
                )?;
                topic.located = Some(located);
            }
            let Some(Located {
                time: (toff, ts, tf),
                instance,
                fields,
            }) = &topic.located
            else {
                continue;
            };
            let inst = instance.map_or(0.0, |(o, s)| s.read_le(&body[o..]));
            if inst != topic.instance as f64 {
                continue;
            }
            let t = ts.read_le(&body[*toff..]) * tf;
            let values = fields
                .iter()
                .map(|(o, s, f)| s.read_le(&body[*o..]) * f)
                .collect();
            topic.messages += 1;
            self.align.push(
                j,
                Message {
                    t,
                    values,
                    loc: Location::Offset(offset),
                    epoch: 0,
                },
            );
            queued = true;
        }
        Ok(queued)
    }

    /// A format was (re)defined for type `ty`: the mapped topics of its name.
    fn define(&mut self, ty: u8) {
        let Some(name) = self.reader.formats[ty as usize]
            .as_ref()
            .map(|f| f.name.clone())
        else {
            return;
        };
        let js: Vec<usize> = (0..self.topics.len())
            .filter(|&j| self.topics[j].name == name)
            .collect();
        for &j in &js {
            self.topics[j].located = None;
        }
        for v in &mut self.by_type {
            v.retain(|j| !js.contains(j));
        }
        self.by_type[ty as usize] = js;
    }
}

impl TopicSource for DataflashSource {
    const GAP_WORDS: (&'static str, &'static str) = ("align_gap", SLOW_MESSAGES);

    fn aligner(&mut self) -> &mut Aligner {
        &mut self.align
    }

    fn read_message(&mut self) -> Result<bool, IoError> {
        while let Some(offset) = self.reader.next_message()? {
            let ty = self.reader.kind;
            if ty == FMT_TYPE {
                let defined = self.reader.body[0];
                self.define(defined);
                continue;
            }
            if self.data(ty, offset)? {
                return Ok(true);
            }
        }
        Ok(false)
    }

    fn missing_topic(&self) -> Option<IoError> {
        let t = self.topics.iter().find(|t| t.messages == 0)?;
        let logged: BTreeSet<&str> = (0..256)
            .filter(|&ty| self.logged[ty])
            .filter_map(|ty| self.reader.formats[ty].as_ref().map(|f| f.name.as_str()))
            .collect();
        let logged: Vec<&str> = logged.into_iter().collect();
        let mut text = if self.data_messages == 0 {
            "the log has no data messages".to_string()
        } else if t.seen > 0 {
            format!(
                "message {} is in the log ({} messages) but none of instance {}",
                t.name, t.seen, t.instance
            )
        } else {
            format!(
                "message not in the log (messages in the log: {})",
                logged.join(", ")
            )
        };
        let feeds_rotors = t
            .fields
            .iter()
            .any(|(slot, _)| self.layout.signal_of_slot(*slot) == Signal::RotorSpeeds);
        if feeds_rotors {
            text += &format!("; {}", MISSING_ROTOR_SPEEDS);
        }
        Some(IoError::new(
            &self.file,
            Location::File,
            field(&t.key),
            ErrorKind::MissingSignal(text),
        ))
    }

    fn cut_off(&self) -> Option<&str> {
        self.reader.cut_off.note()
    }

    fn bytes_read(&self) -> u64 {
        self.reader.position()
    }
}
