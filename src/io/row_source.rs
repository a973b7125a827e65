//! The source of raw samples the [`super::LogReader`] converts: CSV rows, or the
//! time-aligned messages of MCAP and ULog topics, in the slot layout of the mapping.

use super::error::{IoError, Location};
use super::summary::Dropout;

/// The source of raw samples in slot layout (CSV rows, aligned MCAP messages).
pub(crate) trait RowSource {
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
    /// The message the end of the file cut short, once reached (message-based logs).
    fn cut_off(&self) -> Option<&str> {
        None
    }
    /// A note when the rotor speeds come from a topic much slower than the time base
    /// (message-based logs), at the end of the log.
    fn slow_rotor_speeds(&mut self) -> Option<String> {
        None
    }
    /// Bytes of the file read so far (compressed bytes of a compressed file), for
    /// progress: may run ahead of the rows returned, and may end below the file's size
    /// when parts of the file are skipped.
    fn bytes_read(&self) -> u64;
}
