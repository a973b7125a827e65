//! End-to-end `mrsysid fit` against single-threaded `csv::ByteRecord` passes over the
//! same file, in one run: wall time, CPU time, peak RSS of the `fit` process, and two
//! logs on one vs two threads. The reference of issue 12 is pass (a), which parses every
//! field with std's `str::parse::<f64>`; the bare pass (no parsing) is shown as well.
//!
//! ```text
//! cargo build --release
//! cargo run --release --example fit_vs_bare -- 1000000
//! cargo run --release --example fit_vs_bare -- 10000000
//! ```
//!
//! The binary timed is `$MRSYSID_BIN`, else `$CARGO_TARGET_DIR/release/mrsysid`, else
//! `target/release/mrsysid`. With `$MRSYSID_BIN_BEFORE` (e.g. a build of an older
//! commit) every `fit` is also run with that binary, right after, for before/after
//! figures from the same machine state.
//!
//! With `MRSYSID_BENCH_LOG=flight` the log is instead a simulated quad× flight of that
//! many rows at 500 Hz (seed 9) without its `omega_dot` columns, so the fit derives ω̇
//! as it must on most real logs (`mrsysid simulate --mode flight`, minutes at 1 M rows,
//! kept in `$MRSYSID_BENCH_DIR` like the sweep).
//!
//! The argument is the row count. The 1 M-row quad× sweep is simulated once with
//! `target/release/mrsysid simulate --preset quad_x --mode sweep --points 1000000 --seed 9`
//! into `$MRSYSID_BENCH_DIR` (default: the system temp dir) and kept there for later
//! runs; a 10 M-row log is that sweep written ten times, t numbering the rows 0, 1, 2, …
//! throughout as a sweep's t does, because simulating 10 M sweep points takes minutes.
//! The second log of the two-log runs is the same with each copy's rows rotated by one
//! (same size, different bytes); a flight's is the flight shifted in time past its end.
//! Nothing is written into the repository.
//!
//! Every configuration runs `$MRSYSID_BENCH_REPEAT` times (default 3; with a before
//! binary the two alternate) after a warm-up read of the files (page cache warm for all),
//! and the fastest run is reported, with the largest peak RSS of its runs. Pass (a) is
//! timed before the fits and again after each configuration, and the ratios are taken
//! against its fastest pass: on a shared machine whose speed drifts, the minima of
//! interleaved runs are what the ratios compare.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const SWEEP_ROWS: u64 = 1_000_000;

fn main() {
    let rows: u64 = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("row count: a whole number"))
        .unwrap_or(SWEEP_ROWS);
    assert!(
        rows.is_multiple_of(SWEEP_ROWS),
        "row count must be a multiple of {SWEEP_ROWS}"
    );
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let bin = std::env::var_os("MRSYSID_BIN")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("CARGO_TARGET_DIR").map(|d| PathBuf::from(d).join("release/mrsysid"))
        })
        .unwrap_or_else(|| root.join("target/release/mrsysid"));
    assert!(
        bin.exists(),
        "build the binary first: cargo build --release ({})",
        bin.display()
    );
    let before = std::env::var_os("MRSYSID_BIN_BEFORE").map(PathBuf::from);
    let vehicle = root.join("data/vehicles/quad_x.toml");
    let dir = std::env::var_os("MRSYSID_BENCH_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let flight = std::env::var("MRSYSID_BENCH_LOG").is_ok_and(|v| v == "flight");
    let (log, second) = if flight {
        // A flight of `rows` samples at 500 Hz, its ω̇ columns left out (derived).
        let log = dir.join(format!("mrsysid-flight-{rows}-no-omega-dot.csv"));
        if !log.exists() {
            simulate_flight(&bin, rows, &log);
        }
        let second = dir.join(format!("mrsysid-flight-{rows}-no-omega-dot-b.csv"));
        shifted_copies(&log, &second, 1, 1);
        (log, second)
    } else {
        let sweep = dir.join("mrsysid-sweep-1m.csv");
        if !sweep.exists() {
            simulate(&bin, &sweep);
        }
        let copies = rows / SWEEP_ROWS;
        let log = dir.join(format!("mrsysid-fit-{rows}.csv"));
        let second = dir.join(format!("mrsysid-fit-{rows}-rotated.csv"));
        numbered_copies(&sweep, &log, copies, 0);
        numbered_copies(&sweep, &second, copies, 1);
        (log, second)
    };
    let mb = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len()) / 1_000_000;
    println!("log: {} ({} rows, {} MB)", log.display(), rows, mb(&log));

    bare_pass(&log, false); // warm the page cache
    bare_pass(&second, false);
    let repeat = repetitions();
    // Pass (a) is timed once before the fits and once after each fit configuration, so
    // its minimum sees the same spread of machine states as the fits' minima.
    let mut parse = Vec::new();
    let mut bare = Vec::new();
    let mut parse_two = Vec::new();
    let mut time_references = |parse: &mut Vec<Duration>| {
        let (b, records) = bare_pass(&log, false);
        assert!(flight || records == rows, "bare pass record count");
        bare.push(b);
        parse.push(bare_pass(&log, true).0);
    };
    time_references(&mut parse);

    let fit_with = |bin: &Path, logs: &[&Path], threads: usize, diagnose: bool| {
        let mut cmd = Command::new(bin);
        cmd.arg("fit").args(logs).arg("--vehicle").arg(&vehicle);
        cmd.args(["--quiet", "--threads", &threads.to_string()]);
        if !diagnose {
            cmd.arg("--no-diagnose");
        }
        run_measured(cmd)
    };
    let bins: Vec<(&str, &Path)> = std::iter::once(("", bin.as_path()))
        .chain(before.as_deref().map(|b| ("before: ", b)))
        .collect();
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let runs: [(&str, bool, usize); 4] = [
        ("(b) fit --no-diagnose --threads 1", false, 1),
        ("(b) fit --no-diagnose --threads 2", false, 2),
        ("(c) fit (with diagnosis) --threads 1", true, 1),
        ("(c) fit (with diagnosis) --threads 2", true, 2),
    ];
    // Every configuration `repeat` times, the binaries alternating; the fastest run of each.
    let mut single: Vec<(String, Measured)> = Vec::new();
    for (name, diagnose, threads) in runs {
        let mut best: Vec<Option<Measured>> = vec![None; bins.len()];
        for _ in 0..repeat {
            for (k, &(_, b)) in bins.iter().enumerate() {
                best[k] = Some(fastest(best[k], fit_with(b, &[&log], threads, diagnose)));
            }
        }
        for (&(tag, _), m) in bins.iter().zip(best) {
            single.push((format!("{tag}{name}"), m.expect("repeat ≥ 1")));
        }
        time_references(&mut parse);
    }
    let mut two_logs: Vec<(&str, Measured, Measured)> = Vec::new();
    for &(tag, b) in &bins {
        let (mut one, mut two) = (None, None);
        for _ in 0..repeat {
            one = Some(fastest(one, fit_with(b, &[&log, &second], 1, false)));
            two = Some(fastest(two, fit_with(b, &[&log, &second], 2, false)));
        }
        two_logs.push((tag, one.expect("repeat ≥ 1"), two.expect("repeat ≥ 1")));
        parse_two.push(bare_pass(&log, true).0 + bare_pass(&second, true).0);
    }

    let min = |d: &[Duration]| d.iter().copied().min().expect("timed at least once");
    let spread = |d: &[Duration]| {
        let secs: Vec<f64> = d.iter().map(Duration::as_secs_f64).collect();
        let (lo, hi) = secs
            .iter()
            .fold((f64::MAX, 0.0f64), |(l, h), &s| (l.min(s), h.max(s)));
        format!("{lo:.2}–{hi:.2} s over {} passes", secs.len())
    };
    let (parse_min, parse_two_min) = (min(&parse), min(&parse_two));
    println!();
    println!("load average before the fits: {}", load.trim());
    println!(
        "each fit: fastest of {repeat} run(s); × (a) against the fastest pass (a), {}",
        spread(&parse)
    );
    println!(
        "{:<52} {:>9} {:>10} {:>8} {:>13}",
        "run", "wall, s", "× (a)", "CPU, s", "peak RSS, MB"
    );
    let row = |name: &str, m: Measured, base: Duration| {
        println!(
            "{:<52} {:>9.2} {:>10.2} {:>8.2} {:>13.1}",
            name,
            m.wall.as_secs_f64(),
            m.wall.as_secs_f64() / base.as_secs_f64(),
            m.cpu.as_secs_f64(),
            m.rss as f64 / 1024.0
        );
    };
    for (name, t) in [
        ("bare csv::ByteRecord pass, no parsing", min(&bare)),
        (
            "(a) csv::ByteRecord pass + std parse of every field",
            parse_min,
        ),
    ] {
        let ratio = t.as_secs_f64() / parse_min.as_secs_f64();
        let secs = t.as_secs_f64();
        println!(
            "{name:<52} {secs:>9.2} {ratio:>10.2} {:>8} {:>13}",
            "-", "-"
        );
    }
    for (name, m) in single {
        row(&name, m, parse_min);
    }
    for (tag, one, two) in two_logs {
        row(
            &format!("{tag}two logs, --no-diagnose --threads 1"),
            one,
            parse_two_min,
        );
        row(
            &format!("{tag}two logs, --no-diagnose --threads 2"),
            two,
            parse_two_min,
        );
        println!(
            "{tag}two logs: 1 thread / 2 threads = {:.2}× (× (a) is against both (a) passes, {:.2} s)",
            one.wall.as_secs_f64() / two.wall.as_secs_f64(),
            parse_two_min.as_secs_f64()
        );
    }
}

/// Runs per configuration: `$MRSYSID_BENCH_REPEAT`, default 3.
fn repetitions() -> usize {
    std::env::var("MRSYSID_BENCH_REPEAT")
        .ok()
        .map(|r| r.parse().expect("MRSYSID_BENCH_REPEAT: a whole number ≥ 1"))
        .unwrap_or(3)
        .max(1)
}

/// The faster (by wall time) of `best` so far and `m`; peak RSS the larger of the two.
fn fastest(best: Option<Measured>, m: Measured) -> Measured {
    match best {
        Some(b) if b.wall <= m.wall => Measured {
            rss: b.rss.max(m.rss),
            ..b
        },
        Some(b) => Measured {
            rss: b.rss.max(m.rss),
            ..m
        },
        None => m,
    }
}

/// Simulates the 1 M-point quad× sweep into `out`.
/// Simulates a quad× flight of `rows` samples (500 Hz, seed 9) into `out` without its
/// `omega_dot_*` columns, so that the fit derives ω̇ as it must for most real logs.
fn simulate_flight(bin: &Path, rows: u64, out: &Path) {
    let full = out.with_extension("with-omega-dot.csv");
    println!("simulating {} (minutes) ...", full.display());
    let seconds = (rows - 1) as f64 / 500.0;
    let status = Command::new(bin)
        .args(["simulate", "--preset", "quad_x", "--mode", "flight"])
        .args(["--duration", &seconds.to_string(), "--log-rate", "500"])
        .args(["--seed", "9", "--out"])
        .arg(&full)
        .status()
        .expect("run mrsysid simulate");
    assert!(status.success(), "mrsysid simulate failed");
    let mut rows_in = lines(&full);
    let header = rows_in.next().expect("header");
    let keep: Vec<bool> = header
        .split(',')
        .map(|c| !c.starts_with("omega_dot"))
        .collect();
    let mut w = BufWriter::new(File::create(out).expect("create log"));
    for line in std::iter::once(header).chain(rows_in) {
        let fields: Vec<&str> = line
            .split(',')
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(f, _)| f)
            .collect();
        writeln!(w, "{}", fields.join(",")).expect("write");
    }
    w.into_inner()
        .expect("write log")
        .sync_all()
        .expect("sync log");
    std::fs::remove_file(&full).expect("remove the full log");
}

fn simulate(bin: &Path, out: &Path) {
    println!("simulating {} (minutes) ...", out.display());
    let status = Command::new(bin)
        .args(["simulate", "--preset", "quad_x", "--mode", "sweep"])
        .args(["--points", &SWEEP_ROWS.to_string(), "--seed", "9", "--out"])
        .arg(out)
        .status()
        .expect("run mrsysid simulate");
    assert!(status.success(), "mrsysid simulate failed");
}

/// Writes `copies` copies of the sweep `src` to `out` (unless it exists), each with its
/// rows rotated by `rotate` (so that logs of other rotations differ), t numbering the
/// rows written 0, 1, 2, … as a sweep's t does (a sweep's t from another start would
/// be read as a clock in ms).
fn numbered_copies(src: &Path, out: &Path, copies: u64, rotate: usize) {
    if out.exists() {
        return;
    }
    // Streamed, never held: the peak RSS `wait4` reports for a child includes this
    // process's at the spawn, so a log held here would count in every fit's.
    let rows = || {
        lines(src)
            .skip(1)
            .map(|l| l.split_once(',').expect("time field").1.to_string())
    };
    let tmp = out.with_extension("partial");
    let mut w = BufWriter::new(File::create(&tmp).expect("create log"));
    writeln!(w, "{}", lines(src).next().expect("header")).expect("write");
    let mut t = 0u64;
    for _ in 0..copies {
        for row in rows().skip(rotate).chain(rows().take(rotate)) {
            writeln!(w, "{t},{row}").expect("write");
            t += 1;
        }
    }
    synced_rename(w, &tmp, out);
}

/// Writes `copies` copies of the CSV `src` to `out` (unless it exists), copy k's time
/// shifted by (`first` + k) × (time span of `src` + its first step).
fn shifted_copies(src: &Path, out: &Path, copies: u64, first: u64) {
    if out.exists() {
        return;
    }
    let times: Vec<f64> = lines(src).skip(1).take(2).map(|l| time_of(&l)).collect();
    let last = lines(src).last().map(|l| time_of(&l)).expect("rows");
    let period = last - times[0] + (times[1] - times[0]);
    let tmp = out.with_extension("partial");
    let mut w = BufWriter::new(File::create(&tmp).expect("create log"));
    for k in 0..copies {
        let offset = (first + k) as f64 * period;
        for (i, line) in lines(src).enumerate() {
            if i == 0 {
                if k == 0 {
                    writeln!(w, "{line}").expect("write");
                }
                continue;
            }
            if offset == 0.0 {
                writeln!(w, "{line}").expect("write");
            } else {
                let (_, rest) = line.split_once(',').expect("time field");
                writeln!(w, "{},{rest}", time_of(&line) + offset).expect("write");
            }
        }
    }
    synced_rename(w, &tmp, out);
}

/// Flushes `w` (writing `tmp`) to disk and renames `tmp` to `out`: on disk before any
/// timing, otherwise the kernel writes the new gigabytes back during the timed runs, on
/// the same two cores.
fn synced_rename(w: BufWriter<File>, tmp: &Path, out: &Path) {
    let file = w.into_inner().expect("write log");
    file.sync_all().expect("sync log");
    drop(file);
    std::fs::rename(tmp, out).expect("rename log");
}

fn lines(path: &Path) -> impl Iterator<Item = String> {
    BufReader::new(File::open(path).expect("open log"))
        .lines()
        .map(|l| l.expect("read log"))
}

fn time_of(line: &str) -> f64 {
    line.split(',')
        .next()
        .and_then(|t| t.parse().ok())
        .expect("time field")
}

/// Reads every record of `path` as bytes on this thread, with `parse` also parsing every
/// field with std's `str::parse::<f64>`; wall time and record count.
fn bare_pass(path: &Path, parse: bool) -> (Duration, u64) {
    let start = Instant::now();
    let mut reader = csv::ReaderBuilder::new()
        .from_path(path)
        .expect("open for the bare pass");
    let mut record = csv::ByteRecord::new();
    let (mut records, mut bytes, mut sum) = (0u64, 0usize, 0.0f64);
    while reader.read_byte_record(&mut record).expect("bare pass") {
        records += 1;
        bytes += record.as_slice().len();
        if parse {
            for field in &record {
                // An empty or malformed field costs its parse attempt like any other.
                let text = std::str::from_utf8(field).unwrap_or("");
                sum += text.parse::<f64>().unwrap_or(0.0);
            }
        }
    }
    std::hint::black_box((bytes, sum));
    (start.elapsed(), records)
}

/// What one `fit` run cost.
#[derive(Debug, Clone, Copy)]
struct Measured {
    wall: Duration,
    /// User + system CPU time.
    cpu: Duration,
    /// Peak resident set size, KiB.
    rss: u64,
}

/// Runs `cmd` to completion; its wall time, CPU time and peak resident set size (from
/// the kernel's accounting of that child alone via `wait4`).
// The child is reaped by `wait4` (which also returns its own resource usage), not by
// `Child::wait`.
#[allow(clippy::zombie_processes)]
fn run_measured(mut cmd: Command) -> Measured {
    let start = Instant::now();
    let child = cmd.spawn().expect("spawn mrsysid fit");
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: `usage` is a plain C struct the kernel fills in; `pid` is our own child,
    // reaped here (the `Child` handle is not waited on afterwards).
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let reaped = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    let wall = start.elapsed();
    assert_eq!(reaped, pid, "wait4");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "mrsysid fit failed: {cmd:?}"
    );
    let secs = |t: libc::timeval| Duration::new(t.tv_sec as u64, t.tv_usec as u32 * 1000);
    Measured {
        wall,
        cpu: secs(usage.ru_utime) + secs(usage.ru_stime),
        rss: usage.ru_maxrss as u64,
    }
}
