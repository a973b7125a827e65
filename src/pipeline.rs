//! The `mrsysid fit` pipeline, as a library call: read logs in parallel into mergeable
//! statistics (fit data and hold-out validation data), estimate (seed §5), then a
//! streaming second pass for residual diagnostics and plot series. The text of a log
//! file is read once: the first pass spills its parsed chunks to a temporary binary file
//! that the second pass streams back (the `spill` module's docs explain the choice), in
//! segments of equal length (`segments`, cut by the log's length alone) passed on all
//! the log's threads and merged in order (`pass_log`): results never depend on
//! `--threads`.
//!
//! Hold-out: without explicit validation logs, each log's time axis is cut into
//! contiguous segments of [`Holdout::segment_seconds`] from its first sample, and every
//! [`Holdout::every`]-th segment (the last of each group) is held out for validation —
//! 20 % of the data in 2 s segments by default. Rows of a time series are never
//! sampled at random.

use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

use crate::diagnose::local::{ActivityParts, LocalFolds, LocalRegions};
use crate::diagnose::{
    Candidate, CandidateContext, CandidateStatistics, DiagnoseOptions, Diagnosis,
    SCREENING_SAMPLES, Thinned, candidate_set_on_threads, diagnose_on_threads,
    hover_thrust_coefficient,
};
use crate::error::{Error, RequestError};
use crate::estimate::{
    self, AxisMetrics, CrossValidation, DiagnosticOptions, Fit, FitOptions, Folds,
    ResidualDiagnostics, ResidualPass,
};
use crate::identified::IdentifiedModel;
use crate::io::derive::{JerkScratch, rotor_jerk};
use crate::io::{self, DeriveOptions, LogReader, Mapping, ReadOptions, Summary};
use crate::model::{ModelStructure, Reuse, Workspace};
use crate::sample::{CHUNK_SAMPLES, SampleChunk, Signals};
use crate::slow::SlowThrust;
use crate::source::LogSource;
use crate::spill::{Spill, SpillWriter};
use crate::stats::{AccumulateError, Accumulator, stored_columns_of};
use crate::vehicle::Vehicle;

/// Time-segment hold-out of the fit logs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Holdout {
    /// Segment length, s.
    pub segment_seconds: f64,
    /// Every `every`-th segment is held out (fraction 1/every).
    pub every: usize,
}

impl Default for Holdout {
    fn default() -> Self {
        Self {
            segment_seconds: 2.0,
            every: 5,
        }
    }
}

impl Holdout {
    /// True when the sample at `t` (s), in a log starting at `t0` (s), is held out.
    pub fn holds_out(&self, t: f64, t0: f64) -> bool {
        let segment = ((t - t0) / self.segment_seconds).floor() as usize;
        self.every > 0 && segment % self.every == self.every - 1
    }
}

/// Everything `fit` needs.
#[derive(Debug, Clone)]
pub struct FitRequest {
    /// Logs to fit.
    pub logs: Vec<LogSource>,
    /// The vehicle.
    pub vehicle: Vehicle,
    /// Mapping for logs that do not follow the contract.
    pub mapping: Option<Mapping>,
    /// Reader options.
    pub read: ReadOptions,
    /// Eq. 22 structure.
    pub structure: ModelStructure,
    /// Estimation options.
    pub fit: FitOptions,
    /// Segment hold-out of a single fit log (cross-validation of one log).
    pub holdout: Holdout,
    /// Reporting-only validation logs: evaluated, never used for a decision.
    pub validate: Vec<LogSource>,
    /// Threads for reading, accumulating and the diagnosis (≥ 1).
    pub threads: usize,
    /// Run the second pass (residual diagnostics, plot series).
    pub second_pass: bool,
    /// Run the closing-the-loop diagnosis (in the second pass).
    pub diagnose: Option<DiagnoseOptions>,
    /// Samples read so far, over both passes, for a progress display.
    pub progress: Option<Arc<AtomicU64>>,
    /// Set by the caller to stop the fit: checked before every chunk of both passes
    /// (where `progress` is counted), the fit then ends with
    /// [`RequestError::Cancelled`].
    pub cancel: Option<Arc<AtomicBool>>,
}

/// Decimated measured/predicted series for plots, per axis.
#[derive(Debug, Clone, Default)]
pub struct PlotSeries {
    /// Time, s (logs are laid end to end).
    pub t: Vec<f64>,
    /// Measured output per axis.
    pub measured: [Vec<f64>; 6],
    /// Model output per axis.
    pub predicted: [Vec<f64>; 6],
}

/// What the pipeline produced.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    /// The estimates.
    pub fit: Fit,
    /// Fit statistics (for refits with candidate effects).
    pub fit_stats: Accumulator,
    /// Statistics of the reporting-only validation logs (no samples without them).
    pub validation_stats: Accumulator,
    /// Goodness of fit of the Eq. 22 model on the validation logs when given, else
    /// cross-validated (all folds pooled).
    pub validation: [AxisMetrics; 6],
    /// Samples behind `validation`.
    pub validation_samples: u64,
    /// Cross-validation of the Eq. 22 model: fold names and held-out errors.
    pub cross_validation: (Vec<String>, CrossValidation),
    /// Residual diagnostics of the fit data (second pass).
    pub diagnostics: Option<ResidualDiagnostics>,
    /// Fit-data series for plots (second pass).
    pub fit_series: PlotSeries,
    /// Validation-data series for plots (second pass).
    pub validation_series: PlotSeries,
    /// One reader summary per log, fit logs first.
    pub summaries: Vec<Summary>,
    /// Description of the validation data.
    pub validation_source: String,
    /// Closing-the-loop result.
    pub diagnosis: Option<Diagnosis>,
    /// Coloured-residual variance inflation κ = (1 + ρ)/(1 − ρ) of the Eq. 22 fit's
    /// residuals (ρ the largest lag-1 autocorrelation over the axes), ≥ 1; 1 when the
    /// second pass did not run. σ² of white residuals times κ is the corrected variance.
    pub variance_inflation: f64,
}

/// Statistics of one log: the samples fitted and those held out (its hold-out segments,
/// or all samples of a validation log).
struct LogStats {
    fit: Accumulator,
    held_out: Accumulator,
    /// Thinned fit samples for the generic-pool screening.
    screening: Thinned,
    summary: Summary,
    /// Optional signals of the log's first chunk, `None` for a log without samples.
    signals: Option<Signals>,
    /// The log's parsed chunks for the second pass (log files only, when it runs).
    spill: Option<Spill>,
    /// Time the hold-out segments count from (the first sample's), s.
    t0: Option<f64>,
    /// Chunks the log was read in.
    chunks: usize,
}

/// What the second pass needs to know of a log from the first, in job order.
#[derive(Debug, Clone, Copy)]
struct LogCounts {
    /// Samples routed to fit and to validation (for plot decimation).
    kinds: [u64; 2],
    /// Time the log's hold-out segments count from, s.
    t0: Option<f64>,
    /// Chunks the log is read in (the same in both passes).
    chunks: usize,
}

/// The error of accumulating a chunk of the log `source`.
fn accumulate_error(source: &LogSource) -> impl Fn(AccumulateError) -> Error + '_ {
    move |e| Error::Accumulate {
        log: source.name(),
        source: e,
    }
}

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

/// Reads one log, routing each sample to the fit or validation statistics; `share` is
/// the number of threads the job may use (see [`stream_log`]).
fn read_log(
    source: &LogSource,
    role: Role,
    req: &FitRequest,
    share: usize,
) -> Result<LogStats, Error> {
    let mut fit = Accumulator::new(&req.structure);
    let mut held_out = Accumulator::new(&req.structure);
    let mut signals = None;
    let mut screening = Thinned::new(SCREENING_SAMPLES);
    let keep_screening = req.diagnose.is_some();
    let mut ws = Workspace::default();
    let mut split = Splitter::new(role, None);
    let mut spill = match source {
        LogSource::File(_) if req.second_pass || req.diagnose.is_some() => {
            Some(SpillWriter::create()?)
        }
        _ => None,
    };
    let mut sink = |part: &SampleChunk, to_validation: bool| {
        let acc = if to_validation {
            &mut held_out
        } else {
            if keep_screening {
                screening.push(part);
            }
            &mut fit
        };
        acc.push(&req.structure, part, &mut ws)
            .map_err(accumulate_error(source))
    };
    let mut chunks = 0;
    let summary = stream_log(source, req, share, |chunk| {
        chunks += 1;
        signals.get_or_insert_with(|| chunk.signals());
        let kinds = split.route(chunk, &mut sink)?;
        if let Some(w) = spill.as_mut() {
            w.write(chunk, kinds)?;
        }
        Ok(())
    })?;
    split.finish(&mut sink)?;
    Ok(LogStats {
        fit,
        held_out,
        screening,
        summary,
        signals,
        spill: spill.map(SpillWriter::finish).transpose()?,
        t0: split.t0,
        chunks,
    })
}

/// Samples per segment, on average over a fit log, below which the log is taken for a
/// sweep's points rather than a time series (no trim-moment candidates).
const MIN_SEGMENT_SAMPLES: u64 = 256;

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
fn stream_log(
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
            }
            cut.finish(&mut |c| feed.push(c))?;
            feed.finish()?;
            return Ok(Summary::of_memory(log.name(), log.len()));
        }
    };
    if share < 2 {
        let mut reader = open(path, req, 0)?;
        reader.join_segments();
        while let Some(chunk) = reader.next_chunk_mut() {
            feed.push(chunk?)?;
        }
        feed.finish()?;
        return Ok(reader.summary().clone());
    }
    let (tx, rx) = std::sync::mpsc::sync_channel(CHUNKS_IN_FLIGHT);
    let (recycle, reuse) = std::sync::mpsc::channel::<SampleChunk>();
    std::thread::scope(|scope| {
        // The reader is opened on its own thread (it is not `Send`).
        let producer = scope.spawn(move || -> Result<Summary, Error> {
            let mut reader = open(path, req, parse_threads(share))?;
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
                // The consumer stopped on an error of its own, which it reports. (After
                // a read error the reader is over: the loop ends with it.)
                if sent.is_err() {
                    break;
                }
            }
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

/// What happens to each chunk of a log before its consumer sees it: Ω̈ derived from Ω̇
/// ([`rotor_jerk`]), progress counted and, for a diagnosis or a model with a trim
/// moment, the slow rotor thrusts filled in ([`SlowThrust`]; chunks then reach the
/// consumer up to a few seconds of samples later, in order, the last ones at
/// [`Feed::finish`]).
struct Feed<'p, C> {
    derive: DeriveOptions,
    progress: Option<&'p AtomicU64>,
    cancel: Option<&'p AtomicBool>,
    jerk: JerkScratch,
    /// The slow rotor thrusts are wanted; the stage once the first chunk is in.
    slow_wanted: bool,
    slow: Option<SlowThrust>,
    consume: C,
}

impl<'p, C: FnMut(&SampleChunk) -> Result<(), Error>> Feed<'p, C> {
    /// The feed of a fit: the slow thrusts for a diagnosis.
    fn of_fit(req: &'p FitRequest, consume: C) -> Self {
        Self::new(jerk_options(req), req.diagnose.is_some(), consume)
            .counting(req.progress.as_deref(), req.cancel.as_deref())
    }

    fn new(derive: DeriveOptions, slow_wanted: bool, consume: C) -> Self {
        Self {
            derive,
            progress: None,
            cancel: None,
            jerk: JerkScratch::default(),
            slow_wanted,
            slow: None,
            consume,
        }
    }

    /// The feed counting its samples in `progress` and stopping once `cancel` is set.
    fn counting(self, progress: Option<&'p AtomicU64>, cancel: Option<&'p AtomicBool>) -> Self {
        Self {
            progress,
            cancel,
            ..self
        }
    }

    fn push(&mut self, chunk: &mut SampleChunk) -> Result<(), Error> {
        check_cancel(self.cancel)?;
        rotor_jerk(chunk, &self.derive, &mut self.jerk);
        let (progress, consume) = (self.progress, &mut self.consume);
        let mut deliver = |c: &SampleChunk| {
            if let Some(p) = progress {
                p.fetch_add(c.len() as u64, Ordering::Relaxed);
            }
            consume(c)
        };
        if !self.slow_wanted {
            return deliver(chunk);
        }
        let rotors = chunk.rotor_count();
        let stage = self.slow.get_or_insert_with(|| SlowThrust::new(rotors));
        // A copy is held: the reader's chunk goes back to it.
        stage.push(chunk.clone(), |c| deliver(&c))
    }

    fn finish(&mut self) -> Result<(), Error> {
        let (progress, consume) = (self.progress, &mut self.consume);
        match self.slow.as_mut() {
            Some(stage) => stage.finish(|c| {
                if let Some(p) = progress {
                    p.fetch_add(c.len() as u64, Ordering::Relaxed);
                }
                consume(&c)
            }),
            None => Ok(()),
        }
    }
}

/// Streams the log file at `path` as `model` needs it: read with `mapping`, cut into the
/// chunks a fit cuts, with the rates of rotor acceleration and the slow rotor thrusts
/// derived as the fit pipeline derives them (so `predict` and `validate` see the
/// samples the fit saw), each chunk handed to `consume` in order.
pub fn stream_for_model(
    model: &IdentifiedModel,
    path: &std::path::Path,
    mapping: Option<&Mapping>,
    consume: impl FnMut(&SampleChunk) -> Result<(), Error>,
) -> Result<(), Error> {
    let read = ReadOptions::default();
    let derive = mapping.and_then(|m| m.derive).unwrap_or(read.derive);
    let mut feed = Feed::new(derive, model.structure.needs_slow_thrust(), consume);
    let mut reader = io::open_log(path, &model.vehicle, mapping, &read)?;
    reader.join_segments();
    while let Some(chunk) = reader.next_chunk_mut() {
        feed.push(chunk?)?;
    }
    feed.finish()
}

/// Differentiator of the rates of rotor acceleration ([`rotor_jerk`], on the re-cut
/// chunks of every log alike): the mapping file's `[derive]` table when given, else the
/// request's read options.
fn jerk_options(req: &FitRequest) -> DeriveOptions {
    req.mapping
        .as_ref()
        .and_then(|m| m.derive)
        .unwrap_or(req.read.derive)
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
    let mut empty =
        SampleChunk::with_capacity(chunk.rotor_count(), CHUNK_SAMPLES, chunk.has_omega_dot());
    if chunk.has_height() {
        empty.height.reserve(CHUNK_SAMPLES);
    }
    if chunk.has_attitude() {
        empty
            .attitude
            .iter_mut()
            .for_each(|v| v.reserve(CHUNK_SAMPLES));
    }
    empty
}

/// Counts `chunk` in the request's progress, after checking its cancellation flag.
fn count_progress(req: &FitRequest, chunk: &SampleChunk) -> Result<(), Error> {
    check_cancel(req.cancel.as_deref())?;
    if let Some(p) = &req.progress {
        p.fetch_add(chunk.len() as u64, Ordering::Relaxed);
    }
    Ok(())
}

/// [`RequestError::Cancelled`] once `cancel` is set.
fn check_cancel(cancel: Option<&AtomicBool>) -> Result<(), Error> {
    match cancel {
        Some(c) if c.load(Ordering::Relaxed) => Err(RequestError::Cancelled.into()),
        _ => Ok(()),
    }
}

/// How a log's samples are used.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    /// All samples fit.
    Fit,
    /// All samples validate.
    Validation,
    /// Time segments split between the two.
    Split(Holdout),
}

/// Cuts chunks into runs of fit and validation samples.
struct Splitter {
    role: Role,
    t0: Option<f64>,
    /// Fit and validation samples waiting for a full chunk.
    parts: [SampleChunk; 2],
    /// Indices of the routed chunk's samples of each kind not yet in `parts`.
    rows: [Vec<usize>; 2],
}

impl Splitter {
    /// A splitter whose hold-out segments count from `t0` (s), or from the first sample
    /// it routes when `None`.
    fn new(role: Role, t0: Option<f64>) -> Self {
        Self {
            role,
            t0,
            parts: Default::default(),
            rows: Default::default(),
        }
    }

    /// Routes the samples of `chunk` to `sink(part, to_validation)`: whole chunks when
    /// the log has one role, else runs of one kind gathered into chunks of at least
    /// [`CHUNK_SAMPLES`] (time order kept within each kind). Call [`Splitter::finish`]
    /// after the last chunk. Returns the chunk's samples of each kind (fit, validation).
    fn route(
        &mut self,
        chunk: &SampleChunk,
        sink: &mut impl FnMut(&SampleChunk, bool) -> Result<(), Error>,
    ) -> Result<[u64; 2], Error> {
        let n = chunk.len() as u64;
        let holdout = match self.role {
            Role::Fit => return sink(chunk, false).map(|()| [n, 0]),
            Role::Validation => return sink(chunk, true).map(|()| [0, n]),
            Role::Split(h) => h,
        };
        let mut kinds = [0u64; 2];
        if chunk.is_empty() {
            return Ok(kinds);
        }
        let t0 = *self.t0.get_or_insert(chunk.t[0]);
        let mut start = 0;
        while start < chunk.len() {
            let kind = holdout.holds_out(chunk.t[start], t0);
            let mut end = start + 1;
            while end < chunk.len() && holdout.holds_out(chunk.t[end], t0) == kind {
                end += 1;
            }
            let k = usize::from(kind);
            kinds[k] += (end - start) as u64;
            // Runs are gathered by index, a kind's at a time: the part is handed on
            // after the run that fills it, as if each run were appended on its own.
            self.rows[k].extend(start..end);
            if self.parts[k].len() + self.rows[k].len() >= CHUNK_SAMPLES {
                self.parts[k].extend_from_rows(chunk, &self.rows[k]);
                self.rows[k].clear();
                sink(&self.parts[k], kind)?;
                self.parts[k].clear();
            }
            start = end;
        }
        for (part, rows) in self.parts.iter_mut().zip(&mut self.rows) {
            part.extend_from_rows(chunk, rows);
            rows.clear();
        }
        Ok(kinds)
    }

    /// Hands over the samples still waiting.
    fn finish(
        &mut self,
        sink: &mut impl FnMut(&SampleChunk, bool) -> Result<(), Error>,
    ) -> Result<(), Error> {
        for (k, part) in self.parts.iter_mut().enumerate() {
            if !part.is_empty() {
                sink(part, k == 1)?;
                part.clear();
            }
        }
        Ok(())
    }
}

/// Runs `per_log(job index, path, role, share)` for every job on up to `req.threads`
/// threads; results come back in job order, so merged statistics do not depend on
/// scheduling. `share` is the number of threads a job may use: `req.threads` divided
/// among the logs worked on at once (at least 1).
fn run_jobs<T: Send>(
    jobs: &[(LogSource, Role)],
    req: &FitRequest,
    per_log: impl Fn(usize, &LogSource, Role, usize) -> Result<T, Error> + Sync,
) -> Result<Vec<T>, Error> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<T, Error>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    let threads = req.threads.max(1);
    let workers = threads.min(jobs.len().max(1));
    let share = (threads / workers).max(1);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some((path, role)) = jobs.get(i) else {
                        break;
                    };
                    let r = per_log(i, path, *role, share);
                    results.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(r);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .map(|r| r.unwrap_or_else(|| Err(RequestError::WorkerStopped.into())))
        .collect()
}

/// Fit logs first (a single one split by the hold-out), then the validation logs.
fn jobs(req: &FitRequest) -> Vec<(LogSource, Role)> {
    let fit_role = if req.logs.len() == 1 {
        Role::Split(req.holdout)
    } else {
        Role::Fit
    };
    req.logs
        .iter()
        .map(|p| (p.clone(), fit_role))
        .chain(req.validate.iter().map(|p| (p.clone(), Role::Validation)))
        .collect()
}

/// Merges statistics of the same structure (they always have its shape).
fn merge(into: &mut Accumulator, other: &Accumulator) -> Result<(), Error> {
    into.merge(other).map_err(|source| Error::Accumulate {
        log: "merged statistics".into(),
        source,
    })
}

/// The fit logs' statistics ((fit, held-out) per log, job order) arranged for
/// cross-validation and the final fit: leave one log out with two or more logs, else the
/// log's hold-out segments (which `run` has checked hold samples). Returns the folds and
/// the final fit data: all fit logs, the held-out segments of a single log included only
/// when validation logs report instead.
fn arrange(req: &FitRequest, parts: &[[&Accumulator; 2]]) -> Result<(Folds, Accumulator), Error> {
    let merged = |pair: &[&Accumulator; 2]| -> Result<Accumulator, Error> {
        let mut a = pair[0].clone();
        merge(&mut a, pair[1])?;
        Ok(a)
    };
    if let [single] = parts {
        let folds = Folds::holdout("hold-out segments", single[0].clone(), single[1].clone());
        let fit = if req.validate.is_empty() {
            single[0].clone()
        } else {
            merged(single)?
        };
        return Ok((folds, fit));
    }
    let logs = parts
        .iter()
        .zip(&req.logs)
        .map(|(pair, source)| Ok((source.name(), merged(pair)?)))
        .collect::<Result<Vec<_>, Error>>()?;
    let folds = Folds::leave_one_out(&logs).map_err(|source| Error::Accumulate {
        log: "leave-one-out folds".into(),
        source,
    })?;
    let mut fit = logs[0].1.clone();
    for (_, a) in &logs[1..] {
        merge(&mut fit, a)?;
    }
    Ok((folds, fit))
}

/// Refuses a request that cannot be carried out, before any log is read.
fn check(req: &FitRequest) -> Result<(), RequestError> {
    if req.logs.is_empty() {
        return Err(RequestError::NoLogs);
    }
    let h = req.holdout;
    if !(h.segment_seconds.is_finite() && h.segment_seconds > 0.0 && h.every >= 2) {
        return Err(RequestError::InvalidHoldout {
            segment_seconds: h.segment_seconds,
            every: h.every,
        });
    }
    let (structure, vehicle) = (req.structure.rotor_count(), req.vehicle.rotor_count());
    if structure != vehicle {
        return Err(RequestError::StructureMismatch { structure, vehicle });
    }
    crate::inputs::check_logs(&req.logs, &req.validate)
}

/// The error of a single fit log none of whose samples was held out (`log`, read as
/// `req.logs[0]`): its time looks logged in ms or µs (bad input), else it is too short
/// for the hold-out, or sampled more coarsely than its segments.
fn no_holdout(req: &FitRequest, log: &LogStats) -> Error {
    let s = &log.summary;
    let (span, median_step) = match &req.logs[0] {
        LogSource::Memory(m) => {
            let first = m.chunks().first().and_then(|c| c.t.first());
            let last = m.chunks().last().and_then(|c| c.t.last());
            (first.zip(last).map_or(0.0, |(a, b)| b - a), None)
        }
        LogSource::File(_) => (s.span, s.median_time_step),
    };
    let samples = log.fit.count() + log.held_out.count();
    let consequence = ", so no sample falls in a held-out segment";
    if let Some(text) = io::validate::time_unit_suspect(median_step, span, samples, consequence) {
        return io::IoError::new(
            &s.file,
            io::Location::File,
            None,
            io::ErrorKind::Mapping(text),
        )
        .into();
    }
    RequestError::HoldoutTooShort {
        log: s.file.clone(),
        samples,
        span,
        median_step,
        segment_seconds: req.holdout.segment_seconds,
        every: req.holdout.every,
    }
    .into()
}

/// Runs the pipeline.
pub fn run(req: &FitRequest) -> Result<FitOutcome, Error> {
    check(req)?;
    let jobs = jobs(req);
    let per_log = run_jobs(&jobs, req, |_, path, role, share| {
        read_log(path, role, req, share)
    })?;
    let n_fit = req.logs.len();
    let mut validation_stats = Accumulator::new(&req.structure);
    let mut screening = Thinned::new(SCREENING_SAMPLES);
    let signals = per_log.iter().find_map(|s| s.signals);
    for s in &per_log {
        screening.merge(&s.screening);
    }
    for s in &per_log[n_fit..] {
        merge(&mut validation_stats, &s.held_out)?;
    }
    let counts: Vec<LogCounts> = per_log
        .iter()
        .map(|s| LogCounts {
            kinds: [s.fit.count(), s.held_out.count()],
            t0: s.t0,
            chunks: s.chunks,
        })
        .collect();
    let parts: Vec<[&Accumulator; 2]> = per_log[..n_fit]
        .iter()
        .map(|s| [&s.fit, &s.held_out])
        .collect();
    if parts.iter().all(|p| p[0].count() + p[1].count() == 0) {
        return Err(RequestError::NoSamples.into());
    }
    if let [single] = &parts[..]
        && single[1].count() == 0
    {
        return Err(no_holdout(req, &per_log[0]));
    }
    let (folds, fit_stats) = arrange(req, &parts)?;
    let (summaries, spills): (Vec<Summary>, Vec<Option<Spill>>) =
        per_log.into_iter().map(|s| (s.summary, s.spill)).unzip();
    let fit = estimate::fit(&req.structure, &fit_stats, &req.fit)?;
    let cv = estimate::cross_validate(&req.structure, &folds, &req.fit)?;
    let (validation, validation_samples) = if validation_stats.count() > 0 {
        let v = estimate::evaluate(&req.structure, &fit.mmr.theta, &validation_stats)?;
        (v, validation_stats.count())
    } else {
        (cv.pooled_metrics(), folds.test_samples())
    };
    let validation_source = if !req.validate.is_empty() {
        format!(
            "{} validation log(s), not used for any decision",
            req.validate.len()
        )
    } else if n_fit > 1 {
        format!(
            "leave one log out over {n_fit} logs (each predicted by the model fitted on the others), pooled"
        )
    } else {
        format!(
            "hold-out: every {}th {:.1} s segment of the fit log",
            req.holdout.every, req.holdout.segment_seconds
        )
    };
    let mut outcome = FitOutcome {
        fit,
        fit_stats,
        validation_stats,
        validation,
        validation_samples,
        cross_validation: (folds.names.clone(), cv),
        diagnostics: None,
        fit_series: PlotSeries::default(),
        validation_series: PlotSeries::default(),
        summaries,
        validation_source,
        diagnosis: None,
        variance_inflation: 1.0,
    };
    if req.second_pass || req.diagnose.is_some() {
        second_pass(
            req,
            &jobs,
            &spills,
            &counts,
            signals,
            screening.samples(),
            &mut outcome,
        )?;
    }
    Ok(outcome)
}

/// Most chunks per segment of a log's second pass ([`pass_log`]): a log of up to 64
/// chunks (65 536 samples) is one segment.
const SEGMENT_CHUNKS: usize = 64;

/// A longer log is cut into a multiple of this many segments of equal length (to a
/// chunk), so that 1, 2, 3 or 6 threads finish their last segments together: with
/// segments of 64 chunks and a short last one, one thread of two idled for up to a
/// segment at the end (~5 % of a 1 M-sample diagnosed fit).
const SEGMENT_GROUP: usize = 6;

/// The chunks of each segment of a log of `chunks` chunks, in order: one segment of up to
/// [`SEGMENT_CHUNKS`], else the fewest multiple of [`SEGMENT_GROUP`] segments of at most
/// that many, equal to a chunk (the longer first). A function of the length alone, so
/// results never depend on the thread count.
fn segments(chunks: usize) -> Vec<std::ops::Range<usize>> {
    let n = if chunks <= SEGMENT_CHUNKS {
        1
    } else {
        chunks.div_ceil(SEGMENT_CHUNKS * SEGMENT_GROUP) * SEGMENT_GROUP
    };
    let (size, longer) = (chunks / n, chunks % n);
    let mut start = 0;
    (0..n)
        .map(|k| {
            let range = start..start + size + usize::from(k < longer);
            start = range.end;
            range
        })
        .collect()
}

/// Points kept per plotted series: buckets of the whole run keep their first sample.
const PLOT_POINTS: u64 = 4000;

/// Candidate effects added to the base structure, with their parameter indices.
struct Extended {
    structure: ModelStructure,
    candidates: Vec<Candidate>,
    params: Vec<Vec<usize>>,
    regions: LocalRegions,
    /// The columns its accumulators store, and how they are assembled from each other.
    stored: Vec<bool>,
    plan: Vec<Option<Reuse>>,
}

impl Extended {
    /// Named candidates for data with `signals`, plus the generic-pool terms that
    /// survive screening on `screening` (thinned fit samples).
    fn new(
        req: &FitRequest,
        fit: &Fit,
        signals: Signals,
        slow_thrust: bool,
        screening: &SampleChunk,
        options: &DiagnoseOptions,
    ) -> Result<Self, Error> {
        let ctx = CandidateContext {
            vehicle: &req.vehicle,
            structure: &req.structure,
            theta: &fit.mmr.theta,
            has_height: signals.height,
            has_omega_dot: signals.omega_dot,
            has_omega_ddot: signals.omega_ddot,
            has_attitude: signals.attitude,
            has_slow_thrust: slow_thrust,
            hover_thrust_coefficient: hover_thrust_coefficient(&req.vehicle, &[screening]),
        };
        let set = candidate_set_on_threads(&ctx, Some(screening), options, req.threads)?;
        let stored = stored_columns_of(&set.extended);
        Ok(Self {
            plan: set.extended.reuse_plan(&stored),
            stored,
            structure: set.extended,
            candidates: set.candidates,
            params: set.params,
            regions: set.regions,
        })
    }
}

/// What every log's second pass shares (read only).
struct PassContext<'a> {
    req: &'a FitRequest,
    /// MMR estimates θ̂ in `req.structure.params` order.
    theta: &'a [f64],
    /// An empty residual pass to start each log from.
    residuals: ResidualPass,
    /// Candidate effects, when diagnosing.
    extended: Option<Extended>,
    /// Plot decimation: every `stride`-th sample of the whole run (fit, validation).
    strides: [u64; 2],
}

/// One log's share of the second pass. Shares merge in job order into the result of a
/// pass over all logs one after another.
struct LogPass {
    residuals: ResidualPass,
    /// Plot series (fit, validation); time counted from `span.0` of the kind.
    series: [PlotSeries; 2],
    /// First and last sample time of each kind in this log, s (NaN when none).
    span: [(f64, f64); 2],
    /// Candidate-effect statistics (fitted, held-out samples), when diagnosing.
    candidates: Option<[Accumulator; 2]>,
    /// The same over the samples where local candidates act, by activity pattern, from
    /// the kind [`local_kind`] names (empty for a validation log).
    local: ActivityParts,
}

/// Which samples of a log (fit: false, held-out: true) the local-region statistics are
/// built from: the held-out part of a single fit log, every sample of each of several
/// fit logs (each is left out in turn), none of a validation log (it reports, never
/// decides). [`local_folds`] uses nothing else.
fn local_kind(role: Role) -> Option<bool> {
    match role {
        Role::Fit => Some(false),
        Role::Split(_) => Some(true),
        Role::Validation => None,
    }
}

/// Streams the data again (each log file from its spill, in job order with `jobs`):
/// residual diagnostics of the fit samples, decimated series of both parts for plots,
/// and the statistics of every candidate effect. Logs are passed on up to `req.threads`
/// threads and their shares merged in job order, so the result does not depend on the
/// thread count.
fn second_pass(
    req: &FitRequest,
    jobs: &[(LogSource, Role)],
    spills: &[Option<Spill>],
    counts: &[LogCounts],
    signals: Option<Signals>,
    screening: &SampleChunk,
    out: &mut FitOutcome,
) -> Result<(), Error> {
    let stride = |n: u64| n.div_ceil(PLOT_POINTS).max(1);
    let ctx = PassContext {
        req,
        theta: &out.fit.mmr.theta,
        residuals: ResidualPass::new(&req.structure, &out.fit, DiagnosticOptions::default()),
        extended: match (&req.diagnose, signals) {
            (Some(options), Some(s)) => {
                // Time series, not a sweep's points: the slow thrusts have a slow part.
                let fit_logs = &out.summaries[..req.logs.len()];
                let time_series = fit_logs
                    .iter()
                    .all(|s| s.samples >= MIN_SEGMENT_SAMPLES * s.segments.max(1) as u64);
                let slow = s.omega_squared_slow && time_series;
                Some(Extended::new(req, &out.fit, s, slow, screening, options)?)
            }
            _ => None,
        },
        strides: [0, 1].map(|k| stride(counts.iter().map(|c| c.kinds[k]).sum())),
    };
    // Samples of each kind before each log: its first sample's place in the decimation.
    let starts: Vec<[u64; 2]> = counts
        .iter()
        .scan([0u64; 2], |seen, c| {
            let start = *seen;
            seen[0] += c.kinds[0];
            seen[1] += c.kinds[1];
            Some(start)
        })
        .collect();
    let shares = run_jobs(jobs, req, |i, path, role, threads| {
        let at = Start {
            seen: starts[i],
            in_log: [0; 2],
            t0: counts[i].t0,
        };
        let log = Log {
            source: path,
            spill: spills[i].as_ref(),
            role,
            chunks: counts[i].chunks,
        };
        pass_log(&ctx, &log, threads, at)
    })?;
    let mut residuals: Option<ResidualPass> = None;
    let mut t_offset = [0.0f64; 2];
    for share in &shares {
        match residuals.as_mut() {
            Some(r) => r.merge(&share.residuals),
            None => residuals = Some(share.residuals.clone()),
        }
        lay_end_to_end(
            share,
            &mut t_offset,
            &mut out.fit_series,
            &mut out.validation_series,
        );
    }
    let Some(residuals) = residuals else {
        return Ok(());
    };
    let diagnostics = residuals.finish();
    let inflation = coloured_variance_inflation(&diagnostics);
    out.variance_inflation = inflation;
    out.diagnostics = Some(diagnostics);
    let (Some(mut options), Some(ext)) = (req.diagnose, ctx.extended) else {
        return Ok(());
    };
    let local_parts = shares
        .iter()
        .zip(jobs)
        .take(req.logs.len())
        .map(|(s, (source, _))| {
            let regions = ext.regions.per_region(&s.local, &ext.structure);
            regions.map_err(accumulate_error(source))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let per_log: Vec<[Accumulator; 2]> = shares.into_iter().filter_map(|s| s.candidates).collect();
    let n_fit = req.logs.len();
    if per_log.len() != jobs.len() {
        return Ok(());
    }
    let parts: Vec<[&Accumulator; 2]> = per_log[..n_fit].iter().map(|[a, b]| [a, b]).collect();
    let (folds, fit) = arrange(req, &parts)?;
    let mut report = Accumulator::new(&ext.structure);
    for [_, held_out] in &per_log[n_fit..] {
        merge(&mut report, held_out)?;
    }
    let local = local_folds(&ext.regions, &local_parts, &folds);
    options.variance_inflation = options.variance_inflation.max(inflation);
    let stats = CandidateStatistics {
        extended: &ext.structure,
        candidates: &ext.candidates,
        candidate_params: &ext.params,
        base_params: req.structure.params.len(),
        fit: &fit,
        folds: &folds,
        report: (report.count() > 0).then_some(&report),
        local: &local,
    };
    out.diagnosis = Some(diagnose_on_threads(
        &stats,
        &req.fit,
        &options,
        req.threads,
    )?);
    Ok(())
}

/// The held-out statistics where each local candidate acts, per fold as [`arrange`]
/// builds the folds (`parts`: each fit log's local statistics, see [`local_kind`]): the
/// hold-out part of a single log, or each whole log left out. A region with no active
/// held-out sample in some fold is left out (judged globally).
fn local_folds(
    regions: &LocalRegions,
    parts: &[Vec<Accumulator>],
    folds: &Folds,
) -> Vec<LocalFolds> {
    let regions = regions.candidates.iter().enumerate();
    regions
        .filter_map(|(r, &candidate)| {
            let tests = parts.iter().map(|log| log[r].clone()).collect();
            LocalFolds::new(candidate, folds, tests)
        })
        .collect()
}

/// Appends a log's plot series after the logs before it on the plots' time axis
/// (`t_offset`: time already laid out per kind, s).
fn lay_end_to_end(
    share: &LogPass,
    t_offset: &mut [f64; 2],
    fit: &mut PlotSeries,
    validation: &mut PlotSeries,
) {
    for (k, series) in [fit, validation].into_iter().enumerate() {
        let part = &share.series[k];
        series.t.extend(part.t.iter().map(|t| t + t_offset[k]));
        for a in 0..6 {
            series.measured[a].extend_from_slice(&part.measured[a]);
            series.predicted[a].extend_from_slice(&part.predicted[a]);
        }
        let (first, last) = share.span[k];
        if first.is_finite() {
            t_offset[k] += last - first;
        }
    }
}

/// Where a segment of a log's second pass starts.
#[derive(Debug, Clone, Copy)]
struct Start {
    /// Samples of each kind (fit, validation) before it, in this log and the logs before.
    seen: [u64; 2],
    /// The same in this log only.
    in_log: [u64; 2],
    /// Time the log's hold-out segments count from, s.
    t0: Option<f64>,
}

/// A log as its second pass reads it.
struct Log<'a> {
    source: &'a LogSource,
    /// Its parsed chunks, for a log file.
    spill: Option<&'a Spill>,
    role: Role,
    /// Chunks it is read in (from the first pass).
    chunks: usize,
}

/// The second pass over one log, from its spill when there is one, in the segments
/// [`segments`] cuts: each segment is passed from a fresh state (on up to `threads`
/// threads when read from a spill) and the segments' shares are merged in order, so the
/// result depends on the log alone, never on the thread count or on whether the log
/// came from a file or from memory.
fn pass_log(ctx: &PassContext, log: &Log, threads: usize, at: Start) -> Result<LogPass, Error> {
    let (source, role) = (log.source, log.role);
    let mut share = LogPass::empty(ctx);
    let mut append = |part: LogPass| share.append(part).map_err(accumulate_error(source));
    let cuts = segments(log.spill.map_or(log.chunks, Spill::chunks));
    match log.spill {
        Some(spill) => {
            let pass_segment = |s: usize| {
                let chunks = cuts[s].clone();
                let in_log = if chunks.is_empty() {
                    [0; 2]
                } else {
                    spill.before(chunks.start)
                };
                let seen = [0, 1].map(|k| at.seen[k] + in_log[k]);
                let start = Start { seen, in_log, ..at };
                let mut pass = SegmentPass::new(ctx, source, role, start);
                // Spilled with its Ω̈ (derived in the first pass).
                spill.stream_chunks(chunks, |chunk| {
                    count_progress(ctx.req, chunk)?;
                    pass.push(chunk)
                })?;
                pass.finish()
            };
            run_in_order(cuts.len(), threads, pass_segment, &mut append)?;
        }
        None => {
            let mut pass = SegmentPass::new(ctx, source, role, at);
            // Chunks read so far, and the segment being passed.
            let (mut read, mut segment) = (0, 0);
            stream_log(source, ctx.req, threads, |chunk| {
                if cuts.get(segment + 1).is_some_and(|next| next.start == read) {
                    let next = SegmentPass::new(ctx, source, role, pass.next_start());
                    append(std::mem::replace(&mut pass, next).finish()?)?;
                    segment += 1;
                }
                read += 1;
                pass.push(chunk)
            })?;
            append(pass.finish()?)?;
        }
    }
    share.times_from_start();
    Ok(share)
}

/// Runs `task(i)` for i in 0..n on up to `threads` threads, handing the results to
/// `fold` in index order as they come in (tasks are taken in index order, so at most
/// about `threads` results wait). The first error in index order is returned.
fn run_in_order<T: Send>(
    n: usize,
    threads: usize,
    task: impl Fn(usize) -> Result<T, Error> + Sync,
    fold: &mut (impl FnMut(T) -> Result<(), Error> + Send),
) -> Result<(), Error> {
    struct Done<'f, T, F> {
        next: usize,
        waiting: std::collections::BTreeMap<usize, T>,
        fold: &'f mut F,
        failed: Option<(usize, Error)>,
    }
    let done = Mutex::new(Done {
        next: 0,
        waiting: Default::default(),
        fold,
        failed: None,
    });
    let take = AtomicUsize::new(0);
    let work = || {
        loop {
            let i = take.fetch_add(1, Ordering::Relaxed);
            let stop = |d: &Done<T, _>| d.failed.as_ref().is_some_and(|f| f.0 < i);
            if i >= n || stop(&done.lock().unwrap_or_else(|e| e.into_inner())) {
                break;
            }
            let result = task(i);
            let mut d = done.lock().unwrap_or_else(|e| e.into_inner());
            let d = &mut *d;
            match result {
                Ok(r) => {
                    d.waiting.insert(i, r);
                }
                Err(e) => {
                    if d.failed.as_ref().is_none_or(|f| i < f.0) {
                        d.failed = Some((i, e));
                    }
                }
            }
            while d.failed.is_none() {
                let Some(r) = d.waiting.remove(&d.next) else {
                    break;
                };
                d.next += 1;
                if let Err(e) = (d.fold)(r) {
                    d.failed = Some((d.next - 1, e));
                }
            }
        }
    };
    let workers = threads.clamp(1, n.max(1));
    std::thread::scope(|scope| {
        for _ in 1..workers {
            scope.spawn(work);
        }
        work();
    });
    let done = done.into_inner().unwrap_or_else(|e| e.into_inner());
    match done.failed {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

/// The second pass over one segment of a log.
struct SegmentPass<'a> {
    source: &'a LogSource,
    split: Splitter,
    state: SegmentState<'a>,
}

/// What a segment's sink works on (apart from its splitter).
struct SegmentState<'a> {
    ctx: &'a PassContext<'a>,
    role: Role,
    share: LogPass,
    /// Samples of each kind before the segment's next sample (plot decimation).
    seen: [u64; 2],
    /// Samples of each kind in the log before the segment's next sample.
    in_log: [u64; 2],
    /// The same before the segment's first sample (error positions count from them).
    first: [u64; 2],
    ws: Workspace,
    active_ws: Workspace,
    part_ws: Workspace,
    /// The samples the plots keep of a part, and their regressors.
    plot_rows: SampleChunk,
    plot_ws: Workspace,
}

impl<'a> SegmentPass<'a> {
    fn new(ctx: &'a PassContext<'a>, source: &'a LogSource, role: Role, at: Start) -> Self {
        Self {
            source,
            split: Splitter::new(role, at.t0),
            state: SegmentState {
                ctx,
                role,
                share: LogPass::empty(ctx),
                seen: at.seen,
                in_log: at.in_log,
                first: at.in_log,
                ws: Workspace::default(),
                active_ws: Workspace::default(),
                part_ws: Workspace::default(),
                plot_rows: SampleChunk::default(),
                plot_ws: Workspace::default(),
            },
        }
    }

    /// Where the segment after this one starts (call after its last chunk).
    fn next_start(&self) -> Start {
        let waiting = |k: usize| self.split.parts[k].len() as u64;
        Start {
            seen: std::array::from_fn(|k| self.state.seen[k] + waiting(k)),
            in_log: std::array::from_fn(|k| self.state.in_log[k] + waiting(k)),
            t0: self.split.t0,
        }
    }

    fn push(&mut self, chunk: &SampleChunk) -> Result<(), Error> {
        let state = &mut self.state;
        let source = self.source;
        self.split
            .route(chunk, &mut |part, v| state.sink(source, part, v))
            .map(|_| ())
    }

    fn finish(mut self) -> Result<LogPass, Error> {
        let state = &mut self.state;
        let source = self.source;
        self.split
            .finish(&mut |part, v| state.sink(source, part, v))?;
        Ok(self.state.share)
    }
}

impl SegmentState<'_> {
    /// Folds a run of samples of one kind into the segment's share.
    fn sink(
        &mut self,
        source: &LogSource,
        part: &SampleChunk,
        to_validation: bool,
    ) -> Result<(), Error> {
        let k = usize::from(to_validation);
        let ctx = self.ctx;
        let share = &mut self.share;
        let ws = &mut self.ws;
        let at = |e: AccumulateError| accumulate_error(source)(e.after(self.first[k]));
        if let (Some(ext), Some(acc)) = (&ctx.extended, share.candidates.as_mut()) {
            let assembled = ext
                .structure
                .assemble_reusing(part, ws, &ext.stored, &ext.plan);
            assembled.map_err(|e| at(e.into()))?;
            acc[k].push_assembled(ws).map_err(at)?;
            if local_kind(self.role) == Some(to_validation) {
                ext.regions
                    .push(
                        part,
                        ws,
                        &ext.structure,
                        &mut share.local,
                        &mut self.active_ws,
                        &mut self.part_ws,
                    )
                    .map_err(accumulate_error(source))?;
            }
        }
        if !to_validation {
            share.residuals.push(part, ws).map_err(at)?;
        }
        let span = &mut share.span[k];
        if span.0.is_nan() {
            span.0 = part.t[0];
        }
        span.1 = part.t[part.len() - 1];
        self.plot(part, k)?;
        self.seen[k] += part.len() as u64;
        self.in_log[k] += part.len() as u64;
        Ok(())
    }

    /// Appends the samples of `part` (of kind `k`) that the plots keep, with their
    /// predictions: only those samples are assembled (each regressor is a function of
    /// its own sample, so their values are those of the whole part).
    fn plot(&mut self, part: &SampleChunk, k: usize) -> Result<(), Error> {
        let (ctx, stride) = (self.ctx, self.ctx.strides[k]);
        let seen = self.seen[k];
        let kept: Vec<usize> = (0..part.len())
            .filter(|&i| (seen + i as u64).is_multiple_of(stride))
            .collect();
        if kept.is_empty() {
            return Ok(());
        }
        let rows = &mut self.plot_rows;
        rows.clear();
        rows.extend_from_rows(part, &kept);
        ctx.req.structure.assemble(rows, &mut self.plot_ws)?;
        let predicted = ctx
            .req
            .structure
            .predict_assembled(ctx.theta, rows, &self.plot_ws);
        let series = &mut self.share.series[k];
        // Absolute time; [`LogPass::times_from_start`] makes it relative.
        series.t.extend_from_slice(&rows.t);
        for (a, y) in predicted.into_iter().enumerate() {
            series.measured[a].extend_from_slice(&rows.wrench[a]);
            series.predicted[a].extend(y);
        }
        Ok(())
    }
}

impl LogPass {
    /// The share of no samples.
    fn empty(ctx: &PassContext) -> Self {
        Self {
            residuals: ctx.residuals.clone(),
            series: Default::default(),
            span: [(f64::NAN, f64::NAN); 2],
            candidates: ctx.extended.as_ref().map(|e| {
                [
                    Accumulator::new(&e.structure),
                    Accumulator::new(&e.structure),
                ]
            }),
            local: ActivityParts::default(),
        }
    }

    /// Appends `later`, the share of the samples that directly follow this one's.
    fn append(&mut self, later: LogPass) -> Result<(), AccumulateError> {
        self.residuals.merge(&later.residuals);
        for (k, mut part) in later.series.into_iter().enumerate() {
            let series = &mut self.series[k];
            series.t.append(&mut part.t);
            for a in 0..6 {
                series.measured[a].append(&mut part.measured[a]);
                series.predicted[a].append(&mut part.predicted[a]);
            }
            let (span, (first, last)) = (&mut self.span[k], later.span[k]);
            if span.0.is_nan() {
                span.0 = first;
            }
            if !last.is_nan() {
                span.1 = last;
            }
        }
        if let (Some(mine), Some(theirs)) = (self.candidates.as_mut(), later.candidates) {
            for (a, b) in mine.iter_mut().zip(&theirs) {
                a.merge(b)?;
            }
        }
        self.local.merge(&later.local)?;
        Ok(())
    }

    /// Counts the plotted times from the log's first sample of their kind.
    fn times_from_start(&mut self) {
        for (series, span) in self.series.iter_mut().zip(self.span) {
            series.t.iter_mut().for_each(|t| *t -= span.0);
        }
    }
}

/// (1 + ρ)/(1 − ρ) for the largest lag-1 residual autocorrelation ρ over the axes (an
/// AR(1) effective-sample-size correction of parameter variances), held in [1, 100].
fn coloured_variance_inflation(d: &ResidualDiagnostics) -> f64 {
    let rho = d
        .axes
        .iter()
        .filter_map(|a| a.autocorrelation.get(1).copied())
        .filter(|r| r.is_finite())
        .fold(0.0_f64, f64::max)
        .min(0.98);
    ((1.0 + rho) / (1.0 - rho)).clamp(1.0, 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Segments cover the chunks in order, at most [`SEGMENT_CHUNKS`] each and equal to a
    /// chunk, in a multiple of [`SEGMENT_GROUP`] once there is more than one.
    #[test]
    fn segments_are_equal_to_a_chunk_and_a_multiple_of_six() {
        assert_eq!(segments(0), vec![0..0]);
        assert_eq!(segments(64), vec![0..64]);
        assert_eq!(
            segments(65),
            vec![0..11, 11..22, 22..33, 33..44, 44..55, 55..65]
        );
        for chunks in [65, 71, 384, 385, 977, 9766] {
            let cuts = segments(chunks);
            assert_eq!(cuts.len() % SEGMENT_GROUP, 0, "{chunks}");
            assert_eq!((cuts[0].start, cuts[cuts.len() - 1].end), (0, chunks));
            assert!(cuts.windows(2).all(|w| w[0].end == w[1].start));
            let lens: Vec<usize> = cuts.iter().map(|c| c.len()).collect();
            let (lo, hi) = (lens.iter().min().unwrap(), lens.iter().max().unwrap());
            assert!(hi - lo <= 1 && *hi <= SEGMENT_CHUNKS, "{chunks}: {lens:?}");
        }
        // The 1 M-sample sweep: 18 segments of 54–55 chunks, where 64-chunk segments left
        // a 17-chunk last one.
        assert_eq!(segments(977).len(), 18);
    }
}
