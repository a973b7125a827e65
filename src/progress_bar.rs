//! The progress display of `mrsysid fit` on stderr: once a fit has run for a second, a
//! bar with the fraction of the log files' bytes read and the time left in the first
//! pass, of the samples passed in the second, and the phase's name and time between
//! them (with the cut-off of a scan's fit). Nothing when stderr is not a terminal;
//! there, as on a terminal, the fit ends with one line ([`Finished::line`]).

use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mrsysid::{Identification, Phase, Progress};

/// What a finished fit did, for its final line.
pub struct Finished {
    progress: Arc<Progress>,
    elapsed: Duration,
}

impl Finished {
    /// One line: logs, bytes read (by every fit of a cut-off scan), samples passed over
    /// all passes, wall time.
    pub fn line(&self, command: &str, logs: usize) -> String {
        let p = &self.progress;
        let fits = match p.scan_fit() {
            Some((n, _)) => format!(" over {n} fits of the cut-off scan"),
            None => String::new(),
        };
        format!(
            "{command}: {logs} log{}, {} read{fits}, {} samples passed, {:.1} s",
            if logs == 1 { "" } else { "s" },
            megabytes(p.bytes()),
            p.samples(),
            self.elapsed.as_secs_f64()
        )
    }
}

/// `n` bytes in MB (10⁶ bytes), one decimal.
fn megabytes(n: u64) -> String {
    format!("{:.1} MB", n as f64 / 1e6)
}

/// Runs `job` on `request` with its progress shown on stderr when it is a terminal
/// (never with `quiet`); returns what `job` returned and what the fit did.
pub fn with_progress<T>(
    request: Identification,
    quiet: bool,
    job: impl FnOnce(&Identification) -> T,
) -> (T, Finished) {
    let progress = Arc::new(Progress::new());
    let request = request.progress(progress.clone());
    let start = Instant::now();
    if quiet || !std::io::stderr().is_terminal() {
        let out = job(&request);
        let elapsed = start.elapsed();
        return (out, Finished { progress, elapsed });
    }
    let done = Arc::new(AtomicBool::new(false));
    let display = {
        let (progress, done) = (progress.clone(), done.clone());
        std::thread::spawn(move || show(&progress, &done, start))
    };
    let out = job(&request);
    done.store(true, Ordering::Relaxed);
    let _ = display.join();
    let elapsed = start.elapsed();
    (out, Finished { progress, elapsed })
}

/// Draws `progress` every 100 ms until `done`, from one second after `start`: one line,
/// composed here and handed to indicatif whole (so no frame mixes two phases), which cuts
/// it to the terminal's width.
fn show(progress: &Progress, done: &AtomicBool, start: Instant) {
    let bar = ProgressBar::hidden();
    bar.set_style(
        ProgressStyle::with_template("{wide_msg}").unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    // The phase and scan fit drawn, when they were first seen and the units done then.
    let mut drawn: Option<((Phase, Option<u64>), Instant, u64)> = None;
    let mut ticks = 0usize;
    while !done.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(100));
        if start.elapsed() < Duration::from_secs(1) {
            continue;
        }
        let scan_fit = progress.scan_fit();
        let now = (progress.phase(), scan_fit.map(|(n, _)| n));
        let (_, since, done_then) = match drawn {
            Some(d) if d.0 == now => d,
            _ => *drawn.insert((now, Instant::now(), progress.done())),
        };
        ticks += 1;
        bar.set_message(line(
            progress,
            now.0,
            scan_fit,
            since.elapsed(),
            done_then,
            ticks,
        ));
        if bar.is_hidden() {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }
    bar.finish_and_clear();
}

/// Frames of the spinner of a phase without a size.
const SPINNER: [char; 4] = ['|', '/', '-', '\\'];

/// Width of the bar of a pass, characters.
const BAR: usize = 24;

/// The line of `phase` (of the scan's fit `scan_fit`), first drawn `elapsed` ago when
/// `done_then` units were done; `tick` turns the spinner.
fn line(
    progress: &Progress,
    phase: Phase,
    scan_fit: Option<(u64, Option<f64>)>,
    elapsed: Duration,
    done_then: u64,
    tick: usize,
) -> String {
    let name = match scan_fit {
        Some((n, Some(hz))) => format!("fit {n} ({hz:.1} Hz): {}", phase.label()),
        Some((n, None)) => format!("fit {n} (unfiltered): {}", phase.label()),
        None => phase.label().to_string(),
    };
    if !phase.is_pass() {
        let spin = SPINNER[tick % SPINNER.len()];
        return format!("{spin} {name} {}", duration(elapsed.as_secs_f64()));
    }
    let (done, total) = (progress.done(), progress.total().max(1));
    let fraction = (done as f64 / total as f64).min(1.0);
    let filled = (fraction * BAR as f64).round() as usize;
    let bar = format!("{}{}", "=".repeat(filled), " ".repeat(BAR - filled));
    let amount = match phase {
        Phase::Reading => format!("{}/{}", megabytes(done), megabytes(total)),
        _ => format!(
            "{:.2}/{:.2} M samples",
            done as f64 / 1e6,
            total as f64 / 1e6
        ),
    };
    // At the rate since the phase was first drawn.
    let left = match done.saturating_sub(done_then) {
        0 => String::new(),
        d => {
            let rate = d as f64 / elapsed.as_secs_f64().max(1e-3);
            let left = total.saturating_sub(done) as f64 / rate;
            format!(", {} left", duration(left))
        }
    };
    format!("{name} [{bar}] {:>3.0}% {amount}{left}", 100.0 * fraction)
}

/// `seconds` as "7 s" or "2 min 05 s".
fn duration(seconds: f64) -> String {
    let s = seconds.round() as u64;
    if s < 60 {
        format!("{s} s")
    } else {
        format!("{} min {:02} s", s / 60, s % 60)
    }
}
