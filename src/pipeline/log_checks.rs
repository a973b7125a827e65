//! The checks that refuse a request right after the first pass, once each log's clock
//! and length are known.

use super::blocks::TooShort;
use super::first_pass::LogStats;
use super::request::FitRequest;
use crate::error::{Error, RequestError};
use crate::io;
use crate::source::LogSource;

/// The error of the first log file (fit or validation, `per_log` in job order) whose time
/// looks logged in ms or µs: a median step over 1 s or a span over a day
/// ([`io::time_unit_suspect`]), unless its unit is trusted (declared in a mapping, or t
/// numbering the rows of a test-point sweep). Its blocks or its dynamics would be cut on
/// a wrong clock.
pub(super) fn time_unit_error(req: &FitRequest, per_log: &[LogStats]) -> Result<(), Error> {
    let sources = req.logs.iter().chain(&req.validate);
    for (source, log) in sources.zip(per_log) {
        let s = &log.summary;
        if !matches!(source, LogSource::File(_)) || s.time_unit_trusted {
            continue;
        }
        let consequence = ", far slower than any flight log";
        if let Some(text) =
            io::time_unit_suspect(s.median_time_step, s.span, s.rows_read, consequence)
        {
            return Err(io::IoError::new(
                &s.file,
                io::Location::File,
                None,
                io::ErrorKind::Mapping(text),
            )
            .into());
        }
    }
    Ok(())
}

/// The error of the first log file (fit or validation, `per_log` in job order) whose
/// median sample step puts half its sample rate below the request's declared loads
/// low-pass cut-off: that filter would do nothing there. (An estimated cut-off is
/// chosen below a quarter of the rate, [`crate::loads_scan`].)
pub(super) fn low_pass_error(req: &FitRequest, per_log: &[LogStats]) -> Result<(), Error> {
    let Some(hz) = req.effective_loads_low_pass() else {
        return Ok(());
    };
    let steps = per_log.iter().filter_map(|l| {
        let s = &l.summary;
        s.median_time_step.map(|step| (s, step))
    });
    for (s, step) in steps {
        if hz * step > 0.5 {
            return Err(RequestError::LoadsLowPassAboveNyquist {
                hz,
                log: s.file.clone(),
                step,
            }
            .into());
        }
    }
    Ok(())
}

/// The error of a single fit log (`log`, read as `req.logs[0]`) too short for its blocks
/// (`short`); a clock in ms or µs was refused before ([`time_unit_error`]).
pub(super) fn too_short(req: &FitRequest, log: &LogStats, short: TooShort) -> Error {
    let s = &log.summary;
    let (span, median_step) = match &req.logs[0] {
        LogSource::Memory(_) => (short.span, None),
        LogSource::File(_) => (s.span, s.median_time_step),
    };
    let samples = short.samples;
    RequestError::HoldoutTooShort {
        log: s.file.clone(),
        samples,
        span,
        median_step,
        blocks: req.holdout.blocks,
        guard_seconds: req.holdout.guard_seconds,
    }
    .into()
}
