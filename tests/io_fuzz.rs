//! Mutation fuzzing of every parser of the io module: CSV reader (both policies),
//! mapping TOML, vehicle TOML, MCAP reader (JSON and CDR), CDR decoder, ros2msg schema
//! parser, ULog reader and definitions reader, DataFlash reader and parameter reader. Valid inputs are mutated (byte flips, deletions, insertions of hostile tokens,
//! duplication, truncation); every case must return Ok or an error — never panic.
//!
//! CI runs a few thousand cases (well under 20 s); set `MRSYSID_FUZZ_CASES` to run
//! more locally, and `MRSYSID_FUZZ_SEED` to draw other cases than CI's, e.g.
//! `MRSYSID_FUZZ_CASES=200000 MRSYSID_FUZZ_SEED=7 cargo test --test io_fuzz --release`.

mod io_support;
mod scratch;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use io_support::{Px4Log, analytic_chunk, px4_like_log, quad};
use mrsysid::io::fixtures;
use mrsysid::io::fixtures::mcap::{Encoding, write_samples, written_mapping};
use mrsysid::io::fixtures::write_contract_csv;
use mrsysid::io::internals::{decode_cdr as decode, parse_ros2_schema as parse_schema};
use mrsysid::io::{
    InvalidSamples, Mapping, ReadOptions, open_log, read_definitions, read_parameters,
};
use mrsysid::vehicle::{Vehicle, VehicleSource};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// Random source of target `target`: its own stream, shifted by `MRSYSID_FUZZ_SEED`.
fn rng(target: u64) -> StdRng {
    let shift: u64 = std::env::var("MRSYSID_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    StdRng::seed_from_u64(target.wrapping_add(shift.wrapping_mul(1000)))
}

/// Cases per target: `MRSYSID_FUZZ_CASES` or the CI default.
fn cases(ci_default: usize) -> usize {
    std::env::var("MRSYSID_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(ci_default)
}

const TOKENS: [&[u8]; 14] = [
    b"NaN",
    b"inf",
    b"-1e309",
    b",",
    b"\n",
    b"\"",
    b"\r\n",
    b"\xff\xfe",
    b"[",
    b"]",
    b"=",
    b"0",
    b"-",
    b"1e-320",
];

fn mutate(rng: &mut StdRng, base: &[u8]) -> Vec<u8> {
    let mut b = base.to_vec();
    for _ in 0..rng.random_range(1..6) {
        if b.is_empty() {
            b.extend_from_slice(TOKENS[rng.random_range(0..TOKENS.len())]);
            continue;
        }
        let i = rng.random_range(0..b.len());
        match rng.random_range(0..6) {
            0 => b[i] ^= 1 << rng.random_range(0..8),
            1 => {
                let end = (i + rng.random_range(1..16)).min(b.len());
                b.drain(i..end);
            }
            2 => {
                let t = TOKENS[rng.random_range(0..TOKENS.len())];
                b.splice(i..i, t.iter().copied());
            }
            3 => b[i] = rng.random_range(0..=255),
            4 => b.truncate(i),
            _ => {
                let end = (i + rng.random_range(1..64)).min(b.len());
                let piece = b[i..end].to_vec();
                b.splice(i..i, piece);
            }
        }
    }
    b
}

fn tmp(name: &str) -> PathBuf {
    scratch::dir("fuzz").join(name)
}

/// Reads a whole log; returns the number of chunks or the error (never panics).
fn drain(path: &Path, vehicle: &Vehicle, mapping: Option<&Mapping>, opts: &ReadOptions) -> usize {
    match open_log(path, vehicle, mapping, opts) {
        Err(e) => {
            assert!(!e.to_string().is_empty());
            0
        }
        Ok(r) => r.take_while(Result::is_ok).count(),
    }
}

fn no_panic(target: &str, case: usize, input: &[u8], f: impl FnOnce()) {
    if catch_unwind(AssertUnwindSafe(f)).is_err() {
        let keep = tmp(&format!("crash-{target}-{case}.bin"));
        std::fs::write(&keep, input).unwrap();
        panic!(
            "{target}: case {case} panicked; input saved to {}",
            keep.display()
        );
    }
}

#[test]
fn fuzz_csv_reader() {
    let vehicle = quad(3e-5);
    let mut src = analytic_chunk(40, 100.0);
    src.omega_dot = None;
    let base_path = tmp("base.csv");
    write_contract_csv(&base_path, [&src]).unwrap();
    let base = std::fs::read(&base_path).unwrap();
    let mut rng = rng(1);
    let path = tmp("case.csv");
    let drop = ReadOptions {
        invalid: InvalidSamples::DropAndCount,
        ..ReadOptions::default()
    };
    for case in 0..cases(2000) {
        let input = mutate(&mut rng, &base);
        std::fs::write(&path, &input).unwrap();
        no_panic("csv", case, &input, || {
            drain(&path, &vehicle, None, &ReadOptions::default());
            drain(&path, &vehicle, None, &drop);
        });
    }
}

#[test]
fn fuzz_mapping_and_vehicle_toml() {
    let mapping_text = std::fs::read("examples/neurobem.toml").unwrap();
    let vehicle_text = std::fs::read("data/vehicles/neurobem.toml").unwrap();
    let vehicle = Vehicle::from_toml_file(Path::new("data/vehicles/neurobem.toml")).unwrap();
    let log = std::fs::File::open("data/neurobem/figure8_1_20210218170320seg2.csv.gz").unwrap();
    let mut text = String::new();
    std::io::Read::read_to_string(&mut flate2::read::GzDecoder::new(log), &mut text).unwrap();
    let head: String = text.lines().take(40).map(|l| format!("{l}\n")).collect();
    let log_path = tmp("neurobem-head.csv");
    std::fs::write(&log_path, head).unwrap();
    let mut rng = rng(2);
    for case in 0..cases(3000) {
        let input = mutate(&mut rng, &mapping_text);
        no_panic("mapping", case, &input, || {
            if let Ok(m) = Mapping::from_toml_str(&String::from_utf8_lossy(&input), "map.toml") {
                drain(&log_path, &vehicle, Some(&m), &ReadOptions::default());
            }
        });
        let input = mutate(&mut rng, &vehicle_text);
        no_panic("vehicle", case, &input, || {
            let _ = Vehicle::from_toml_str(&String::from_utf8_lossy(&input), VehicleSource::Code);
        });
    }
}

#[test]
fn fuzz_mcap_reader_json_and_cdr() {
    let vehicle = quad(3e-5);
    let src = analytic_chunk(30, 100.0);
    let mapping = written_mapping(4, true, true, true);
    let mut rng = rng(3);
    for encoding in [Encoding::Json, Encoding::Cdr] {
        let base_path = tmp(&format!("base-{encoding:?}.mcap"));
        write_samples(&base_path, &vehicle, [&src], encoding).unwrap();
        let base = std::fs::read(&base_path).unwrap();
        let path = tmp("case.mcap");
        for case in 0..cases(800) {
            let input = mutate(&mut rng, &base);
            std::fs::write(&path, &input).unwrap();
            no_panic("mcap", case, &input, || {
                drain(&path, &vehicle, Some(&mapping), &ReadOptions::default());
            });
        }
    }
}

#[test]
fn fuzz_cdr_decoder_and_schema_parser() {
    let schema_text = "std_msgs/Header header\nfloat64[3] v\nint16[] s\nstring name\npkg/Inner[2] inner\n\
        ================================================================================\n\
        MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
        ================================================================================\n\
        MSG: pkg/Inner\nuint8 a\nfloat32[] b\n";
    let schema = parse_schema("pkg/msg/Outer", schema_text).unwrap();
    let mut base = vec![0u8, 1, 0, 0];
    base.extend_from_slice(&[1, 0, 0, 0, 2, 0, 0, 0, 4, 0, 0, 0, b'm', b'a', b'p', 0]);
    for x in [1.0f64, 2.0, 3.0] {
        base.extend_from_slice(&x.to_le_bytes());
    }
    // s = [1, 2]; name = "n"; inner[0] = {a: 7, b: [1.0]}; inner[1] = {a: 9, b: []}.
    base.extend_from_slice(&[2, 0, 0, 0, 1, 0, 2, 0, 2, 0, 0, 0, b'n', 0]);
    base.extend_from_slice(&[7, 0, 1, 0, 0, 0, 0, 0, 128, 63, 9, 0, 0, 0, 0, 0, 0, 0]);
    assert!(
        decode(&schema, &base).is_ok(),
        "{:?}",
        decode(&schema, &base)
    );
    let mut rng = rng(4);
    for case in 0..cases(20000) {
        let input = mutate(&mut rng, &base);
        no_panic("cdr", case, &input, || {
            let _ = decode(&schema, &input);
        });
        let text = mutate(&mut rng, schema_text.as_bytes());
        no_panic("ros2msg", case, &text, || {
            if let Ok(s) = parse_schema("pkg/msg/Outer", &String::from_utf8_lossy(&text)) {
                let _ = decode(&s, &base);
            }
        });
    }
}

#[test]
fn fuzz_ulog_reader() {
    let vehicle = quad(0.0);
    let src = analytic_chunk(30, 100.0);
    let written = tmp("base.ulg");
    fixtures::ulog::write_samples(&written, [&src]).unwrap();
    let px4 = px4_like_log(Px4Log {
        duration_us: 300_000,
        dropout_at: Some(1_150_000),
    });
    let px4_mapping = Mapping::from_toml_file(Path::new("examples/px4.toml")).unwrap();
    let bases = [
        (
            std::fs::read(&written).unwrap(),
            fixtures::ulog::written_mapping(4, true, true, true),
        ),
        (px4, px4_mapping),
    ];
    let mut rng = rng(5);
    let path = tmp("case.ulg");
    for (base, mapping) in &bases {
        for case in 0..cases(800) {
            let input = mutate(&mut rng, base);
            std::fs::write(&path, &input).unwrap();
            no_panic("ulog", case, &input, || {
                drain(&path, &vehicle, Some(mapping), &ReadOptions::default());
                let _ = read_definitions(&path);
            });
        }
    }
}

/// DataFlash: a written flight (ESC telemetry, and RCOU instead) through the shipped
/// mapping, and the parameter reader, over truncations and mutations.
#[test]
fn fuzz_dataflash_reader() {
    let vehicle = quad(0.0);
    let src = analytic_chunk(30, 100.0);
    let sf = [0, 1, 2].map(|a| src.wrench[a].clone());
    let params = [("FRAME_CLASS", 1.0), ("FRAME_TYPE", 1.0)];
    let curve = fixtures::dataflash::RcouCurve {
        pwm_min: 1150.0,
        pwm_max: 1950.0,
        expo: 0.65,
        max_speed: 2500.0,
    };
    let mapping = Mapping::from_toml_file(Path::new("examples/ardupilot.toml")).unwrap();
    let bases = [
        fixtures::dataflash::write_flight(&src, &sf, &params, None, 2),
        fixtures::dataflash::write_flight(&src, &sf, &params, Some(curve), 2),
    ];
    let mut rng = rng(6);
    let path = tmp("case.bin");
    for base in &bases {
        // Every truncation point of the first 2 kB (the metadata), then mutations.
        for cut in (0..base.len().min(2048)).step_by(7) {
            std::fs::write(&path, &base[..cut]).unwrap();
            no_panic("dataflash-cut", cut, &base[..cut], || {
                drain(&path, &vehicle, Some(&mapping), &ReadOptions::default());
                let _ = read_parameters(&path);
            });
        }
        for case in 0..cases(800) {
            let input = mutate(&mut rng, base);
            std::fs::write(&path, &input).unwrap();
            no_panic("dataflash", case, &input, || {
                drain(&path, &vehicle, Some(&mapping), &ReadOptions::default());
                let _ = read_parameters(&path);
            });
        }
    }
}
