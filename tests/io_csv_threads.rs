//! The CSV reader tokenises (and parses the first slots) on a second thread, in batches
//! of records: errors must still come out first-in-file and first-in-slot-order, with the
//! same messages, wherever they fall relative to batch and thread boundaries.

mod io_support;

use std::path::{Path, PathBuf};

use io_support::quad;
use mrsysid::io::contract_csv::BATCH_RECORDS;
use mrsysid::io::{InvalidSamples, ReadOptions, open_log};

const HEADER: &str = "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz";

/// Data row `k` (line k + 2) of a valid contract file at 100 Hz.
fn row(k: usize) -> String {
    format!(
        "{},1,0,0,0.1,0,0,900,900,900,900,0,0,-11.8,0,0,0",
        0.01 * k as f64
    )
}

/// `n` rows with row `k` edited by `edit(k, fields)`.
fn file(name: &str, n: usize, edit: impl Fn(usize, &mut Vec<String>)) -> PathBuf {
    let mut text = format!("{HEADER}\n");
    for k in 0..n {
        let mut fields: Vec<String> = row(k).split(',').map(str::to_string).collect();
        edit(k, &mut fields);
        text += &fields.join(",");
        text.push('\n');
    }
    let dir = std::env::temp_dir().join(format!("mrsysid-csv-threads-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn column(name: &str) -> usize {
    HEADER.split(',').position(|c| c == name).unwrap()
}

/// The first error reading `path`, the same with the tokeniser on its own thread and
/// inline (`--threads 1`).
fn first_error(path: &Path) -> String {
    let read = |reader_thread: bool| {
        let opts = ReadOptions {
            reader_thread,
            ..ReadOptions::default()
        };
        let reader = open_log(path, &quad(0.0), None, &opts).unwrap();
        for c in reader {
            if let Err(e) = c {
                return e.to_string();
            }
        }
        panic!("{}: no error", path.display())
    };
    let threaded = read(true);
    assert_eq!(
        threaded,
        read(false),
        "threaded and inline tokenising differ"
    );
    threaded
}

#[test]
fn first_bad_slot_of_a_row_is_named_whichever_thread_parses_it() {
    // "v" is parsed on the tokenising thread, "q" and "fx" on the caller's (it takes
    // the first 30 % of the 17 slots: t,u,v,w,p): the message names the first in slot
    // order (t,u,v,w,p,q,r,omega..,fx..).
    let both = file("both.csv", 10, |k, f| {
        if k == 4 {
            f[column("fx")] = "late".into();
            f[column("v")] = "early".into();
        }
    });
    assert_eq!(
        first_error(&both),
        "both.csv: line 6, column \"v\": not a number (\"early\")"
    );
    let late = file("late.csv", 10, |k, f| {
        if k == 4 {
            f[column("fx")] = "x".into();
            f[column("q")] = "y".into();
        }
    });
    assert_eq!(
        first_error(&late),
        "late.csv: line 6, column \"q\": not a number (\"y\")"
    );
}

#[test]
fn first_bad_row_is_named_across_batch_boundaries() {
    // Bad rows in the second and third batches: the earlier one in the file wins.
    let first = BATCH_RECORDS + 3;
    let path = file("batches.csv", 3 * BATCH_RECORDS, |k, f| {
        if k == first {
            f[column("mz")] = "nope".into();
        }
        if k == 2 * BATCH_RECORDS + 1 {
            f[column("t")] = "bad".into();
        }
    });
    assert_eq!(
        first_error(&path),
        format!(
            "batches.csv: line {}, column \"mz\": not a number (\"nope\")",
            first + 2
        )
    );
}

#[test]
fn invalid_utf8_in_a_late_column_names_it() {
    let mut text = format!("{HEADER}\n{}\n{}\n", row(0), row(1)).into_bytes();
    text.extend_from_slice(b"0.02,1,0,0,0.1,0,0,900,900,900,900,\xff,0,-11.8,0,0,0\n");
    let path = std::env::temp_dir().join(format!(
        "mrsysid-csv-threads-utf8-{}.csv",
        std::process::id()
    ));
    std::fs::write(&path, text).unwrap();
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    assert_eq!(
        first_error(&path),
        format!("{name}: line 4, column \"fx\": not a number (\"\u{fffd}\")")
    );
}

#[test]
fn dropped_rows_are_counted_on_both_sides_of_batch_boundaries() {
    // Bad rows at the last record of the first batch, the first of the second (one
    // failing on each thread's slots) and in the middle of the fourth batch.
    let bad = [BATCH_RECORDS - 1, BATCH_RECORDS, 3 * BATCH_RECORDS + 17];
    let n = 4 * BATCH_RECORDS;
    let path = file("drop.csv", n, |k, f| {
        if k == bad[0] {
            f[column("u")] = "u?".into();
        } else if k == bad[1] {
            f[column("fz")] = "fz?".into();
        } else if k == bad[2] {
            f[column("w")] = "w?".into();
            f[column("mx")] = "mx?".into();
        }
    });
    for reader_thread in [true, false] {
        let opts = ReadOptions {
            invalid: InvalidSamples::DropAndCount,
            reader_thread,
            ..ReadOptions::default()
        };
        check_drops(&path, &opts, n, &bad);
    }
}

fn check_drops(path: &Path, opts: &ReadOptions, n: usize, bad: &[usize; 3]) {
    let mut reader = open_log(path, &quad(0.0), None, opts).unwrap();
    let samples: usize = reader.by_ref().map(|c| c.unwrap().len()).sum();
    let s = reader.summary();
    assert_eq!(samples, n - bad.len());
    // rows_read counts the rows that parsed (as before the reader was threaded).
    assert_eq!(s.rows_read, (n - bad.len()) as u64);
    assert_eq!(s.dropped.get("not a number"), Some(&(bad.len() as u64)));
    assert_eq!(
        s.first_dropped,
        vec![
            format!(
                "drop.csv: line {}, column \"u\": not a number (\"u?\")",
                bad[0] + 2
            ),
            format!(
                "drop.csv: line {}, column \"fz\": not a number (\"fz?\")",
                bad[1] + 2
            ),
            format!(
                "drop.csv: line {}, column \"w\": not a number (\"w?\")",
                bad[2] + 2
            ),
        ]
    );
}
