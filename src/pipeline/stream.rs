//! Reading a log as the pipeline streams it: in chunks of [`CHUNK_SAMPLES`] cut by the
//! sample sequence alone (a file's reader cuts them, a log in memory is re-cut), through
//! the [`Feed`] stage, a file read on a thread of its own when the job may use two or
//! more.

use super::FitRequest;
use super::feed::Feed;
use crate::error::{Error, RequestError};
use crate::io::{self, LogReader, ReadOptions, Summary};
use crate::progress::Progress;
use crate::sample::{CHUNK_SAMPLES, SampleChunk};
use crate::source::LogSource;

/// Opens a log file with `parse_threads` CSV parsing threads (capped to 0 when the
/// request's [`ReadOptions::parse_threads`] is 0).
fn open(
    path: &std::path::Path,
    req: &FitRequest,
    parse_threads: usize,
) -> Result<LogReader, Error> {
    let read = ReadOptions {
        parse_threads: if req.read.parse_threads == 0 {
            0
        } else {
            parse_threads
        },
        ..req.read
    };
    Ok(io::open_log(
        path,
        &req.vehicle,
        req.mapping.as_ref(),
        &read,
    )?)
}

/// Chunks in flight between a log's reader thread and its consumer.
const CHUNKS_IN_FLIGHT: usize = 4;

/// CSV parsing threads of a job that may use `share` threads: none on one thread (all
/// work inline); else `share`, beside the reader thread and the consumer. Parsing is the
/// first pass's critical path: with a worker per thread, the scheduler gives it the time
/// the reader's checks and derivations and the accumulation leave idle (one worker beside
/// them on two threads bounded a 1 M-row `fit --no-diagnose` at 1.42–1.53 s, two took
/// 1.32–1.33 s; docs/benchmarks.md).
fn parse_threads(share: usize) -> usize {
    if share < 2 { 0 } else { share }
}

/// Feeds the log `source` to `consume` in chunks of [`CHUNK_SAMPLES`] (the last one
/// shorter) and returns the reader's summary. The chunks do not depend on how the reader
/// or the caller chunked the samples, so a log gives the same statistics from a file and
/// from memory: a file's reader cuts them so itself ([`LogReader::join_segments`]), a
/// log in memory is re-cut ([`Rechunker`]). With a `share` of two threads or more,
/// reading a file runs on a thread of its own that hands chunks over a bounded channel,
/// so reading overlaps the consumer's work (memory stays at [`CHUNKS_IN_FLIGHT`] chunks,
/// their buffers reused), and CSV text is parsed on [`parse_threads`] more.
pub(super) fn stream_log(
    source: &LogSource,
    req: &FitRequest,
    share: usize,
    consume: impl FnMut(&SampleChunk) -> Result<(), Error>,
) -> Result<Summary, Error> {
    let mut feed = Feed::of_fit(req, consume);
    let path = match source {
        LogSource::File(path) => path,
        LogSource::Memory(log) => {
            let mut cut = Rechunker::default();
            for chunk in log.chunks() {
                cut.push(chunk, &mut |c| feed.push(c))?;
                if let Some(p) = &req.progress {
                    p.add_read(chunk.len() as u64, false);
                }
            }
            cut.finish(&mut |c| feed.push(c))?;
            feed.finish()?;
            return Ok(Summary::of_memory(log.name(), log.len()));
        }
    };
    if share < 2 {
        let mut reader = open(path, req, 0)?;
        let mut bytes = BytesRead::new(req);
        reader.join_segments();
        while let Some(chunk) = reader.next_chunk_mut() {
            feed.push(chunk?)?;
            bytes.count(&reader);
        }
        feed.finish()?;
        bytes.finish(path);
        return Ok(reader.summary().clone());
    }
    let (tx, rx) = std::sync::mpsc::sync_channel(CHUNKS_IN_FLIGHT);
    let (recycle, reuse) = std::sync::mpsc::channel::<SampleChunk>();
    std::thread::scope(|scope| {
        // The reader is opened on its own thread (it is not `Send`).
        let producer = scope.spawn(move || -> Result<Summary, Error> {
            let mut reader = open(path, req, parse_threads(share))?;
            let mut bytes = BytesRead::new(req);
            reader.join_segments();
            while let Some(chunk) = reader.next_chunk_mut() {
                let sent = match chunk {
                    Ok(c) => {
                        // Handed over whole, a consumed chunk (or a new one) in its place.
                        let next = reuse.try_recv().unwrap_or_else(|_| empty_like(c));
                        tx.send(Ok(std::mem::replace(c, next)))
                    }
                    Err(e) => tx.send(Err(e)),
                };
                bytes.count(&reader);
                // The consumer stopped on an error of its own, which it reports. (After
                // a read error the reader is over: the loop ends with it.)
                if sent.is_err() {
                    break;
                }
            }
            bytes.finish(path);
            Ok(reader.summary().clone())
        });
        let mut consumed = Ok(());
        while let Ok(chunk) = rx.recv() {
            consumed = chunk.map_err(Error::from).and_then(|mut c| {
                feed.push(&mut c)?;
                c.clear();
                // The reader may have finished already; the chunk is then dropped.
                let _ = recycle.send(c);
                Ok(())
            });
            if consumed.is_err() {
                break;
            }
        }
        drop(rx);
        let summary = producer
            .join()
            .unwrap_or_else(|_| Err(RequestError::WorkerStopped.into()));
        consumed
            .and(summary)
            .and_then(|s| feed.finish().map(|()| s))
    })
}

/// The bytes a log file's reader has read, counted in the request's progress as they
/// grow (once a chunk), the rest of the file once the reader is done.
struct BytesRead<'p> {
    progress: Option<&'p Progress>,
    counted: u64,
}

impl<'p> BytesRead<'p> {
    fn new(req: &'p FitRequest) -> Self {
        Self {
            progress: req.progress.as_deref(),
            counted: 0,
        }
    }

    /// Counts what `reader` has read since the last call.
    fn count(&mut self, reader: &LogReader) {
        if let Some(p) = self.progress {
            let now = reader.bytes_read();
            p.add_read(now.saturating_sub(self.counted), true);
            self.counted = self.counted.max(now);
        }
    }

    /// Counts the rest of the file at `path` (a reader may skip parts of it).
    fn finish(&mut self, path: &std::path::Path) {
        if let Some(p) = self.progress {
            let size = std::fs::metadata(path).map_or(0, |m| m.len());
            p.add_read(size.saturating_sub(self.counted), true);
            self.counted = self.counted.max(size);
        }
    }
}

/// Re-cuts the chunks of a log in memory (across segment boundaries) into chunks of exactly
/// [`CHUNK_SAMPLES`] samples, the last one shorter. The factorisation is updated once
/// per chunk, so fixed chunks make the statistics a function of the sample sequence
/// alone, bit for bit, whoever produced it; and a log of one-sample segments (a sweep,
/// whose rows are independent test points) costs one update per chunk, not per sample.
/// Residual autocorrelation lags then run across segment joins, a negligible share of
/// the lag products. The chunk being filled is reused once handed out.
#[derive(Default)]
struct Rechunker {
    pending: SampleChunk,
}

impl Rechunker {
    /// Appends the samples of `chunk`, handing every full chunk to `out` (which may
    /// take it, leaving an empty chunk in its place).
    fn push<E>(
        &mut self,
        chunk: &SampleChunk,
        out: &mut impl FnMut(&mut SampleChunk) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut start = 0;
        while start < chunk.len() {
            if self.pending.is_empty() && self.pending.t.capacity() < CHUNK_SAMPLES {
                // Room for a full chunk, so filling it one sample at a time (a sweep)
                // does not reallocate.
                self.pending = empty_like(chunk);
            }
            let take = (CHUNK_SAMPLES - self.pending.len()).min(chunk.len() - start);
            self.pending.extend_from(chunk, start..start + take);
            start += take;
            if self.pending.len() == CHUNK_SAMPLES {
                out(&mut self.pending)?;
                self.pending.clear();
            }
        }
        Ok(())
    }

    /// Hands the last, shorter chunk to `out`, if any samples wait.
    fn finish<E>(
        &mut self,
        out: &mut impl FnMut(&mut SampleChunk) -> Result<(), E>,
    ) -> Result<(), E> {
        if self.pending.is_empty() {
            return Ok(());
        }
        out(&mut self.pending)?;
        self.pending.clear();
        Ok(())
    }
}

/// An empty chunk with the signals of `chunk` and room for [`CHUNK_SAMPLES`] samples in
/// each, so that filling it does not reallocate (a sweep arrives one sample at a time).
fn empty_like(chunk: &SampleChunk) -> SampleChunk {
    let mut empty = SampleChunk::with_capacity(
        chunk.rotor_count(),
        CHUNK_SAMPLES,
        chunk.omega_dot.is_some(),
    );
    let room = || Vec::with_capacity(CHUNK_SAMPLES);
    if chunk.height.is_some() {
        empty.height = Some(room());
    }
    if chunk.attitude.is_some() {
        empty.attitude = Some([room(), room(), room(), room()]);
    }
    empty
}
