//! Log ingestion: contract and mapped CSV, MCAP (JSON and ROS 2 CDR) and PX4 ULog, turned
//! into the [`SampleChunk`] stream of the data contract (`docs/data-contract.md`),
//! streaming in
//! bounded memory.
//!
//! Pipeline per sample: a source (CSV row or time-aligned MCAP messages) fills the slot
//! layout of the mapping → values checked finite, converted to SI and FRD/NED, checked
//! against physical ranges → time checked strictly increasing; a gap longer than
//! [`ReadOptions::max_gap`] closes the segment (never bridged) → in a short look-ahead
//! window: spikes flagged, ω̇ and Ω̇ differentiated when not logged, F = m a and
//! M = I ω̇ + ω × I ω derived when not logged → chunks of at most
//! [`crate::CHUNK_SAMPLES`] samples, each inside one segment.

pub mod cdr;
pub mod contract_csv;
pub mod csv_input;
pub mod decimal;
pub mod derive;
pub mod error;
pub mod json_error;
pub mod layout;
pub mod mapping;
pub mod mcap_read;
pub mod mcap_write;
pub mod px4;
pub mod ros2msg;
pub mod slots;
pub mod ulog;
pub mod ulog_write;
pub mod units;
pub mod validate;

use std::collections::{BTreeMap, VecDeque};
use std::io::Read;
use std::path::Path;

pub use derive::DeriveOptions;
pub use error::{ErrorKind, IoError, Location};
pub use layout::LayoutReport;
pub use mapping::Mapping;

use derive::{SgWeights, body_velocity, euler_moment, matrix_to_quat, specific_force_at_cg};
use mapping::{AxisMap, Signal};
use slots::SlotLayout;
use validate::{
    QUATERNION_NORM_TOLERANCE, SPIKE_HALF_WINDOW, UnitStats, is_spike, physical_range, spike_floor,
};

use crate::sample::{CHUNK_SAMPLES, SampleChunk};
use crate::util::quat_to_matrix;
use crate::vehicle::Vehicle;

/// Largest rotor count the readers handle.
pub const MAX_ROTORS: usize = 16;

/// What to do with a sample whose values are invalid (not a number, not finite, out of
/// physical range, time not strictly increasing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InvalidSamples {
    /// Stop with an error naming file, line/record and field (default).
    #[default]
    Error,
    /// Drop the sample and count it per reason in the [`Summary`].
    DropAndCount,
}

/// Options of [`open_log`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReadOptions {
    /// Policy for invalid samples.
    pub invalid: InvalidSamples,
    /// Largest time step bridged inside a segment, s; a longer step starts a new segment.
    pub max_gap: f64,
    /// Derivation options (a mapping file's `[derive]` table overrides them).
    pub derive: DeriveOptions,
    /// Worker threads that tokenise and parse the byte ranges of a CSV file (0: parse on
    /// the reading thread). The values read do not depend on it. The `fit` pipeline sets
    /// it from its thread budget ([`crate::pipeline::FitRequest::threads`]) unless it is
    /// 0, which keeps parsing on the reading thread.
    pub parse_threads: usize,
    /// Size of the byte ranges a CSV file is cut into for parsing, bytes (a range is
    /// longer when one record is; values below 1 count as 1). The values read do not
    /// depend on it; memory holds a few ranges per parse thread.
    pub range_bytes: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            invalid: InvalidSamples::Error,
            max_gap: 0.1,
            derive: DeriveOptions::default(),
            parse_threads: 1,
            range_bytes: contract_csv::DEFAULT_RANGE_BYTES,
        }
    }
}

/// A time gap that split the log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gap {
    /// Last time before the gap, s.
    pub from: f64,
    /// First time after the gap, s.
    pub to: f64,
}

/// A logger dropout recorded in a log (ULog `O` message): data were lost; the reader
/// never interpolates across it and starts a new segment after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dropout {
    /// Byte offset of the dropout message in the file.
    pub offset: u64,
    /// Latest mapped-topic time read before the dropout, s (−∞ before any).
    pub after: f64,
    /// Duration the logger reports, s.
    pub duration: f64,
}

/// What happened while reading a log; complete once the reader is exhausted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Summary {
    /// File name.
    pub file: String,
    /// Rows (CSV) or aligned samples (MCAP, ULog) read from the file.
    pub rows_read: u64,
    /// Samples emitted in chunks.
    pub samples: u64,
    /// Segments emitted.
    pub segments: usize,
    /// Dropped samples per reason (drop-and-count policy, and samples of a segment too
    /// short to differentiate).
    pub dropped: BTreeMap<String, u64>,
    /// The first few drop messages, for the user to look at.
    pub first_dropped: Vec<String>,
    /// Samples flagged as spikes per signal (kept, not dropped).
    pub spikes: BTreeMap<String, u64>,
    /// Gaps that split the log (the first 100), dropouts included.
    pub gaps: Vec<Gap>,
    /// Logger dropouts the log records (ULog; the first 1000).
    pub dropouts: Vec<Dropout>,
    /// Which signals were derived and how.
    pub derived: Vec<String>,
    /// Warnings about implausible units.
    pub unit_warnings: Vec<String>,
    /// Median step between the times of consecutive rows read, s (`None` with fewer
    /// than two, and for a log in memory): a sample interval, or a test point's spacing
    /// in a sweep.
    pub median_time_step: Option<f64>,
    /// Time from the first row read to the last, s (0 for a log in memory).
    pub span: f64,
    /// Motor layout inferred from moments vs individual rotor speeds.
    pub layout: Option<LayoutReport>,
}

impl Summary {
    /// The summary of a log held in memory: `samples` samples, all kept, one segment.
    pub fn of_memory(name: &str, samples: u64) -> Self {
        Self {
            file: name.to_string(),
            rows_read: samples,
            samples,
            segments: usize::from(samples > 0),
            ..Self::default()
        }
    }
}

/// The source of raw samples in slot layout (CSV rows, aligned MCAP messages).
pub trait RowSource {
    /// File name for messages.
    fn file(&self) -> &str;
    /// Fills `raw` with the next sample's raw values (source units and axes); returns its
    /// location and, when the source supplies it outside the slots (MCAP log time, or
    /// the aligned base time), its time in seconds; `None` at end of file. After a
    /// sample-level error the source is ready for the next sample.
    fn next_row(&mut self, raw: &mut [f64]) -> Result<Option<(Location, Option<f64>)>, IoError>;
    /// True (once) when the sample returned last follows a logger dropout and must start
    /// a new segment whatever the time step.
    fn take_segment_break(&mut self) -> bool {
        false
    }
    /// Logger dropouts read so far.
    fn dropouts(&self) -> &[Dropout] {
        &[]
    }
}

/// One converted sample (SI, FRD/NED) inside the look-ahead window.
#[derive(Debug, Clone, Copy)]
struct Row {
    loc: Location,
    t: f64,
    velocity: [f64; 3],
    rates: [f64; 3],
    ang_acc: [f64; 3],
    omega: [f64; MAX_ROTORS],
    omega_dot: [f64; MAX_ROTORS],
    /// Commanded rotor speeds (actuator map), before the motor lag.
    command: [f64; MAX_ROTORS],
    force: [f64; 3],
    moment: [f64; 3],
    specific_force: [f64; 3],
    height: f64,
    attitude: [f64; 4],
}

impl Default for Row {
    fn default() -> Self {
        Self {
            loc: Location::File,
            t: 0.0,
            velocity: [0.0; 3],
            rates: [0.0; 3],
            ang_acc: [0.0; 3],
            omega: [0.0; MAX_ROTORS],
            omega_dot: [0.0; MAX_ROTORS],
            command: [0.0; MAX_ROTORS],
            force: [0.0; 3],
            moment: [0.0; 3],
            specific_force: [0.0; 3],
            height: 0.0,
            attitude: [1.0, 0.0, 0.0, 0.0],
        }
    }
}

/// Vehicle facts used by derivations and checks.
#[derive(Debug, Clone)]
struct VehicleFacts {
    rotors: usize,
    mass: f64,
    inertia: [[f64; 3]; 3],
    rotor_inertia: f64,
    arm: f64,
    rotor_radius: f64,
    air_density: f64,
}

/// How each output signal is obtained.
#[derive(Debug, Clone, Copy)]
struct Plan {
    /// ω̇ from a smoothing derivative of the rates (no logged ω̇ and needed).
    diff_rates: bool,
    /// Ω̇ from a smoothing derivative of Ω (not logged, J_z > 0).
    diff_omega: bool,
    /// Ω̇ emitted at all.
    has_omega_dot: bool,
    /// Look-ahead needed before a sample can be emitted.
    lookahead: usize,
}

/// Streams a log as [`SampleChunk`]s; see [`open_log`].
pub struct LogReader {
    source: Box<dyn RowSource>,
    layout: SlotLayout,
    body: AxisMap,
    world: AxisMap,
    vehicle: VehicleFacts,
    opts: ReadOptions,
    plan: Plan,
    ranges: Vec<Option<(f64, f64, String)>>,
    raw: Vec<f64>,
    window: VecDeque<Row>,
    next_emit: usize,
    pending: Option<Row>,
    segment: usize,
    segment_samples: u64,
    last_segment: usize,
    done: bool,
    /// No more chunks: the end was reached or an error was returned (the reader is
    /// fused, as the iterator contract asks).
    over: bool,
    chunk: SampleChunk,
    /// `chunk` was lent out by [`LogReader::next_chunk`]: cleared at the next step.
    lent: bool,
    summary: Summary,
    layout_acc: layout::LayoutAccumulator,
    unit_stats: UnitStats,
    times: Vec<f64>,
    weights: SgWeights,
    is_mcap: bool,
    actuator: Option<mapping::ActuatorMap>,
    /// Chunks run on across segment ends ([`LogReader::join_segments`]).
    join: bool,
}

/// Opens a CSV (contract or mapped), MCAP or ULog log for streaming; the format is
/// chosen by the MCAP or ULog magic bytes. `mapping` is required for MCAP and ULog and
/// for CSV files that do not follow the contract.
pub fn open_log(
    path: &Path,
    vehicle: &Vehicle,
    mapping: Option<&Mapping>,
    options: &ReadOptions,
) -> Result<LogReader, IoError> {
    let file = error::display_name(path);
    let rotors = vehicle.rotor_count();
    if rotors > MAX_ROTORS {
        return Err(IoError::new(
            &file,
            Location::File,
            None,
            ErrorKind::Mapping(format!(
                "vehicle has {rotors} rotors, at most {MAX_ROTORS} supported"
            )),
        ));
    }
    let mut opts = *options;
    if let Some(d) = mapping.and_then(|m| m.derive) {
        opts.derive = d;
    }
    opts.derive.check().map_err(|m| {
        IoError::new(
            &file,
            Location::File,
            error::key("derive"),
            ErrorKind::Mapping(m),
        )
    })?;
    if opts.max_gap.is_nan() || opts.max_gap <= 0.0 {
        return Err(IoError::new(
            &file,
            Location::File,
            None,
            ErrorKind::Mapping(format!("max_gap = {} s must be positive", opts.max_gap)),
        ));
    }
    let magic = sniff(path)
        .map_err(|e| IoError::new(&file, Location::File, None, ErrorKind::Read(e.to_string())))?;
    if magic != Magic::Csv {
        let what = if magic == Magic::Mcap {
            "an MCAP"
        } else {
            "a ULog"
        };
        let mapping = mapping.ok_or_else(|| {
            IoError::new(
                &file,
                Location::File,
                None,
                ErrorKind::Mapping(format!(
                    "{what} log needs a mapping file naming topics and fields"
                )),
            )
        })?;
        let align_gap = mapping.mcap.align_gap.unwrap_or(opts.max_gap);
        if align_gap.is_nan() || align_gap <= 0.0 {
            return Err(IoError::new(
                &file,
                Location::File,
                error::key("mcap.align_gap"),
                ErrorKind::Mapping(format!("align_gap = {align_gap} s must be positive")),
            ));
        }
        let (source, layout): (Box<dyn RowSource>, _) = if magic == Magic::Mcap {
            let (s, l) = mcap_read::McapSource::open(path, &file, mapping, rotors, align_gap)?;
            (Box::new(s), l)
        } else {
            let (s, l) = ulog::UlogSource::open(path, &file, mapping, rotors, align_gap)?;
            (Box::new(s), l)
        };
        return Ok(LogReader::new(
            source, layout, mapping, vehicle, opts, &file, true,
        ));
    }
    let (source, resolved, layout) = contract_csv::CsvSource::open(
        path,
        &file,
        mapping,
        rotors,
        opts.parse_threads,
        opts.range_bytes,
    )?;
    Ok(LogReader::new(
        Box::new(source),
        layout,
        &resolved,
        vehicle,
        opts,
        &file,
        false,
    ))
}

/// A log's format, from its first bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Magic {
    Csv,
    Mcap,
    Ulog,
}

/// The format of the file by its magic bytes (MCAP, ULog), else CSV; a `.ulg` file is
/// ULog whatever its first bytes (so a corrupt one is told so).
fn sniff(path: &Path) -> std::io::Result<Magic> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ulg"))
    {
        return Ok(Magic::Ulog);
    }
    let mut magic = [0u8; 8];
    let mut f = std::fs::File::open(path)?;
    let mut n = 0;
    while n < 8 {
        let k = f.read(&mut magic[n..])?;
        if k == 0 {
            break;
        }
        n += k;
    }
    Ok(if n >= 5 && &magic[..5] == b"\x89MCAP" {
        Magic::Mcap
    } else if n >= 7 && magic[..7] == ulog::MAGIC {
        Magic::Ulog
    } else {
        Magic::Csv
    })
}

impl LogReader {
    /// Builds the reader over a resolved source.
    pub fn new(
        source: Box<dyn RowSource>,
        layout: SlotLayout,
        mapping: &Mapping,
        vehicle: &Vehicle,
        opts: ReadOptions,
        file: &str,
        is_mcap: bool,
    ) -> Self {
        let facts = VehicleFacts {
            rotors: vehicle.rotor_count(),
            mass: vehicle.props.mass,
            inertia: vehicle.props.inertia,
            rotor_inertia: vehicle.props.rotor_inertia,
            arm: vehicle.arm_length(),
            rotor_radius: vehicle.props.rotor_radius,
            air_density: vehicle.props.air_density,
        };
        let needs_ang_acc = !layout.has(Signal::Moment) || opts.derive.imu_lever_arm.is_some();
        let diff_rates = needs_ang_acc && !layout.has(Signal::AngularAcceleration);
        let diff_omega = !layout.has(Signal::RotorAccelerations) && facts.rotor_inertia > 0.0;
        let half = opts.derive.sg_window / 2;
        let plan = Plan {
            diff_rates,
            diff_omega,
            has_omega_dot: layout.has(Signal::RotorAccelerations) || diff_omega,
            lookahead: if diff_rates || diff_omega {
                half.max(SPIKE_HALF_WINDOW)
            } else {
                SPIKE_HALF_WINDOW
            },
        };
        let mut summary = Summary {
            file: file.to_string(),
            ..Summary::default()
        };
        let sg = format!(
            "Savitzky-Golay derivative (window {}, order {})",
            opts.derive.sg_window, opts.derive.sg_order
        );
        if diff_rates {
            summary
                .derived
                .push(format!("angular acceleration from body rates by {sg}"));
        }
        if diff_omega {
            summary
                .derived
                .push(format!("rotor accelerations from rotor speeds by {sg}"));
        }
        if !layout.has(Signal::Moment) {
            summary.derived.push("moment M = I w_dot + w x I w".into());
        }
        if !layout.has(Signal::Force) {
            summary.derived.push(match opts.derive.imu_lever_arm {
                Some(r) => {
                    format!("force F = m a, accelerometer carried to the CG from lever arm {r:?} m")
                }
                None => "force F = m a from the accelerometer".into(),
            });
        }
        let actuator = mapping
            .get(Signal::RotorSpeeds)
            .and_then(|m| m.actuator)
            .filter(|_| layout.has(Signal::RotorSpeeds));
        if let Some(a) = &actuator {
            summary.derived.push(a.describe());
        }
        if !layout.has(Signal::VelocityBody) {
            summary
                .derived
                .push("body velocity from world velocity and attitude".into());
        }
        let ranges = (0..layout.len())
            .map(|s| physical_range(layout.signal_of_slot(s), facts.mass, facts.arm))
            .collect();
        let rotors = facts.rotors;
        let mut chunk = SampleChunk::with_capacity(rotors, CHUNK_SAMPLES, plan.has_omega_dot);
        prepare_optional(&mut chunk, &layout);
        Self {
            source,
            raw: vec![0.0; layout.len()],
            body: mapping.frames.body.to_frd(),
            world: mapping.frames.world.to_ned(),
            layout,
            vehicle: facts,
            opts,
            plan,
            ranges,
            window: VecDeque::new(),
            next_emit: 0,
            pending: None,
            segment: 0,
            segment_samples: 0,
            last_segment: 0,
            done: false,
            over: false,
            chunk,
            lent: false,
            summary,
            layout_acc: layout::LayoutAccumulator::new(rotors, plan.has_omega_dot),
            unit_stats: UnitStats::default(),
            times: Vec::new(),
            weights: SgWeights::default(),
            is_mcap,
            actuator,
            join: false,
        }
    }

    /// From now on a chunk is handed out only when it holds [`CHUNK_SAMPLES`] samples, or
    /// at the end of the log: chunks run on across segment ends (gaps), so every chunk but
    /// the last is full, and [`LogReader::segment_index`] is the segment of a chunk's last
    /// sample. The samples and the summary are the same as without it; a log of short
    /// segments (a sweep's one-sample test points) then costs one chunk per
    /// [`CHUNK_SAMPLES`] samples instead of one per segment.
    pub fn join_segments(&mut self) {
        self.join = true;
    }

    /// Segment index (0-based) of the chunk returned last (of its last sample, when
    /// [`LogReader::join_segments`] was called).
    pub fn segment_index(&self) -> usize {
        self.last_segment
    }

    /// The summary so far; complete once the iterator returned `None`.
    pub fn summary(&self) -> &Summary {
        &self.summary
    }

    fn label(&self, slot: usize) -> Option<String> {
        let name = self.layout.source_name(slot);
        if self.is_mcap {
            error::field(&format!(
                "{}.{}",
                self.layout.topic(slot).unwrap_or(""),
                name
            ))
        } else {
            error::column(name)
        }
    }

    /// Reads, converts and checks the next sample into `row`; `Ok(false)` at end of file.
    fn pull(&mut self, row: &mut Row) -> Result<bool, IoError> {
        let Some((loc, source_time)) = self.source.next_row(&mut self.raw)? else {
            return Ok(false);
        };
        self.summary.rows_read += 1;
        if let (Some(a), Some(start)) = (&self.actuator, self.layout.start(Signal::RotorSpeeds)) {
            for v in &mut self.raw[start..start + self.vehicle.rotors] {
                if v.is_finite() {
                    *v = a.speed(*v);
                }
            }
        }
        let file = self.summary.file.as_str();
        for slot in 0..self.raw.len() {
            let v = self.raw[slot] * self.layout.factor(slot);
            if !v.is_finite() {
                return Err(IoError::new(
                    file,
                    loc,
                    self.label(slot),
                    ErrorKind::NotFinite(self.raw[slot]),
                ));
            }
            self.raw[slot] = v;
            if let Some((lo, hi, text)) = &self.ranges[slot]
                && !(*lo..=*hi).contains(&v)
            {
                return Err(IoError::new(
                    file,
                    loc,
                    self.label(slot),
                    ErrorKind::OutOfRange {
                        value: v,
                        range: text.clone(),
                    },
                ));
            }
        }
        *row = Row {
            loc,
            t: source_time.unwrap_or(0.0),
            ..Row::default()
        };
        self.convert(row)
            .map_err(|(slot, kind)| IoError::new(file, loc, self.label(slot), kind))?;
        self.unit_stats.time(row.t);
        Ok(true)
    }

    /// Slot values (already SI) → row in FRD/NED.
    fn convert(&self, row: &mut Row) -> Result<(), (usize, ErrorKind)> {
        let l = &self.layout;
        let raw = &self.raw;
        let vec3 = |s: Signal| l.start(s).map(|i| [raw[i], raw[i + 1], raw[i + 2]]);
        row.t = match l.start(Signal::Time) {
            Some(i) => raw[i],
            None => row.t,
        };
        if let Some(i) = l.start(Signal::Attitude) {
            let q = [raw[i], raw[i + 1], raw[i + 2], raw[i + 3]];
            let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
                return Err((
                    i,
                    ErrorKind::OutOfRange {
                        value: norm,
                        range: format!(
                            "1 ± {QUATERNION_NORM_TOLERANCE} (norm of the attitude quaternion)"
                        ),
                    },
                ));
            }
            row.attitude = self.attitude_to_ned(q);
        }
        if let Some(v) = vec3(Signal::VelocityBody) {
            row.velocity = self.body.apply(v);
        } else if let Some(v) = vec3(Signal::VelocityWorld) {
            row.velocity = body_velocity(row.attitude, self.world.apply(v));
        }
        let body = |s: Signal, dst: &mut [f64; 3]| {
            if let Some(v) = vec3(s) {
                *dst = self.body.apply(v);
            }
        };
        body(Signal::Rates, &mut row.rates);
        body(Signal::AngularAcceleration, &mut row.ang_acc);
        body(Signal::Force, &mut row.force);
        body(Signal::Moment, &mut row.moment);
        body(Signal::SpecificForce, &mut row.specific_force);
        let n = self.vehicle.rotors;
        if let Some(i) = l.start(Signal::RotorSpeeds) {
            row.omega[..n].copy_from_slice(&raw[i..i + n]);
            row.command = row.omega;
        }
        if let Some(i) = l.start(Signal::RotorAccelerations) {
            row.omega_dot[..n].copy_from_slice(&raw[i..i + n]);
        }
        if let Some(i) = l.start(Signal::Height) {
            row.height = raw[i];
        }
        Ok(())
    }

    /// Attitude body→world of the log → body FRD → world NED: R' = W R Bᵀ.
    fn attitude_to_ned(&self, q: [f64; 4]) -> [f64; 4] {
        let identity = AxisMap {
            perm: [0, 1, 2],
            sign: [1.0; 3],
        };
        if self.body == identity && self.world == identity {
            return if q[0] < 0.0 { q.map(|c| -c) } else { q };
        }
        let r = quat_to_matrix(q);
        let w = self.world.matrix();
        let b = self.body.matrix();
        let mut out = [[0.0; 3]; 3];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                let mut s = 0.0;
                for k in 0..3 {
                    for m in 0..3 {
                        s += w[i][k] * r[k][m] * b[j][m];
                    }
                }
                *v = s;
            }
        }
        matrix_to_quat(&out)
    }

    fn drop_or_fail(&mut self, e: IoError) -> Result<(), IoError> {
        let always_dropped = matches!(e.kind, ErrorKind::NotAligned(_));
        if always_dropped
            || (self.opts.invalid == InvalidSamples::DropAndCount && e.is_sample_level())
        {
            self.count_drop(e.reason(), e.to_string());
            Ok(())
        } else {
            Err(e)
        }
    }

    fn count_drop(&mut self, reason: &str, message: String) {
        *self.summary.dropped.entry(reason.to_string()).or_default() += 1;
        if self.summary.first_dropped.len() < 10 {
            self.summary.first_dropped.push(message);
        }
    }

    /// Gets the next row that continues the current segment into the window, or marks
    /// the segment end (gap or end of file). Returns false when nothing more can come.
    fn fill(&mut self) -> Result<(), IoError> {
        let mut row = Row::default();
        loop {
            match self.pull(&mut row) {
                Ok(true) => {}
                Ok(false) => {
                    self.done = true;
                    return Ok(());
                }
                Err(e) => {
                    self.drop_or_fail(e)?;
                    continue;
                }
            }
            let forced = self.source.take_segment_break();
            if let Some(last) = self.window.back() {
                if forced && row.t > last.t {
                    if self.summary.gaps.len() < 100 {
                        self.summary.gaps.push(Gap {
                            from: last.t,
                            to: row.t,
                        });
                    }
                    self.pending = Some(row);
                    return Ok(());
                }
                if row.t <= last.t {
                    let e = IoError::new(
                        &self.summary.file,
                        row.loc,
                        self.time_label(),
                        ErrorKind::Time {
                            t: row.t,
                            previous: last.t,
                        },
                    );
                    self.drop_or_fail(e)?;
                    continue;
                }
                if row.t - last.t > self.opts.max_gap {
                    if self.summary.gaps.len() < 100 {
                        self.summary.gaps.push(Gap {
                            from: last.t,
                            to: row.t,
                        });
                    }
                    self.pending = Some(row);
                    return Ok(());
                }
            }
            if let (Some(tau), Some(last)) = (
                self.actuator.and_then(|a| a.time_constant),
                self.window.back(),
            ) {
                // Ω̇ = (c − Ω)/τ solved exactly for a command c linear over the step (as the
                // aligned command is): Ω = c − ċτ + (Ω_prev − c_prev + ċτ) e^(−Δt/τ).
                let h = row.t - last.t;
                let decay = crate::util::exp(-h / tau);
                let n = self.vehicle.rotors;
                let previous = last.omega[..n].iter().zip(&last.command[..n]);
                let now = row.omega[..n].iter_mut().zip(&row.command[..n]);
                for ((w, &c), (&w_prev, &c_prev)) in now.zip(previous) {
                    let lag = (c - c_prev) / h * tau;
                    *w = c - lag + (w_prev - c_prev + lag) * decay;
                }
            }
            self.window.push_back(row);
            return Ok(());
        }
    }

    fn time_label(&self) -> Option<String> {
        match self.layout.start(Signal::Time) {
            Some(slot) => self.label(slot),
            None => error::field("log time"),
        }
    }

    /// True when the segment is closed (gap seen or end of file).
    fn segment_closed(&self) -> bool {
        self.done || self.pending.is_some()
    }

    /// Emits the sample at window index `k` into the chunk.
    fn emit(&mut self, k: usize) {
        let n = self.vehicle.rotors;
        let Some((ang_acc, omega_dot)) = self.derivatives(k) else {
            return;
        };
        self.flag_spikes(k);
        // Borrowed, not copied: a row is some 600 bytes, most of them unused here.
        let row = &self.window[k];
        let force = if self.layout.has(Signal::Force) {
            row.force
        } else {
            let a = match self.opts.derive.imu_lever_arm {
                Some(r) => specific_force_at_cg(row.specific_force, r, row.rates, ang_acc),
                None => row.specific_force,
            };
            a.map(|c| self.vehicle.mass * c)
        };
        let moment = if self.layout.has(Signal::Moment) {
            row.moment
        } else {
            euler_moment(&self.vehicle.inertia, row.rates, ang_acc)
        };
        let wrench = [
            force[0], force[1], force[2], moment[0], moment[1], moment[2],
        ];
        let c = &mut self.chunk;
        c.t.push(row.t);
        for a in 0..3 {
            c.velocity[a].push(row.velocity[a]);
            c.rates[a].push(row.rates[a]);
        }
        for i in 0..n {
            c.omega[i].push(row.omega[i]);
        }
        for (i, v) in c.omega_dot.iter_mut().enumerate() {
            v.push(omega_dot[i]);
        }
        for (dst, v) in c.wrench.iter_mut().zip(wrench) {
            dst.push(v);
        }
        if self.layout.has(Signal::Height) {
            c.height.push(row.height);
        }
        if self.layout.has(Signal::Attitude) {
            for a in 0..4 {
                c.attitude[a].push(row.attitude[a]);
            }
        }
        self.layout_acc
            .push(&row.omega[..n], &omega_dot[..n], &wrench);
        self.unit_stats
            .push(force, self.vehicle.mass, row.rates, &row.omega[..n]);
        self.summary.samples += 1;
        self.segment_samples += 1;
    }

    /// Angular and rotor accelerations of the sample at window index `k`: logged, or
    /// differentiated over the window as the plan says. `None` (the sample dropped and
    /// counted) when the segment is too short to differentiate.
    fn derivatives(&mut self, k: usize) -> Option<([f64; 3], [f64; MAX_ROTORS])> {
        let row = &self.window[k];
        let (mut ang_acc, mut omega_dot) = (row.ang_acc, row.omega_dot);
        if !self.plan.diff_rates && !self.plan.diff_omega {
            return Some((ang_acc, omega_dot));
        }
        let n = self.vehicle.rotors;
        let d = self.opts.derive;
        let len = self.window.len();
        let w = d.sg_window.min(len);
        let lo = k.saturating_sub(d.sg_window / 2).min(len - w);
        self.times.clear();
        self.times
            .extend(self.window.range(lo..lo + w).map(|r| r.t));
        let Some(wts) = self.weights.get(&self.times, k - lo, d.sg_order) else {
            let msg = format!(
                "{}: {}: segment of {len} samples is too short to differentiate (sg_order {})",
                self.summary.file,
                loc_text(self.window[k].loc),
                d.sg_order
            );
            self.count_drop("segment too short to differentiate", msg);
            return None;
        };
        let win = self.window.range(lo..lo + w);
        if self.plan.diff_rates {
            ang_acc = [0.0; 3];
            for (wt, r) in wts.iter().zip(win.clone()) {
                for (acc, rate) in ang_acc.iter_mut().zip(r.rates) {
                    *acc += wt * rate;
                }
            }
        }
        if self.plan.diff_omega {
            omega_dot = [0.0; MAX_ROTORS];
            for (wt, r) in wts.iter().zip(win) {
                for (acc, w) in omega_dot[..n].iter_mut().zip(&r.omega[..n]) {
                    *acc += wt * w;
                }
            }
        }
        Some((ang_acc, omega_dot))
    }

    /// Hampel test of rates, rotor speeds and force source at window index `k`.
    fn flag_spikes(&mut self, k: usize) {
        let len = self.window.len();
        if len < 2 * SPIKE_HALF_WINDOW + 1 {
            return;
        }
        let lo = k
            .saturating_sub(SPIKE_HALF_WINDOW)
            .min(len - 2 * SPIKE_HALF_WINDOW - 1);
        if lo + SPIKE_HALF_WINDOW != k {
            return; // one-sided windows at segment ends are not tested
        }
        let force_signal = if self.layout.has(Signal::Force) {
            Signal::Force
        } else {
            Signal::SpecificForce
        };
        let groups: [(Signal, usize); 3] = [
            (Signal::Rates, 3),
            (Signal::RotorSpeeds, self.vehicle.rotors),
            (force_signal, 3),
        ];
        const WIDTH: usize = 2 * SPIKE_HALF_WINDOW + 1;
        for (signal, count) in groups {
            let floor = spike_floor(signal);
            let value = |r: &Row, comp: usize| match signal {
                Signal::Rates => r.rates[comp],
                Signal::RotorSpeeds => r.omega[comp],
                Signal::Force => r.force[comp],
                _ => r.specific_force[comp],
            };
            let mut spiked = false;
            for comp in 0..count {
                // The neighbourhood, read once into a stack array for both tests.
                let mut window = [0.0; WIDTH];
                for (v, r) in window.iter_mut().zip(self.window.range(lo..lo + WIDTH)) {
                    *v = value(r, comp);
                }
                // Exact pre-test: the median is a window value, so a centre within
                // `floor` of every neighbour cannot depart from it by more than `floor`.
                let x = window[SPIKE_HALF_WINDOW];
                if window.iter().all(|v| (v - x).abs() <= floor) {
                    continue;
                }
                spiked |= is_spike(&mut window, floor);
            }
            if spiked {
                *self
                    .summary
                    .spikes
                    .entry(signal.key().to_string())
                    .or_default() += 1;
            }
        }
    }

    /// Emits every sample that has enough look-ahead (all, once the segment closed),
    /// stopping when the chunk is full. Trims the window behind.
    fn emit_ready(&mut self) {
        let keep_behind = self.plan.lookahead.max(self.opts.derive.sg_window);
        while self.chunk.len() < CHUNK_SAMPLES && self.next_emit < self.window.len() {
            let ready =
                self.segment_closed() || self.next_emit + self.plan.lookahead < self.window.len();
            if !ready {
                break;
            }
            self.emit(self.next_emit);
            self.next_emit += 1;
            if self.next_emit > keep_behind && !self.segment_closed() {
                self.window.pop_front();
                self.next_emit -= 1;
            }
        }
    }

    /// Hands `chunk` out by value, leaving an empty one with room for as many samples.
    fn take_chunk(&mut self) -> SampleChunk {
        // Room for as many samples as the chunk handed out: a full chunk's worth in a
        // long segment, little in a log of short segments (a sweep is one-sample
        // segments; reserving a full chunk per row cost a sixth of its read time).
        let room = self.chunk.len().clamp(16, CHUNK_SAMPLES);
        let mut next =
            SampleChunk::with_capacity(self.vehicle.rotors, room, self.plan.has_omega_dot);
        prepare_optional(&mut next, &self.layout);
        std::mem::replace(&mut self.chunk, next)
    }

    /// The next chunk, lent until the next call: the same chunks as the iterator, with
    /// no allocation per chunk (a sweep's one-sample segments each make a chunk).
    /// `None` at the end; after an error, `None` too.
    pub fn next_chunk(&mut self) -> Option<Result<&SampleChunk, IoError>> {
        match self.advance()? {
            Ok(()) => Some(Ok(&self.chunk)),
            Err(e) => Some(Err(e)),
        }
    }

    /// [`LogReader::next_chunk`], lent mutably: the fit pipeline derives Ω̈ into it, or
    /// swaps it for an empty chunk of the same signals (taken from an earlier chunk).
    pub(crate) fn next_chunk_mut(&mut self) -> Option<Result<&mut SampleChunk, IoError>> {
        match self.advance()? {
            Ok(()) => Some(Ok(&mut self.chunk)),
            Err(e) => Some(Err(e)),
        }
    }

    /// Steps to the next chunk, left in `chunk`: `None` at the end or after an error.
    fn advance(&mut self) -> Option<Result<(), IoError>> {
        if self.over {
            return None;
        }
        if self.lent {
            self.chunk.clear();
            self.lent = false;
        }
        match self.step() {
            Ok(true) => {
                self.last_segment = self.segment;
                self.lent = true;
                Some(Ok(()))
            }
            Ok(false) => {
                self.over = true;
                None
            }
            Err(e) => {
                self.over = true;
                Some(Err(e))
            }
        }
    }

    /// Completes the summary at the end of the log; refuses rotor speeds whose blade
    /// tips would be supersonic (RPM logged as rad/s).
    fn finish_summary(&mut self) -> Result<(), IoError> {
        self.summary.layout = self.layout_acc.finish();
        self.summary.unit_warnings = self.unit_stats.warnings();
        self.summary.dropouts = self.source.dropouts().to_vec();
        self.summary.median_time_step = self.unit_stats.median_time_step();
        self.summary.span = self.unit_stats.span();
        let v = &self.vehicle;
        match self
            .unit_stats
            .rotor_speed_check(v.rotors, v.rotor_radius, v.mass, v.air_density)
        {
            Ok(note) => self.summary.unit_warnings.extend(note),
            Err(why) => {
                return Err(IoError::new(
                    &self.summary.file,
                    Location::File,
                    self.layout
                        .start(Signal::RotorSpeeds)
                        .and_then(|slot| self.label(slot)),
                    ErrorKind::Mapping(why),
                ));
            }
        }
        Ok(())
    }

    /// Fills `chunk` with the next chunk (true), or finds the end (false).
    fn step(&mut self) -> Result<bool, IoError> {
        loop {
            self.emit_ready();
            if self.chunk.len() == CHUNK_SAMPLES {
                return Ok(true);
            }
            if self.segment_closed() && self.next_emit == self.window.len() {
                // Segment complete: hand out its last partial chunk (unless chunks join
                // segments and another follows), then start the next.
                if !self.chunk.is_empty() && (!self.join || self.pending.is_none()) {
                    return Ok(true);
                }
                if self.segment_samples > 0 {
                    self.summary.segments += 1;
                    self.segment_samples = 0;
                }
                self.segment = self.summary.segments;
                self.window.clear();
                self.next_emit = 0;
                match self.pending.take() {
                    Some(row) => self.window.push_back(row),
                    None => {
                        if self.summary.samples == 0 {
                            self.summary.median_time_step = self.unit_stats.median_time_step();
                            self.summary.span = self.unit_stats.span();
                            return Err(validate::no_samples_error(
                                &self.summary,
                                &self.opts,
                                self.time_label(),
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

fn loc_text(loc: Location) -> String {
    match loc {
        Location::File => "file".into(),
        Location::Line(n) => format!("line {n}"),
        Location::Record(n) => format!("message {n}"),
        Location::Offset(n) => format!("byte {n}"),
        Location::Sample(n) => format!("sample {n}"),
    }
}

/// Gives the optional vectors (height, attitude) capacity when the log carries them.
fn prepare_optional(chunk: &mut SampleChunk, layout: &SlotLayout) {
    if layout.has(Signal::Height) {
        chunk.height.reserve(CHUNK_SAMPLES);
    }
    if layout.has(Signal::Attitude) {
        chunk
            .attitude
            .iter_mut()
            .for_each(|v| v.reserve(CHUNK_SAMPLES));
    }
}

impl Iterator for LogReader {
    type Item = Result<SampleChunk, IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        match self.advance()? {
            Ok(()) => {
                self.lent = false;
                Some(Ok(self.take_chunk()))
            }
            Err(e) => Some(Err(e)),
        }
    }
}
