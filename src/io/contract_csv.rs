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

use std::collections::VecDeque;
use std::io::Read;
use std::path::Path;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use super::RowSource;
use super::csv_input::{GzipPosition, decimal_comma_value, open_text};
use super::decimal::{fast_path_in, parse_f64};
use super::error::{ErrorKind, IoError, Location, column};
use super::mapping::{Mapping, contract_mapping};
use super::slots::SlotLayout;

/// Default byte-range size, bytes (512 KiB: about 2 500 rows of a 20-column log; a few
/// ranges in flight, text and parsed values, stay within a few MB).
pub const DEFAULT_RANGE_BYTES: usize = 1 << 19;

/// Ranges queued or being parsed per worker thread, beyond one more: enough to keep the
/// workers busy while the caller consumes rows, few enough to bound memory.
pub const RANGES_PER_WORKER: usize = 2;

/// Why a row could not be read; turned into an [`IoError`] with its true line when the
/// row is consumed.
#[derive(Debug, Clone)]
enum Fault {
    /// The row has this many fields, not the header's count.
    Width(usize),
    /// The value of this slot is not a number (its text).
    NotANumber(usize, String),
    /// The tokeniser failed (the message).
    Tokenise(String),
}

/// One byte range of the file and, once parsed, its rows.
#[derive(Debug, Default)]
struct Range {
    /// The text: whole records.
    bytes: Vec<u8>,
    /// Slot values, row after row (a faulty row's values are unspecified).
    values: Vec<f64>,
    /// Line of each row counted from the range start (the range's first line is 0).
    lines: Vec<u64>,
    /// Faulty rows (row index, fault), in row order.
    faults: Vec<(usize, Fault)>,
    /// Line feeds in `bytes`.
    newlines: u64,
}

/// What parsing a range needs to know of the file.
#[derive(Debug)]
struct Columns {
    /// Header column of each slot.
    of_slot: Vec<usize>,
    /// Header width.
    header_len: usize,
    /// Field delimiter: `,`, `;` or tab.
    delimiter: u8,
}

/// A csv reader over whole records in memory, fields split at `delimiter`, with the
/// settings of every read here.
fn tokeniser(bytes: &[u8], delimiter: u8) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(delimiter)
        .from_reader(bytes)
}

/// The line (0-based, from the start of `bytes`) and byte offset of the first byte of
/// `record`: the tokeniser places a record after the previous one's terminator, so the
/// record terminators it skipped (blank lines, the LF of a CRLF) are counted here.
fn record_start(bytes: &[u8], record: &csv::ByteRecord) -> u64 {
    let (mut byte, mut line) = record
        .position()
        .map_or((0, 1), |p| (p.byte() as usize, p.line()));
    while let Some(&b) = bytes.get(byte) {
        match b {
            b'\n' => line += 1,
            b'\r' => {}
            _ => break,
        }
        byte += 1;
    }
    line - 1
}

impl Range {
    /// Tokenises and parses `bytes` into rows (blank lines skipped, as the csv
    /// tokeniser does); each row's first failure in slot order is kept as its fault.
    /// Text without quotes whose lines end in LF or CRLF (every contract log we write,
    /// and Windows exports) is split on its commas and line ends directly, which is what
    /// the csv tokeniser would do with it; any other text (quoted fields, a lone CR)
    /// goes through the tokeniser.
    fn parse(&mut self, columns: &Columns) {
        self.values.clear();
        self.lines.clear();
        self.faults.clear();
        let bytes = &self.bytes;
        self.newlines = memchr::memchr_iter(b'\n', bytes).count() as u64;
        let quoted = memchr::memchr(b'"', bytes).is_some();
        let lone_cr = memchr::memchr_iter(b'\r', bytes).any(|i| bytes.get(i + 1) != Some(&b'\n'));
        if quoted || lone_cr {
            self.parse_tokenised(columns);
        } else {
            self.parse_plain(columns);
        }
    }

    /// [`Range::parse`] of text without quotes in which every CR starts a CRLF: records
    /// are its non-empty lines (without their CR), fields the text between commas.
    fn parse_plain(&mut self, columns: &Columns) {
        let bytes = std::mem::take(&mut self.bytes);
        let mut ends = Vec::with_capacity(columns.header_len + 1);
        let mut start = 0;
        let mut line = 0;
        while start < bytes.len() {
            let end = memchr::memchr(b'\n', &bytes[start..]).map_or(bytes.len(), |i| start + i);
            let line_text = &bytes[start..end];
            let record = line_text.strip_suffix(b"\r").unwrap_or(line_text);
            if !record.is_empty() {
                field_ends(record, columns.delimiter, &mut ends);
                let field = |c: usize| (if c == 0 { 0 } else { ends[c - 1] + 1 })..ends[c];
                self.push_row(line, ends.len(), columns, record, field);
            }
            start = end + 1;
            line += 1;
        }
        self.bytes = bytes;
    }

    /// [`Range::parse`] through the csv tokeniser (quoted fields, lone CR line ends).
    fn parse_tokenised(&mut self, columns: &Columns) {
        let bytes = std::mem::take(&mut self.bytes);
        let mut reader = tokeniser(&bytes, columns.delimiter);
        let mut record = csv::ByteRecord::new();
        loop {
            match reader.read_byte_record(&mut record) {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => {
                    let line = e.position().map_or(1, |p| p.line());
                    self.lines.push(line - 1);
                    let k = columns.of_slot.len();
                    self.values.resize(self.values.len() + k, 0.0);
                    self.faults
                        .push((self.lines.len() - 1, Fault::Tokenise(e.to_string())));
                    break;
                }
            }
            if record.len() == 1 && record[0].is_empty() {
                continue;
            }
            let line = record_start(&bytes, &record);
            let field = |c: usize| record.range(c).unwrap_or_default();
            self.push_row(line, record.len(), columns, record.as_slice(), field);
        }
        self.bytes = bytes;
    }

    /// Adds the record on `line` with `width` fields, field c being `text[field(c)]`:
    /// its slot values, or its fault (the width, else the first slot that is not a
    /// number).
    fn push_row(
        &mut self,
        line: u64,
        width: usize,
        columns: &Columns,
        text: &[u8],
        field: impl Fn(usize) -> std::ops::Range<usize>,
    ) {
        let row = self.lines.len();
        self.lines.push(line);
        let start = self.values.len();
        self.values.resize(start + columns.of_slot.len(), 0.0);
        if width != columns.header_len {
            self.faults.push((row, Fault::Width(width)));
            return;
        }
        // A field the fast path reads is ASCII. For the others, one UTF-8 check of the
        // whole row (when the first comes) instead of one per field; a row that fails it
        // is checked field by field so the error names the offending field.
        let mut utf8 = None;
        let values = &mut self.values[start..];
        for (slot, (&col, v)) in columns.of_slot.iter().zip(values).enumerate() {
            let range = field(col);
            if let Some(x) = fast_path_in(text, range.clone()) {
                *v = x;
                continue;
            }
            if columns.delimiter != b','
                && let Some(x) = decimal_comma_value(&text[range.clone()])
            {
                *v = x;
                continue;
            }
            let checked = *utf8.get_or_insert_with(|| std::str::from_utf8(text).ok());
            let parsed = match checked.and_then(|t| t.get(range.clone())) {
                Some(f) => parse_text(f),
                None => parse_field(&text[range]),
            };
            match parsed {
                Ok(x) => *v = x,
                Err(t) => {
                    self.faults.push((row, Fault::NotANumber(slot, t)));
                    break;
                }
            }
        }
    }
}

/// Sets `ends` to the offset of every `delimiter` in `record`, then its length: field c
/// ends at `ends[c]`. Eight bytes at a time.
fn field_ends(record: &[u8], delimiter: u8, ends: &mut Vec<usize>) {
    ends.clear();
    let pattern = u64::from(delimiter) * 0x0101_0101_0101_0101;
    let words = record.chunks_exact(8);
    let tail = words.remainder();
    for (w, word) in words.enumerate() {
        let word = u64::from_le_bytes(word.try_into().unwrap_or_default());
        let mut found = delimiter_bytes(word, pattern);
        while found != 0 {
            ends.push(8 * w + found.trailing_zeros() as usize / 8);
            found &= found - 1;
        }
    }
    let base = record.len() - tail.len();
    ends.extend(memchr::memchr_iter(delimiter, tail).map(|i| base + i));
    ends.push(record.len());
}

/// 0x80 in each byte of `word` equal to the delimiter whose byte `pattern` repeats eight
/// times, 0 in the others (exact: no carries between bytes).
fn delimiter_bytes(word: u64, pattern: u64) -> u64 {
    const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    let x = word ^ pattern;
    !(((x & LOW7) + LOW7) | x | LOW7)
}

/// Offset just past the last whole record of `bytes` (which start at a record start),
/// if a record ends before the last one begins; see the module notes.
fn range_end(bytes: &[u8], delimiter: u8) -> Option<usize> {
    if memchr::memchr(b'"', bytes).is_none()
        && let Some(i) = memchr::memrchr(b'\n', bytes)
    {
        return Some(i + 1);
    }
    let mut reader = tokeniser(bytes, delimiter);
    let mut record = csv::ByteRecord::new();
    let mut last = 0;
    while let Ok(true) = reader.read_byte_record(&mut record) {
        last = record.position().map_or(0, |p| p.byte() as usize);
    }
    (last > 0).then_some(last)
}

/// Cuts the text into ranges of whole records, reading it once in file order.
struct Cutter {
    input: Box<dyn Read + Send>,
    /// Text read past the end of the last range.
    carry: Vec<u8>,
    /// End of input reached.
    eof: bool,
    /// Nominal range size, bytes (≥ 1).
    range_bytes: usize,
    /// Field delimiter.
    delimiter: u8,
    /// Bytes of text read so far (decompressed, for a gzip-compressed file).
    text_read: u64,
    /// The compressed position reached, for a gzip-compressed file.
    gzip: Option<GzipPosition>,
}

impl Cutter {
    /// Reads on until `bytes` holds `want` bytes or the input ends.
    fn fill(&mut self, bytes: &mut Vec<u8>, want: usize) -> std::io::Result<()> {
        if bytes.len() < want && !self.eof {
            let asked = (want - bytes.len()) as u64;
            bytes.reserve(want - bytes.len());
            let before = bytes.len();
            // On an error the bytes read before it are kept (`read_to_end`'s contract).
            let got = self.input.by_ref().take(asked).read_to_end(bytes);
            self.text_read += (bytes.len() - before) as u64;
            self.eof = (got? as u64) < asked;
        }
        Ok(())
    }

    /// The first record (the header) of the text and the offset just past it, read into
    /// `first` (which may hold text read already) with the cutter's delimiter: read on
    /// until one more byte follows it (or the text ends), so that it is whole.
    fn header(&mut self, first: &mut Vec<u8>) -> std::io::Result<(csv::ByteRecord, usize)> {
        let mut want = self.range_bytes.min(1 << 16).max(first.len());
        loop {
            self.fill(first, want)?;
            let mut reader = tokeniser(first, self.delimiter);
            let mut record = csv::ByteRecord::new();
            let found = reader.read_byte_record(&mut record).unwrap_or(false);
            let end = reader.position().byte() as usize;
            if self.eof || (found && end < first.len()) {
                return Ok((record, end.min(first.len())));
            }
            want = 2 * first.len().max(self.range_bytes);
        }
    }

    /// The text of read error `e`: with the compressed and text positions reached for a
    /// gzip-compressed file.
    fn describe(&self, e: &std::io::Error) -> String {
        match &self.gzip {
            Some(g) => g.describe(e, self.text_read),
            None => e.to_string(),
        }
    }

    /// Fills `bytes` with the next range (about `range_bytes`, more when one record is
    /// longer); false when the text is used up.
    fn next(&mut self, bytes: &mut Vec<u8>) -> std::io::Result<bool> {
        bytes.clear();
        bytes.append(&mut self.carry);
        let mut want = self.range_bytes;
        loop {
            self.fill(bytes, want)?;
            if self.eof {
                return Ok(!bytes.is_empty());
            }
            if let Some(end) = range_end(bytes, self.delimiter) {
                self.carry.extend_from_slice(&bytes[end..]);
                bytes.truncate(end);
                return Ok(true);
            }
            // Doubling keeps the re-tokenising of a long quoted record linear.
            want = 2 * bytes.len().max(self.range_bytes);
        }
    }
}

/// A range to parse and where to send it back parsed.
type Job = (Range, SyncSender<Range>);

/// Worker threads parsing ranges; they stop when the job channel closes.
struct Workers {
    jobs: Option<SyncSender<Job>>,
    handles: Vec<JoinHandle<()>>,
}

impl Workers {
    fn start(count: usize, columns: &Arc<Columns>) -> std::io::Result<Self> {
        let (jobs, queue) = sync_channel::<Job>(count * RANGES_PER_WORKER);
        let queue = Arc::new(Mutex::new(queue));
        let mut workers = Self {
            jobs: Some(jobs),
            handles: Vec::with_capacity(count),
        };
        for _ in 0..count {
            let queue = Arc::clone(&queue);
            let columns = Arc::clone(columns);
            let handle = std::thread::Builder::new()
                .name("csv-parse".into())
                .spawn(move || {
                    loop {
                        // A poisoned lock means another worker panicked: stop too.
                        let job = match queue.lock() {
                            Ok(q) => q.recv(),
                            Err(_) => return,
                        };
                        let Ok((mut range, reply)) = job else {
                            return;
                        };
                        range.parse(&columns);
                        // The reader may be gone (dropped after an error): nothing to do.
                        let _ = reply.send(range);
                    }
                })?;
            workers.handles.push(handle);
        }
        Ok(workers)
    }
}

impl Drop for Workers {
    fn drop(&mut self) {
        self.jobs = None;
        for h in self.handles.drain(..) {
            // A worker that panicked has nothing left to report.
            let _ = h.join();
        }
    }
}

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

/// Parses one CSV field as f64 (surrounding spaces allowed), a field whose untrimmed text
/// the fast path ([`fast_path_in`]) has already left to std; the error carries the text.
fn parse_field(bytes: &[u8]) -> Result<f64, String> {
    let text =
        std::str::from_utf8(bytes).map_err(|_| String::from_utf8_lossy(bytes).into_owned())?;
    parse_text(text)
}

/// [`parse_field`] of a field already known to be UTF-8. Only a padded field gets the
/// fast path again (on its trimmed text); any other goes to std at once.
fn parse_text(text: &str) -> Result<f64, String> {
    let bytes = text.as_bytes();
    let padded = bytes.first().is_some_and(u8::is_ascii_whitespace)
        || bytes.last().is_some_and(u8::is_ascii_whitespace);
    let parsed = if padded {
        parse_f64(text.trim())
    } else {
        text.parse::<f64>()
    };
    parsed.map_err(|_| text.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A range of `text` parsed both ways.
    fn both_ways(text: &[u8], columns: &Columns) -> [Range; 2] {
        let mut plain = Range {
            bytes: text.to_vec(),
            ..Range::default()
        };
        let mut tokenised = Range {
            bytes: text.to_vec(),
            ..Range::default()
        };
        plain.parse_plain(columns);
        tokenised.parse_tokenised(columns);
        [plain, tokenised]
    }

    /// The direct split gives the rows, values (bit for bit), line numbers and faults of
    /// the csv tokeniser on random quote-free text with LF and CRLF line ends: numbers,
    /// junk, empty fields, blank lines, rows too short or too long, invalid UTF-8, a last
    /// line with or without its line end.
    #[test]
    fn plain_split_equals_the_tokeniser() {
        let mut rng = StdRng::seed_from_u64(5);
        let columns = Columns {
            of_slot: vec![3, 0, 2, 5],
            header_len: 6,
            delimiter: b',',
        };
        let pieces: [&[u8]; 12] = [
            b"1.5",
            b"-0.25",
            b"7",
            b"1e3",
            b"",
            b" 2 ",
            b"x",
            b"nan",
            b"\xc3",
            b"\xc3\xa9",
            b"123456789012345678901",
            b"-",
        ];
        for case in 0..2000 {
            // Half the texts end some lines in CRLF (Windows exports), mixed with LF.
            let crlf = case % 2 == 1;
            let mut text = Vec::new();
            for _ in 0..rng.random_range(0..30) {
                let line_end: &[u8] = if crlf && rng.random_bool(0.7) {
                    b"\r\n"
                } else {
                    b"\n"
                };
                if rng.random_bool(0.1) {
                    text.extend_from_slice(line_end);
                    continue;
                }
                let width = if rng.random_bool(0.8) {
                    6
                } else {
                    rng.random_range(1..9)
                };
                for f in 0..width {
                    if f > 0 {
                        text.push(b',');
                    }
                    let piece = if rng.random_bool(0.85) {
                        format!("{}", rng.random_range(-1e4..1e4)).into_bytes()
                    } else {
                        pieces[rng.random_range(0..pieces.len())].to_vec()
                    };
                    text.extend_from_slice(&piece);
                }
                text.extend_from_slice(line_end);
            }
            if rng.random_bool(0.5) && text.last() == Some(&b'\n') {
                text.pop();
                if text.last() == Some(&b'\r') {
                    text.pop();
                }
            }
            let [plain, tokenised] = both_ways(&text, &columns);
            let what = String::from_utf8_lossy(&text);
            assert_eq!(plain.lines, tokenised.lines, "{what}");
            let bits = |r: &Range| r.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let faulty: Vec<usize> = plain.faults.iter().map(|f| f.0).collect();
            let k = columns.of_slot.len();
            let good = |r: &Range| -> Vec<u64> {
                let b = bits(r);
                (0..r.lines.len())
                    .filter(|i| !faulty.contains(i))
                    .flat_map(|i| b[i * k..(i + 1) * k].to_vec())
                    .collect()
            };
            assert_eq!(good(&plain), good(&tokenised), "{what}");
            assert_eq!(
                format!("{:?}", plain.faults),
                format!("{:?}", tokenised.faults),
                "{what}"
            );
        }
    }

    /// Text the direct split cannot read (a lone CR ends a record; a quoted field may
    /// hold a comma or a line end) goes to the tokeniser.
    #[test]
    fn lone_cr_and_quotes_go_to_the_tokeniser() {
        let columns = Columns {
            of_slot: vec![0, 1],
            header_len: 2,
            delimiter: b',',
        };
        for text in [
            &b"1,2\r3,4\n"[..],
            b"1,2\r\n3,4\r",
            b"\"1\",2\n3,4\n",
            b"\"1,5\",2\n",
        ] {
            let mut parsed = Range {
                bytes: text.to_vec(),
                ..Range::default()
            };
            parsed.parse(&columns);
            let [_, tokenised] = both_ways(text, &columns);
            assert_eq!(parsed.lines, tokenised.lines, "{text:?}");
            assert_eq!(parsed.values, tokenised.values, "{text:?}");
            assert_eq!(
                format!("{:?}", parsed.faults),
                format!("{:?}", tokenised.faults),
                "{text:?}"
            );
        }
        // Two records where a lone CR ends the first.
        let [_, tokenised] = both_ways(b"1,2\r3,4\n", &columns);
        assert_eq!(tokenised.values, [1.0, 2.0, 3.0, 4.0]);
    }

    /// Commas are found in every byte position of a word and nowhere else.
    #[test]
    fn field_ends_are_the_commas() {
        let record = b"a,bc,,defghij,k,lmnopqrstu,v,";
        let mut ends = Vec::new();
        field_ends(record, b',', &mut ends);
        let expected: Vec<usize> = record
            .iter()
            .enumerate()
            .filter(|(_, c)| **c == b',')
            .map(|(i, _)| i)
            .chain([record.len()])
            .collect();
        assert_eq!(ends, expected);
        for b in 0..=255u8 {
            let word = u64::from_le_bytes([b, b',', b, 0x2c ^ 0x80, b, b'-', b'.', b]);
            let want = (0..8).filter(|&i| word.to_le_bytes()[i] == b',');
            let got = delimiter_bytes(word, 0x2c2c_2c2c_2c2c_2c2c);
            assert_eq!(got, want.map(|i| 0x80u64 << (8 * i)).sum::<u64>(), "{b:#x}");
        }
    }
}
