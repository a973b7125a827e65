//! What happened while reading a log: rows, samples, segments, drops, spikes, gaps,
//! dropouts, derivations, unit warnings and the inferred motor layout.

use std::collections::BTreeMap;

use super::layout::LayoutReport;

/// Gaps kept in [`Summary::gaps`]; later ones split the log all the same.
const MAX_GAPS: usize = 100;
/// Drop messages kept in [`Summary::first_dropped`].
const MAX_DROP_MESSAGES: usize = 10;

/// A time gap that split the log.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Gap {
    /// Last time before the gap, s.
    pub from: f64,
    /// First time after the gap, s.
    pub to: f64,
}

/// A logger dropout recorded in a log (ULog `O` message): data were lost; the reader
/// never interpolates across it and starts a new segment after it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dropout {
    /// Byte offset of the dropout message in the file.
    pub offset: u64,
    /// Latest mapped-topic time read before the dropout, s (−∞ before any).
    pub after: f64,
    /// Duration the logger reports, s.
    pub duration: f64,
}

/// What happened while reading a log; complete once the reader is exhausted.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// Warnings about implausible units, and about sampling too slow for the dynamics.
    pub unit_warnings: Vec<String>,
    /// Median step between the times of consecutive rows read, s (`None` with fewer
    /// than two, and for a log in memory): a sample interval, or a test point's spacing
    /// in a sweep.
    pub median_time_step: Option<f64>,
    /// Time from the first row read to the last, s (0 for a log in memory).
    pub span: f64,
    /// The time's unit is not suspected of being ms or µs however slow or long the clock
    /// looks: a mapping declared it, or t numbers the rows 0, 1, 2, … (a test-point
    /// sweep).
    #[serde(default)]
    pub time_unit_trusted: bool,
    /// Motor layout inferred from moments vs individual rotor speeds.
    pub layout: Option<LayoutReport>,
    /// The message the end of the file cut short, where the log was read up to (a
    /// message-based log closed by a power cut or a killed simulator; `None` when the file
    /// ends between messages).
    #[serde(default)]
    pub cut_off: Option<String>,
    /// What the airborne detection kept, when it left ground samples out (`None` when
    /// every sample was kept, and without [`super::ReadOptions::airborne_only`]).
    pub airborne: Option<AirborneSpan>,
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

    /// Records the gap from `from` to `to` (s) that split the log (the first 100 kept).
    pub(super) fn record_gap(&mut self, from: f64, to: f64) {
        if self.gaps.len() < MAX_GAPS {
            self.gaps.push(Gap { from, to });
        }
    }

    /// Counts a dropped sample under `reason`, keeping the first ten messages.
    pub(super) fn count_drop(&mut self, reason: &str, message: String) {
        *self.dropped.entry(reason.to_string()).or_default() += 1;
        if self.first_dropped.len() < MAX_DROP_MESSAGES {
            self.first_dropped.push(message);
        }
    }
}

/// What was kept of a log by the airborne detection.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct AirborneSpan {
    /// Flights: runs of airborne samples between ground time.
    pub flights: usize,
    /// Time airborne, s: the sum of the flights' spans (first to last kept sample).
    pub airborne_seconds: f64,
    /// Samples left out on the ground.
    pub ground_samples: u64,
    /// Highest rotor speed of the log, rad/s: the root mean square over the rotors of
    /// its fastest sample.
    pub peak_speed: f64,
    /// Rotor speed, rad/s, at which the rotors would carry the weight at the highest
    /// plausible thrust coefficient (φ = 1, every rotor alike).
    pub lift_speed: f64,
}

/// Where the end of a message-based log's file cut a message short: the log ends
/// there, and its summary says so ([`Summary::cut_off`]).
#[derive(Debug, Clone, Default)]
pub(super) struct CutOff(Option<String>);

impl CutOff {
    /// The note, once the reading reached the cut (`None` for a file that ends between
    /// messages).
    pub(super) fn note(&self) -> Option<&str> {
        self.0.as_deref()
    }

    /// Records that the file, `len` bytes long, ends inside `what` (a message or its
    /// header, `length` bytes long) starting at byte `start`.
    pub(super) fn record(&mut self, start: u64, what: &str, len: u64, length: u64) {
        let left = len - start;
        self.0 = Some(format!(
            "the file ends inside a {what} at byte {start} ({left} of its {length} bytes): \
             the log was cut off while being written (a power cut, a full card or a stopped \
             simulator); it was read up to that message"
        ));
    }
}
