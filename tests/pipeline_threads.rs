//! The fit pipeline gives the same report whatever the thread count: every log's
//! statistics (first pass) and residual/plot/candidate shares (second pass) are computed
//! by the same code on whichever thread picks the log up, and merged in job order.

mod scratch;
use std::path::{Path, PathBuf};

use mrsysid::internals::diagnose::DiagnoseOptions;
use mrsysid::internals::estimate::FitOptions;
use mrsysid::internals::pipeline::{self, FitRequest};
use mrsysid::io::ReadOptions;
use mrsysid::vehicle::Vehicle;
use mrsysid::{FitOutcome, Holdout, PlotSeries};
use mrsysid::{ModelOptions, ModelStructure};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Writes the header and data rows `rows` of the shipped 30 s quad× flight to a file.
fn flight_part(name: &str, rows: std::ops::Range<usize>) -> PathBuf {
    let text = std::fs::read_to_string(root().join("data/quad_x_flight_quadratic_drag.csv"))
        .expect("shipped flight");
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().expect("header"));
    for line in lines.skip(rows.start).take(rows.len()) {
        out.push_str(line);
        out.push('\n');
    }
    let path = scratch::dir("threads").join(name);
    std::fs::write(&path, out).expect("write part");
    path
}

fn request(logs: &[&Path], validate: &[&Path], threads: usize) -> FitRequest {
    let vehicle =
        Vehicle::from_toml_file(&root().join("data/vehicles/quad_x.toml")).expect("vehicle");
    let structure = ModelStructure::eq22(&vehicle, ModelOptions::default());
    FitRequest {
        logs: logs.iter().map(|&p| p.into()).collect(),
        vehicle,
        mapping: None,
        read: ReadOptions::default(),
        structure,
        fit: FitOptions::default(),
        holdout: Holdout::default(),
        validate: validate.iter().map(|&p| p.into()).collect(),
        groups: Vec::new(),
        threads,
        second_pass: true,
        diagnose: Some(DiagnoseOptions::default()),
        progress: None,
        cancel: None,
        loads_low_pass_hz: None,
    }
}

fn assert_same_series(a: &PlotSeries, b: &PlotSeries, what: &str) {
    assert_eq!(a.t, b.t, "{what}: time");
    assert_eq!(a.measured, b.measured, "{what}: measured");
    assert_eq!(a.predicted, b.predicted, "{what}: predicted");
}

/// Tolerance zero: the same per-log computations merged in the same order give the same
/// bits, so any difference is a scheduling dependence.
fn assert_same_outcome(a: &FitOutcome, b: &FitOutcome, what: &str) {
    assert_eq!(a.fit.mmr.theta, b.fit.mmr.theta, "{what}: θ̂");
    assert_eq!(a.fit.mmr.covariance, b.fit.mmr.covariance, "{what}: cov");
    assert_eq!(a.diagnostics, b.diagnostics, "{what}: residual diagnostics");
    assert_eq!(a.diagnosis, b.diagnosis, "{what}: diagnosis");
    assert_same_series(&a.fit_series, &b.fit_series, what);
    assert_same_series(&a.validation_series, &b.validation_series, what);
}

/// Plotted points are every `stride`-th sample of the whole run, stride = ⌈N/4000⌉, so
/// there are ⌈N/stride⌉ of them; logs are laid end to end, so time never goes back.
fn assert_decimated(series: &PlotSeries, samples: u64) {
    let stride = samples.div_ceil(4000).max(1);
    assert_eq!(series.t.len() as u64, samples.div_ceil(stride));
    assert!(series.t.windows(2).all(|w| w[1] >= w[0]), "time goes back");
}

#[test]
fn one_two_and_four_threads_give_the_same_report() {
    // Three fit logs of 11.01, 11.01 and 30 s at 100 Hz (each predicted from the others
    // in the cross-validation): 1101 + 1101 + 3000 fit samples, so the plot stride is 2
    // and the second log's first sample has an odd place in the run: decimating each log
    // from zero would plot one point too many there. A fourth log validates.
    let logs = [
        flight_part("a.csv", 0..1101),
        flight_part("b.csv", 1101..2202),
        flight_part("c.csv", 0..3000),
    ];
    let validate = flight_part("d.csv", 500..2500);
    let logs: Vec<&Path> = logs.iter().map(|p| p.as_path()).collect();
    let validate = [validate.as_path()];
    let one = pipeline::run(&request(&logs, &validate, 1)).expect("fit on one thread");
    assert!(one.diagnosis.is_some() && one.diagnostics.is_some());
    assert_eq!(one.fit_stats.count(), 1101 + 1101 + 3000);
    assert_eq!(one.validation_stats.count(), 2000);
    assert_eq!(one.cross_validation.0, ["a.csv", "b.csv", "c.csv"]);
    assert_decimated(&one.fit_series, one.fit_stats.count());
    assert_decimated(&one.validation_series, one.validation_stats.count());
    // Two threads: two logs at a time; four threads: reading overlapped within a log.
    for threads in [2, 4] {
        let many = pipeline::run(&request(&logs, &validate, threads)).expect("fit on threads");
        assert_same_outcome(&one, &many, &format!("{threads} threads"));
    }
    // One log (cross-validated on its contiguous blocks, every sample fitted), two
    // threads: its reading overlaps the accumulation.
    let single = pipeline::run(&request(&logs[..1], &[], 1)).expect("one log");
    assert_eq!(single.fit_stats.count(), 1101);
    assert_eq!(single.cross_validation.0.len(), Holdout::DEFAULT.blocks);
    let overlapped = pipeline::run(&request(&logs[..1], &[], 2)).expect("one log, 2 threads");
    assert_same_outcome(&single, &overlapped, "one log, overlapped reading");
}

/// The log at `path` read by the library's reader into a memory log of the file's name
/// (the cross-validation folds and the diagnosis name the logs).
fn in_memory(path: &Path, vehicle: &Vehicle) -> mrsysid::MemoryLog {
    let reader =
        mrsysid::io::open_log(path, vehicle, None, &ReadOptions::default()).expect("open log");
    let chunks: Vec<_> = reader.map(|c| c.expect("chunk")).collect();
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .expect("file name");
    mrsysid::MemoryLog::from_chunks(name, chunks).expect("memory log")
}

#[test]
fn the_spilled_second_pass_matches_the_samples_streamed_from_memory() {
    // A file's second pass streams the parsed chunks back from its temporary spill; a
    // memory log's streams its own chunks: the same chunks in the same order, so the
    // residual diagnostics, plot series and diagnosis agree bit for bit (tolerance
    // zero), on one thread and with reading overlapped on two; with two fit logs too.
    let files = [
        flight_part("spill-a.csv", 0..1500),
        flight_part("spill-b.csv", 1200..3000),
    ];
    for threads in [1, 2] {
        let from_files = pipeline::run(&request(&[&files[0]], &[], threads)).expect("file");
        let mut memory = request(&[], &[], threads);
        memory.logs = vec![in_memory(&files[0], &memory.vehicle).into()];
        let from_memory = pipeline::run(&memory).expect("memory");
        assert!(from_files.diagnosis.is_some() && from_files.diagnostics.is_some());
        assert_same_outcome(&from_files, &from_memory, &format!("{threads} threads"));

        let two = pipeline::run(&request(&[&files[0], &files[1]], &[], threads)).expect("files");
        let mut memory = request(&[], &[], threads);
        memory.logs = files
            .iter()
            .map(|f| in_memory(f, &memory.vehicle).into())
            .collect();
        let two_memory = pipeline::run(&memory).expect("memory logs");
        assert_same_outcome(&two, &two_memory, &format!("two logs, {threads} threads"));
    }
}

/// `copies` copies of the shipped 2000-point quad× sweep (t = 0, 1, … s), each after
/// the one before in time, written to a file.
fn long_sweep(name: &str, copies: usize) -> PathBuf {
    let text = std::fs::read_to_string(root().join("data/quad_x_sweep.csv")).expect("sweep");
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().expect("header"));
    let rows: Vec<&str> = lines.collect();
    for copy in 0..copies {
        for row in &rows {
            let (t, rest) = row.split_once(',').expect("time column");
            let t: f64 = t.parse().expect("time");
            out.push_str(&format!("{},{rest}\n", t + (copy * rows.len()) as f64));
        }
    }
    let path = scratch::dir("threads").join(name);
    std::fs::write(&path, out).expect("write sweep");
    path
}

#[test]
fn a_log_of_several_second_pass_segments_gives_one_report() {
    // 72 000 samples (71 chunks): more than one 65 536-sample segment of the second
    // pass, so the log's second pass runs as six segments of 11–12 chunks (on two
    // threads when it has them) merged in order. Tolerance zero: the segments are fixed
    // by the chunk count, not by the threads, and a memory log is cut into the same
    // segments.
    let file = long_sweep("long-sweep.csv", 36);
    let one = pipeline::run(&request(&[&file], &[], 1)).expect("one thread");
    // Every sample is fitted (the contiguous blocks cross-validate it), none is held
    // out for reporting.
    assert_eq!(one.fit_stats.count(), 72_000);
    assert!(one.diagnosis.is_some() && one.diagnostics.is_some());
    assert_decimated(&one.fit_series, 72_000);
    assert!(one.validation_series.t.is_empty());
    // Plotted time counts from the first sample.
    assert_eq!(one.fit_series.t[0], 0.0);
    let two = pipeline::run(&request(&[&file], &[], 2)).expect("two threads");
    assert_same_outcome(&one, &two, "two threads");
    let mut memory = request(&[], &[], 2);
    memory.logs = vec![in_memory(&file, &memory.vehicle).into()];
    let from_memory = pipeline::run(&memory).expect("memory");
    assert_same_outcome(&one, &from_memory, "memory log");
}

/// The JSON report (as `mrsysid fit --json` writes it) of fitting the shipped log `name`
/// with diagnosis on `threads` threads, its CSV cut into `range_bytes`-byte ranges.
fn json_report(name: &str, threads: usize, range_bytes: usize) -> String {
    let vehicle =
        Vehicle::from_toml_file(&root().join("data/vehicles/quad_x.toml")).expect("vehicle");
    let results = mrsysid::Identification::new(vehicle)
        .log(root().join("data").join(name))
        .read_options(ReadOptions {
            range_bytes,
            ..ReadOptions::default()
        })
        .threads(threads)
        .diagnose(true)
        .run()
        .expect("fit");
    serde_json::to_string_pretty(&results.report()).expect("json")
}

#[test]
fn json_reports_are_identical_for_any_thread_count_and_range_size() {
    // Tolerance zero (the text compared byte for byte): a CSV row becomes the same f64
    // values whichever range and thread parse it, and the rows reach the stateful reader
    // in file order, so nothing downstream can tell. The 769 kB flight is two ranges at
    // the default 512 KiB, 188 of 4 KiB and ~7 900 of 97 bytes (one or two rows each);
    // one thread parses inline, two give one parse worker, four two.
    let name = "quad_x_flight_quadratic_drag.csv";
    let reference = json_report(name, 1, mrsysid::io::DEFAULT_RANGE_BYTES);
    assert!(
        reference.contains("\"diagnosis\""),
        "report has a diagnosis"
    );
    for (threads, range_bytes) in [(2, 1 << 19), (4, 1 << 19), (1, 4096), (2, 4096), (4, 97)] {
        assert!(
            json_report(name, threads, range_bytes) == reference,
            "{threads} threads, {range_bytes}-byte ranges: report differs"
        );
    }
}

/// Statistics as data: each log's first pass kept as a part, saved and loaded, merged
/// in another grouping, and fitted, gives the report of the same logs fitted directly
/// with the residual pass off and no diagnosis, bit for bit (the same per-log
/// statistics merged in the same log order). And the parts refuse what would be wrong.
#[test]
fn a_fit_from_saved_and_merged_statistics_equals_the_direct_fit() {
    use mrsysid::{Error, Identification, StatsError, StatsPart};
    let logs: Vec<PathBuf> = [(0, 900), (900, 1800), (1800, 2400), (2400, 3001)]
        .iter()
        .map(|&(a, b)| flight_part(&format!("stats-{a}.csv"), a..b))
        .collect();
    let vehicle =
        Vehicle::from_toml_file(&root().join("data/vehicles/quad_x.toml")).expect("vehicle");
    let builder = || Identification::new(vehicle.clone()).threads(2);
    let direct = builder()
        .log(logs[0].clone())
        .log(logs[1].clone())
        .log(logs[2].clone())
        .validate(logs[3].clone())
        .residual_pass(false)
        .diagnose(false)
        .run()
        .expect("direct fit");
    // One part for the first log, one for the next two; the validation log's own.
    let dir = scratch::dir("threads");
    let save_load = |part: StatsPart, name: &str| {
        let path = dir.join(name);
        part.save(&path).expect("save");
        StatsPart::load(&path).expect("load")
    };
    let mut fit = save_load(
        builder().log(logs[0].clone()).accumulate().expect("a"),
        "a.stats",
    );
    let two = builder()
        .log(logs[1].clone())
        .log(logs[2].clone())
        .accumulate();
    fit.merge(&save_load(two.expect("b"), "b.stats"))
        .expect("merge");
    let validation = builder().log(logs[3].clone()).accumulate().expect("v");
    let from_stats = builder()
        .run_from_stats(&fit, Some(&validation))
        .expect("fit from statistics");
    let json = |r: &mrsysid::Results| serde_json::to_string(&r.report()).expect("json");
    assert_eq!(json(&from_stats), json(&direct));
    assert_eq!(fit.samples(), 2400);

    // Corrupted, other settings, the same log twice, a single fit log.
    let mut bytes = fit.to_bytes();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    let e = StatsPart::from_bytes(&bytes, "x.stats").expect_err("corrupted");
    assert!(e.to_string().contains("checksum mismatch"), "{e}");
    let other = Identification::new(vehicle.clone())
        .loads_low_pass(20.0)
        .log(logs[3].clone())
        .accumulate()
        .expect("other settings");
    let e = fit.clone().merge(&other).expect_err("other settings");
    assert!(matches!(e, StatsError::OtherSettings { .. }), "{e}");
    let e = fit.clone().merge(&fit).expect_err("twice");
    assert!(matches!(e, StatsError::DuplicateLog { .. }), "{e}");
    let single = builder().log(logs[0].clone()).accumulate().expect("single");
    let e = builder()
        .run_from_stats(&single, None)
        .expect_err("one log");
    assert!(
        matches!(e, Error::Stats(StatsError::TooFewLogs { logs: 1 })),
        "{e}"
    );
    let e = builder()
        .run_from_stats(&fit, Some(&fit))
        .expect_err("in-sample");
    assert!(
        matches!(e, Error::Stats(StatsError::DuplicateLog { .. })),
        "{e}"
    );

    // A forged part: the settings (fingerprint and text) of `fit`, the statistics of a
    // model without the terms linear in V_h (fewer columns), checksum recomputed. It
    // must be refused by name, not index out of bounds.
    let narrow = Identification::new(vehicle.clone())
        .model_options(mrsysid::ModelOptions {
            linear_vh_terms: false,
            ..Default::default()
        })
        .log(logs[3].clone())
        .accumulate()
        .expect("narrow");
    let forged = forge(&fit.to_bytes(), &narrow.to_bytes());
    let forged = StatsPart::from_bytes(&forged, "forged.stats").expect("checksum matches");
    let mut two = fit.clone();
    two.merge(&forged).expect("same settings");
    let e = builder()
        .run_from_stats(&two, None)
        .expect_err("forged layout");
    assert!(e.to_string().contains("not laid out"), "{e}");
}

/// The statistics file `logs_from` with the settings of `settings_from` (both in the
/// format of docs/stats-format.md): the payload starts with the fingerprint (varint)
/// and the settings text (varint length, bytes), then the logs.
fn forge(settings_from: &[u8], logs_from: &[u8]) -> Vec<u8> {
    const HEADER: usize = 32;
    let varint_end = |b: &[u8], mut at: usize| {
        while b[at] & 0x80 != 0 {
            at += 1;
        }
        at + 1
    };
    let settings_end = |b: &[u8]| {
        let at = varint_end(b, HEADER);
        let (mut len, mut shift, mut i) = (0usize, 0, at);
        loop {
            len |= usize::from(b[i] & 0x7f) << shift;
            shift += 7;
            i += 1;
            if b[i - 1] & 0x80 == 0 {
                break;
            }
        }
        i + len
    };
    let mut payload = settings_from[HEADER..settings_end(settings_from)].to_vec();
    payload.extend_from_slice(&logs_from[settings_end(logs_from)..]);
    let mut out = settings_from[..20].to_vec();
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
    out.extend_from_slice(&payload);
    out
}

/// Cross-validation groups: with logs a1, a2 in group `a` and b1, b2 in group `b`, the
/// folds are the two groups, and fold `group b` is the model fitted on a1 and a2
/// predicting b1 and b2, which a fit of a1 and a2 with b1 and b2 as validation logs
/// computes on its own (to 1e-9 relative: the two merge the same statistics in other
/// orders). Groups naming each log alone give the leave-one-log-out report, and bad
/// groups are refused before any log is read.
#[test]
fn cross_validation_groups_leave_their_logs_out_together() {
    use mrsysid::{Error, Identification, RequestError};
    let logs: Vec<PathBuf> = [(0, 750), (750, 1500), (1500, 2250), (2250, 3001)]
        .iter()
        .map(|&(a, b)| flight_part(&format!("groups-{a}.csv"), a..b))
        .collect();
    let vehicle =
        Vehicle::from_toml_file(&root().join("data/vehicles/quad_x.toml")).expect("vehicle");
    let builder = || {
        Identification::new(vehicle.clone())
            .threads(2)
            .residual_pass(false)
            .diagnose(false)
    };
    let grouped = builder()
        .logs(logs.clone())
        .groups(["a", "a", "b", "b"])
        .run()
        .expect("grouped")
        .report();
    let names: Vec<&str> = grouped
        .cross_validation
        .iter()
        .map(|f| f.name.as_str())
        .collect();
    assert_eq!(names, ["group a", "group b", "pooled"]);
    let direct = builder()
        .logs(logs[..2].to_vec())
        .validate(logs[2].clone())
        .validate(logs[3].clone())
        .run()
        .expect("a predicting b")
        .report();
    for (fold, valid) in grouped.cross_validation[1]
        .axes
        .iter()
        .zip(&direct.validation)
    {
        for (x, y) in [(fold.r2, valid.r2), (fold.rmse, valid.rmse)] {
            assert!(
                (x - y).abs() <= 1e-9 * y.abs().max(1e-12),
                "{fold:?} vs {valid:?}"
            );
        }
    }
    // Each log its own group: the leave-one-log-out folds, renamed.
    let names: Vec<String> = (1..=4).map(|i| format!("log{i}")).collect();
    let alone = builder()
        .logs(logs.clone())
        .groups(names)
        .run()
        .expect("alone");
    let plain = builder().logs(logs.clone()).run().expect("plain").report();
    for (g, p) in alone
        .report()
        .cross_validation
        .iter()
        .zip(&plain.cross_validation)
    {
        assert_eq!(g.axes, p.axes);
    }
    for groups in [vec!["a", "a", "a", "a"], vec!["a", "b"]] {
        let e = builder()
            .logs(logs.clone())
            .groups(groups)
            .run()
            .expect_err("bad groups");
        assert!(
            matches!(e, Error::Request(RequestError::InvalidGroups { .. })),
            "{e}"
        );
    }
}

/// The diagnosis from statistics (the second and third passes as data): parts of the
/// first pass, a plan, one second-pass part per log made by a prepared plan (as a
/// worker makes them, each sent as bytes), the reduce, the remainder parts, the finish:
/// the report equals that of the same logs fitted and diagnosed directly, bit for bit
/// (the same per-log statistics merged in the same order). Parts of another plan, a
/// missing part and parts accumulated without the diagnosis are refused by name.
#[test]
fn the_diagnosis_from_statistics_equals_the_direct_fit() {
    use mrsysid::{
        Error, Identification, LogSource, PassPart, PassPlan, RemainderPart, StatsError, StatsPart,
    };
    let logs: Vec<PathBuf> = [(0, 900), (900, 1800), (1800, 2400), (2400, 3001)]
        .iter()
        .map(|&(a, b)| flight_part(&format!("passes-{a}.csv"), a..b))
        .collect();
    let vehicle =
        Vehicle::from_toml_file(&root().join("data/vehicles/quad_x.toml")).expect("vehicle");
    let builder = || Identification::new(vehicle.clone()).threads(2);
    let direct = builder()
        .logs(logs[..3].to_vec())
        .validate(logs[3].clone())
        .run()
        .expect("direct fit");
    assert!(
        !direct
            .outcome()
            .diagnosis
            .as_ref()
            .expect("diagnosis")
            .remainder
            .is_empty(),
        "the flight's pieces are time series: the remainder pass runs"
    );
    let part = |log: &PathBuf| builder().log(log.clone()).accumulate().expect("part");
    let mut fit = part(&logs[0]);
    for log in &logs[1..3] {
        fit.merge(&part(log)).expect("merge");
    }
    let validation = part(&logs[3]);

    // The driver's fit and plan, the plan sent to the workers as bytes.
    let planned = || builder().plan_from_stats(&fit, Some(&validation));
    let plan = planned().expect("plan").plan().to_bytes();
    let plan = PassPlan::from_bytes(&plan, "plan").expect("plan bytes");
    let worker = builder().prepare_pass(plan.clone()).expect("prepared");
    let pass = |log: &PathBuf| {
        let part = worker
            .pass_part(&LogSource::from(log.clone()))
            .expect("pass");
        PassPart::from_bytes(&part.to_bytes(), "pass").expect("pass bytes")
    };
    // Any order: the reduce puts them in the plan's.
    let passes: Vec<PassPart> = logs.iter().rev().map(pass).collect();
    let pending =
        (planned().expect("plan").diagnose(passes.clone())).expect("diagnosis from statistics");
    let (model, fit_logs) = pending.remainder_plan().expect("a remainder pass");
    let (model, fit_logs) = (model.clone(), fit_logs.to_vec());
    assert_eq!(fit_logs.len(), 3, "the fit logs only");
    let remainders: Vec<RemainderPart> = (fit_logs.iter())
        .map(|name| {
            // The parts name each log by its file name.
            let path = logs.iter().find(|p| p.ends_with(name)).expect("a fit log");
            let part = worker.remainder_part(&model, &LogSource::from(path.clone()));
            let bytes = part.expect("remainder").to_bytes();
            RemainderPart::from_bytes(&bytes, "remainder").expect("remainder bytes")
        })
        .collect();
    let from_stats = builder()
        .finish_from_stats(pending, &remainders)
        .expect("finish");
    let json = |r: &mrsysid::Results| serde_json::to_string(&r.report()).expect("json");
    assert_eq!(json(&from_stats), json(&direct));

    // A log the plan does not name, a pass of another plan (validation log left out), a
    // missing pass, a missing remainder, parts without screening samples.
    let other = builder().plan_from_stats(&fit, None).expect("other plan");
    let other = builder()
        .prepare_pass(other.plan().clone())
        .expect("other prepared");
    let e = (other.pass_part(&LogSource::from(logs[3].clone()))).expect_err("not its log");
    assert!(
        matches!(&e, Error::Stats(StatsError::NotInPlan { log }) if log == "passes-2400.csv"),
        "{e}"
    );
    let mut mixed = passes.clone();
    // passes[1] is logs[2]'s.
    mixed[1] = (other.pass_part(&LogSource::from(logs[2].clone()))).expect("other pass");
    let e = planned()
        .expect("plan")
        .diagnose(mixed)
        .expect_err("another plan");
    assert!(
        matches!(&e, Error::Stats(StatsError::OtherPlan { file }) if file.ends_with("passes-1800.csv")),
        "{e}"
    );
    let e = (planned().expect("plan").diagnose(passes[1..].to_vec())).expect_err("missing");
    assert!(
        matches!(&e, Error::Stats(StatsError::MissingPass { .. })),
        "{e}"
    );
    let pending = (planned().expect("plan").diagnose(passes)).expect("again");
    let Err(e) = builder().finish_from_stats(pending, &remainders[1..]) else {
        panic!("a missing remainder part must be refused");
    };
    assert!(e.to_string().contains("no remainder part"), "{e}");
    let unscreened = |log: &PathBuf| {
        (builder().diagnose(false).log(log.clone()).accumulate()).expect("no screening")
    };
    let mut bare: StatsPart = unscreened(&logs[0]);
    bare.merge(&unscreened(&logs[1])).expect("merge");
    let e = builder()
        .plan_from_stats(&bare, None)
        .expect_err("not diagnosable");
    assert!(
        matches!(&e, Error::Stats(StatsError::NotDiagnosable { .. })),
        "{e}"
    );
}
