//! ArduPilot DataFlash reader: round trip of a written flight through the shipped
//! `examples/ardupilot.toml`, instance selection, the log's units against the mapping's,
//! commanded speeds from `RCOU` through the `MOT_*` actuator map, parameters, the
//! guidance when ESC telemetry is missing, and a catalogue of malformed files, each
//! answered with its own error naming the byte offset and message.

mod io_support;
mod scratch;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use io_support::{analytic_chunk, concat, quad};
use mrsysid::SampleChunk;
use mrsysid::io::fixtures::dataflash::{DataflashWriter, RcouCurve, Value, write_flight};
use mrsysid::io::{IoError, Mapping, ReadOptions, Summary, open_log, read_parameters};

fn tmp(name: &str) -> PathBuf {
    scratch::dir("dataflash").join(name)
}

fn read_all(path: &Path, mapping: &Mapping) -> Result<(SampleChunk, Summary), IoError> {
    let mut reader = open_log(path, &quad(0.0), Some(mapping), &ReadOptions::default())?;
    let mut chunks = Vec::new();
    for c in reader.by_ref() {
        chunks.push(c?);
    }
    Ok((concat(&chunks), reader.summary().clone()))
}

fn example() -> Mapping {
    Mapping::from_toml_file(Path::new("examples/ardupilot.toml")).unwrap()
}

/// 300 samples at 100 Hz of the analytic signals with specific force = wrench / 1.2 kg.
fn flight(params: &[(&str, f64)], rcou: Option<RcouCurve>) -> (SampleChunk, Vec<u8>) {
    let src = analytic_chunk(300, 100.0);
    let sf = [0, 1, 2].map(|a| src.wrench[a].iter().map(|f| f / 1.2).collect::<Vec<_>>());
    let bytes = write_flight(&src, &sf, params, rcou, 2);
    (src, bytes)
}

fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let path = tmp(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn written_flight_reads_back_through_the_example_mapping() {
    let (src, bytes) = flight(&[], None);
    let (got, summary) = read_all(&write("flight.bin", &bytes), &example()).unwrap();
    // IMU at every sample; XKQ, XKF1 and ESC at every second one: the last IMU sample
    // lies after the last slow message and is dropped as not aligned.
    assert_eq!(got.len(), 299, "{summary:?}");
    assert_eq!(summary.segments, 1);
    for k in 0..got.len() {
        // Whole µs: 1e-9 s covers the rounding of t = 1 + k/100.
        assert!((got.t[k] - src.t[k]).abs() < 1e-9, "t[{k}]");
        for a in 0..3 {
            // f32 storage: 1e-7 relative of values below 1 rad/s.
            assert!(
                (got.rates[a][k] - src.rates[a][k]).abs() < 1e-7,
                "p[{a}][{k}]"
            );
            // F = m a (f32 specific force, 1e-6 relative of ~12 N).
            let f = src.wrench[a][k];
            assert!((got.wrench[a][k] - f).abs() < 2e-5, "F[{a}][{k}]");
        }
        for i in 0..4 {
            // rpm (f32, 1e-7 relative) -> rad/s by the log's FMTU unit; odd samples are
            // interpolated linearly between 50 Hz messages of a 50 rad/s tone at 2 rad/s
            // (Ω'' ≤ 200 rad/s³): at most 200 · 0.02² / 8 = 0.01 rad/s.
            let e = (got.omega[i][k] - src.omega[i][k]).abs();
            assert!(
                e < if k % 2 == 0 { 2e-4 } else { 1.1e-2 },
                "omega[{i}][{k}]: {e}"
            );
        }
        for a in 0..3 {
            // Body velocity from the NED velocity and the quaternion, both interpolated
            // on odd samples: 1e-4 m/s.
            let e = (got.velocity[a][k] - src.velocity[a][k]).abs();
            assert!(e < 1e-4, "v[{a}][{k}]: {e}");
        }
    }
}

#[test]
fn instances_and_units_follow_the_mapping() {
    let (src, bytes) = flight(&[], None);
    let path = write("instances.bin", &bytes);
    // IMU[1] is the decoy at half values.
    let text = std::fs::read_to_string("examples/ardupilot.toml")
        .unwrap()
        .replace("topic = \"IMU\"", "topic = \"IMU[1]\"")
        .replace("time_base = \"IMU\"", "time_base = \"IMU[1]\"");
    let (got, _) = read_all(&path, &Mapping::from_toml_str(&text, "m.toml").unwrap()).unwrap();
    assert!((got.rates[0][10] - 0.5 * src.rates[0][10]).abs() < 1e-7);
    // A unit in the mapping overrides the log's: RPM numbers read as deg/s.
    let text = std::fs::read_to_string("examples/ardupilot.toml")
        .unwrap()
        .replace("\"ESC[3].RPM\"]", "\"ESC[3].RPM\"]\nunit = \"deg/s\"");
    let (got, _) = read_all(&path, &Mapping::from_toml_str(&text, "m.toml").unwrap()).unwrap();
    // rpm · π/180 = (rad/s · 30/π) · π/180 = rad/s / 6 (f32: 1e-6 relative).
    assert!((got.omega[0][10] * 6.0 / src.omega[0][10] - 1.0).abs() < 1e-6);
    // A field of another dimension by the log's units is refused, naming it.
    let text = std::fs::read_to_string("examples/ardupilot.toml")
        .unwrap()
        .replace(
            "fields = [\"GyrX\", \"GyrY\", \"GyrZ\"]",
            "fields = [\"AccX\", \"GyrY\", \"GyrZ\"]",
        );
    let e = read_all(&path, &Mapping::from_toml_str(&text, "m.toml").unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("field \"IMU.AccX\"") && e.contains("m/s^2"),
        "{e}"
    );
}

#[test]
fn commanded_speeds_from_rcou_and_the_mot_parameters() {
    let params = [
        ("FRAME_CLASS", 1.0),
        ("FRAME_TYPE", 1.0),
        ("MOT_PWM_MIN", 1100.0),
        ("MOT_PWM_MAX", 1900.0),
        ("MOT_SPIN_MIN", 0.1),
        ("MOT_SPIN_MAX", 0.95),
        ("MOT_THST_EXPO", 0.6),
    ];
    // ArduPilot's curve with the parameters above: PWM 1180..1860.
    let curve = RcouCurve {
        pwm_min: 1180.0,
        pwm_max: 1860.0,
        expo: 0.6,
        max_speed: 2000.0,
    };
    let (src, bytes) = flight(&params, Some(curve));
    let path = write("rcou.bin", &bytes);
    let p = read_parameters(&path).unwrap();
    assert_eq!(p.parameters["MOT_THST_EXPO"], 0.6f32 as f64);
    assert_eq!(p.parameters.len(), params.len());
    assert!(p.firmware.unwrap().starts_with("ArduCopter V4.5.7"));
    let map: BTreeMap<String, f64> = params.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    let actuator = mrsysid::io::actuator_lines(&map)
        .unwrap()
        .replace("# max_speed = 2500.0", "max_speed = 2000.0");
    let text = std::fs::read_to_string("examples/ardupilot.toml")
        .unwrap()
        .replace(
            "topic = \"ESC\"                        # one ESC message per motor: each field names its instance\nfields = [\"ESC[0].RPM\", \"ESC[1].RPM\", \"ESC[2].RPM\", \"ESC[3].RPM\"]",
            &format!("topic = \"RCOU\"\nfields = [\"C1\", \"C2\", \"C3\", \"C4\"]\n{actuator}"),
        );
    let (got, summary) =
        read_all(&path, &Mapping::from_toml_str(&text, "m.toml").unwrap()).unwrap();
    assert!(
        summary.derived.iter().any(|d| d.contains("COMMANDED")),
        "{:?}",
        summary.derived
    );
    for k in (0..got.len()).step_by(2) {
        for i in 0..4 {
            // Whole-µs PWM over a 680 µs span: 0.5 µs is 0.07 % of the command, at most
            // 0.1 % of the speed near 900 rad/s (dΩ/Ω = dT/2T, T ≈ 0.2).
            let e = (got.omega[i][k] / src.omega[i][k] - 1.0).abs();
            assert!(
                e < 2e-3,
                "omega[{i}][{k}] {} vs {}",
                got.omega[i][k],
                src.omega[i][k]
            );
        }
    }
}

#[test]
fn missing_esc_telemetry_says_what_to_change_on_the_vehicle() {
    let (_, bytes) = flight(
        &[],
        Some(RcouCurve {
            pwm_min: 1150.0,
            pwm_max: 1950.0,
            expo: 0.65,
            max_speed: 2500.0,
        }),
    );
    let e = read_all(&write("no-esc.bin", &bytes), &example())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("no-esc.bin: field \"ESC[0]\": message not in the log (messages in the log: FMTU, IMU, MSG, MULT, RCOU, UNIT, XKF1, XKQ)"),
        "{e}"
    );
    for words in [
        "SERVO_BLH_BDMASK",
        "SERVO_BLH_TRATE",
        "LOG_BITMASK",
        "RCOU",
        "IMU_FAST",
        "SYSID",
    ] {
        assert!(e.contains(words), "{words}: {e}");
    }
}

#[test]
fn slow_esc_telemetry_says_what_to_change_on_the_vehicle() {
    // ESC (and EKF) messages at 2 Hz: 0.5 s apart, more than align_gap = 0.3 s.
    let src = analytic_chunk(300, 100.0);
    let sf = [0, 1, 2].map(|a| src.wrench[a].clone());
    let path = write("slow.bin", &write_flight(&src, &sf, &[], None, 50));
    let mut reader =
        open_log(&path, &quad(0.0), Some(&example()), &ReadOptions::default()).unwrap();
    let read: Result<Vec<_>, _> = reader.by_ref().collect();
    let summary = reader.summary().clone();
    assert!(
        read.is_err(),
        "every sample is unaligned: nothing is left to read"
    );
    let dropped = summary.first_dropped.join("\n");
    for words in [
        "no messages within align_gap = 0.3 s",
        "SERVO_BLH_TRATE",
        "SERVO_BLH_BDMASK",
        "LOG_BITMASK",
    ] {
        assert!(dropped.contains(words), "{words}: {dropped}");
    }
}

/// A small valid log: FMT of FMT, one format `TST` (type 20: TimeUS Q, I B, GyrX..Z f),
/// and `n` messages at 100 Hz.
fn small(n: usize) -> (DataflashWriter, usize) {
    let mut w = DataflashWriter::new();
    w.format(20, "TST", "QBfff", "TimeUS,I,GyrX,GyrY,GyrZ");
    let head = w.bytes().len();
    for k in 0..n {
        let us = 1_000_000.0 + k as f64 * 10_000.0;
        w.message(
            20,
            &[
                Value::N(us),
                Value::N(0.0),
                Value::N(0.1),
                Value::N(0.2),
                Value::N(0.3),
            ],
        );
    }
    (w, head)
}

fn small_mapping() -> Mapping {
    let mut text = String::from(
        "[mcap]\ntime_base = \"TST\"\n[signals.rates]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrY\", \"GyrZ\"]\n",
    );
    text += "[signals.rotor_speeds]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrX\", \"GyrX\", \"GyrX\"]\n";
    text += "[signals.velocity_body]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrY\", \"GyrZ\"]\n";
    text += "[signals.specific_force]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrY\", \"GyrZ\"]\n";
    Mapping::from_toml_str(&text, "m.toml").unwrap()
}

fn error_of(bytes: &[u8], name: &str) -> String {
    let path = write(&format!("{name}.bin"), bytes);
    match read_all(&path, &small_mapping()) {
        Ok((c, _)) => panic!("{name}: read {} samples, expected an error", c.len()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn malformed_catalogue() {
    let (good, head) = small(50);
    let b = good.bytes();
    let msg = 3 + 8 + 1 + 12; // bytes of one TST message
    let third = head + 2 * msg;
    let cases: Vec<(&str, Vec<u8>, String)> = vec![
        (
            "not-dataflash",
            b"t,p,q,r\n0,0,0,0\n".to_vec(),
            "not-dataflash.bin: byte 0: corrupted message header: bytes 0x74 0x2C, expected 0xA3 0x95 (not an ArduPilot DataFlash log)".into(),
        ),
        (
            "bad-head",
            { let mut c = b.to_vec(); c[third + 1] = 0x00; c },
            format!("bad-head.bin: byte {third}: corrupted message header: bytes 0xA3 0x00, expected 0xA3 0x95"),
        ),
        (
            "unknown-type",
            { let mut c = b.to_vec(); c[third + 2] = 21; c },
            format!("unknown-type.bin: byte {third}: unknown message type 21: no FMT message defines it before this one"),
        ),
        (
            "bad-fmt-char",
            { let mut c = b.to_vec(); c[89 + 3 + 2 + 4 + 1] = b'x'; c },
            "bad-fmt-char.bin: byte 89: bad FMT message: FMT of TST (type 20): unknown format character 'x' of field \"I\"".into(),
        ),
        (
            "bad-fmt-length",
            { let mut c = b.to_vec(); c[89 + 3 + 1] = 30; c },
            "bad-fmt-length.bin: byte 89: bad FMT message: FMT of TST (type 20): length 30 bytes, but its fields take 21 + 3 header bytes".into(),
        ),
    ];
    for (name, bytes, want) in cases {
        let got = error_of(&bytes, name);
        assert!(got.starts_with(&want), "{name}:\n got  {got}\n want {want}");
    }
    let path = write("small.bin", b);
    let (c, summary) = read_all(&path, &small_mapping()).unwrap();
    assert_eq!((c.len(), summary.cut_off), (50, None));
    // A file the end cuts inside a message or its header (a log closed by a power cut)
    // is read up to that message, and says where it was cut.
    for (name, bytes, samples, want) in [
        (
            "truncated",
            &b[..b.len() - 5],
            49,
            format!(
                "a TST (type 20) message at byte {} (19 of its 24 bytes)",
                b.len() - msg
            ),
        ),
        (
            "short-header",
            &b[..head + 10 * msg + 2],
            10,
            format!(
                "a message header at byte {} (2 of its 3 bytes)",
                head + 10 * msg
            ),
        ),
    ] {
        let path = write(&format!("{name}.bin"), bytes);
        let (c, summary) = read_all(&path, &small_mapping()).unwrap();
        assert_eq!(c.len(), samples, "{name}");
        let note = summary.cut_off.unwrap_or_default();
        assert!(
            note.starts_with(&format!("the file ends inside {want}: the log was cut off")),
            "{name}: {note}"
        );
    }
    // A mapped field the format lacks names the message's fields.
    let text = "[mcap]\ntime_base = \"TST\"\n[signals.rates]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrY\", \"Gyr\"]\n[signals.rotor_speeds]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrX\", \"GyrX\", \"GyrX\"]\n[signals.velocity_body]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrY\", \"GyrZ\"]\n[signals.specific_force]\ntopic = \"TST\"\nfields = [\"GyrX\", \"GyrY\", \"GyrZ\"]\n";
    let e = read_all(&path, &Mapping::from_toml_str(text, "m.toml").unwrap())
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        format!(
            "small.bin: byte {head}, field \"TST.Gyr\": field not in message TST (fields: TimeUS, I, GyrX, GyrY, GyrZ)"
        )
    );
}
