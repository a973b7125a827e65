//! Cutting the text into ranges of whole records, read once in file order, and the
//! worker threads that parse them.

use std::io::Read;
use std::sync::mpsc::{SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use super::super::csv_input::GzipPosition;
use super::RANGES_PER_WORKER;
use super::range::{Columns, Range, range_end, tokeniser};

/// Cuts the text into ranges of whole records, reading it once in file order.
pub(super) struct Cutter {
    pub(super) input: Box<dyn Read + Send>,
    /// Text read past the end of the last range.
    pub(super) carry: Vec<u8>,
    /// End of input reached.
    pub(super) eof: bool,
    /// Nominal range size, bytes (≥ 1).
    pub(super) range_bytes: usize,
    /// Field delimiter.
    pub(super) delimiter: u8,
    /// Bytes of text read so far (decompressed, for a gzip-compressed file).
    pub(super) text_read: u64,
    /// The compressed position reached, for a gzip-compressed file.
    pub(super) gzip: Option<GzipPosition>,
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
    pub(super) fn header(
        &mut self,
        first: &mut Vec<u8>,
    ) -> std::io::Result<(csv::ByteRecord, usize)> {
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
    pub(super) fn describe(&self, e: &std::io::Error) -> String {
        match &self.gzip {
            Some(g) => g.describe(e, self.text_read),
            None => e.to_string(),
        }
    }

    /// Fills `bytes` with the next range (about `range_bytes`, more when one record is
    /// longer); false when the text is used up.
    pub(super) fn next(&mut self, bytes: &mut Vec<u8>) -> std::io::Result<bool> {
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
pub(super) struct Workers {
    pub(super) jobs: Option<SyncSender<Job>>,
    handles: Vec<JoinHandle<()>>,
}

impl Workers {
    pub(super) fn start(count: usize, columns: &Arc<Columns>) -> std::io::Result<Self> {
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
