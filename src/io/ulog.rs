//! PX4 ULog reader (PX4 docs, "ULog File Format"): a streaming parser of the header,
//! definitions and data sections, and the [`RowSource`] that maps topics and fields onto
//! the sample slots the same way as MCAP (one mapping format for both).
//!
//! - Header: 7 magic bytes `ULog 01 12 35`, a version byte (0 or 1), the start time (µs).
//! - Messages: `uint16 size`, `uint8 type`, `size` payload bytes. Known types: `B` flag
//!   bits (first message only; unknown incompatible bits refuse the file, the data-appended
//!   bit is honoured), `F` formats, `I`/`M` info, `P`/`Q` parameters, `A`/`R` subscriptions,
//!   `D` data, `O` dropouts, `L`/`C` strings, `S` sync. Other types are skipped, as the
//!   spec asks.
//! - A mapped topic is `name` (instance 0) or `name[k]` (multi-instance id k); fields are
//!   paths into its format (`xyz[1]`, `esc[2].esc_rpm`), located once per subscription as
//!   a byte offset and scalar type, so a data message is decoded by reading only the
//!   mapped fields. Time is the topic's `timestamp` field (µs) unless the mapping names
//!   another (`[time]` or `[mcap.topic_time]`).
//! - Asynchronous topics are aligned on the time-base topic by linear interpolation
//!   between messages at most `align_gap` apart. A logger dropout (`O`) is never bridged:
//!   messages on either side are not interpolated between, and the time-base sample after
//!   it starts a new segment.
//! - Memory is bounded: one message buffer (≤ 64 KiB) and the alignment queues.
//!
//! Errors name the file, the byte offset of the message, its type and the field.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use super::Dropout;
use super::align::{Aligner, Message, TopicSource, base_topic, topic_time};
use super::error::{ErrorKind, IoError, Location, field, key};
use super::field_path::{self, Step, Style};
use super::mapping::{Mapping, Signal};
use super::scalar::Scalar;
use super::slots::SlotLayout;

/// The seven magic bytes a ULog file starts with.
pub const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// Size of the file header, bytes.
pub const HEADER_BYTES: u64 = 16;
/// Size of a message header (`uint16 size`, `uint8 type`), bytes.
pub const MESSAGE_HEADER_BYTES: u64 = 3;
/// Smallest payload of a flag-bits (`B`) message, bytes.
pub const FLAG_BITS_BYTES: usize = 40;
/// Deepest nesting of formats accepted (a cycle is an error, not a stack overflow).
pub const MAX_NESTING: usize = 16;

/// The scalar of a ULog type name, if it is one (`char` is a byte).
fn scalar_named(name: &str) -> Option<Scalar> {
    Some(match name {
        "int8_t" => Scalar::I8,
        "uint8_t" | "char" => Scalar::U8,
        "int16_t" => Scalar::I16,
        "uint16_t" => Scalar::U16,
        "int32_t" => Scalar::I32,
        "uint32_t" => Scalar::U32,
        "int64_t" => Scalar::I64,
        "uint64_t" => Scalar::U64,
        "float" => Scalar::F32,
        "double" => Scalar::F64,
        "bool" => Scalar::Bool,
        _ => return None,
    })
}

/// One field of a format: `type[array] name`.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldDef {
    /// Type name: a scalar type or another format's name.
    pub ty: String,
    /// Array length, when the field is an array.
    pub array: Option<usize>,
    /// Field name.
    pub name: String,
}

/// Parses the text of an `F` message, `name:type field;type[n] field;…`.
pub fn parse_format(text: &str) -> Result<(String, Vec<FieldDef>), String> {
    let (name, body) = text
        .split_once(':')
        .ok_or_else(|| format!("format {text:?} has no ':' after the message name"))?;
    if name.is_empty() {
        return Err("format with an empty message name".into());
    }
    let mut fields = Vec::new();
    for item in body.split(';').filter(|s| !s.is_empty()) {
        let (ty, fname) = item
            .split_once(' ')
            .ok_or_else(|| format!("field {item:?} of format {name:?} is not `type name`"))?;
        let (ty, array) = match ty.split_once('[') {
            Some((t, rest)) => {
                let n = rest
                    .strip_suffix(']')
                    .and_then(|n| n.parse::<usize>().ok())
                    .ok_or_else(|| {
                        format!("field {fname:?} of format {name:?}: bad array type {ty:?}")
                    })?;
                (t, Some(n))
            }
            None => (ty, None),
        };
        if ty.is_empty() || fname.is_empty() || fname.contains(' ') {
            return Err(format!(
                "field {item:?} of format {name:?} is not `type name`"
            ));
        }
        fields.push(FieldDef {
            ty: ty.to_string(),
            array,
            name: fname.to_string(),
        });
    }
    Ok((name.to_string(), fields))
}

/// Parses a ULog field path `a.b[2].c`.
fn parse_path(path: &str) -> Result<Vec<Step>, String> {
    field_path::parse(path, Style::Ulog)
}

/// Splits a mapped topic `name[k]` into name and multi-instance id (0 when absent).
pub fn split_instance(topic: &str) -> Result<(&str, u8), String> {
    match topic.strip_suffix(']').and_then(|t| t.rsplit_once('[')) {
        Some((name, k)) => k
            .parse::<u8>()
            .map(|k| (name, k))
            .map_err(|_| format!("topic {topic:?}: instance {k:?} is not a number 0..=255")),
        None => Ok((topic, 0)),
    }
}

/// The formats of a file, by message name.
#[derive(Debug, Clone, Default)]
pub struct Formats {
    by_name: HashMap<String, Vec<FieldDef>>,
}

impl Formats {
    /// Adds the format of an `F` message.
    pub fn insert(&mut self, name: String, fields: Vec<FieldDef>) {
        self.by_name.insert(name, fields);
    }

    /// The fields of format `name`.
    pub fn get(&self, name: &str) -> Option<&[FieldDef]> {
        self.by_name.get(name).map(Vec::as_slice)
    }

    /// Size of one value of type `ty`, bytes.
    fn size_of(&self, ty: &str, depth: usize) -> Result<usize, String> {
        if let Some(s) = scalar_named(ty) {
            return Ok(s.size());
        }
        if depth > MAX_NESTING {
            return Err(format!(
                "format {ty:?} nests deeper than {MAX_NESTING} levels (a cycle?)"
            ));
        }
        let fields = self
            .get(ty)
            .ok_or_else(|| format!("unknown type {ty:?} (neither a scalar nor a format)"))?;
        let mut size = 0usize;
        for f in fields {
            size = size
                .checked_add(self.field_size(f, depth + 1)?)
                .ok_or("format too large")?;
        }
        Ok(size)
    }

    /// Size of field `f` (all its array elements), bytes.
    fn field_size(&self, f: &FieldDef, depth: usize) -> Result<usize, String> {
        self.size_of(&f.ty, depth)?
            .checked_mul(f.array.unwrap_or(1))
            .ok_or_else(|| format!("field {:?} is too large", f.name))
    }

    /// Byte offset and scalar type of `path` inside a message of format `format`.
    pub fn locate(&self, format: &str, path: &str) -> Result<(usize, Scalar), String> {
        let steps = parse_path(path)?;
        let mut ty = format.to_string();
        let mut offset = 0usize;
        let mut i = 0;
        while i < steps.len() {
            let Step::Key(name) = &steps[i] else {
                return Err(format!("field path {path:?}: index without a field name"));
            };
            let fields = self
                .get(&ty)
                .ok_or_else(|| format!("field path {path:?}: {ty:?} has no fields"))?;
            let mut found = None;
            for f in fields {
                if f.name == *name {
                    found = Some(f);
                    break;
                }
                offset = offset
                    .checked_add(self.field_size(f, 0)?)
                    .ok_or("format too large")?;
            }
            let f = found.ok_or_else(|| {
                let names: Vec<&str> = fields
                    .iter()
                    .filter(|f| !f.name.starts_with("_padding"))
                    .map(|f| f.name.as_str())
                    .collect();
                format!(
                    "format {ty:?} has no field {name:?} (fields: {})",
                    names.join(", ")
                )
            })?;
            i += 1;
            if let Some(n) = f.array {
                let Some(Step::Index(k)) = steps.get(i) else {
                    return Err(format!(
                        "field {name:?} of {ty:?} is an array of {n}: give an index, e.g. {name}[0]"
                    ));
                };
                if *k >= n {
                    return Err(format!(
                        "index {k} out of range: field {name:?} of {ty:?} has {n} elements"
                    ));
                }
                // k < n and the n elements' size fits (checked): k * size cannot overflow.
                let element = self.size_of(&f.ty, 0)?;
                self.field_size(f, 0)?;
                offset = offset.checked_add(k * element).ok_or("format too large")?;
                i += 1;
            }
            match scalar_named(&f.ty) {
                Some(s) if i == steps.len() => return Ok((offset, s)),
                Some(_) => {
                    return Err(format!(
                        "field path {path:?}: {name:?} is a {} and has no sub-fields",
                        f.ty
                    ));
                }
                None => {
                    if i == steps.len() {
                        return Err(format!(
                            "field path {path:?} ends at {name:?}, a nested {:?}: name one of its fields",
                            f.ty
                        ));
                    }
                    self.size_of(&f.ty, 0)?;
                    ty = f.ty.clone();
                }
            }
        }
        Err(format!("empty field path {path:?}"))
    }
}

/// Name of a message type for errors: `'D'`, or its byte value.
fn type_name(kind: u8) -> String {
    if kind.is_ascii_graphic() {
        format!("'{}'", kind as char)
    } else {
        format!("type 0x{kind:02x}")
    }
}

/// Sequential reader of ULog messages from a file, tracking byte offsets and appended
/// data.
struct MessageReader {
    file: String,
    input: BufReader<File>,
    /// Byte offset of the next unread byte.
    pos: u64,
    len: u64,
    /// Appended-data offsets not reached yet, ascending.
    appended: Vec<u64>,
    /// Payload of the message returned last.
    buf: Vec<u8>,
    /// Type of the message returned last.
    kind: u8,
}

impl MessageReader {
    /// Opens `path` and checks the header.
    fn open(path: &Path, file: &str) -> Result<(Self, u64), IoError> {
        let read_err = |e: std::io::Error| {
            IoError::new(file, Location::File, None, ErrorKind::Read(e.to_string()))
        };
        let handle = File::open(path).map_err(read_err)?;
        let len = handle.metadata().map_err(read_err)?.len();
        let mut r = Self {
            file: file.to_string(),
            input: BufReader::with_capacity(1 << 16, handle),
            pos: 0,
            len,
            appended: Vec::new(),
            buf: Vec::with_capacity(1 << 16),
            kind: 0,
        };
        if len < HEADER_BYTES {
            return Err(r.err(
                0,
                format!("truncated header: the file has {len} bytes, a ULog header {HEADER_BYTES}"),
            ));
        }
        let mut header = [0u8; 16];
        r.read_into(&mut header)?;
        if header[..7] != MAGIC {
            return Err(r.err(0, "not a ULog file (bad magic bytes)".into()));
        }
        if header[7] > 1 {
            return Err(r.err(
                7,
                format!(
                    "ULog version {} is not supported (supported: 0, 1)",
                    header[7]
                ),
            ));
        }
        let start = u64::from_le_bytes(header[8..16].try_into().unwrap_or([0; 8]));
        Ok((r, start))
    }

    fn err(&self, offset: u64, text: String) -> IoError {
        IoError::new(
            &self.file,
            Location::Offset(offset),
            None,
            ErrorKind::Format(text),
        )
    }

    fn read_into(&mut self, dst: &mut [u8]) -> Result<(), IoError> {
        self.input.read_exact(dst).map_err(|e| {
            IoError::new(
                &self.file,
                Location::Offset(self.pos),
                None,
                ErrorKind::Read(e.to_string()),
            )
        })?;
        self.pos += dst.len() as u64;
        Ok(())
    }

    fn skip(&mut self, n: u64) -> Result<(), IoError> {
        let copied =
            std::io::copy(&mut (&mut self.input).take(n), &mut std::io::sink()).map_err(|e| {
                IoError::new(
                    &self.file,
                    Location::Offset(self.pos),
                    None,
                    ErrorKind::Read(e.to_string()),
                )
            })?;
        self.pos += copied;
        if copied < n {
            return Err(self.err(
                self.pos,
                "file ended while skipping to appended data".into(),
            ));
        }
        Ok(())
    }

    /// Reads the next message; returns its byte offset (type in `kind`, payload in `buf`),
    /// `None` at the end of the file.
    fn next_message(&mut self) -> Result<Option<u64>, IoError> {
        loop {
            while self.appended.first().is_some_and(|&a| a <= self.pos) {
                self.appended.remove(0);
            }
            let start = self.pos;
            if start == self.len {
                return Ok(None);
            }
            if start + MESSAGE_HEADER_BYTES > self.len {
                return Err(self.err(
                    start,
                    format!(
                        "truncated message header: {} bytes left at the end of the file",
                        self.len - start
                    ),
                ));
            }
            if let Some(&a) = self.appended.first()
                && a < start + MESSAGE_HEADER_BYTES
            {
                // The writer stopped inside this message's header.
                self.skip(a - start)?;
                continue;
            }
            let mut h = [0u8; 3];
            self.read_into(&mut h)?;
            let size = u16::from_le_bytes([h[0], h[1]]) as u64;
            let end = start + MESSAGE_HEADER_BYTES + size;
            if let Some(&a) = self.appended.first()
                && end > a
            {
                // The writer stopped inside this message and appended data at `a`.
                self.skip(a - self.pos)?;
                continue;
            }
            if end > self.len {
                return Err(self.err(
                    start,
                    format!(
                        "truncated {} message: {size} payload bytes announced, {} left in the file",
                        type_name(h[2]),
                        self.len - start - MESSAGE_HEADER_BYTES
                    ),
                ));
            }
            self.kind = h[2];
            self.buf.resize(size as usize, 0);
            let mut buf = std::mem::take(&mut self.buf);
            let r = self.read_into(&mut buf);
            self.buf = buf;
            r?;
            return Ok(Some(start));
        }
    }

    /// Applies a `B` message at `offset` (the first message after the header).
    fn flag_bits(&mut self, offset: u64) -> Result<(), IoError> {
        let b = &self.buf;
        if b.len() < FLAG_BITS_BYTES {
            return Err(self.err(
                offset,
                format!(
                    "'B' flag-bits message has {} bytes, at least {FLAG_BITS_BYTES} expected",
                    b.len()
                ),
            ));
        }
        let incompat = &b[8..16];
        if incompat[0] & !1 != 0 || incompat[1..].iter().any(|&x| x != 0) {
            return Err(self.err(
                offset,
                format!(
                    "'B' flag-bits message sets incompatible flags {incompat:02x?} this reader does not know (known: data appended, bit 0 of byte 0)"
                ),
            ));
        }
        let mut offsets = Vec::new();
        for k in 0..3 {
            let at = 16 + 8 * k;
            let o = u64::from_le_bytes(b[at..at + 8].try_into().unwrap_or([0; 8]));
            if o != 0 {
                offsets.push(o);
            }
        }
        if incompat[0] & 1 == 1 {
            let mut last = self.pos;
            for &o in &offsets {
                if o < last || o > self.len {
                    return Err(self.err(
                        offset,
                        format!(
                            "'B' flag-bits message: appended-data offset {o} is not between {last} and the file length {}",
                            self.len
                        ),
                    ));
                }
                last = o;
            }
            self.appended = offsets;
        }
        Ok(())
    }
}

/// The key/value of an `I`, `P` or `M` message: `(type, name, value bytes)`.
fn key_value(payload: &[u8], skip: usize) -> Option<(&str, &str, &[u8])> {
    let len = *payload.get(skip)? as usize;
    let key = payload.get(skip + 1..skip + 1 + len)?;
    let key = std::str::from_utf8(key).ok()?;
    let (ty, name) = key.split_once(' ')?;
    Some((ty, name, &payload[skip + 1 + len..]))
}

/// A parameter value of a `P` message (`int32_t` or `float`) as a number.
fn param_value(ty: &str, v: &[u8]) -> Option<f64> {
    let b: [u8; 4] = v.get(..4)?.try_into().ok()?;
    match ty {
        "int32_t" => Some(i32::from_le_bytes(b) as f64),
        "float" => Some(f32::from_le_bytes(b) as f64),
        _ => None,
    }
}

/// What a ULog file says about itself: the definitions section's parameters and info.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogDefinitions {
    /// Logging start time from the header, µs.
    pub start_us: u64,
    /// Initial parameter values by name (`int32_t` and `float` parameters).
    pub parameters: BTreeMap<String, f64>,
    /// String-valued info messages (`I`, `char[n]` values) by key name, e.g. `sys_name`.
    pub info: BTreeMap<String, String>,
}

/// Reads the header and definitions section of a ULog file (stops at the first
/// subscription or data message): parameters and string info. Errors name the byte
/// offset and message.
pub fn read_definitions(path: &Path) -> Result<LogDefinitions, IoError> {
    let file = super::error::display_name(path);
    let (mut r, start_us) = MessageReader::open(path, &file)?;
    let mut defs = LogDefinitions {
        start_us,
        ..LogDefinitions::default()
    };
    let mut first = true;
    while let Some(offset) = r.next_message()? {
        let kind = r.kind;
        if std::mem::take(&mut first) && kind == b'B' {
            r.flag_bits(offset)?;
            continue;
        }
        match kind {
            b'A' | b'D' => break,
            b'P' => {
                let (ty, name, v) = key_value(&r.buf, 0)
                    .ok_or_else(|| r.err(offset, "malformed 'P' parameter message".into()))?;
                if let Some(x) = param_value(ty, v) {
                    defs.parameters.insert(name.to_string(), x);
                }
            }
            b'I' => {
                let (ty, name, v) = key_value(&r.buf, 0)
                    .ok_or_else(|| r.err(offset, "malformed 'I' info message".into()))?;
                if ty.starts_with("char[") {
                    defs.info
                        .insert(name.to_string(), String::from_utf8_lossy(v).into_owned());
                }
            }
            _ => {}
        }
    }
    Ok(defs)
}

/// Where a mapped topic's time and fields sit in its data messages.
struct Located {
    /// Byte offset and type of the time field.
    time: (usize, Scalar),
    /// Byte offset and type of each mapped field, in mapping order.
    fields: Vec<(usize, Scalar)>,
    /// Data bytes a message needs to hold all of them.
    need: usize,
}

/// A mapped topic instance.
struct Topic {
    /// Key as written in the mapping, `name` or `name[k]`.
    key: String,
    name: String,
    instance: u8,
    /// (slot, field path) of every mapped field.
    fields: Vec<(usize, String)>,
    /// Time field path and its factor to seconds.
    time: (String, f64),
    /// Time and fields located in the topic's format, once subscribed.
    located: Option<Located>,
    seen: bool,
    /// Data messages read.
    messages: u64,
}

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
            parse_path(&path).map_err(|m| {
                IoError::new(
                    file,
                    Location::File,
                    field(&format!("{topic_key}.{path}")),
                    ErrorKind::Mapping(m),
                )
            })?;
            let idx = match topics.iter().position(|t| t.key == topic_key) {
                Some(i) => i,
                None => {
                    let (name, instance) = split_instance(&topic_key).map_err(|m| {
                        mapping_err(&format!("signals.{}", layout.signal_of_slot(slot).key()), m)
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
            align: Aligner::new(file, slots, base, align_gap),
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
            let t = &self.topics[j];
            let locate = |path: &str| {
                self.formats.locate(&name, path).map_err(|m| {
                    IoError::new(
                        &self.file,
                        Location::Offset(offset),
                        field(&format!("{}.{path}", t.key)),
                        ErrorKind::Mapping(m),
                    )
                })
            };
            let (toff, tscalar) = locate(&t.time.0)?;
            let mut fields = Vec::with_capacity(t.fields.len());
            let mut need = toff.saturating_add(tscalar.size());
            for (_, path) in &t.fields {
                let (o, s) = locate(path)?;
                need = need.max(o.saturating_add(s.size()));
                fields.push((o, s));
            }
            self.topics[j].located = Some(Located {
                time: (toff, tscalar),
                fields,
                need,
            });
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
    const GAP_WORDS: (&'static str, &'static str) =
        ("align_gap", " (or a logger dropout between them)");

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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_and_paths() {
        let mut f = Formats::default();
        let (n, fields) =
            parse_format("esc_report:int32_t esc_rpm;float v;uint8_t[4] _padding0;").unwrap();
        f.insert(n, fields);
        let (n, fields) = parse_format(
            "esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[8] esc",
        )
        .unwrap();
        f.insert(n, fields);
        assert_eq!(
            f.locate("esc_status", "timestamp").unwrap(),
            (0, Scalar::U64)
        );
        assert_eq!(
            f.locate("esc_status", "esc[2].esc_rpm").unwrap(),
            (16 + 2 * 12, Scalar::I32)
        );
        assert_eq!(
            f.locate("esc_status", "esc[0].v").unwrap(),
            (20, Scalar::F32)
        );
        assert!(
            f.locate("esc_status", "esc[8].v")
                .unwrap_err()
                .contains("out of range")
        );
        assert!(
            f.locate("esc_status", "esc")
                .unwrap_err()
                .contains("give an index")
        );
        assert!(
            f.locate("esc_status", "esc[1]")
                .unwrap_err()
                .contains("nested")
        );
        assert!(
            f.locate("esc_status", "rpm")
                .unwrap_err()
                .contains("fields: timestamp, esc_count, esc")
        );
        assert_eq!(
            split_instance("actuator_outputs[1]").unwrap(),
            ("actuator_outputs", 1)
        );
        assert_eq!(split_instance("a").unwrap(), ("a", 0));
        assert!(split_instance("a[x]").is_err());
        let (n, fields) = parse_format("loop:uint64_t timestamp;loop[1] me").unwrap();
        f.insert(n, fields);
        assert!(
            f.locate("loop", "me[0].timestamp")
                .unwrap_err()
                .contains("nests deeper")
        );
        let big = "big:uint64_t timestamp;double[4611686018427387904] b;double x";
        let (n, fields) = parse_format(big).unwrap();
        f.insert(n, fields);
        assert!(f.locate("big", "x").unwrap_err().contains("too large"));
        assert!(f.locate("big", "b[3]").unwrap_err().contains("too large"));
    }
}
