//! What a running fit says of its progress (the library's [`Progress`] and the final line
//! of `mrsysid fit`), and a fit whose cancellation flag is set stopping before reading
//! any chunk.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use mrsysid::error::RequestError;
use mrsysid::{Error, Identification, Phase, Progress, Vehicle};

#[test]
fn a_set_flag_stops_the_fit_before_the_first_chunk() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let vehicle =
        Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).expect("vehicle");
    let flag = Arc::new(AtomicBool::new(true));
    let progress = Arc::new(Progress::new());
    let run = Identification::new(vehicle)
        .log(root.join("data/quad_x_sweep.csv"))
        .threads(1)
        .progress(progress.clone())
        .cancel(flag)
        .run();
    assert!(
        matches!(run, Err(Error::Request(RequestError::Cancelled))),
        "{run:?}"
    );
    assert_eq!(progress.samples(), 0, "no chunk was passed on");
}

/// After a fit, the progress has counted every byte of the log file in the first pass
/// and every sample in both passes, whatever the thread count (the reader reports what
/// it has read once a chunk, and the rest of the file at its end).
#[test]
fn progress_counts_the_file_bytes_and_the_samples_of_both_passes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let vehicle =
        Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).expect("vehicle");
    let log = root.join("data/quad_x_flight_quadratic_drag.csv");
    let bytes = std::fs::metadata(&log).expect("log").len();
    for threads in [1, 2] {
        let progress = Arc::new(Progress::new());
        let results = Identification::new(vehicle.clone())
            .log(log.clone())
            .threads(threads)
            .diagnose(false)
            .progress(progress.clone())
            .run()
            .expect("fit");
        let samples = results.outcome().summaries[0].samples;
        assert_eq!(samples, 3001, "30 s at 100 Hz");
        assert_eq!(progress.bytes(), bytes, "{threads} threads");
        assert_eq!(progress.samples(), 2 * samples, "{threads} threads");
        assert_eq!(progress.phase(), Phase::SecondPass);
        assert_eq!((progress.done(), progress.total()), (samples, samples));
        assert_eq!(progress.scan_fit(), None);
    }
}

/// `mrsysid fit` with stderr not a terminal writes no progress display: its reader
/// notes, then one final line naming the logs, the megabytes read and the samples
/// passed; `--quiet` not even that.
#[test]
fn fit_ends_with_one_line_on_stderr_when_it_is_not_a_terminal() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let log = root.join("data/quad_x_sweep.csv");
    let mb = std::fs::metadata(&log).expect("log").len() as f64 / 1e6;
    let fit = |extra: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mrsysid"))
            .arg("fit")
            .arg(&log)
            .args(["--vehicle", "data/vehicles/quad_x.toml", "--no-diagnose"])
            .args(extra)
            .current_dir(root)
            .output()
            .expect("run mrsysid");
        assert!(out.status.success(), "{out:?}");
        String::from_utf8(out.stderr).expect("utf-8")
    };
    let stderr = fit(&[]);
    let (last, notes) = stderr
        .lines()
        .collect::<Vec<_>>()
        .split_last()
        .map(|(l, n)| (*l, n.to_vec()))
        .expect("a line");
    assert_eq!(
        notes,
        [
            "note: quad_x_sweep.csv: 2000 samples, each a point of its own (every time step over max_gap): a test-point sweep, not a time series"
        ]
    );
    let expected = format!("fit: 1 log, {mb:.1} MB read, 4000 samples passed, ");
    assert!(last.starts_with(&expected), "{stderr}");
    assert!(last.ends_with(" s") && !stderr.contains('\r'), "{stderr}");
    assert_eq!(fit(&["--quiet"]), "");
}
