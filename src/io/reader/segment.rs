//! The look-ahead window of the current segment and how rows enter it: a row whose time
//! does not increase is dropped or refused, a step longer than `max_gap` (or a logger
//! dropout) closes the segment, never bridged; the motor lag of an actuator map is
//! applied between consecutive rows; then the airborne detector ([`super::airborne`])
//! leaves ground time out, closing the segment at it.

use std::collections::VecDeque;

use super::super::error::{ErrorKind, IoError};
use super::super::options::InvalidSamples;
use super::LogReader;
use super::airborne::Break;
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
    /// Time of the last row that passed the time checks (kept or not), s.
    pub last_t: Option<f64>,
    /// That row, when a motor lag needs it.
    pub last_row: Option<Row>,
    /// The source is exhausted (rows may still wait in the airborne detector).
    pub read_all: bool,
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

    /// Closes the segment before `row`, which starts the next: at a time gap (recorded
    /// in the summary) or after ground time.
    fn close_segment(&mut self, brk: Break, row: Row) {
        if let Break::Gap(last) = brk {
            self.tally.summary.record_gap(last, row.t);
        }
        self.window.pending = Some(row);
    }

    /// Gets the next row that continues the current segment into the window, or marks
    /// the segment end (gap, ground time or end of file).
    pub(super) fn fill(&mut self) -> Result<(), IoError> {
        loop {
            if let Some((row, brk)) = self.air.released.pop_front() {
                if brk != Break::None && !self.window.rows.is_empty() {
                    self.close_segment(brk, row);
                } else {
                    self.window.rows.push_back(row);
                }
                return Ok(());
            }
            if self.window.read_all {
                self.window.done = true;
                return Ok(());
            }
            self.next_row()?;
        }
    }

    /// Reads the next row that passes the time checks, applies the motor lag, and hands
    /// it to the airborne detector; at the end of file, lets the detector finish.
    fn next_row(&mut self) -> Result<(), IoError> {
        let mut row = Row::default();
        loop {
            match self.pull(&mut row) {
                Ok(true) => {}
                Ok(false) => {
                    self.window.read_all = true;
                    self.tally.summary.airborne =
                        Some(self.air.finish()).filter(|span| span.ground_samples > 0);
                    return Ok(());
                }
                Err(e) => {
                    self.drop_or_fail(e)?;
                    continue;
                }
            }
            let forced = self.source.take_segment_break();
            let mut brk = Break::None;
            if let Some(last) = self.window.last_t {
                if forced && row.t > last {
                    brk = Break::Gap(last);
                } else if row.t <= last {
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
                } else if row.t - last > self.opts.max_gap {
                    brk = Break::Gap(last);
                }
            }
            if let (Some(tau), Some(last), Break::None) = (
                self.convert.actuator.and_then(|a| a.time_constant),
                self.window.last_row.as_ref(),
                brk,
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
            self.window.last_t = Some(row.t);
            if self
                .convert
                .actuator
                .is_some_and(|a| a.time_constant.is_some())
            {
                self.window.last_row = Some(row);
            }
            self.air.push(row, brk, self.vehicle.rotors);
            return Ok(());
        }
    }
}
