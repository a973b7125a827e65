//! Reading a DataFlash log message by message: each message's two head bytes and type
//! checked, its length taken from the type's `FMT` definition, its body kept; `FMT`,
//! `FMTU`, `UNIT` and `MULT` applied on the way, so the caller sees every message with
//! its format known. Every error names the byte offset of the message. A message the end
//! of the file cuts short ends the log ([`super::super::summary::CutOff`]): a log closed
//! by a power cut or a killed simulator is read up to it.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use super::super::error::{ErrorKind, IoError, Location};
use super::super::summary::CutOff;
use super::format::{Format, UnitTables, parse_fmt, text};
use super::{FMT_TYPE, HEAD, HEADER_BYTES};

/// Sequential reader of DataFlash messages, with the formats read so far.
pub(super) struct MessageReader {
    file: String,
    input: BufReader<File>,
    /// Byte offset of the next unread byte.
    pos: u64,
    len: u64,
    /// Formats by message type.
    pub(super) formats: Vec<Option<Format>>,
    pub(super) tables: UnitTables,
    /// Body (after the header bytes) of the message returned last.
    pub(super) body: Vec<u8>,
    /// Type of the message returned last.
    pub(super) kind: u8,
    /// What the end of the file cut short, once reached.
    pub(super) cut_off: CutOff,
}

impl MessageReader {
    /// Opens `path`; the first message must be a DataFlash message.
    pub(super) fn open(path: &Path, file: &str) -> Result<Self, IoError> {
        let read_err = |e: std::io::Error| {
            IoError::new(file, Location::File, None, ErrorKind::Read(e.to_string()))
        };
        let handle = File::open(path).map_err(read_err)?;
        let len = handle.metadata().map_err(read_err)?.len();
        Ok(Self {
            file: file.to_string(),
            input: BufReader::with_capacity(1 << 16, handle),
            pos: 0,
            len,
            formats: vec![None; 256],
            tables: UnitTables::default(),
            body: Vec::with_capacity(256),
            kind: 0,
            cut_off: CutOff::default(),
        })
    }

    /// Bytes of the file read so far.
    pub(super) fn position(&self) -> u64 {
        self.pos
    }

    /// Ends the log at `start`, where the file ends inside `what` (`length` bytes long):
    /// nothing more is read.
    fn end_inside(&mut self, start: u64, what: &str, length: u64) -> Option<u64> {
        self.cut_off.record(start, what, self.len, length);
        self.pos = self.len;
        None
    }

    pub(super) fn err(&self, offset: u64, text: String) -> IoError {
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

    /// The name of message type `ty` for errors.
    pub(super) fn name(&self, ty: u8) -> String {
        match &self.formats[ty as usize] {
            Some(f) => format!("{} (type {ty})", f.name),
            None if ty == FMT_TYPE => "FMT (type 128)".into(),
            None => format!("type {ty}"),
        }
    }

    /// Reads the next message; returns its byte offset (type in `kind`, body in `body`),
    /// `None` at the end of the file. `FMT`, `FMTU`, `UNIT` and `MULT` messages are
    /// applied and also returned.
    pub(super) fn next_message(&mut self) -> Result<Option<u64>, IoError> {
        let start = self.pos;
        if start == self.len {
            return Ok(None);
        }
        if start + HEADER_BYTES as u64 > self.len {
            return Ok(self.end_inside(start, "message header", HEADER_BYTES as u64));
        }
        let mut h = [0u8; HEADER_BYTES];
        self.read_into(&mut h)?;
        if h[..2] != HEAD {
            return Err(self.err(
                start,
                format!(
                    "corrupted message header: bytes 0x{:02X} 0x{:02X}, expected 0xA3 0x95{}",
                    h[0],
                    h[1],
                    if start == 0 {
                        " (not an ArduPilot DataFlash log)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let ty = h[2];
        let length = match &self.formats[ty as usize] {
            Some(f) => f.length,
            None if ty == FMT_TYPE => HEADER_BYTES + super::FMT_BODY_BYTES,
            None => {
                return Err(self.err(
                    start,
                    format!("unknown message type {ty}: no FMT message defines it before this one"),
                ));
            }
        };
        let size = length - HEADER_BYTES;
        if start + length as u64 > self.len {
            let what = format!("{} message", self.name(ty));
            return Ok(self.end_inside(start, &what, length as u64));
        }
        self.kind = ty;
        self.body.resize(size, 0);
        let mut body = std::mem::take(&mut self.body);
        let r = self.read_into(&mut body);
        self.body = body;
        r?;
        self.apply_metadata(start)?;
        Ok(Some(start))
    }

    /// Applies the message just read when it is `FMT`, `FMTU`, `UNIT` or `MULT`.
    fn apply_metadata(&mut self, offset: u64) -> Result<(), IoError> {
        if self.kind == FMT_TYPE {
            let (ty, format) = parse_fmt(&self.body)
                .map_err(|m| self.err(offset, format!("bad FMT message: {m}")))?;
            if ty == FMT_TYPE && format.length != HEADER_BYTES + super::FMT_BODY_BYTES {
                return Err(self.err(
                    offset,
                    format!(
                        "bad FMT message: FMT itself defined {} bytes long, {} expected",
                        format.length,
                        HEADER_BYTES + super::FMT_BODY_BYTES
                    ),
                ));
            }
            self.formats[ty as usize] = Some(format);
            return Ok(());
        }
        let Some(name) = self.formats[self.kind as usize]
            .as_ref()
            .map(|f| f.name.as_str())
        else {
            return Ok(());
        };
        let b = &self.body;
        // TimeUS (8 bytes) leads each of the three.
        match name {
            "FMTU" if b.len() >= 8 + 1 + 32 => {
                let ty = b[8] as usize;
                let chars = |s: &[u8]| {
                    s.iter()
                        .copied()
                        .take_while(|&c| c != 0)
                        .collect::<Vec<u8>>()
                };
                let (units, mults) = (chars(&b[9..25]), chars(&b[25..41]));
                // An FMTU that does not match its format (one per field) is ignored:
                // the fields then keep the scales their format characters imply.
                if let Some(f) = self.formats[ty].as_mut()
                    && units.len() == f.fields.len()
                    && mults.len() == f.fields.len()
                {
                    f.units = Some((units, mults));
                }
            }
            "UNIT" if b.len() >= 9 + 64 => {
                self.tables.units.insert(b[8], text(&b[9..73]));
            }
            "MULT" if b.len() >= 9 + 8 => {
                let m = f64::from_le_bytes(b[9..17].try_into().unwrap_or([0; 8]));
                self.tables.mults.insert(b[8], m);
            }
            _ => {}
        }
        Ok(())
    }
}
