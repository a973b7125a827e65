//! Streaming CSV source: only the mapped columns parsed, memory bounded whatever the file
//! size. A gzip-compressed file (`.csv.gz`, recognised by its magic bytes, not its name)
//! is decompressed on the fly.
//!
//! Tokenising (the `csv` crate splitting bytes into records) runs on its own thread
//! ([`crate::io::ReadOptions::reader_thread`]; else inline, for a one-thread budget), one
//! batch of records ahead of the parsing and checking on the caller's thread: the two
//! cost about the same, so a large file reads in roughly the time of a bare tokenising
//! pass. Batches arrive in file order and a read error travels after the records before
//! it, so errors come out in the same order and with the same text as when reading on
//! one thread. At most [`BATCHES_IN_FLIGHT`] + 2 batches of [`BATCH_RECORDS`] reused
//! records exist at any time.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::mpsc::{Receiver, Sender, SyncSender, channel, sync_channel};

use flate2::read::MultiGzDecoder;

use super::RowSource;
use super::error::{ErrorKind, IoError, Location, column};
use super::mapping::{Mapping, contract_mapping};
use super::slots::SlotLayout;

/// Records per batch handed from the tokenising thread to the parser.
pub const BATCH_RECORDS: usize = 256;

/// Full batches queued between the tokenising thread and the parser.
pub const BATCHES_IN_FLIGHT: usize = 4;

/// Percentage of the slots the tokenising thread parses too (the first ones, in slot
/// order), so that both threads carry about the same work. Tried on the 17-column bench
/// file (`benches/ingest.rs`): 4, 5 and 6 early slots of 17 read in about 0.52, 0.49 and
/// 0.52 s; 30 % gives the 5.
const TOKENISER_SLOT_PERCENT: usize = 30;

/// What the tokenising thread found out about one record besides its fields.
#[derive(Debug, Clone, Default)]
struct Early {
    /// The whole record is valid UTF-8.
    utf8: bool,
    /// First slot parsed early that is not a number, with its text.
    failed: Option<(usize, String)>,
}

/// Records tokenised in file order, with the values of the early slots; all reused from
/// batch to batch.
struct Batch {
    records: Vec<csv::ByteRecord>,
    /// Per record, what the early parse found.
    early: Vec<Early>,
    /// Values of the early slots, record after record.
    values: Vec<f64>,
    /// Records filled in this batch.
    len: usize,
    /// Set on the last batch: end of file, or the read error met after its records.
    end: Option<Result<(), IoError>>,
}

impl Batch {
    fn new(early_slots: usize) -> Self {
        Self {
            records: Vec::new(),
            early: Vec::new(),
            values: vec![0.0; BATCH_RECORDS * early_slots],
            len: 0,
            end: None,
        }
    }
}

/// Header column of each slot the tokenising thread parses, and the header width.
struct EarlySlots {
    columns: Vec<usize>,
    header_len: usize,
}

impl EarlySlots {
    /// Parses the early slots of `record` into `values`, stopping at the first that is not
    /// a number; a record of the wrong width (or a blank line) is left to the parser.
    fn parse(&self, record: &csv::ByteRecord, values: &mut [f64], early: &mut Early) {
        early.failed = None;
        early.utf8 = false;
        if record.len() != self.header_len {
            return;
        }
        let text = std::str::from_utf8(record.as_slice()).ok();
        early.utf8 = text.is_some();
        for (slot, &col) in self.columns.iter().enumerate() {
            match parse_column(record, text, col) {
                Ok(v) => values[slot] = v,
                Err(text) => {
                    early.failed = Some((slot, text));
                    return;
                }
            }
        }
    }
}

/// True when the file starts with the gzip magic bytes (RFC 1952): the CSV text is then
/// decompressed on the fly. Leaves the file at its start.
fn is_gzip(file: &mut File) -> std::io::Result<bool> {
    let mut magic = [0u8; 2];
    let mut n = 0;
    while n < magic.len() {
        let k = file.read(&mut magic[n..])?;
        if k == 0 {
            break;
        }
        n += k;
    }
    file.seek(SeekFrom::Start(0))?;
    Ok(n == 2 && magic == [0x1f, 0x8b])
}

/// The csv reader of a file with what it needs to fill batches.
struct Tokeniser {
    reader: csv::Reader<BufReader<Box<dyn Read + Send>>>,
    file: String,
    slots: EarlySlots,
}

impl Tokeniser {
    /// Refills `batch` with up to [`BATCH_RECORDS`] records; sets `batch.end` at end of
    /// file or on a read error (after the records before it).
    fn fill(&mut self, batch: &mut Batch) {
        let k = self.slots.columns.len();
        batch.len = 0;
        while batch.len < BATCH_RECORDS {
            let i = batch.len;
            if batch.records.len() == i {
                batch.records.push(csv::ByteRecord::new());
                batch.early.push(Early::default());
            }
            match self.reader.read_byte_record(&mut batch.records[i]) {
                Ok(true) => {
                    let values = &mut batch.values[i * k..(i + 1) * k];
                    self.slots
                        .parse(&batch.records[i], values, &mut batch.early[i]);
                    batch.len += 1;
                }
                Ok(false) => {
                    batch.end = Some(Ok(()));
                    break;
                }
                Err(e) => {
                    batch.end = Some(Err(csv_error(&self.file, &e)));
                    break;
                }
            }
        }
    }

    /// Tokenising thread: fills batches (reusing those the parser sent back) until end
    /// of file, a read error, or the parser hung up.
    fn run(mut self, full: SyncSender<Batch>, empty: Receiver<Batch>) {
        let k = self.slots.columns.len();
        loop {
            let mut batch = empty.try_recv().unwrap_or_else(|_| Batch::new(k));
            self.fill(&mut batch);
            let last = batch.end.is_some();
            if full.send(batch).is_err() || last {
                return;
            }
        }
    }
}

/// Where the parser's batches come from.
enum Feed {
    /// A tokenising thread, over a bounded channel, with parsed batches sent back.
    Thread {
        batches: Receiver<Batch>,
        recycle: Sender<Batch>,
    },
    /// The parser's own thread, refilling one batch in place.
    Inline(Box<Tokeniser>),
}

/// A CSV file read row by row into the slot layout of its mapping.
pub struct CsvSource {
    file: String,
    /// Source of the batches, in file order.
    feed: Feed,
    /// The batch being parsed.
    batch: Batch,
    /// Next record of `batch`.
    next: usize,
    /// End of file (or a read error) was returned.
    finished: bool,
    /// Header column index of each slot.
    column_of_slot: Vec<usize>,
    /// Header names, for error labels.
    header: Vec<String>,
    /// Slots parsed on the tokenising thread (the first ones).
    early_slots: usize,
}

impl CsvSource {
    /// Opens `path`, reads the header and resolves the mapping (the contract mapping
    /// when `mapping` is `None`) for a vehicle with `rotors` rotors. With
    /// `reader_thread`, tokenising runs on a thread of its own.
    pub fn open(
        path: &Path,
        file: &str,
        mapping: Option<&Mapping>,
        rotors: usize,
        reader_thread: bool,
    ) -> Result<(Self, Mapping, SlotLayout), IoError> {
        let read_error = |e: std::io::Error| {
            IoError::new(file, Location::File, None, ErrorKind::Read(e.to_string()))
        };
        let mut handle = File::open(path).map_err(read_error)?;
        let source: Box<dyn Read + Send> = if is_gzip(&mut handle).map_err(read_error)? {
            Box::new(MultiGzDecoder::new(BufReader::with_capacity(
                1 << 16,
                handle,
            )))
        } else {
            Box::new(handle)
        };
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .buffer_capacity(1 << 16)
            .from_reader(BufReader::with_capacity(1 << 16, source));
        let header_record = reader
            .byte_headers()
            .map_err(|e| csv_error(file, &e))?
            .clone();
        if header_record.is_empty() || header_record.iter().all(|f| f.is_empty()) {
            return Err(IoError::new(
                file,
                Location::Line(1),
                None,
                ErrorKind::Empty,
            ));
        }
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
        let mut column_of_slot = Vec::with_capacity(layout.len());
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
            column_of_slot.push(idx);
        }
        let early_slots = column_of_slot.len() * TOKENISER_SLOT_PERCENT / 100;
        let tokeniser = Tokeniser {
            reader,
            file: file.to_string(),
            slots: EarlySlots {
                columns: column_of_slot[..early_slots].to_vec(),
                header_len: header.len(),
            },
        };
        let feed = if reader_thread {
            let (full_tx, full_rx) = sync_channel(BATCHES_IN_FLIGHT);
            let (empty_tx, empty_rx) = channel();
            std::thread::Builder::new()
                .name("csv-tokeniser".into())
                .spawn(move || tokeniser.run(full_tx, empty_rx))
                .map_err(|e| {
                    IoError::new(
                        file,
                        Location::File,
                        None,
                        ErrorKind::Read(format!("cannot start the reading thread: {e}")),
                    )
                })?;
            Feed::Thread {
                batches: full_rx,
                recycle: empty_tx,
            }
        } else {
            Feed::Inline(Box::new(tokeniser))
        };
        let source = Self {
            file: file.to_string(),
            feed,
            batch: Batch::new(early_slots),
            next: 0,
            finished: false,
            column_of_slot,
            header,
            early_slots,
        };
        Ok((source, mapping, layout))
    }

    /// Moves on to the next batch once `batch` is parsed; false at end of file (after a
    /// read error too: the error is returned once, then the file counts as ended).
    fn next_batch(&mut self) -> Result<bool, IoError> {
        if self.finished {
            return Ok(false);
        }
        if let Some(end) = self.batch.end.take() {
            self.finished = true;
            return end.map(|()| false);
        }
        match &mut self.feed {
            Feed::Inline(tokeniser) => tokeniser.fill(&mut self.batch),
            Feed::Thread { batches, recycle } => {
                let batch = batches.recv().map_err(|_| {
                    IoError::new(
                        &self.file,
                        Location::File,
                        None,
                        ErrorKind::Read("the reading thread stopped".into()),
                    )
                })?;
                let done = std::mem::replace(&mut self.batch, batch);
                // The tokeniser may have finished already; the batch is then dropped.
                let _ = recycle.send(done);
            }
        }
        self.next = 0;
        Ok(true)
    }
}

fn csv_error(file: &str, e: &csv::Error) -> IoError {
    let line = e
        .position()
        .map_or(Location::File, |p| Location::Line(p.line()));
    let kind = match e.kind() {
        csv::ErrorKind::Io(io) => ErrorKind::Read(io.to_string()),
        csv::ErrorKind::Utf8 { .. } => ErrorKind::Format("not valid UTF-8".into()),
        _ => ErrorKind::Format(e.to_string()),
    };
    IoError::new(file, line, None, kind)
}

impl RowSource for CsvSource {
    fn file(&self) -> &str {
        &self.file
    }

    fn next_row(&mut self, raw: &mut [f64]) -> Result<Option<(Location, Option<f64>)>, IoError> {
        loop {
            while self.next == self.batch.len {
                if !self.next_batch()? {
                    return Ok(None);
                }
            }
            let i = self.next;
            let record = &self.batch.records[i];
            self.next += 1;
            let line = record.position().map_or(0, |p| p.line());
            let loc = Location::Line(line);
            // A blank line (single empty field) is skipped like the csv crate does.
            if record.len() == 1 && record[0].is_empty() {
                continue;
            }
            if record.len() != self.header.len() {
                return Err(IoError::new(
                    &self.file,
                    loc,
                    None,
                    ErrorKind::Format(format!(
                        "row has {} fields, header has {}",
                        record.len(),
                        self.header.len()
                    )),
                ));
            }
            let not_a_number = |slot: usize, text: String| {
                let col = self.column_of_slot[slot];
                IoError::new(
                    &self.file,
                    loc,
                    column(&self.header[col]),
                    ErrorKind::NotANumber(text),
                )
            };
            // The early slots come before the others, so their first failure is the
            // row's first.
            let early = &self.batch.early[i];
            if let Some((slot, text)) = &early.failed {
                return Err(not_a_number(*slot, text.clone()));
            }
            let k = self.early_slots;
            raw[..k].copy_from_slice(&self.batch.values[i * k..(i + 1) * k]);
            // One UTF-8 check of the whole row instead of one per field; a row that fails
            // it is checked field by field so the error names the offending field.
            let text = if early.utf8 {
                std::str::from_utf8(record.as_slice()).ok()
            } else {
                None
            };
            for (slot, &col) in self.column_of_slot.iter().enumerate().skip(k) {
                raw[slot] = parse_column(record, text, col).map_err(|t| not_a_number(slot, t))?;
            }
            return Ok(Some((loc, None)));
        }
    }
}

/// Parses column `col` of `record`, taking it from `text` (the whole record) when the
/// record is known to be UTF-8.
fn parse_column(record: &csv::ByteRecord, text: Option<&str>, col: usize) -> Result<f64, String> {
    match text.and_then(|t| record.range(col).and_then(|r| t.get(r))) {
        Some(field) => parse_text(field),
        None => parse_field(&record[col]),
    }
}

/// Parses one CSV field as f64 (surrounding spaces allowed); the error carries the text.
fn parse_field(bytes: &[u8]) -> Result<f64, String> {
    let text =
        std::str::from_utf8(bytes).map_err(|_| String::from_utf8_lossy(bytes).into_owned())?;
    parse_text(text)
}

/// [`parse_field`] of a field already known to be UTF-8.
fn parse_text(text: &str) -> Result<f64, String> {
    let bytes = text.as_bytes();
    let padded = bytes.first().is_some_and(u8::is_ascii_whitespace)
        || bytes.last().is_some_and(u8::is_ascii_whitespace);
    let number = if padded { text.trim() } else { text };
    number.parse::<f64>().map_err(|_| text.to_string())
}

/// Writes samples as a contract CSV (`docs/data-contract.md`; header
/// `t,u,v,w,p,q,r,omega_1..N,[omega_dot_1..N,]fx,fy,fz,mx,my,mz[,height][,qw,qx,qy,qz]`),
/// shortest round-trip float formatting so reading back gives identical values.
pub fn write_contract_csv<'a>(
    path: &Path,
    chunks: impl IntoIterator<Item = &'a crate::sample::SampleChunk>,
) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::BufWriter::new(File::create(path)?);
    let mut header_written = false;
    let mut line = String::new();
    for c in chunks {
        if !header_written {
            let mut h = String::from("t,u,v,w,p,q,r");
            for i in 1..=c.rotor_count() {
                h += &format!(",omega_{i}");
            }
            for i in 1..=c.omega_dot.len() {
                h += &format!(",omega_dot_{i}");
            }
            h += ",fx,fy,fz,mx,my,mz";
            if c.has_height() {
                h += ",height";
            }
            if c.has_attitude() {
                h += ",qw,qx,qy,qz";
            }
            writeln!(out, "{h}")?;
            header_written = true;
        }
        for k in 0..c.len() {
            line.clear();
            let mut put = |v: f64| {
                if !line.is_empty() {
                    line.push(',');
                }
                line.push_str(&format!("{v:?}"));
            };
            put(c.t[k]);
            c.velocity.iter().for_each(|v| put(v[k]));
            c.rates.iter().for_each(|v| put(v[k]));
            c.omega.iter().for_each(|v| put(v[k]));
            c.omega_dot.iter().for_each(|v| put(v[k]));
            c.wrench.iter().for_each(|v| put(v[k]));
            if c.has_height() {
                put(c.height[k]);
            }
            if c.has_attitude() {
                c.attitude.iter().for_each(|v| put(v[k]));
            }
            writeln!(out, "{line}")?;
        }
    }
    out.flush()
}
