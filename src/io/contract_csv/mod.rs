//! Streaming CSV source: only the mapped columns parsed, memory bounded whatever the file
//! size. A gzip-compressed file (`.csv.gz`, recognised by its magic bytes, not its name)
//! is decompressed on the fly. Fields are separated by commas, or by `;` or tabs with
//! decimal commas allowed (a European spreadsheet export; see `csv_input`).
//!
//! Turning text into numbers is the same work for every row, so the file is cut into
//! byte ranges of whole records ([`crate::io::ReadOptions::range_bytes`], a size that
//! does not depend on the thread count) and each range is tokenised and parsed on its
//! own: on [`crate::io::ReadOptions::parse_threads`] worker threads, or on the caller's
//! thread when that is 0. Parsed ranges come back in file order, so the rows, their
//! values and every error (with its true line number and field) are the same for any
//! range size and thread count. A range ends where a record ends: after its last line
//! feed when it holds no quote character; otherwise (a quoted field may hold a line
//! end, and a lone CR ends a record too) where the csv tokeniser says its last record
//! starts. At most [`RANGES_PER_WORKER`] ranges per worker plus one (and the one being
//! read) exist at any time, their buffers reused.

mod contract;
mod cutting;
mod range;

use std::collections::VecDeque;
use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, sync_channel};

use super::RowSource;
use super::csv_input::open_text;
use super::error::{ErrorKind, IoError, Location, column};
use super::mapping::Mapping;
use super::slots::SlotLayout;
use contract::contract_mapping;
use cutting::{Cutter, Workers};
use range::{Columns, Fault, Range};

/// Default byte-range size, bytes (512 KiB: about 2 500 rows of a 20-column log; a few
/// ranges in flight, text and parsed values, stay within a few MB).
pub const DEFAULT_RANGE_BYTES: usize = 1 << 19;

/// Ranges queued or being parsed per worker thread, beyond one more: enough to keep the
/// workers busy while the caller consumes rows, few enough to bound memory.
pub const RANGES_PER_WORKER: usize = 2;

/// A range in flight: parsed inline on demand, or by a worker.
enum Pending {
    Inline(Range),
    Worker(Receiver<Range>),
}

/// A CSV file read row by row into the slot layout of its mapping.
pub struct CsvSource {
    file: String,
    cutter: Cutter,
    columns: Arc<Columns>,
    workers: Option<Workers>,
    /// Ranges cut and not yet read, in file order.
    pending: VecDeque<Pending>,
    /// Most ranges in `pending`.
    in_flight: usize,
    /// Buffers of ranges read, for reuse.
    free: Vec<Range>,
    /// The range being read and its next row and next fault.
    current: Range,
    row: usize,
    fault: usize,
    /// Line of the first byte of `current` (1-based).
    first_line: u64,
    /// A read error met while cutting, returned after the rows before it: its text, and
    /// the line feeds of the text read in the range it broke.
    read_error: Option<(String, u64)>,
    /// End of text (or a read error) was returned.
    finished: bool,
    /// Header names, for error labels.
    header: Vec<String>,
}

impl CsvSource {
    /// Opens `path`, reads the header and resolves the mapping (the contract mapping
    /// when `mapping` is `None`) for a vehicle with `rotors` rotors. The text is cut
    /// into ranges of about `range_bytes` bytes (≥ 1), parsed on `parse_threads` worker
    /// threads (0: on the caller's thread).
    pub fn open(
        path: &Path,
        file: &str,
        mapping: Option<&Mapping>,
        rotors: usize,
        parse_threads: usize,
        range_bytes: usize,
    ) -> Result<(Self, Mapping, SlotLayout), IoError> {
        let read_error = |e: std::io::Error| {
            IoError::new(file, Location::File, None, ErrorKind::Read(e.to_string()))
        };
        let (input, gzip) = open_text(path).map_err(read_error)?;
        let mut cutter = Cutter {
            input,
            carry: Vec::new(),
            eof: false,
            range_bytes: range_bytes.max(1),
            delimiter: b',',
            text_read: 0,
            gzip,
        };
        // The header is the first record; one field holding `;` or tabs names the
        // delimiter, and the header is read again with it.
        let mut first = Vec::new();
        let header_error = |cutter: &Cutter, first: &[u8], e: std::io::Error| {
            let location = match cutter.gzip {
                Some(_) => Location::Line(1 + memchr::memchr_iter(b'\n', first).count() as u64),
                None => Location::File,
            };
            IoError::new(file, location, None, ErrorKind::Read(cutter.describe(&e)))
        };
        let (mut header_record, mut data_start) = cutter
            .header(&mut first)
            .map_err(|e| header_error(&cutter, &first, e))?;
        let delimiter = super::csv_input::delimiter(&header_record);
        if delimiter != b',' {
            cutter.delimiter = delimiter;
            (header_record, data_start) = cutter
                .header(&mut first)
                .map_err(|e| header_error(&cutter, &first, e))?;
        }
        if header_record.is_empty() || header_record.iter().all(|f| f.is_empty()) {
            return Err(IoError::new(
                file,
                Location::Line(1),
                None,
                ErrorKind::Empty,
            ));
        }
        let first_line = 1 + memchr::memchr_iter(b'\n', &first[..data_start]).count() as u64;
        cutter.carry = first.split_off(data_start);
        let mut header = Vec::with_capacity(header_record.len());
        for (i, field) in header_record.iter().enumerate() {
            let name = std::str::from_utf8(field).map_err(|_| {
                IoError::new(
                    file,
                    Location::Line(1),
                    None,
                    ErrorKind::Format(format!("header field {} is not valid UTF-8", i + 1)),
                )
            })?;
            // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first name.
            header.push(name.trim_start_matches('\u{feff}').trim().to_string());
        }
        let names: Vec<&str> = header.iter().map(String::as_str).collect();
        let mapping = match mapping {
            Some(m) => m.clone(),
            None => contract_mapping(&names, rotors, file)?,
        };
        let layout = SlotLayout::resolve(&mapping, rotors, file, false)?;
        let mut of_slot = Vec::with_capacity(layout.len());
        for slot in 0..layout.len() {
            let name = layout.source_name(slot);
            let idx = names.iter().position(|h| *h == name).ok_or_else(|| {
                IoError::new(
                    file,
                    Location::Line(1),
                    column(name),
                    ErrorKind::MissingSignal(format!(
                        "column of {} not in the header",
                        layout.signal_of_slot(slot).key()
                    )),
                )
            })?;
            of_slot.push(idx);
        }
        let columns = Arc::new(Columns {
            of_slot,
            header_len: header.len(),
            delimiter,
        });
        let workers = if parse_threads > 0 {
            Some(Workers::start(parse_threads, &columns).map_err(|e| {
                IoError::new(
                    file,
                    Location::File,
                    None,
                    ErrorKind::Read(format!("cannot start the parsing threads: {e}")),
                )
            })?)
        } else {
            None
        };
        let source = Self {
            file: file.to_string(),
            cutter,
            columns,
            workers,
            pending: VecDeque::new(),
            in_flight: parse_threads * RANGES_PER_WORKER + 1,
            free: Vec::new(),
            current: Range::default(),
            row: 0,
            fault: 0,
            first_line,
            read_error: None,
            finished: false,
            header,
        };
        Ok((source, mapping, layout))
    }

    /// Cuts ranges and hands them to the workers until `in_flight` are pending or the
    /// text is used up (a read error is kept for after the rows before it).
    fn cut_ahead(&mut self) -> Result<(), IoError> {
        while self.pending.len() < self.in_flight && self.read_error.is_none() {
            let mut range = self.free.pop().unwrap_or_default();
            match self.cutter.next(&mut range.bytes) {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => {
                    let lines = memchr::memchr_iter(b'\n', &range.bytes).count() as u64;
                    self.read_error = Some((self.cutter.describe(&e), lines));
                    break;
                }
            }
            let pending = match &self.workers {
                None => Pending::Inline(range),
                Some(w) => {
                    let (reply, result) = sync_channel(1);
                    let sent = w.jobs.as_ref().map(|jobs| jobs.send((range, reply)));
                    if !matches!(sent, Some(Ok(()))) {
                        return Err(self.workers_stopped());
                    }
                    Pending::Worker(result)
                }
            };
            self.pending.push_back(pending);
        }
        Ok(())
    }

    fn workers_stopped(&self) -> IoError {
        IoError::new(
            &self.file,
            Location::File,
            None,
            ErrorKind::Read("the parsing threads stopped".into()),
        )
    }

    /// Moves on to the next parsed range; false at the end of the text (after a read
    /// error too: the error is returned once, then the file counts as ended).
    fn next_range(&mut self) -> Result<bool, IoError> {
        if self.finished {
            return Ok(false);
        }
        self.cut_ahead()?;
        let range = match self.pending.pop_front() {
            Some(Pending::Inline(mut range)) => {
                range.parse(&self.columns);
                range
            }
            Some(Pending::Worker(result)) => result.recv().map_err(|_| self.workers_stopped())?,
            None => {
                self.finished = true;
                let Some((text, lines)) = self.read_error.take() else {
                    return Ok(false);
                };
                // A gzip stream breaks at a place worth naming: the line it reached.
                let location = match self.cutter.gzip {
                    Some(_) => Location::Line(self.first_line + self.current.newlines + lines),
                    None => Location::File,
                };
                return Err(IoError::new(
                    &self.file,
                    location,
                    None,
                    ErrorKind::Read(text),
                ));
            }
        };
        self.first_line += self.current.newlines;
        let done = std::mem::replace(&mut self.current, range);
        self.free.push(done);
        self.row = 0;
        self.fault = 0;
        Ok(true)
    }
}

impl RowSource for CsvSource {
    fn bytes_read(&self) -> u64 {
        match &self.cutter.gzip {
            Some(gzip) => gzip.consumed.load(std::sync::atomic::Ordering::Relaxed),
            None => self.cutter.text_read,
        }
    }

    fn next_row(&mut self, raw: &mut [f64]) -> Result<Option<(Location, Option<f64>)>, IoError> {
        while self.row == self.current.lines.len() {
            if !self.next_range()? {
                return Ok(None);
            }
        }
        let i = self.row;
        self.row += 1;
        let loc = Location::Line(self.first_line + self.current.lines[i]);
        if let Some((row, fault)) = self.current.faults.get(self.fault)
            && *row == i
        {
            self.fault += 1;
            let (field, kind) = match fault {
                Fault::Width(n) => (
                    None,
                    ErrorKind::Format(format!(
                        "row has {n} fields, header has {}",
                        self.header.len()
                    )),
                ),
                Fault::NotANumber(slot, text) => (
                    column(&self.header[self.columns.of_slot[*slot]]),
                    ErrorKind::NotANumber(text.clone()),
                ),
                Fault::Tokenise(message) => (None, ErrorKind::Format(message.clone())),
            };
            return Err(IoError::new(&self.file, loc, field, kind));
        }
        let k = self.columns.of_slot.len();
        let n = k.min(raw.len());
        raw[..n].copy_from_slice(&self.current.values[i * k..i * k + n]);
        Ok(Some((loc, None)))
    }
}
