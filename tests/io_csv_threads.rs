//! The CSV reader cuts the text into byte ranges of whole records and parses them on
//! worker threads (or inline): rows, values and errors must come out first-in-file and
//! first-in-slot-order, with the same messages and true line numbers, wherever they fall
//! relative to range boundaries, for any range size and thread count; line ends (LF,
//! CRLF, CR, none at the end) and quoting must not change what is read.

mod io_support;
mod scratch;

use std::path::{Path, PathBuf};

use io_support::quad;
use mrsysid::SampleChunk;
use mrsysid::io::{InvalidSamples, ReadOptions, open_log};

/// A block of rows (10–12 kB: a data row of [`row`] is 50–60 bytes) for placing bad rows
/// many ranges apart.
const ROWS: usize = 200;

/// (parse threads, range bytes) combinations every check reads with: inline, one and
/// three workers; the default range size (one range for these files), ranges of about
/// 17 rows, and 97-byte ranges (one or two rows each).
const SETTINGS: [(usize, usize); 6] = [
    (0, mrsysid::io::DEFAULT_RANGE_BYTES),
    (1, mrsysid::io::DEFAULT_RANGE_BYTES),
    (0, 1000),
    (1, 1000),
    (3, 1000),
    (3, 97),
];

fn options(parse_threads: usize, range_bytes: usize) -> ReadOptions {
    ReadOptions {
        parse_threads,
        range_bytes,
        ..ReadOptions::default()
    }
}

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
    let path = scratch::dir("csv-threads").join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn column(name: &str) -> usize {
    HEADER.split(',').position(|c| c == name).unwrap()
}

/// The first error reading `path`, the same for every [`SETTINGS`] entry.
fn first_error(path: &Path) -> String {
    let read = |(threads, bytes): (usize, usize)| {
        let reader = open_log(path, &quad(0.0), None, &options(threads, bytes)).unwrap();
        for c in reader {
            if let Err(e) = c {
                return e.to_string();
            }
        }
        panic!("{}: no error", path.display())
    };
    let first = read(SETTINGS[0]);
    for s in SETTINGS {
        assert_eq!(first, read(s), "{s:?} differs from {:?}", SETTINGS[0]);
    }
    first
}

/// Every chunk of `path` read with `opts`.
fn chunks(path: &Path, opts: &ReadOptions) -> Vec<SampleChunk> {
    let reader = open_log(path, &quad(0.0), None, opts).unwrap();
    reader.map(|c| c.unwrap()).collect()
}

#[test]
fn first_bad_slot_of_a_row_is_named_whatever_the_ranges() {
    // The message names the first bad value in slot order (t,u,v,w,p,q,r,omega..,fx..),
    // not in column order.
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
fn first_bad_row_is_named_across_range_boundaries() {
    // Bad rows ~200 and ~400 rows in (past many ranges of 97 and 1000 bytes, and parsed
    // by different workers): the earlier one in the file wins.
    let first = ROWS + 3;
    let path = file("batches.csv", 3 * ROWS, |k, f| {
        if k == first {
            f[column("mz")] = "nope".into();
        }
        if k == 2 * ROWS + 1 {
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
    let path = scratch::dir("csv-threads").join("utf8.csv");
    std::fs::write(&path, text).unwrap();
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    assert_eq!(
        first_error(&path),
        format!("{name}: line 4, column \"fx\": not a number (\"\u{fffd}\")")
    );
}

#[test]
fn dropped_rows_are_counted_on_both_sides_of_range_boundaries() {
    // Two neighbouring bad rows and one further on, for every range size and thread
    // count: counted once each, named with their true lines, in file order.
    let bad = [ROWS - 1, ROWS, 3 * ROWS + 17];
    let n = 4 * ROWS;
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
    for (threads, bytes) in SETTINGS {
        let opts = ReadOptions {
            invalid: InvalidSamples::DropAndCount,
            ..options(threads, bytes)
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

#[test]
fn a_bad_value_deep_in_a_large_file_names_its_true_line() {
    // 60 000 rows (~3.4 MB): with the default 512 KiB ranges the bad row, 50 000 rows in,
    // is in the sixth range; with 64 KiB ranges in about the 45th.
    let bad = 50_000;
    let path = file("deep.csv", 60_000, |k, f| {
        if k == bad {
            f[column("omega_3")] = "9OO".into();
        }
    });
    for (threads, bytes) in [(0, 1 << 19), (1, 1 << 19), (3, 1 << 16), (0, 1 << 16)] {
        let mut reader = open_log(&path, &quad(0.0), None, &options(threads, bytes)).unwrap();
        let mut samples = 0;
        let error = loop {
            match reader.next_chunk() {
                Some(Ok(c)) => samples += c.len(),
                Some(Err(e)) => break e.to_string(),
                None => panic!("no error"),
            }
        };
        assert_eq!(
            error,
            format!(
                "deep.csv: line {}, column \"omega_3\": not a number (\"9OO\")",
                bad + 2
            ),
            "{threads} threads, {bytes}-byte ranges"
        );
        // The rows before it were read and handed out in full chunks (the last partial
        // chunk is not handed out when the error stops the reader).
        assert!(
            samples <= bad && bad - samples < mrsysid::CHUNK_SAMPLES,
            "{samples} samples"
        );
    }
}

/// The text of a valid 500-row file with `end` between rows, and after the last row
/// when `trailing`.
fn text_with(end: &str, trailing: bool) -> Vec<u8> {
    let mut text = format!("{HEADER}{end}");
    for k in 0..500 {
        text += &row(k);
        if k + 1 < 500 || trailing {
            text += end;
        }
    }
    text.into_bytes()
}

fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch::dir("csv-threads").join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn line_ends_and_quoting_do_not_change_what_is_read() {
    // Tolerance zero: the same text of every value gives the same f64. Every variant is
    // read with every setting and compared with the LF file read in one range inline.
    let reference = chunks(
        &write("lf.csv", &text_with("\n", true)),
        &options(0, 1 << 19),
    );
    assert_eq!(reference.iter().map(SampleChunk::len).sum::<usize>(), 500);
    let quoted: String = String::from_utf8(text_with("\n", true))
        .unwrap()
        .lines()
        .map(|l| {
            let fields: Vec<String> = l.split(',').map(|f| format!("\"{f}\"")).collect();
            fields.join(",") + "\n"
        })
        .collect();
    let variants = [
        ("no-final-lf.csv", text_with("\n", false)),
        ("crlf.csv", text_with("\r\n", true)),
        ("crlf-no-final.csv", text_with("\r\n", false)),
        ("cr.csv", text_with("\r", true)),
        ("quoted.csv", quoted.into_bytes()),
    ];
    for (name, bytes) in variants {
        let path = write(name, &bytes);
        for (threads, range) in SETTINGS {
            assert_eq!(
                chunks(&path, &options(threads, range)),
                reference,
                "{name}, {threads} threads, {range}-byte ranges"
            );
        }
    }
}

#[test]
fn errors_name_the_true_line_whatever_the_line_ends() {
    // Row 300 (line 302) is bad; a blank line after row 100 (CRLF: two) pushes it to
    // line 303. The CR-only file has no line feeds: the csv tokeniser counts lines by
    // line feeds, so everything is on line 1.
    let bad = |end: &str, blank: bool| {
        let mut text = format!("{HEADER}{end}");
        for k in 0..500 {
            text += &if k == 300 {
                row(k).replacen(",900,", ",x,", 1)
            } else {
                row(k)
            };
            text += end;
            if blank && k == 100 {
                text += end;
            }
        }
        text.into_bytes()
    };
    let cases = [
        ("bad-lf.csv", bad("\n", false), 302),
        ("bad-crlf.csv", bad("\r\n", false), 302),
        ("bad-blank-lf.csv", bad("\n", true), 303),
        ("bad-blank-crlf.csv", bad("\r\n", true), 303),
        ("bad-cr.csv", bad("\r", false), 1),
    ];
    for (name, bytes, line) in cases {
        assert_eq!(
            first_error(&write(name, &bytes)),
            format!("{name}: line {line}, column \"omega_1\": not a number (\"x\")")
        );
    }
}
