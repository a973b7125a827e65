//! Ingestion errors: every error names the file, the line or record, and the field, in
//! words a user can act on, e.g. `flight.csv: line 502, column "u": not a finite number
//! (NaN)`. The Display text is part of the API and asserted in `tests/io_malformed.rs`.

use std::fmt;
use std::path::Path;

/// Where in a file an error sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (e.g. it cannot be opened, or it holds no sample).
    File,
    /// A 1-based text line of a CSV or TOML file.
    Line(u64),
    /// A 0-based message index of an MCAP file, in the order read (log-time order
    /// through the chunk indexes when the file has them, else file order).
    Record(u64),
    /// A 0-based byte offset of a binary file (ULog: the start of a message).
    Offset(u64),
    /// A 0-based sample index of a log held in memory ([`crate::source::MemoryLog`]).
    Sample(u64),
}

/// An ingestion error: file, location, optional field, and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct IoError {
    /// File name as given by the user (display form).
    pub file: String,
    /// Line or record.
    pub location: Location,
    /// The field concerned, when one is, already labelled: `column "u"` (CSV),
    /// `field "/imu.angular_velocity.x"` (MCAP), `key "signals.rates"` (TOML).
    pub field: Option<String>,
    /// What is wrong.
    pub kind: ErrorKind,
}

/// What is wrong, independent of where.
#[derive(Debug, Clone, PartialEq)]
pub enum ErrorKind {
    /// The file cannot be read (operating-system message).
    Read(String),
    /// The file holds no data row / message.
    Empty,
    /// Malformed structure: CSV row width, header, MCAP record, TOML syntax…
    Format(String),
    /// A required signal is absent; the text says which alternatives exist.
    MissingSignal(String),
    /// A field is not a number.
    NotANumber(String),
    /// A field is NaN or infinite.
    NotFinite(f64),
    /// A value is outside its physical range.
    OutOfRange {
        /// Value in SI units after conversion.
        value: f64,
        /// The admissible range, in words with units.
        range: String,
    },
    /// Timestamp does not increase strictly.
    Time {
        /// This row's time, s.
        t: f64,
        /// Previous kept row's time, s.
        previous: f64,
    },
    /// Mapping or vehicle inconsistency (unit, rotor count, frame…).
    Mapping(String),
    /// An asynchronous topic has no messages close enough to align with the time base;
    /// the sample is always dropped and counted (never bridged).
    NotAligned(String),
    /// The log's samples are too few, or its segments too short, to support a fit (the
    /// text says what is short and what is needed).
    TooShort(String),
}

impl IoError {
    /// An error at `location` of `file`, about the labelled `field` when given (see
    /// [`column()`], [`field`], [`key`]).
    pub(crate) fn new(
        file: &str,
        location: Location,
        field: Option<String>,
        kind: ErrorKind,
    ) -> Self {
        Self {
            file: file.to_string(),
            location,
            field,
            kind,
        }
    }

    /// True for errors about one sample's values, which the drop-and-count policy may
    /// skip: anything else (structure, mapping, missing signals) is always fatal.
    pub(crate) fn is_sample_level(&self) -> bool {
        matches!(
            self.kind,
            ErrorKind::NotANumber(_)
                | ErrorKind::NotFinite(_)
                | ErrorKind::OutOfRange { .. }
                | ErrorKind::Time { .. }
                | ErrorKind::NotAligned(_)
        )
    }

    /// Short reason name used to count dropped samples ("not finite", …).
    pub fn reason(&self) -> &'static str {
        match self.kind {
            ErrorKind::Read(_) => "unreadable",
            ErrorKind::Empty => "empty",
            ErrorKind::Format(_) => "malformed record",
            ErrorKind::MissingSignal(_) => "missing signal",
            ErrorKind::NotANumber(_) => "not a number",
            ErrorKind::NotFinite(_) => "not finite",
            ErrorKind::OutOfRange { .. } => "out of physical range",
            ErrorKind::Time { .. } => "time not strictly increasing",
            ErrorKind::Mapping(_) => "mapping",
            ErrorKind::NotAligned(_) => "topic not aligned within max_gap",
            ErrorKind::TooShort(_) => "too short",
        }
    }
}

/// Label of a CSV column: `column "u"`.
pub fn column(name: &str) -> Option<String> {
    Some(format!("column {name:?}"))
}

/// Label of an MCAP message field: `field "/imu.angular_velocity.x"`.
pub fn field(path: &str) -> Option<String> {
    Some(format!("field {path:?}"))
}

/// Label of a TOML key: `key "signals.rates"`.
pub fn key(name: &str) -> Option<String> {
    Some(format!("key {name:?}"))
}

/// The display name of a path: its file name when it has one.
pub fn display_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

impl fmt::Display for IoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        match self.location {
            Location::File => {}
            Location::Line(n) => write!(f, ": line {n}")?,
            Location::Record(n) => write!(f, ": message {n}")?,
            Location::Offset(n) => write!(f, ": byte {n}")?,
            Location::Sample(n) => write!(f, ": sample {n}")?,
        }
        if let Some(field) = &self.field {
            let sep = if self.location == Location::File {
                ":"
            } else {
                ","
            };
            write!(f, "{sep} {field}")?;
        }
        write!(f, ": {}", self.kind)
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Read(m) => write!(f, "cannot read: {m}"),
            Self::Empty => f.write_str("no data rows"),
            Self::Format(m)
            | Self::MissingSignal(m)
            | Self::Mapping(m)
            | Self::NotAligned(m)
            | Self::TooShort(m) => f.write_str(m),
            Self::NotANumber(text) => write!(f, "not a number ({text:?})"),
            Self::NotFinite(v) => write!(f, "not a finite number ({v})"),
            Self::OutOfRange { value, range } => {
                write!(f, "value {value} outside the physical range {range}")
            }
            Self::Time { t, previous } if t == previous => {
                write!(f, "duplicate timestamp t = {t} s")
            }
            Self::Time { t, previous } => write!(
                f,
                "timestamp t = {t} s goes backwards (previous row t = {previous} s)"
            ),
        }
    }
}

impl std::error::Error for IoError {}
