//! The mapped topics of a ULog file: which topic instance (`name` or `name[k]`) feeds
//! which slots through which field paths, with which time field; and, once the topic
//! is subscribed, where those fields sit in its data messages.

use super::super::align::{split_instance, topic_time};
use super::super::error::{ErrorKind, IoError, Location, field, key};
use super::super::mapping::{Mapping, Signal};
use super::super::scalar::Scalar;
use super::super::slots::SlotLayout;
use super::format::{Formats, parse_path};

/// Where a mapped topic's time and fields sit in its data messages.
pub(super) struct Located {
    /// Byte offset and type of the time field.
    pub time: (usize, Scalar),
    /// Byte offset and type of each mapped field, in mapping order.
    pub fields: Vec<(usize, Scalar)>,
    /// Data bytes a message needs to hold all of them.
    pub need: usize,
}

/// A mapped topic instance.
pub(super) struct Topic {
    /// Key as written in the mapping, `name` or `name[k]`.
    pub key: String,
    pub name: String,
    pub instance: u8,
    /// (slot, field path) of every mapped field.
    pub fields: Vec<(usize, String)>,
    /// Time field path and its factor to seconds.
    pub time: (String, f64),
    /// Time and fields located in the topic's format, once subscribed.
    pub located: Option<Located>,
    pub seen: bool,
    /// Data messages read.
    pub messages: u64,
}

/// The topics `mapping` maps onto the slots of `layout` (in slot order), for `file`.
/// A topic's time is its `[mcap.topic_time]` field, else the `[time]` field, else
/// `timestamp` in µs.
pub(super) fn mapped_topics(
    mapping: &Mapping,
    layout: &SlotLayout,
    file: &str,
) -> Result<Vec<Topic>, IoError> {
    let mapping_err =
        |k: &str, m: String| IoError::new(file, Location::File, key(k), ErrorKind::Mapping(m));
    let default_time = match mapping.get(Signal::Time) {
        Some(m) if !m.fields.is_empty() => (m.fields[0].clone(), mapping.factor(Signal::Time)),
        _ => ("timestamp".to_string(), 1e-6),
    };
    let mut topics: Vec<Topic> = Vec::new();
    for slot in 0..layout.len() {
        let topic_key = layout.topic(slot).unwrap_or_default().to_string();
        let path = layout.source_name(slot).to_string();
        parse_path(&path).map_err(|e| {
            IoError::new(
                file,
                Location::File,
                field(&format!("{topic_key}.{path}")),
                ErrorKind::Mapping(e.to_string()),
            )
        })?;
        let idx = match topics.iter().position(|t| t.key == topic_key) {
            Some(i) => i,
            None => {
                let (name, instance) = split_instance(&topic_key, "topic").map_err(|e| {
                    mapping_err(
                        &format!("signals.{}", layout.signal_of_slot(slot).key()),
                        e.to_string(),
                    )
                })?;
                let check = |path: &str| parse_path(path).map(|_| path.to_string());
                let time = topic_time(mapping, &topic_key, file, check)?
                    .unwrap_or_else(|| default_time.clone());
                topics.push(Topic {
                    key: topic_key.clone(),
                    name: name.to_string(),
                    instance,
                    fields: Vec::new(),
                    time,
                    located: None,
                    seen: false,
                    messages: 0,
                });
                topics.len() - 1
            }
        };
        topics[idx].fields.push((slot, path));
    }
    Ok(topics)
}

impl Topic {
    /// Locates the time and mapped fields in format `format` of `formats`; errors name
    /// the field and the subscription at byte `offset` of `file`.
    pub fn locate(
        &self,
        formats: &Formats,
        format: &str,
        file: &str,
        offset: u64,
    ) -> Result<Located, IoError> {
        let locate = |path: &str| {
            formats.locate(format, path).map_err(|e| {
                IoError::new(
                    file,
                    Location::Offset(offset),
                    field(&format!("{}.{path}", self.key)),
                    ErrorKind::Mapping(e.to_string()),
                )
            })
        };
        let (toff, tscalar) = locate(&self.time.0)?;
        let mut fields = Vec::with_capacity(self.fields.len());
        let mut need = toff.saturating_add(tscalar.size());
        for (_, path) in &self.fields {
            let (o, s) = locate(path)?;
            need = need.max(o.saturating_add(s.size()));
            fields.push((o, s));
        }
        Ok(Located {
            time: (toff, tscalar),
            fields,
            need,
        })
    }
}
