//! What the caller chooses when opening a log: the invalid-sample policy, the largest
//! time step bridged, the derivation options and the CSV parse threads.

use super::contract_csv::DEFAULT_RANGE_BYTES;
use super::derive::DeriveOptions;

/// What to do with a sample whose values are invalid (not a number, not finite, out of
/// physical range, time not strictly increasing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InvalidSamples {
    /// Stop with an error naming file, line/record and field (default).
    #[default]
    Error,
    /// Drop the sample and count it per reason in the [`super::Summary`].
    DropAndCount,
}

/// Options of [`super::open_log`].
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
    /// it from its thread budget unless that is 0, which keeps parsing on the reading
    /// thread.
    pub parse_threads: usize,
    /// Size of the byte ranges a CSV file is cut into for parsing, bytes (a range is
    /// longer when one record is; values below 1 count as 1). The values read do not
    /// depend on it; memory holds a few ranges per parse thread.
    pub range_bytes: usize,
    /// Fit airborne samples only: samples on the ground (rotors stopped or idling: they
    /// could not carry the weight at the highest plausible thrust coefficient, for a
    /// second or more) are left out and the log is split at them
    /// ([`super::Summary::airborne`]). Off by default here (every sample is kept, as a
    /// library caller gave it); `mrsysid fit` turns it on unless `--keep-ground`.
    pub airborne_only: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            invalid: InvalidSamples::Error,
            max_gap: 0.1,
            derive: DeriveOptions::default(),
            parse_threads: 1,
            range_bytes: DEFAULT_RANGE_BYTES,
            airborne_only: false,
        }
    }
}
