//! The look-ahead window of the current segment and how rows enter it: a row whose time
//! does not increase is dropped or refused, a step longer than `max_gap` (or a logger
//! dropout) closes the segment, never bridged; the motor lag of an actuator map is
//! applied between consecutive rows.

use std::collections::VecDeque;

use super::super::error::{ErrorKind, IoError};
use super::super::options::InvalidSamples;
use super::LogReader;
use super::convert::Row;

/// The rows of the current segment not yet dropped behind, and where the segment stands.
#[derive(Debug, Default)]
pub(super) struct Window {
    /// Converted rows, oldest first.
    pub rows: VecDeque<Row>,
    /// Index in `rows` of the next row to emit.
    pub next_emit: usize,
    /// The first row of the next segment, read when the current one closed.
    pub pending: Option<Row>,
    /// The source is exhausted.
    pub done: bool,
    /// Index of the segment being emitted.
    pub segment: usize,
    /// Samples emitted from the current segment.
    pub segment_samples: u64,
}

impl Window {
    /// True when the segment is closed (gap seen or end of file).
    pub fn closed(&self) -> bool {
        self.done || self.pending.is_some()
    }
}

impl LogReader {
    /// Reads, converts and checks the next sample into `row`; `Ok(false)` at end of file.
    fn pull(&mut self, row: &mut Row) -> Result<bool, IoError> {
        let Some((loc, source_time)) = self.source.next_row(&mut self.convert.raw)? else {
            return Ok(false);
        };
        self.tally.summary.rows_read += 1;
        self.convert
            .row(&self.tally.summary.file, loc, source_time, row)?;
        self.tally.unit_stats.time(row.t);
        Ok(true)
    }

    /// Drops and counts the sample of `e` when the policy (or the error) says so, else
    /// returns the error.
    pub(super) fn drop_or_fail(&mut self, e: IoError) -> Result<(), IoError> {
        let always_dropped = matches!(e.kind, ErrorKind::NotAligned(_));
        if always_dropped
            || (self.opts.invalid == InvalidSamples::DropAndCount && e.is_sample_level())
        {
            self.tally.summary.count_drop(e.reason(), e.to_string());
            Ok(())
        } else {
            Err(e)
        }
    }

    /// Closes the segment at the gap from `last` (s) to `row`, which starts the next.
    fn close_segment(&mut self, last: f64, row: Row) {
        self.tally.summary.record_gap(last, row.t);
        self.window.pending = Some(row);
    }

    /// Gets the next row that continues the current segment into the window, or marks
    /// the segment end (gap or end of file).
    pub(super) fn fill(&mut self) -> Result<(), IoError> {
        let mut row = Row::default();
        loop {
            match self.pull(&mut row) {
                Ok(true) => {}
                Ok(false) => {
                    self.window.done = true;
                    return Ok(());
                }
                Err(e) => {
                    self.drop_or_fail(e)?;
                    continue;
                }
            }
            let forced = self.source.take_segment_break();
            if let Some(last) = self.window.rows.back().map(|r| r.t) {
                if forced && row.t > last {
                    self.close_segment(last, row);
                    return Ok(());
                }
                if row.t <= last {
                    let e = IoError::new(
                        &self.tally.summary.file,
                        row.loc,
                        self.convert.time_label(),
                        ErrorKind::Time {
                            t: row.t,
                            previous: last,
                        },
                    );
                    self.drop_or_fail(e)?;
                    continue;
                }
                if row.t - last > self.opts.max_gap {
                    self.close_segment(last, row);
                    return Ok(());
                }
            }
            if let (Some(tau), Some(last)) = (
                self.convert.actuator.and_then(|a| a.time_constant),
                self.window.rows.back(),
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
            self.window.rows.push_back(row);
            return Ok(());
        }
    }
}
