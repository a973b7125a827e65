//! Reading a ULog file message by message: the header checked, each message's size and
//! type read and its payload kept, appended data (flag bits) followed, and every error
//! naming the byte offset of the message. A message the end of the file cuts short ends
//! the log ([`super::super::summary::CutOff`]): a log closed by a power cut is read up to
//! it.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use super::super::error::{ErrorKind, IoError, Location};
use super::super::summary::CutOff;
use super::{FLAG_BITS_BYTES, HEADER_BYTES, MAGIC, MESSAGE_HEADER_BYTES};

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
pub(super) struct MessageReader {
    file: String,
    input: BufReader<File>,
    /// Byte offset of the next unread byte.
    pos: u64,
    len: u64,
    /// Appended-data offsets not reached yet, ascending.
    appended: Vec<u64>,
    /// Payload of the message returned last.
    pub(super) buf: Vec<u8>,
    /// Type of the message returned last.
    pub(super) kind: u8,
    /// What the end of the file cut short, once reached.
    pub(super) cut_off: CutOff,
}

impl MessageReader {
    /// Opens `path` and checks the header.
    pub(super) fn open(path: &Path, file: &str) -> Result<(Self, u64), IoError> {
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
            cut_off: CutOff::default(),
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

    /// The error of a read that failed at the current position.
    fn read_err(&self, e: std::io::Error) -> IoError {
        IoError::new(
            &self.file,
            Location::Offset(self.pos),
            None,
            ErrorKind::Read(e.to_string()),
        )
    }

    fn read_into(&mut self, dst: &mut [u8]) -> Result<(), IoError> {
        self.input.read_exact(dst).map_err(|e| self.read_err(e))?;
        self.pos += dst.len() as u64;
        Ok(())
    }

    fn skip(&mut self, n: u64) -> Result<(), IoError> {
        let copied = std::io::copy(&mut (&mut self.input).take(n), &mut std::io::sink())
            .map_err(|e| self.read_err(e))?;
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
    pub(super) fn next_message(&mut self) -> Result<Option<u64>, IoError> {
        loop {
            while self.appended.first().is_some_and(|&a| a <= self.pos) {
                self.appended.remove(0);
            }
            let start = self.pos;
            if start == self.len {
                return Ok(None);
            }
            if start + MESSAGE_HEADER_BYTES > self.len {
                return Ok(self.end_inside(start, "message header", MESSAGE_HEADER_BYTES));
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
                let what = format!("{} message", type_name(h[2]));
                return Ok(self.end_inside(start, &what, end - start));
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
    pub(super) fn flag_bits(&mut self, offset: u64) -> Result<(), IoError> {
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
