//! What a running fit has done so far, for a progress display: shared in an `Arc`
//! between the fit ([`crate::Identification::progress`]) and a display thread, which
//! reads it while the fit runs. Updated with relaxed atomics: a reader sees each figure
//! as it was at some recent moment, never a torn value.
//!
//! The fit runs in phases ([`Phase`]). The two passes over the data have a size known
//! when they start: the first pass the bytes of the log files (a log in memory counts
//! one unit per sample), the second the samples the first pass counted. The other
//! phases (solves on merged statistics, screening, the diagnosis's decisions, the short
//! remainder pass) have none.

use std::sync::atomic::{AtomicU8, AtomicU64, Ordering};

/// A phase of a fit, in the order a fit runs them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Not started.
    Starting,
    /// The first pass: every log read and accumulated (sized in bytes of the log files).
    Reading,
    /// The Eq. 22 fit and its cross-validation, on the merged statistics.
    Fitting,
    /// The generic-pool screening on thinned fit samples, before the second pass.
    Screening,
    /// The second pass: residual diagnostics, plot series, candidate statistics (sized in
    /// samples).
    SecondPass,
    /// The diagnosis's decisions, on the candidate statistics.
    Diagnosis,
    /// The remainder pass of a time-series diagnosis (the first samples of each fit log).
    Remainder,
}

impl Phase {
    const ALL: [Phase; 7] = [
        Phase::Starting,
        Phase::Reading,
        Phase::Fitting,
        Phase::Screening,
        Phase::SecondPass,
        Phase::Diagnosis,
        Phase::Remainder,
    ];

    /// What the phase does, for a display ("reading logs", …).
    pub fn label(self) -> &'static str {
        match self {
            Phase::Starting => "starting",
            Phase::Reading => "reading logs",
            Phase::Fitting => "fitting Eq. 22",
            Phase::Screening => "screening generic terms",
            Phase::SecondPass => "second pass",
            Phase::Diagnosis => "diagnosis",
            Phase::Remainder => "remainder pass",
        }
    }

    /// True when the phase has a size ([`Progress::done`] of [`Progress::total`]).
    pub fn is_pass(self) -> bool {
        matches!(self, Phase::Reading | Phase::SecondPass)
    }
}

/// The progress of one fit (or of the fits of a cut-off scan, one after another).
#[derive(Debug, Default)]
pub struct Progress {
    phase: AtomicU8,
    /// Units done in the current pass: bytes of log files (compressed bytes for a
    /// gzip-compressed file) in the first pass, samples in later passes.
    done: AtomicU64,
    /// Units of the current pass.
    total: AtomicU64,
    /// Samples passed on by every pass so far.
    samples: AtomicU64,
    /// Bytes of log files read by every first pass so far.
    bytes: AtomicU64,
    /// The cut-off (Hz, as `f64` bits) of the scan's fit under way; 0: no scan, or its
    /// unfiltered fit.
    scan_cutoff: AtomicU64,
    /// Fits of a cut-off scan started so far (0: no scan).
    scan_fits: AtomicU64,
}

impl Progress {
    /// No work done yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// The phase under way.
    pub fn phase(&self) -> Phase {
        Phase::ALL
            .get(self.phase.load(Ordering::Relaxed) as usize)
            .copied()
            .unwrap_or(Phase::Starting)
    }

    /// Units done in the current pass: bytes in [`Phase::Reading`] (a log in memory
    /// counts one per sample), samples in the later passes; 0 between passes.
    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }

    /// Units of the current pass (see [`Progress::done`]); 0 between passes.
    pub fn total(&self) -> u64 {
        self.total.load(Ordering::Relaxed)
    }

    /// Samples passed on by every pass so far (a sample read twice counts twice).
    pub fn samples(&self) -> u64 {
        self.samples.load(Ordering::Relaxed)
    }

    /// Bytes of log files read by every first pass so far (compressed bytes of a
    /// gzip-compressed file), bytes.
    pub fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }

    /// The fit of a cut-off scan under way ([`crate::Identification::estimate_loads_low_pass`]):
    /// its number from 1 and its cut-off (Hz; `None` for the unfiltered fit). `None`
    /// outside a scan.
    pub fn scan_fit(&self) -> Option<(u64, Option<f64>)> {
        let n = self.scan_fits.load(Ordering::Relaxed);
        let hz = f64::from_bits(self.scan_cutoff.load(Ordering::Relaxed));
        (n > 0).then_some((n, (hz > 0.0).then_some(hz)))
    }

    /// Enters `phase`, of `total` units when it is a pass (else 0).
    pub(crate) fn start(&self, phase: Phase, total: u64) {
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
        let index = Phase::ALL.iter().position(|&p| p == phase).unwrap_or(0);
        self.phase.store(index as u8, Ordering::Relaxed);
    }

    /// Counts `samples` passed on; outside the first pass they are the units done.
    pub(crate) fn add_samples(&self, samples: u64) {
        self.samples.fetch_add(samples, Ordering::Relaxed);
        if self.phase() != Phase::Reading {
            self.done.fetch_add(samples, Ordering::Relaxed);
        }
    }

    /// Counts `units` read in the first pass: bytes of a log file (`bytes`), or samples
    /// of a log in memory. Ignored outside the first pass (a pass that reads a log's text
    /// again counts samples only).
    pub(crate) fn add_read(&self, units: u64, bytes: bool) {
        if self.phase() != Phase::Reading {
            return;
        }
        if bytes {
            self.bytes.fetch_add(units, Ordering::Relaxed);
        }
        self.done.fetch_add(units, Ordering::Relaxed);
    }

    /// A scan's next fit starts, at `cutoff_hz` (`None`: unfiltered).
    pub(crate) fn start_scan_fit(&self, cutoff_hz: Option<f64>) {
        self.scan_cutoff
            .store(cutoff_hz.unwrap_or(0.0).to_bits(), Ordering::Relaxed);
        self.scan_fits.fetch_add(1, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_passes_and_the_scan_read_back_as_set() {
        let p = Progress::new();
        assert_eq!(p.phase(), Phase::Starting);
        p.add_read(5, true);
        assert_eq!(p.done(), 0, "bytes count in the first pass only");
        p.start(Phase::Reading, 1000);
        p.add_read(400, true);
        p.add_read(20, false);
        p.add_samples(30);
        assert_eq!(
            (p.phase(), p.done(), p.total()),
            (Phase::Reading, 420, 1000)
        );
        p.start(Phase::SecondPass, 60);
        p.add_samples(30);
        p.add_read(7, true);
        assert_eq!(
            (p.done(), p.total(), p.samples(), p.bytes()),
            (30, 60, 60, 400)
        );
        assert!(p.phase().is_pass() && !Phase::Diagnosis.is_pass());
        assert_eq!(p.scan_fit(), None);
        p.start_scan_fit(None);
        assert_eq!(p.scan_fit(), Some((1, None)));
        p.start_scan_fit(Some(22.6));
        assert_eq!(p.scan_fit(), Some((2, Some(22.6))));
    }
}
