//! Catalogue of malformed inputs: each gets its specific error, naming file, line and
//! column. The messages are part of the API; no input panics.

mod io_support;
mod scratch;

use std::path::PathBuf;

use io_support::quad;
use mrsysid::io::{InvalidSamples, Mapping, ReadOptions, open_log};

const HEADER: &str = "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz";
const ROW: &str = "0.00,1,0,0,0.1,0,0,900,900,900,900,0,0,-11.8,0,0,0";

fn row(t: f64) -> String {
    ROW.replacen("0.00", &format!("{t}"), 1)
}

fn rows(n: usize) -> String {
    (0..n).map(|k| row(0.01 * k as f64) + "\n").collect()
}

fn write(name: &str, bytes: &[u8]) -> PathBuf {
    // One directory per call: tests run in parallel and some share a file name.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = scratch::dir(&format!("malformed-{call}"));
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The first error reading `text` as `name`, with an optional mapping.
fn first_error(name: &str, text: &[u8], mapping: Option<&Mapping>) -> String {
    let path = write(name, text);
    let vehicle = quad(0.0);
    match open_log(&path, &vehicle, mapping, &ReadOptions::default()) {
        Err(e) => e.to_string(),
        Ok(reader) => {
            for c in reader {
                if let Err(e) = c {
                    return e.to_string();
                }
            }
            panic!("{name}: no error")
        }
    }
}

/// A contract file whose data row 3 (line 4) has `column` replaced by `value`.
fn bad_value(column: &str, value: &str) -> String {
    let idx = HEADER.split(',').position(|c| c == column).unwrap();
    let mut lines: Vec<String> = rows(6).lines().map(str::to_string).collect();
    let mut fields: Vec<String> = lines[2].split(',').map(str::to_string).collect();
    fields[idx] = value.to_string();
    lines[2] = fields.join(",");
    format!("{HEADER}\n{}\n", lines.join("\n"))
}

fn check(name: &str, text: &str, expected: &str) {
    assert_eq!(first_error(name, text.as_bytes(), None), expected);
}

#[test]
fn m01_empty_file() {
    check("empty.csv", "", "empty.csv: line 1: no data rows");
}

#[test]
fn m02_header_only() {
    check(
        "header.csv",
        &format!("{HEADER}\n"),
        "header.csv: no data rows",
    );
}

#[test]
fn m03_missing_velocity_columns() {
    let text =
        "t,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz\n0,0,0,0,1,1,1,1,0,0,0,0,0,0\n";
    check(
        "nov.csv",
        text,
        "nov.csv: no body velocity: map `velocity_body` (contract columns \"u\",\"v\",\"w\"), or \
         `velocity_world` together with `attitude`",
    );
}

#[test]
fn m04_partial_velocity_triad() {
    let text = HEADER.replace(",w,", ",ww,") + "\n" + &rows(3);
    check(
        "triad.csv",
        &text,
        "triad.csv: line 1, column \"w\": missing column of velocity_body (has 2 of u,v,w)",
    );
}

#[test]
fn m05_no_force_and_no_accelerometer() {
    let text = "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4\n0,0,0,0,0,0,0,1,1,1,1\n";
    check(
        "noforce.csv",
        text,
        "noforce.csv: no force: map `force` (contract columns \"fx\",\"fy\",\"fz\"), or \
         `specific_force` (contract columns \"ax\",\"ay\",\"az\") to derive F = m a",
    );
}

#[test]
fn m06_duplicate_column() {
    let text = HEADER.replace(",fx,", ",u,") + "\n" + &rows(3);
    check(
        "dup.csv",
        &text,
        "dup.csv: line 1, column \"u\": duplicate column name",
    );
}

#[test]
fn m07_rotor_count_mismatch() {
    let text = "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,fx,fy,fz,mx,my,mz\n0,0,0,0,0,0,0,1,1,1,0,0,0,0,0,0\n";
    check(
        "rotors.csv",
        text,
        "rotors.csv: line 1: header has 3 omega_* columns but the vehicle has 4 rotors",
    );
}

#[test]
fn m08_rotor_numbering_hole() {
    let text = HEADER.replace("omega_4", "omega_5") + "\n" + &rows(3);
    check(
        "hole.csv",
        &text,
        "hole.csv: line 1, column \"omega_4\": missing column (rotors are numbered omega_1..omega_4)",
    );
}

#[test]
fn m09_short_row() {
    let text = format!("{HEADER}\n{}{}\n", rows(2), "0.05,1,0,0");
    check(
        "short.csv",
        &text,
        "short.csv: line 4: row has 4 fields, header has 17",
    );
}

#[test]
fn m10_long_row() {
    let text = format!("{HEADER}\n{}{},7\n", rows(2), row(0.05));
    check(
        "long.csv",
        &text,
        "long.csv: line 4: row has 18 fields, header has 17",
    );
}

#[test]
fn m11_text_in_number() {
    check(
        "text.csv",
        &bad_value("p", "abc"),
        "text.csv: line 4, column \"p\": not a number (\"abc\")",
    );
}

#[test]
fn m12_empty_field() {
    check(
        "blank.csv",
        &bad_value("q", ""),
        "blank.csv: line 4, column \"q\": not a number (\"\")",
    );
}

#[test]
fn m13_nan() {
    check(
        "nan.csv",
        &bad_value("u", "NaN"),
        "nan.csv: line 4, column \"u\": not a finite number (NaN)",
    );
}

#[test]
fn m14_infinity() {
    check(
        "inf.csv",
        &bad_value("fz", "-inf"),
        "inf.csv: line 4, column \"fz\": not a finite number (-inf)",
    );
}

#[test]
fn m15_duplicate_timestamp() {
    check(
        "dupt.csv",
        &bad_value("t", "0.01"),
        "dupt.csv: line 4, column \"t\": duplicate timestamp t = 0.01 s",
    );
}

#[test]
fn m16_time_backwards() {
    check(
        "back.csv",
        &bad_value("t", "0.005"),
        "back.csv: line 4, column \"t\": timestamp t = 0.005 s goes backwards (previous row t = 0.01 s)",
    );
}

#[test]
fn m17_negative_rotor_speed() {
    check(
        "negw.csv",
        &bad_value("omega_3", "-900"),
        "negw.csv: line 4, column \"omega_3\": value -900 outside the physical range [0, 15000] rad/s \
         (magnitudes, about 143000 RPM; a log in RPM needs unit \"rpm\")",
    );
}

#[test]
fn m18_rotor_speed_in_rpm_by_mistake() {
    check(
        "rpm.csv",
        &bad_value("omega_1", "20000"),
        "rpm.csv: line 4, column \"omega_1\": value 20000 outside the physical range [0, 15000] rad/s \
         (magnitudes, about 143000 RPM; a log in RPM needs unit \"rpm\")",
    );
}

#[test]
fn m19_rates_in_degrees_by_mistake() {
    check(
        "deg.csv",
        &bad_value("r", "180"),
        "deg.csv: line 4, column \"r\": value 180 outside the physical range [-100, 100] rad/s \
         (about 5730 deg/s; a log in deg/s needs unit \"deg/s\")",
    );
}

#[test]
fn m20_velocity_out_of_range() {
    check(
        "fast.csv",
        &bad_value("v", "400"),
        "fast.csv: line 4, column \"v\": value 400 outside the physical range [-150, 150] m/s (150 m/s)",
    );
}

#[test]
fn m21_quaternion_not_unit() {
    let header = format!("{HEADER},qw,qx,qy,qz");
    let body: String = (0..4)
        .map(|k| {
            format!(
                "{},{}\n",
                row(0.01 * k as f64),
                if k == 2 { "0.5,0,0,0" } else { "1,0,0,0" }
            )
        })
        .collect();
    check(
        "quat.csv",
        &format!("{header}\n{body}"),
        "quat.csv: line 4, column \"qw\": value 0.5 outside the physical range 1 ± 0.01 (norm of the \
         attitude quaternion)",
    );
}

#[test]
fn m22_invalid_utf8() {
    let mut bytes = format!("{HEADER}\n{}", rows(2)).into_bytes();
    bytes.extend_from_slice(b"0.05,\xff\xfe,0,0,0.1,0,0,900,900,900,900,0,0,-11.8,0,0,0\n");
    assert_eq!(
        first_error("utf8.csv", &bytes, None),
        "utf8.csv: line 4, column \"u\": not a number (\"\u{fffd}\u{fffd}\")"
    );
}

#[test]
fn m23_force_beyond_50g() {
    check(
        "force.csv",
        &bad_value("fz", "-1000"),
        "force.csv: line 4, column \"fz\": value -1000 outside the physical range [-588.399, 588.399] N \
         (50 g times the vehicle mass)",
    );
}

#[test]
fn m24_partial_omega_dot() {
    let text = format!("{HEADER},omega_dot_1\n") + &rows(2).replace('\n', ",0\n");
    check(
        "wdot.csv",
        &text,
        "wdot.csv: line 1: header has 1 omega_dot_* columns but the vehicle has 4 rotors",
    );
}

fn mapping(text: &str) -> Result<Mapping, String> {
    Mapping::from_toml_str(text, "map.toml").map_err(|e| e.to_string())
}

#[test]
fn m25_mapping_unknown_unit() {
    let e = mapping("[signals.rates]\ncolumns = [\"a\",\"b\",\"c\"]\nunit = \"furlong\"\n")
        .unwrap_err();
    assert!(
        e.starts_with("map.toml: key \"signals.rates\": unknown unit \"furlong\""),
        "{e}"
    );
}

#[test]
fn m26_mapping_wrong_dimension() {
    let e =
        mapping("[signals.rates]\ncolumns = [\"a\",\"b\",\"c\"]\nunit = \"m/s\"\n").unwrap_err();
    assert_eq!(
        e,
        "map.toml: key \"signals.rates\": unit \"m/s\" is a Speed unit, but rates needs a AngularRate \
         unit such as \"rad/s\""
    );
}

#[test]
fn m27_mapping_erpm_without_pole_pairs() {
    let e =
        mapping("[signals.rotor_speeds]\ncolumns = [\"a\",\"b\",\"c\",\"d\"]\nunit = \"erpm\"\n")
            .unwrap_err();
    assert_eq!(
        e,
        "map.toml: key \"signals.rotor_speeds\": unit \"erpm\" needs `pole_pairs` (motor pole pairs)"
    );
}

#[test]
fn m28_mapping_toml_syntax_and_unknown_key() {
    let e = mapping("[frames]\nbody = \"flu\"\nbogus = 1\n").unwrap_err();
    assert!(
        e.starts_with("map.toml: line 3: unknown field `bogus`"),
        "{e}"
    );
    let e = mapping("[frames]\nbody = \"left\"\n").unwrap_err();
    assert!(
        e.starts_with("map.toml: line 2: unknown variant `left`"),
        "{e}"
    );
}

#[test]
fn m29_mapping_column_absent_from_header() {
    let m = Mapping::from_toml_str(
        "[time]\ncolumns = [\"time\"]\n[signals.rates]\ncolumns = [\"p\",\"q\",\"r\"]\n\
         [signals.velocity_body]\ncolumns = [\"u\",\"v\",\"w\"]\n\
         [signals.rotor_speeds]\ncolumns = [\"omega_1\",\"omega_2\",\"omega_3\",\"omega_4\"]\n\
         [signals.force]\ncolumns = [\"fx\",\"fy\",\"fz\"]\n",
        "map.toml",
    )
    .unwrap();
    let text = format!("{HEADER}\n{}", rows(3));
    assert_eq!(
        first_error("mapped.csv", text.as_bytes(), Some(&m)),
        "mapped.csv: line 1, column \"time\": column of time not in the header"
    );
}

#[test]
fn m30_mapping_rotor_count_mismatch() {
    let m = Mapping::from_toml_str(
        "[time]\ncolumns = [\"t\"]\n[signals.rates]\ncolumns = [\"p\",\"q\",\"r\"]\n\
         [signals.velocity_body]\ncolumns = [\"u\",\"v\",\"w\"]\n\
         [signals.rotor_speeds]\ncolumns = [\"omega_1\",\"omega_2\",\"omega_3\"]\n\
         [signals.force]\ncolumns = [\"fx\",\"fy\",\"fz\"]\n",
        "map.toml",
    )
    .unwrap();
    let text = format!("{HEADER}\n{}", rows(3));
    assert_eq!(
        first_error("mapped.csv", text.as_bytes(), Some(&m)),
        "mapped.csv: key \"signals.rotor_speeds\": lists 3 names but rotor_speeds needs 4 (the vehicle has 4 rotors)"
    );
}

#[test]
fn drop_and_count_keeps_going_and_counts_per_reason() {
    let mut text = format!("{HEADER}\n");
    for k in 0..20 {
        let mut r = row(0.01 * k as f64);
        if k == 5 {
            r = r.replacen(",1,", ",NaN,", 1);
        }
        if k == 9 {
            r = r.replacen(",900,", ",-1,", 1);
        }
        text += &r;
        text.push('\n');
        if k == 12 {
            text += &row(0.01 * k as f64); // duplicate timestamp
            text.push('\n');
        }
    }
    let path = write("drop.csv", text.as_bytes());
    let opts = ReadOptions {
        invalid: InvalidSamples::DropAndCount,
        ..ReadOptions::default()
    };
    let mut reader = open_log(&path, &quad(0.0), None, &opts).unwrap();
    let n: usize = reader.by_ref().map(|c| c.unwrap().len()).sum();
    let s = reader.summary();
    assert_eq!(n, 18, "21 rows, 3 dropped");
    assert_eq!(s.rows_read, 21);
    assert_eq!(s.dropped.get("not finite"), Some(&1));
    assert_eq!(s.dropped.get("out of physical range"), Some(&1));
    assert_eq!(s.dropped.get("time not strictly increasing"), Some(&1));
    assert_eq!(
        s.first_dropped[0],
        "drop.csv: line 7, column \"u\": not a finite number (NaN)"
    );
}
