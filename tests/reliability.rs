//! Mistakes users make, end to end (issue 41): a closed stdout, an output path that is an
//! input, the same log twice, a validation log that is also fitted, rotor speeds in RPM,
//! time in milliseconds, logs too short to fit, semicolon CSV with decimal commas, a
//! broken `.csv.gz`, `--threads 0`; and the messages of empty ULog and MCAP inputs. Each
//! run ends with the documented exit code and a message naming the file and what to do,
//! and no input is ever overwritten.

mod io_support;
mod scratch;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use io_support::quad;
use mrsysid::error::Error;
use mrsysid::io::{Mapping, ReadOptions, open_log};
use mrsysid::{Identification, Vehicle};

const VEHICLE: &str = "data/vehicles/quad_x.toml";
const FLIGHT: &str = "data/quad_x_flight_quadratic_drag.csv";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A scratch directory of its own for test `tag`.
fn dir(tag: &str) -> PathBuf {
    let d = scratch::dir("reliability").join(tag);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn mrsysid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mrsysid"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("binary runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The shipped 30 s quad-x flight (100 Hz, every contract column) as text.
fn flight_text() -> String {
    std::fs::read_to_string(root().join(FLIGHT)).unwrap()
}

/// `text` (a contract CSV) with `f(column, value)` applied to every data value.
fn map_values(text: &str, f: impl Fn(&str, f64) -> f64) -> String {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = header.join(",") + "\n";
    for line in lines {
        let row: Vec<String> = line
            .split(',')
            .zip(&header)
            .map(|(v, c)| format!("{}", f(c, v.parse().unwrap())))
            .collect();
        out += &row.join(",");
        out.push('\n');
    }
    out
}

/// The header and the first `rows` data rows of `text`.
fn head(text: &str, rows: usize) -> String {
    text.lines()
        .take(rows + 1)
        .map(|l| l.to_string() + "\n")
        .collect()
}

fn write(path: &Path, bytes: impl AsRef<[u8]>) -> PathBuf {
    std::fs::write(path, bytes).unwrap();
    path.to_path_buf()
}

// 1. A closed stdout.

/// `fit … | head` with the reader gone before anything is printed: the run ends quietly
/// (exit 0, no panic) and still writes its files; so does `vehicle` printing its TOML.
#[test]
fn a_closed_stdout_ends_the_run_quietly() {
    let d = dir("pipe");
    let json = d.join("report.json");
    let ulog = write(
        &d.join("px4.ulg"),
        io_support::px4_like_log(io_support::Px4Log {
            duration_us: 2_000_000,
            dropout_at: None,
        }),
    );
    let cases: [Vec<&str>; 3] = [
        vec!["fit", FLIGHT, "--vehicle", VEHICLE, "--no-diagnose"],
        vec!["diagnose", FLIGHT, "--vehicle", VEHICLE, "--json", s(&json)],
        vec!["vehicle", "--from-ulog", s(&ulog)],
    ];
    for args in cases {
        // The reading end is closed before the binary starts: its first write fails.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_mrsysid"))
            .args(&args)
            .current_dir(root())
            .stdout(writer)
            .output()
            .unwrap();
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    // The JSON report of the diagnose run was written after the printing failed.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["schema_version"], 2);
}

// 2. An output that is an input.

/// A cheap fingerprint of a file's bytes, to show an input was not touched.
fn bytes_of(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap()
}

/// Every output option naming an input — by the same string, a symbolic link, a hard
/// link, a path through `..` — is refused with exit 2 before any work, naming both, and
/// the input keeps its bytes. Two outputs naming one file are refused too.
#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_kept() {
    let d = dir("outputs");
    let log = write(&d.join("flight.csv"), flight_text());
    let vehicle = write(
        &d.join("quad.toml"),
        std::fs::read(root().join(VEHICLE)).unwrap(),
    );
    let mapping = write(
        &d.join("map.toml"),
        std::fs::read(root().join("examples/neurobem.toml")).unwrap(),
    );
    let ulog = write(
        &d.join("px4.ulg"),
        io_support::px4_like_log(io_support::Px4Log {
            duration_us: 2_000_000,
            dropout_at: None,
        }),
    );
    let symlink = d.join("symlink.csv");
    std::os::unix::fs::symlink(&log, &symlink).unwrap();
    let hard = d.join("hard.csv");
    std::fs::hard_link(&log, &hard).unwrap();
    std::fs::create_dir_all(d.join("sub")).unwrap();
    let dotted = d.join("sub/../flight.csv");
    let plots = d.join("plots");
    std::fs::create_dir_all(&plots).unwrap();
    std::fs::hard_link(&log, plots.join("fit_time_histories.svg")).unwrap();
    // A model to predict and validate with.
    let model = d.join("model.toml");
    let out = mrsysid(&[
        "fit",
        s(&log),
        "--vehicle",
        s(&vehicle),
        "--model-out",
        s(&model),
        "--no-diagnose",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let fit = |extra: &[&str]| -> Vec<String> {
        let mut a = vec!["fit", s(&log), "--vehicle", s(&vehicle), "--quiet"];
        a.extend_from_slice(extra);
        a.into_iter().map(String::from).collect()
    };
    let owned = |a: &[&str]| -> Vec<String> { a.iter().map(|x| x.to_string()).collect() };
    let cases: Vec<(Vec<String>, &Path, &str)> = vec![
        (fit(&["--json", s(&log)]), &log, "--json"),
        (fit(&["--json", s(&symlink)]), &log, "--json"),
        (fit(&["--model-out", s(&hard)]), &log, "--model-out"),
        (fit(&["--json", s(&dotted)]), &log, "--json"),
        (fit(&["--json", s(&vehicle)]), &vehicle, "--json"),
        (
            fit(&["--mapping", s(&mapping), "--model-out", s(&mapping)]),
            &mapping,
            "--model-out",
        ),
        (fit(&["--plots", s(&plots)]), &log, "--plots"),
        (
            owned(&["predict", "--model", s(&model), s(&log), "--out", s(&model)]),
            &model,
            "--out",
        ),
        (
            owned(&["predict", "--model", s(&model), s(&log), "--out", s(&hard)]),
            &log,
            "--out",
        ),
        (
            owned(&["validate", "--model", s(&model), s(&log), "--json", s(&log)]),
            &log,
            "--json",
        ),
        (
            owned(&["vehicle", "--from-ulog", s(&ulog), "--out", s(&ulog)]),
            &ulog,
            "--out",
        ),
        (
            owned(&[
                "simulate",
                "--vehicle",
                s(&vehicle),
                "--mode",
                "sweep",
                "--points",
                "10",
                "--out",
                s(&vehicle),
            ]),
            &vehicle,
            "--out",
        ),
    ];
    for (args, input, option) in cases {
        let before = bytes_of(input);
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = mrsysid(&a);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{a:?}: {err}");
        assert!(
            err.contains(option) && err.contains("is the same file as"),
            "{a:?}: {err}"
        );
        let name = input.file_name().unwrap().to_str().unwrap();
        assert!(err.contains(name), "{a:?} must name {name}: {err}");
        assert!(err.contains("refusing to overwrite"), "{a:?}: {err}");
        assert!(bytes_of(input) == before, "{a:?} changed {name}");
    }
    // Two outputs naming one file.
    let both = d.join("both.out");
    let out = mrsysid(
        &fit(&["--json", s(&both), "--model-out", s(&both)])
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--json") && err.contains("--model-out") && err.contains("same file"),
        "{err}"
    );
    assert!(!both.exists());
}

// 3. and 4. The same log twice; a validation log that is fitted.

/// A log given twice — the same path, a copy under another name, a compressed copy — is
/// refused with exit 2 naming both; two logs of the same size that differ are fitted.
#[test]
fn the_same_log_twice_is_refused_naming_both() {
    let d = dir("twice");
    let text = flight_text();
    let a = write(&d.join("a.csv"), &text);
    let b = write(&d.join("b.csv"), &text);
    let gz = |name: &str| {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(text.as_bytes()).unwrap();
        write(&d.join(name), e.finish().unwrap())
    };
    let (agz, bgz) = (gz("a.csv.gz"), gz("b.csv.gz"));
    for (x, y) in [(&a, &b), (&a, &a), (&agz, &bgz)] {
        let out = mrsysid(&["fit", s(x), s(y), "--vehicle", VEHICLE, "--quiet"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains(s(x)) && err.contains(s(y)) && err.contains("same log"),
            "{err}"
        );
    }
    // The same size, one digit different (the last digit of the file): not the same log.
    let mut other = text.clone().into_bytes();
    let at = other.iter().rposition(u8::is_ascii_digit).unwrap();
    other[at] = if other[at] == b'9' { b'8' } else { b'9' };
    let c = write(&d.join("c.csv"), &other);
    assert_eq!(bytes_of(&a).len(), bytes_of(&c).len());
    let out = mrsysid(&[
        "fit",
        s(&a),
        s(&c),
        "--vehicle",
        VEHICLE,
        "--quiet",
        "--no-diagnose",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    // The library refuses it too, files and logs in memory alike.
    let vehicle = Vehicle::from_toml_file(&root().join(VEHICLE)).unwrap();
    let e = Identification::new(vehicle.clone())
        .log(a.as_path())
        .log(b.as_path())
        .run()
        .unwrap_err();
    assert!(matches!(e, Error::Request(_)), "{e:?}");
    assert!(e.to_string().contains("same log"), "{e}");
    assert_eq!(e.exit_code(), 2);
    let samples: Vec<mrsysid::Sample> = {
        let mut reader = open_log(&a, &vehicle, None, &ReadOptions::default()).unwrap();
        let mut v = Vec::new();
        while let Some(c) = reader.next_chunk() {
            let c = c.unwrap();
            v.extend((0..c.len()).map(|k| c.sample(k)));
        }
        v
    };
    let e = Identification::new(vehicle)
        .samples("first", samples.clone())
        .samples("second", samples)
        .run()
        .unwrap_err();
    assert!(e.to_string().contains("first"), "{e}");
    assert!(e.to_string().contains("second"), "{e}");
}

/// A `--validate` log that is also a fit log (the same path, or a copy) is refused with
/// exit 2 naming it: figures called unbiased must not come from fitted data.
#[test]
fn a_validation_log_that_is_fitted_is_refused() {
    let d = dir("validate");
    let a = write(&d.join("a.csv"), flight_text());
    let copy = write(&d.join("copy.csv"), flight_text());
    for v in [&a, &copy] {
        let out = mrsysid(&[
            "fit",
            s(&a),
            "--validate",
            s(v),
            "--vehicle",
            VEHICLE,
            "--quiet",
        ]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!("validation log {}", s(v))) && err.contains("fit log"),
            "{err}"
        );
    }
}

// 5. Rotor speeds in RPM.

/// A vehicle with 8-inch rotors hovering at about 9 750 RPM, logged in RPM under the
/// contract's rad/s (all values within the 15 000 rad/s range check): refused with exit 2
/// naming the file, the column, the tip Mach number and the unit to declare.
#[test]
fn rotor_speeds_in_rpm_are_refused_by_their_tip_mach_number() {
    let d = dir("rpm");
    let vehicle = write(
        &d.join("eight_inch.toml"),
        std::fs::read_to_string(root().join(VEHICLE))
            .unwrap()
            .replace("rotor_radius = 0.0635", "rotor_radius = 0.098"),
    );
    // The shipped flight's rotor speeds (hover 2168 rad/s, peaks 3281 rad/s) times 4.5:
    // peaks below the 15 000 rad/s range check, hover about 9 750 — RPM of 1021 rad/s.
    let scale = 4.5;
    let log = write(
        &d.join("rpm.csv"),
        map_values(&flight_text(), |c, v| {
            if c.starts_with("omega_") && !c.starts_with("omega_dot") {
                v * scale
            } else {
                v
            }
        }),
    );
    let out = mrsysid(&["fit", s(&log), "--vehicle", s(&vehicle), "--quiet"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for needle in ["rpm.csv", "column \"omega_1\"", "Mach ", "unit = \"rpm\""] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
}

// 6. Time in milliseconds.

/// Every contract signal in its own `[signals]` table, time in `time_unit`.
fn contract_mapping(time_unit: &str) -> String {
    let mut m = format!("[time]\ncolumns = [\"t\"]\nunit = \"{time_unit}\"\n");
    for (name, cols) in [
        ("velocity_body", "\"u\", \"v\", \"w\""),
        ("rates", "\"p\", \"q\", \"r\""),
        (
            "rotor_speeds",
            "\"omega_1\", \"omega_2\", \"omega_3\", \"omega_4\"",
        ),
        (
            "rotor_accelerations",
            "\"omega_dot_1\", \"omega_dot_2\", \"omega_dot_3\", \"omega_dot_4\"",
        ),
        ("force", "\"fx\", \"fy\", \"fz\""),
        ("moment", "\"mx\", \"my\", \"mz\""),
        ("height", "\"height\""),
        ("attitude", "\"qw\", \"qx\", \"qy\", \"qz\""),
    ] {
        m += &format!("[signals.{name}]\ncolumns = [{cols}]\n");
    }
    m
}

/// The shipped flight's first 2000 rows (20 s at 100 Hz) with time in ms or µs: refused
/// with exit 2 naming the file and the likely unit; the fix the message gives (a mapping
/// declaring that unit) makes the same file fit.
#[test]
fn time_in_milliseconds_is_named_and_the_suggested_fix_works() {
    let d = dir("ms");
    for (unit, factor, word) in [("ms", 1e3, "milliseconds"), ("us", 1e6, "microseconds")] {
        let log = write(
            &d.join(format!("time_{unit}.csv")),
            map_values(&head(&flight_text(), 2000), |c, v| {
                if c == "t" { (v * factor).round() } else { v }
            }),
        );
        let out = mrsysid(&["fit", s(&log), "--vehicle", VEHICLE, "--quiet"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        let (file, unit_line) = (format!("time_{unit}.csv"), format!("unit = \"{unit}\""));
        for needle in [file.as_str(), word, unit_line.as_str()] {
            assert!(err.contains(needle), "missing {needle}: {err}");
        }
        let mapping = write(&d.join(format!("{unit}.toml")), contract_mapping(unit));
        let out = mrsysid(&[
            "fit",
            s(&log),
            "--vehicle",
            VEHICLE,
            "--mapping",
            s(&mapping),
            "--quiet",
            "--no-diagnose",
        ]);
        assert!(out.status.success(), "{unit}: {}", stderr(&out));
    }
}

/// A test-point sweep whose t numbers its points 0, 1, 2, … (as `mrsysid simulate --mode
/// sweep` writes it) spans more than a day from 86 401 points on: the shipped sweep's 2000
/// points written 45 times (90 000, "spanning" 25 h) fit. The same rows with t starting
/// at 7, which is what a 1 kHz clock in whole ms looks like, are refused as ms; a mapping
/// declaring seconds is believed.
#[test]
fn a_long_numbered_sweep_fits_and_a_declared_time_unit_is_believed() {
    let d = dir("numbered");
    let sweep = std::fs::read_to_string(root().join("data/quad_x_sweep.csv")).unwrap();
    let mut lines = sweep.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.map(|l| l.split_once(',').unwrap().1).collect();
    let numbered = |first: usize| {
        let mut text = format!("{header}\n");
        for k in 0..45 * rows.len() {
            text += &format!("{},{}\n", first + k, rows[k % rows.len()]);
        }
        text
    };
    let fit = |log: &Path, mapping: Option<&Path>| {
        let mut args = vec![
            "fit",
            s(log),
            "--vehicle",
            VEHICLE,
            "--quiet",
            "--no-diagnose",
        ];
        if let Some(m) = mapping {
            args.extend(["--mapping", s(m)]);
        }
        mrsysid(&args)
    };
    let sweep_log = write(&d.join("sweep.csv"), numbered(0));
    let out = fit(&sweep_log, None);
    assert!(out.status.success(), "{}", stderr(&out));
    let clock = write(&d.join("clock.csv"), numbered(7));
    let out = fit(&clock, None);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for needle in ["clock.csv", "milliseconds", "unit = \"ms\""] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
    let mut mapping = "[time]\ncolumns = [\"t\"]\nunit = \"s\"\n".to_string();
    for (name, cols) in [
        ("velocity_body", "u v w"),
        ("rates", "p q r"),
        ("rotor_speeds", "omega_1 omega_2 omega_3 omega_4"),
        (
            "rotor_accelerations",
            "omega_dot_1 omega_dot_2 omega_dot_3 omega_dot_4",
        ),
        ("force", "fx fy fz"),
        ("moment", "mx my mz"),
    ] {
        let cols: Vec<String> = cols.split(' ').map(|c| format!("\"{c}\"")).collect();
        mapping += &format!("[signals.{name}]\ncolumns = [{}]\n", cols.join(", "));
    }
    let seconds = write(&d.join("seconds.toml"), mapping);
    let out = fit(&clock, Some(&seconds));
    assert!(out.status.success(), "{}", stderr(&out));
}

/// The shipped sweep without its `omega_dot` columns: its points, 1 s apart, cannot be
/// differentiated; the refusal (exit 1) says so and names what the log must carry.
#[test]
fn a_sweep_without_rotor_accelerations_is_told_to_carry_them() {
    let d = dir("sweep-no-omega-dot");
    let sweep = std::fs::read_to_string(root().join("data/quad_x_sweep.csv")).unwrap();
    let cut: String = sweep
        .lines()
        .map(|l| l.split(',').take(17).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    assert!(cut.starts_with("t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz\n"));
    let log = write(&d.join("points.csv"), cut);
    let out = mrsysid(&["fit", s(&log), "--vehicle", VEHICLE, "--quiet"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    for needle in [
        "points.csv",
        "rows are 1 s apart",
        "must carry",
        "rotor accelerations",
    ] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
}

// 7. Logs too short to fit.

/// A header and one data row, a 3 s log, and one row whose moments must be derived: exit
/// 1 (the data cannot support a fit), naming the file and saying what is too short.
#[test]
fn logs_too_short_to_fit_exit_1_saying_what_is_too_short() {
    let d = dir("short");
    let text = flight_text();
    let one = write(&d.join("one.csv"), head(&text, 1));
    let out = mrsysid(&["fit", s(&one), "--vehicle", VEHICLE, "--quiet"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    for needle in ["one.csv", "1 sample", "at least 10 s"] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
    let short = write(&d.join("short.csv"), head(&text, 300));
    let out = mrsysid(&["fit", s(&short), "--vehicle", VEHICLE, "--quiet"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    for needle in ["short.csv", "300 samples", "2.99 s", "at least 10 s"] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
    // Without moments they are derived from the rates, which one row cannot give.
    let no_moments: String = head(&text, 1)
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            [&f[..14], &f[17..]].concat().join(",") + "\n"
        })
        .collect();
    assert!(
        no_moments
            .starts_with("t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,omega_dot_1")
    );
    let derived = write(&d.join("derived.csv"), no_moments);
    let out = mrsysid(&["fit", s(&derived), "--vehicle", VEHICLE, "--quiet"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    for needle in ["derived.csv", "1 row", "too short to differentiate"] {
        assert!(err.contains(needle), "missing {needle}: {err}");
    }
}

// 8. Semicolon CSV with decimal commas.

/// A European spreadsheet export (`;` between fields, decimal commas) and a tab-separated
/// file read as the comma file: the same report, bit for bit. A bad value in the
/// semicolon file is named with its line, column and text as written.
#[test]
fn semicolon_csv_with_decimal_commas_reads_as_the_comma_file() {
    let text = head(&flight_text(), 1500);
    let report = |tag: &str, body: &str| -> String {
        // The same file name in every directory: reports name their logs.
        let d = dir(&format!("dialect-{tag}"));
        let log = write(&d.join("log.csv"), body);
        let json = d.join("report.json");
        let out = mrsysid(&[
            "fit",
            s(&log),
            "--vehicle",
            VEHICLE,
            "--json",
            s(&json),
            "--no-diagnose",
            "--quiet",
        ]);
        assert!(out.status.success(), "{tag}: {}", stderr(&out));
        std::fs::read_to_string(json).unwrap()
    };
    let comma = report("comma", &text);
    let semicolon = text.replace(',', ";").replace('.', ",");
    assert!(semicolon.contains("0,057897"));
    assert_eq!(report("semicolon", &semicolon), comma);
    assert_eq!(report("tab", &text.replace(',', "\t")), comma);
    // A bad value: named as in the comma file, with the text as written.
    let d = dir("dialect-bad");
    let mut lines: Vec<String> = semicolon.lines().map(String::from).collect();
    let mut fields: Vec<String> = lines[3].split(';').map(String::from).collect();
    fields[1] = "1,2,3".into();
    lines[3] = fields.join(";");
    let bad = write(&d.join("bad.csv"), lines.join("\n") + "\n");
    let out = mrsysid(&["fit", s(&bad), "--vehicle", VEHICLE, "--quiet"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("bad.csv: line 4, column \"u\": not a number (\"1,2,3\")"),
        "{}",
        stderr(&out)
    );
}

// 9. A broken .csv.gz.

/// A truncated `.csv.gz` and one whose checksum does not match: the error names the
/// file, the line reached and the compressed and decompressed byte offsets.
#[test]
fn a_broken_csv_gz_names_the_line_and_offset_reached() {
    use std::io::Write;
    let d = dir("gz");
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(flight_text().as_bytes()).unwrap();
    let gz = e.finish().unwrap();
    let truncated = write(&d.join("truncated.csv.gz"), &gz[..gz.len() / 2]);
    // A flipped bit in the CRC-32 of the trailer (the last 8 bytes: CRC-32, size): the
    // text decodes whole, and the check at its end fails. (Flipped bits inside the
    // deflate data may decode to other text without any error until then.)
    let mut bytes = gz.clone();
    let crc = bytes.len() - 8;
    bytes[crc] ^= 1;
    let corrupt = write(&d.join("corrupt.csv.gz"), bytes);
    for path in [truncated, corrupt] {
        let out = mrsysid(&["fit", s(&path), "--vehicle", VEHICLE, "--quiet"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        let name = path.file_name().unwrap().to_str().unwrap();
        assert!(err.contains(&format!("{name}: line ")), "{err}");
        assert!(err.contains("compressed byte"), "{err}");
        assert!(err.contains("byte") && err.contains("of text"), "{err}");
    }
}

// 10. --threads 0.

#[test]
fn zero_threads_is_refused() {
    let out = mrsysid(&["fit", FLIGHT, "--vehicle", VEHICLE, "--threads", "0"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--threads") && err.contains("at least 1"),
        "{err}"
    );
}

// Also: empty ULog and MCAP inputs, missing MCAP topics and fields, NaN in JSON.

/// The first error reading `path` with `mapping`.
fn first_error(path: &Path, mapping: &Mapping) -> String {
    match open_log(path, &quad(0.0), Some(mapping), &ReadOptions::default()) {
        Err(e) => e.to_string(),
        Ok(mut r) => loop {
            match r.next_chunk() {
                Some(Err(e)) => break e.to_string(),
                Some(Ok(_)) => {}
                None => panic!("{}: no error", path.display()),
            }
        },
    }
}

/// A ULog with formats and parameters but no data message says so.
#[test]
fn a_ulog_without_data_messages_says_so() {
    use mrsysid::io::fixtures::ulog::UlogWriter;
    let mut w = UlogWriter::new(0);
    w.flag_bits([0; 8], [0; 8], [0; 3]);
    w.format("s:uint64_t timestamp;double[3] v;double[3] w;double[4] o;double[3] f;");
    w.param_i32("CA_ROTOR_COUNT", 4);
    let path = write(&dir("ulog").join("nodata.ulg"), w.bytes());
    let mapping = Mapping::from_toml_str(
        r#"
        [signals.velocity_body]
        topic = "s"
        fields = ["v[0]", "v[1]", "v[2]"]
        [signals.rates]
        topic = "s"
        fields = ["w[0]", "w[1]", "w[2]"]
        [signals.rotor_speeds]
        topic = "s"
        fields = ["o[0]", "o[1]", "o[2]", "o[3]"]
        [signals.force]
        topic = "s"
        fields = ["f[0]", "f[1]", "f[2]"]
        "#,
        "m.toml",
    )
    .unwrap();
    let e = first_error(&path, &mapping);
    assert!(e.starts_with("nodata.ulg: "), "{e}");
    assert!(e.contains("the log has no data messages"), "{e}");
}

/// An MCAP file with JSON channels `/imu` and `/esc` and the given `/imu` messages.
fn json_mcap(path: &Path, imu: &[String]) {
    use mcap::records::MessageHeader;
    let meta = std::collections::BTreeMap::new();
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(path).unwrap(),
    ))
    .unwrap();
    let ch = w.add_channel(0, "/imu", "json", &meta).unwrap();
    let esc = w.add_channel(0, "/esc", "json", &meta).unwrap();
    for (k, msg) in imu.iter().enumerate() {
        let ns = k as u64 * 5_000_000;
        for (channel, data) in [(ch, msg.as_str()), (esc, r#"{"rpm":[1,2,3,4]}"#)] {
            let header = MessageHeader {
                channel_id: channel,
                sequence: k as u32,
                log_time: ns,
                publish_time: ns,
            };
            w.write_to_known_channel(&header, data.as_bytes()).unwrap();
        }
    }
    w.finish().unwrap();
}

fn imu_mapping(rates_topic: &str, rate_field: &str) -> Mapping {
    Mapping::from_toml_str(
        &format!(
            r#"
            [signals.rates]
            topic = "{rates_topic}"
            fields = ["gyro[0]", "{rate_field}", "gyro[2]"]
            [signals.velocity_body]
            topic = "{rates_topic}"
            fields = ["vel.x", "vel.y", "vel.z"]
            [signals.force]
            topic = "{rates_topic}"
            fields = ["f[0]", "f[1]", "f[2]"]
            [signals.moment]
            topic = "{rates_topic}"
            fields = ["f[0]", "f[1]", "f[2]"]
            [signals.rotor_speeds]
            topic = "/esc"
            fields = ["rpm[0]", "rpm[1]", "rpm[2]", "rpm[3]"]
            unit = "rpm"
            "#
        ),
        "imu.toml",
    )
    .unwrap()
}

fn imu_message(gyro_y: &str) -> String {
    format!(r#"{{"gyro":[0.1,{gyro_y},0.3],"vel":{{"x":1,"y":0,"z":0}},"f":[0,0,-11.7]}}"#)
}

/// Missing topics and fields list what the file has; a NaN in a JSON message names its
/// field; a file of the magic bytes only gives the offset where it ends.
#[test]
fn mcap_errors_say_what_the_file_has() {
    let d = dir("mcap");
    let good: Vec<String> = (0..20).map(|_| imu_message("0.2")).collect();
    let path = d.join("good.mcap");
    json_mcap(&path, &good);
    assert_eq!(
        first_error(&path, &imu_mapping("/gyro", "gyro[1]")),
        "good.mcap: field \"/gyro\": topic not in the file (topics in the file: /esc, /imu)"
    );
    assert_eq!(
        first_error(&path, &imu_mapping("/imu", "gyro[7]")),
        "good.mcap: message 0, field \"/imu.gyro[7]\": field not in the message \
         (gyro has 3 elements)"
    );
    assert_eq!(
        first_error(&path, &imu_mapping("/imu", "gyr[1]")),
        "good.mcap: message 0, field \"/imu.gyr[1]\": field not in the message \
         (the message has fields f, gyro, vel)"
    );
    let mut nan = good.clone();
    nan[3] = imu_message("NaN");
    let nan_path = d.join("nan.mcap");
    json_mcap(&nan_path, &nan);
    let e = first_error(&nan_path, &imu_mapping("/imu", "gyro[1]"));
    assert!(
        e.starts_with("nan.mcap: message 6, field \"/imu.gyro[1]\": "),
        "{e}"
    );
    assert!(e.contains("NaN"), "{e}");
    let magic = write(&d.join("magic.mcap"), b"\x89MCAP0\r\n");
    let e = first_error(&magic, &imu_mapping("/imu", "gyro[1]"));
    assert!(e.starts_with("magic.mcap: byte 8: "), "{e}");
}
