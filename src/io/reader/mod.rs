//! [`LogReader`]: the stream of [`SampleChunk`]s of one log. A source gives raw samples
//! ([`RowSource`]); each is converted and checked ([`convert`]), enters the look-ahead
//! window of its segment ([`segment`]), and is emitted into the chunk once enough rows
//! follow it to differentiate and flag spikes ([`emit`]). Chunks hold at most
//! [`CHUNK_SAMPLES`] samples, each inside one segment unless segments are joined.

mod airborne;
mod convert;
mod emit;
mod plan;
mod segment;

use airborne::Detector;
pub(crate) use airborne::LEAVE_GROUND;
use convert::Converter;
use emit::Differentiator;
pub(crate) use plan::DIFFERENTIATED;
use plan::{Plan, VehicleFacts};
use segment::Window;

use super::error::{ErrorKind, IoError, Location};
use super::layout::LayoutAccumulator;
use super::mapping::{Mapping, Signal};
use super::options::ReadOptions;
use super::row_source::RowSource;
use super::slots::SlotLayout;
use super::summary::Summary;
use super::validate::{self, UnitStats};
use crate::sample::{CHUNK_SAMPLES, SampleChunk};
use crate::vehicle::Vehicle;

/// The summary of the log and the running statistics that complete it at the end.
struct Tally {
    summary: Summary,
    /// Regressions of the motor layout.
    layout: LayoutAccumulator,
    /// Unit plausibility statistics.
    unit_stats: UnitStats,
}

/// The chunk being filled, and how chunks are handed out.
struct Handout {
    chunk: SampleChunk,
    /// `chunk` was lent out by [`LogReader::next_chunk`]: cleared at the next step.
    lent: bool,
    /// No more chunks: the end was reached or an error was returned (the reader is
    /// fused, as the iterator contract asks).
    over: bool,
    /// Chunks run on across segment ends ([`LogReader::join_segments`]).
    join: bool,
    /// Segment of the chunk handed out last.
    last_segment: usize,
}

/// Streams a log as [`SampleChunk`]s; see [`super::open_log`].
pub struct LogReader {
    source: Box<dyn RowSource>,
    convert: Converter,
    vehicle: VehicleFacts,
    opts: ReadOptions,
    plan: Plan,
    window: Window,
    out: Handout,
    tally: Tally,
    diff: Differentiator,
    /// Leaves ground time out.
    air: Detector,
}

impl LogReader {
    /// Builds the reader over a resolved source; `topics` when the source names fields
    /// by topic (MCAP, ULog).
    pub(crate) fn new(
        source: Box<dyn RowSource>,
        layout: SlotLayout,
        mapping: &Mapping,
        vehicle: &Vehicle,
        opts: ReadOptions,
        file: &str,
        topics: bool,
    ) -> Self {
        let facts = VehicleFacts::of(vehicle);
        let plan = Plan::new(&layout, &opts.derive, &facts);
        let convert = Converter::new(layout, mapping, &facts, topics);
        let summary = Summary {
            file: file.to_string(),
            derived: plan.describe(&convert.layout, &opts.derive, convert.actuator.as_ref()),
            ..Summary::default()
        };
        let rotors = facts.rotors;
        let time_unit_declared = mapping.get(Signal::Time).is_some_and(|m| m.unit.is_some());
        let air = Detector::new(&facts, opts.airborne_only);
        let mut chunk = SampleChunk::with_capacity(rotors, CHUNK_SAMPLES, plan.has_omega_dot);
        prepare_optional(&mut chunk, &convert.layout);
        Self {
            source,
            convert,
            vehicle: facts,
            opts,
            plan,
            window: Window::default(),
            out: Handout {
                chunk,
                lent: false,
                over: false,
                join: false,
                last_segment: 0,
            },
            tally: Tally {
                summary,
                layout: LayoutAccumulator::new(rotors, plan.has_omega_dot),
                unit_stats: UnitStats::new(time_unit_declared),
            },
            diff: Differentiator::default(),
            air,
        }
    }

    /// From now on a chunk is handed out only when it holds [`CHUNK_SAMPLES`] samples, or
    /// at the end of the log: chunks run on across segment ends (gaps), so every chunk but
    /// the last is full, and [`LogReader::segment_index`] is the segment of a chunk's last
    /// sample. The samples and the summary are the same as without it; a log of short
    /// segments (a sweep's one-sample test points) then costs one chunk per
    /// [`CHUNK_SAMPLES`] samples instead of one per segment.
    pub fn join_segments(&mut self) {
        self.out.join = true;
    }

    /// Segment index (0-based) of the chunk returned last (of its last sample, when
    /// [`LogReader::join_segments`] was called).
    pub fn segment_index(&self) -> usize {
        self.out.last_segment
    }

    /// Bytes of the file read so far (compressed bytes of a compressed file), for
    /// progress: may run ahead of the samples returned, and end below the file's size
    /// when the reader skips parts of it (MCAP chunks of unmapped topics).
    pub fn bytes_read(&self) -> u64 {
        self.source.bytes_read()
    }

    /// The summary so far; complete once the iterator returned `None`.
    pub fn summary(&self) -> &Summary {
        &self.tally.summary
    }

    /// Hands `chunk` out by value, leaving an empty one with room for as many samples.
    fn take_chunk(&mut self) -> SampleChunk {
        // Room for as many samples as the chunk handed out: a full chunk's worth in a
        // long segment, little in a log of short segments (a sweep is one-sample
        // segments; reserving a full chunk per row cost a sixth of its read time).
        let room = self.out.chunk.len().clamp(16, CHUNK_SAMPLES);
        let mut next =
            SampleChunk::with_capacity(self.vehicle.rotors, room, self.plan.has_omega_dot);
        prepare_optional(&mut next, &self.convert.layout);
        std::mem::replace(&mut self.out.chunk, next)
    }

    /// The next chunk, lent until the next call: the same chunks as the iterator, with
    /// no allocation per chunk (a sweep's one-sample segments each make a chunk).
    /// `None` at the end; after an error, `None` too.
    pub fn next_chunk(&mut self) -> Option<Result<&SampleChunk, IoError>> {
        match self.advance()? {
            Ok(()) => Some(Ok(&self.out.chunk)),
            Err(e) => Some(Err(e)),
        }
    }

    /// [`LogReader::next_chunk`], lent mutably: the fit pipeline derives Ω̈ into it, or
    /// swaps it for an empty chunk of the same signals (taken from an earlier chunk).
    pub(crate) fn next_chunk_mut(&mut self) -> Option<Result<&mut SampleChunk, IoError>> {
        match self.advance()? {
            Ok(()) => Some(Ok(&mut self.out.chunk)),
            Err(e) => Some(Err(e)),
        }
    }

    /// Steps to the next chunk, left in `chunk`: `None` at the end or after an error.
    fn advance(&mut self) -> Option<Result<(), IoError>> {
        if self.out.over {
            return None;
        }
        if self.out.lent {
            self.out.chunk.clear();
            self.out.lent = false;
        }
        match self.step() {
            Ok(true) => {
                self.out.last_segment = self.window.segment;
                self.out.lent = true;
                Some(Ok(()))
            }
            Ok(false) => {
                self.out.over = true;
                None
            }
            Err(e) => {
                self.out.over = true;
                Some(Err(e))
            }
        }
    }

    /// Completes the summary at the end of the log; refuses rotor speeds whose blade
    /// tips would be supersonic (RPM logged as rad/s).
    fn finish_summary(&mut self) -> Result<(), IoError> {
        let t = &mut self.tally;
        t.summary.layout = t.layout.finish();
        t.summary.unit_warnings = t.unit_stats.warnings();
        t.summary.dropouts = self.source.dropouts().to_vec();
        t.summary.cut_off = self.source.cut_off().map(str::to_string);
        t.summary
            .unit_warnings
            .extend(self.source.slow_rotor_speeds());
        t.summary.median_time_step = t.unit_stats.median_time_step();
        t.summary.span = t.unit_stats.span();
        t.summary.time_unit_trusted = t.unit_stats.time_unit_trusted();
        let v = &self.vehicle;
        match t
            .unit_stats
            .rotor_speed_check(v.rotors, v.rotor_radius, v.mass, v.air_density)
        {
            Ok(note) => t.summary.unit_warnings.extend(note),
            Err(why) => {
                return Err(IoError::new(
                    &t.summary.file,
                    Location::File,
                    self.convert
                        .layout
                        .start(Signal::RotorSpeeds)
                        .and_then(|slot| self.convert.label(slot)),
                    ErrorKind::Mapping(why.to_string()),
                ));
            }
        }
        Ok(())
    }

    /// Fills `chunk` with the next chunk (true), or finds the end (false).
    fn step(&mut self) -> Result<bool, IoError> {
        loop {
            self.emit_ready();
            if self.out.chunk.len() == CHUNK_SAMPLES {
                return Ok(true);
            }
            let w = &mut self.window;
            if w.closed() && w.next_emit == w.rows.len() {
                // Segment complete: hand out its last partial chunk (unless chunks join
                // segments and another follows), then start the next.
                if !self.out.chunk.is_empty() && (!self.out.join || w.pending.is_none()) {
                    return Ok(true);
                }
                let summary = &mut self.tally.summary;
                if w.segment_samples > 0 {
                    summary.segments += 1;
                    w.segment_samples = 0;
                }
                w.segment = summary.segments;
                w.rows.clear();
                w.next_emit = 0;
                match w.pending.take() {
                    Some(row) => w.rows.push_back(row),
                    None => {
                        if summary.samples == 0 {
                            summary.median_time_step = self.tally.unit_stats.median_time_step();
                            summary.span = self.tally.unit_stats.span();
                            summary.time_unit_trusted = self.tally.unit_stats.time_unit_trusted();
                            return Err(validate::no_samples_error(
                                summary,
                                &self.opts,
                                self.convert.time_label(),
                            ));
                        }
                        self.finish_summary()?;
                        return Ok(false);
                    }
                }
                continue;
            }
            self.fill()?;
        }
    }
}

/// Makes `chunk` carry the optional signals (height, attitude) the log carries, with
/// room for a full chunk in each.
fn prepare_optional(chunk: &mut SampleChunk, layout: &SlotLayout) {
    let room = || Vec::with_capacity(CHUNK_SAMPLES);
    if layout.has(Signal::Height) {
        chunk.height = Some(room());
    }
    if layout.has(Signal::Attitude) {
        chunk.attitude = Some([room(), room(), room(), room()]);
    }
}

impl Iterator for LogReader {
    type Item = Result<SampleChunk, IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        match self.advance()? {
            Ok(()) => {
                self.out.lent = false;
                Some(Ok(self.take_chunk()))
            }
            Err(e) => Some(Err(e)),
        }
    }
}
