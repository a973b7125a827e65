//! ULog reader: round trip of written samples, multi-instance and nested fields, multi-rate
//! alignment with the shipped `examples/px4.toml` mapping, dropouts, appended data, the
//! vehicle skeleton from control-allocation parameters, and a catalogue of malformed
//! files, each answered with its own error naming the byte offset and message.

mod io_support;
mod scratch;

use std::path::{Path, PathBuf};

use io_support::{
    Px4Log, analytic_chunk, concat, px4_gyro, px4_like_log, px4_pwm, px4_rpm, px4_velocity, quad,
};
use mrsysid::SampleChunk;
use mrsysid::io::fixtures::ulog::{UlogWriter, write_samples, written_mapping};
use mrsysid::io::{IoError, Mapping, ReadOptions, Summary, open_log, read_definitions};
use mrsysid::vehicle::Vehicle;

fn tmp(name: &str) -> PathBuf {
    scratch::dir("ulog").join(name)
}

fn read_all(
    path: &Path,
    vehicle: &Vehicle,
    mapping: &Mapping,
) -> Result<(SampleChunk, Summary), IoError> {
    let mut reader = open_log(path, vehicle, Some(mapping), &ReadOptions::default())?;
    let mut chunks = Vec::new();
    for c in reader.by_ref() {
        chunks.push(c?);
    }
    Ok((concat(&chunks), reader.summary().clone()))
}

fn px4_mapping() -> Mapping {
    Mapping::from_toml_file(Path::new("examples/px4.toml")).unwrap()
}

#[test]
fn round_trip_of_written_samples_reads_instance_one() {
    let vehicle = quad(0.0);
    let src = analytic_chunk(300, 100.0);
    let path = tmp("round.ulg");
    write_samples(&path, [&src]).unwrap();
    let (got, summary) = read_all(&path, &vehicle, &written_mapping(4, true, true, true)).unwrap();
    assert_eq!(got.len(), 300);
    assert_eq!(summary.segments, 1);
    let (got_dot, src_dot) = (got.omega_dot.unwrap(), src.omega_dot.unwrap());
    let (got_height, src_height) = (got.height.unwrap(), src.height.unwrap());
    let (got_attitude, src_attitude) = (got.attitude.unwrap(), src.attitude.unwrap());
    for k in 0..300 {
        // Times are whole µs in ULog: 1e-9 s covers the rounding of t = 1 + k/100.
        assert!((got.t[k] - src.t[k]).abs() < 1e-9, "t[{k}]");
        for a in 0..3 {
            assert_eq!(got.velocity[a][k], src.velocity[a][k]);
            assert_eq!(got.rates[a][k], src.rates[a][k]);
        }
        for i in 0..4 {
            // Instance 1 carries the true values; instance 0 is a decoy at half.
            assert_eq!(got.omega[i][k], src.omega[i][k]);
            assert_eq!(got_dot[i][k], src_dot[i][k]);
        }
        for a in 0..6 {
            assert_eq!(got.wrench[a][k], src.wrench[a][k]);
        }
        assert_eq!(got_height[k], src_height[k]);
        for a in 0..4 {
            assert!((got_attitude[a][k] - src_attitude[a][k]).abs() < 1e-15);
        }
    }
}

#[test]
fn px4_like_log_aligns_slow_topics_on_the_gyro() {
    let vehicle = quad(0.0);
    let path = tmp("px4.ulg");
    std::fs::write(
        &path,
        px4_like_log(Px4Log {
            duration_us: 2_000_000,
            dropout_at: None,
        }),
    )
    .unwrap();
    let (got, summary) = read_all(&path, &vehicle, &px4_mapping()).unwrap();
    // 500 gyro samples in [1, 3) s; the first lies before the first esc/position message
    // and the last few after the last: only bracketed samples are kept.
    assert!(got.len() > 450 && got.len() < 500, "{}", got.len());
    let dropped: u64 = summary.dropped.values().sum();
    assert_eq!(got.len() as u64 + dropped, 500);
    for k in 0..got.len() {
        let t = got.t[k];
        let g = px4_gyro(t);
        for (a, g) in g.into_iter().enumerate() {
            assert_eq!(got.rates[a][k], g as f64, "rates[{a}] at t = {t}");
        }
        // Identity attitude: body velocity = NED velocity, interpolated linearly (f32 data).
        let v = px4_velocity(t);
        for (a, v) in v.into_iter().enumerate() {
            assert!((got.velocity[a][k] - v).abs() < 2e-6, "v[{a}] at t = {t}");
        }
        for i in 0..4 {
            let want = px4_rpm(i, (t * 1e6).round() as u64) * std::f64::consts::PI / 30.0;
            assert!(
                (got.omega[i][k] - want).abs() < 1e-9,
                "omega[{i}] at t = {t}"
            );
        }
        // F = m a from the accelerometer (f32 data), m = 1.2 kg.
        assert!((got.wrench[2][k] - 1.2 * -9.81f32 as f64).abs() < 1e-9);
    }
    assert!(summary.dropouts.is_empty());
    assert_eq!(summary.segments, 1);
}

#[test]
fn dropout_is_reported_and_never_bridged() {
    let vehicle = quad(0.0);
    let path = tmp("dropout.ulg");
    let at = 2_050_000;
    std::fs::write(
        &path,
        px4_like_log(Px4Log {
            duration_us: 2_000_000,
            dropout_at: Some(at),
        }),
    )
    .unwrap();
    let (got, summary) = read_all(&path, &vehicle, &px4_mapping()).unwrap();
    assert_eq!(summary.dropouts.len(), 1);
    assert!((summary.dropouts[0].duration - 0.020).abs() < 1e-12);
    assert_eq!(summary.segments, 2, "{summary:?}");
    // Samples between the last slow messages before and the first after the dropout
    // have no bracket on one side: dropped as not aligned, never interpolated across.
    let before = got.t.iter().filter(|&&t| t < 2.05).count();
    assert!(before > 0 && before < got.len());
    let nearest_after = got.t.iter().copied().find(|&t| t > 2.05).unwrap();
    assert!(
        nearest_after >= 2.103,
        "first sample after the dropout at {nearest_after}"
    );
    assert!(summary.dropped.values().sum::<u64>() > 10);
    // The first sample after the last slow message before the dropout, in words.
    assert_eq!(
        summary.first_dropped[2],
        "dropout.ulg: byte 20187, field \"vehicle_local_position\": no messages within \
         align_gap = 0.3 s around t = 2.004 s (or a logger dropout between them; raise \
         `[mcap] align_gap` for a slow topic, or log it faster next time: SDLOG_PROFILE bit 4 \
         (high rate) or bit 3 (system identification), ESC telemetry by bidirectional DShot, \
         DSHOT_BIDIR_EN = 1)"
    );
}

#[test]
fn appended_data_after_a_cut_message_is_read() {
    let vehicle = quad(0.0);
    let src = analytic_chunk(100, 100.0);
    let full = tmp("full.ulg");
    write_samples(&full, [&src]).unwrap();
    let mut bytes = std::fs::read(&full).unwrap();
    let more = analytic_chunk(150, 100.0);
    let tail = tmp("tail.ulg");
    write_samples(&tail, [&more]).unwrap();
    let tail_bytes = std::fs::read(&tail).unwrap();
    // Both files have the same definitions: the 150-sample file's bytes past the
    // 100-sample file's length are the data messages of samples 100..150. Cut the short
    // file inside its last message (sample 99's instance-1 rotors) and append them.
    let cut = bytes.len() - 5;
    bytes.truncate(cut);
    let offset = bytes.len() as u64;
    let start_of_100 = std::fs::read(&full).unwrap().len();
    bytes.extend_from_slice(&tail_bytes[start_of_100..]);
    // Flag bits: the 'B' message is the first after the 16-byte header; its payload
    // starts at byte 19: compat[8], incompat[8], offsets[3].
    bytes[19 + 8] = 1;
    bytes[19 + 16..19 + 24].copy_from_slice(&offset.to_le_bytes());
    let path = tmp("appended.ulg");
    std::fs::write(&path, &bytes).unwrap();
    let (got, _) = read_all(&path, &vehicle, &written_mapping(4, true, true, true)).unwrap();
    // All 150 samples: sample 99's rotor speeds are interpolated between samples 98 and
    // 100 (20 ms apart), the others are exact.
    assert_eq!(got.len(), 150);
    assert!((got.t[149] - more.t[149]).abs() < 1e-9);
    for k in [0, 98, 100, 149] {
        assert_eq!(got.omega[0][k], more.omega[0][k], "sample {k}");
    }
    let mid = 0.5 * (more.omega[0][98] + more.omega[0][100]);
    assert!((got.omega[0][99] - mid).abs() < 1e-9);
}

#[test]
fn vehicle_skeleton_from_ca_parameters() {
    let path = tmp("params.ulg");
    std::fs::write(
        &path,
        px4_like_log(Px4Log {
            duration_us: 10_000,
            dropout_at: None,
        }),
    )
    .unwrap();
    let defs = read_definitions(&path).unwrap();
    assert_eq!(defs.parameters["CA_ROTOR_COUNT"], 4.0);
    assert_eq!(defs.info["ver_hw"], "TEST_BOARD");
    let rotors = mrsysid::io::rotors_from_parameters(&defs.parameters).unwrap();
    let text = mrsysid::io::vehicle_skeleton(&rotors, "PX4", "params.ulg");
    let filled = text
        .replace("# mass = 1.5", "mass = 1.5")
        .replace("# inertia", "inertia")
        .replace("# rotor_radius", "rotor_radius");
    let v = Vehicle::from_toml_str(&filled, mrsysid::vehicle::VehicleSource::Code).unwrap();
    // 0.2 m arms within f32 rounding; hub 2 cm above the CG; KM > 0 is CCW: spin -1.
    assert!((v.arm_length() - 0.2).abs() < 1e-6);
    assert!((v.props.hub_height - 0.02).abs() < 1e-6);
    let spins: Vec<f64> = v.rotors().iter().map(|r| r.spin).collect();
    assert_eq!(spins, [-1.0, -1.0, 1.0, 1.0]);
}

/// Samples of [`small_log`] (enough to differentiate the rates for the moment).
const SMALL_SAMPLES: u64 = 20;

/// A small valid file for the malformed cases: formats, a subscription, 20 samples.
fn small_log() -> UlogWriter {
    let mut w = UlogWriter::new(0);
    w.flag_bits([0; 8], [0; 8], [0; 3]);
    w.format("s:uint64_t timestamp;double[3] v;double[3] w;double[4] o;double[3] f;");
    w.add(0, 7, "s");
    for k in 0..SMALL_SAMPLES {
        let mut d = (1_000_000 + 10_000 * k).to_le_bytes().to_vec();
        for x in [
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 900.0, 900.0, 900.0, 900.0, 0.0, 0.0, -11.0,
        ] {
            d.extend_from_slice(&f64::to_le_bytes(x));
        }
        w.data(7, &d);
    }
    w
}

fn small_mapping() -> Mapping {
    Mapping::from_toml_str(
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
        "small.toml",
    )
    .unwrap()
}

fn error_of(bytes: &[u8], mapping: &Mapping, name: &str) -> String {
    let path = tmp(&format!("{name}.ulg"));
    std::fs::write(&path, bytes).unwrap();
    match read_all(&path, &quad(0.0), mapping) {
        Ok((c, _)) => panic!("{name}: read {} samples, expected an error", c.len()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn small_log_reads() {
    let path = tmp("small.ulg");
    std::fs::write(&path, small_log().bytes()).unwrap();
    let (c, _) = read_all(&path, &quad(0.0), &small_mapping()).unwrap();
    assert_eq!(c.len(), SMALL_SAMPLES as usize);
    assert_eq!(c.omega[3][1], 900.0);
}

#[test]
fn malformed_catalogue() {
    let m = small_mapping();
    let good = small_log();
    let header_end = 16;
    let first_data = good.bytes().len() - SMALL_SAMPLES as usize * (3 + 2 + 8 + 13 * 8);
    let mut cases: Vec<(&str, Vec<u8>, Mapping, String)> = Vec::new();
    let mut push = |name: &'static str, bytes: Vec<u8>, mapping: &Mapping, want: String| {
        cases.push((name, bytes, mapping.clone(), want));
    };

    // 1. Bad magic.
    let mut b = good.bytes().to_vec();
    b[0] = b'X';
    push(
        "bad-magic",
        b,
        &m,
        "small: byte 0: not a ULog file (bad magic bytes)".into(),
    );
    // 2. Truncated header (the magic sniffing sees ULog, the header is cut).
    push(
        "short-header",
        good.bytes()[..10].to_vec(),
        &m,
        "byte 0: truncated header: the file has 10 bytes".into(),
    );
    // 3. Unsupported version.
    let mut b = good.bytes().to_vec();
    b[7] = 9;
    push(
        "version",
        b,
        &m,
        "byte 7: ULog version 9 is not supported".into(),
    );
    // 6. Unknown incompatible flag bit.
    let mut b = good.bytes().to_vec();
    b[header_end + 3 + 8] = 2;
    push(
        "incompat",
        b,
        &m,
        "byte 16: 'B' flag-bits message sets incompatible flags".into(),
    );
    // 7. Flag bits too short (bad message size).
    let mut w = UlogWriter::new(0);
    w.message(b'B', &[0; 12]);
    push(
        "short-flags",
        w.bytes().to_vec(),
        &m,
        "byte 16: 'B' flag-bits message has 12 bytes, at least 40 expected".into(),
    );
    // 8. Appended offset past the end of the file.
    let mut w = UlogWriter::new(0);
    w.flag_bits([0; 8], [1, 0, 0, 0, 0, 0, 0, 0], [99_999, 0, 0]);
    push(
        "appended-offset",
        w.bytes().to_vec(),
        &m,
        "byte 16: 'B' flag-bits message: appended-data offset 99999".into(),
    );
    // 9. Subscription of a topic without a format ("unknown format").
    let mut w = UlogWriter::new(0);
    w.add(0, 1, "nope");
    push(
        "unknown-format",
        w.bytes().to_vec(),
        &m,
        "byte 16: 'A' subscription of msg_id 1 to \"nope\", which has no 'F' format definition"
            .into(),
    );
    // 10. Data for an unsubscribed msg_id.
    let mut b = good.bytes().to_vec();
    b[first_data + 3] = 8;
    push(
        "unsubscribed",
        b,
        &m,
        format!(
            "byte {first_data}: 'D' data message for msg_id 8, which no 'A' message subscribed"
        ),
    );
    // 11. Bad field type in a mapped topic's format.
    let mut w = UlogWriter::new(0);
    w.format("s:uint64_t timestamp;float3[3] v;");
    w.add(0, 7, "s");
    push(
        "bad-type",
        w.bytes().to_vec(),
        &m,
        "field \"s.v[0]\": unknown type \"float3\" (neither a scalar nor a format)".into(),
    );
    // 12. Malformed format text.
    let mut w = UlogWriter::new(0);
    w.format("s uint64_t timestamp");
    push(
        "bad-format",
        w.bytes().to_vec(),
        &m,
        "byte 16: 'F' format message: format \"s uint64_t timestamp\" has no ':'".into(),
    );
    // 13. Bad array length in a format.
    let mut w = UlogWriter::new(0);
    w.format("s:uint64_t timestamp;double[x] v;");
    push(
        "bad-array",
        w.bytes().to_vec(),
        &m,
        "'F' format message: field \"v\" of format \"s\": bad array type \"double[x]\"".into(),
    );
    // 14. Data message too short for the mapped fields.
    let mut w = small_log();
    w.data(7, &[0; 20]);
    let at = small_log().bytes().len();
    push(
        "short-data",
        w.bytes().to_vec(),
        &m,
        format!(
            "byte {at}, field \"s\": 'D' data message of \"s\" has 20 data bytes, the mapped fields need 112"
        ),
    );
    // 15. Mapped field not in the format.
    let mut mm = m.clone();
    mm.signals.rates.as_mut().unwrap().fields[0] = "gyro[0]".into();
    push(
        "no-field",
        good.bytes().to_vec(),
        &mm,
        "field \"s.gyro[0]\": format \"s\" has no field \"gyro\" (fields: timestamp, v, w, o, f)"
            .into(),
    );
    // 16. Mapped topic not in the log.
    let mut mm = m.clone();
    mm.signals.force.as_mut().unwrap().topic = Some("vehicle_acceleration".into());
    push(
        "no-topic",
        good.bytes().to_vec(),
        &mm,
        "small: field \"vehicle_acceleration\": topic not in the log (logged topics: s)".into(),
    );
    // 16b. Rotor speeds from a topic not in the log: what to set on the vehicle next time.
    let mut mm = m.clone();
    mm.signals.rotor_speeds.as_mut().unwrap().topic = Some("esc_status".into());
    push(
        "no-esc-status",
        good.bytes().to_vec(),
        &mm,
        "small: field \"esc_status\": topic not in the log (logged topics: s); PX4 logs \
         esc_status with rotor speeds only from ESCs that report them: bidirectional DShot \
         (DSHOT_BIDIR_EN = 1"
            .into(),
    );
    // 17. Mapped topic subscribed but without data.
    let mut w = small_log();
    w.format("e:uint64_t timestamp;double x;");
    w.add(0, 9, "e");
    let mut mm = m.clone();
    mm.signals.force.as_mut().unwrap().topic = Some("e".into());
    mm.signals.force.as_mut().unwrap().fields = vec!["x".into(), "x".into(), "x".into()];
    push(
        "no-data",
        w.bytes().to_vec(),
        &mm,
        "small: field \"e\": topic is subscribed but has no data messages in the log".into(),
    );
    // 18. Cyclic nested formats.
    let mut w = UlogWriter::new(0);
    w.format("s:uint64_t timestamp;s[1] v;");
    w.add(0, 7, "s");
    push(
        "cycle",
        w.bytes().to_vec(),
        &m,
        "nests deeper than 16 levels".into(),
    );
    // 19. Flag bits later in the file.
    let mut w = small_log();
    w.flag_bits([0; 8], [0; 8], [0; 3]);
    push(
        "late-flags",
        w.bytes().to_vec(),
        &m,
        "'B' flag-bits message after the first message".into(),
    );
    // 20. Instance that is not a number.
    let mut mm = m.clone();
    mm.signals.force.as_mut().unwrap().topic = Some("s[x]".into());
    push(
        "bad-instance",
        good.bytes().to_vec(),
        &mm,
        "topic \"s[x]\": instance \"x\" is not a number".into(),
    );

    assert!(cases.len() >= 10);
    for (name, bytes, mapping, want) in cases {
        let got = error_of(&bytes, &mapping, &format!("small-{name}"));
        let want = want.replace("small:", &format!("small-{name}.ulg:"));
        assert!(got.contains(&want), "{name}:\n got: {got}\nwant: {want}");
    }
}

/// A file the end cuts inside its last message or a message header (a log closed by a
/// power cut) is read up to that message, and its summary says where it was cut.
#[test]
fn a_file_cut_inside_a_message_is_read_up_to_it() {
    let good = small_log();
    let b = good.bytes();
    let last = b.len() - (3 + 2 + 8 + 13 * 8);
    let mut one_more = b.to_vec();
    one_more.push(5);
    for (name, bytes, samples, want) in [
        (
            "cut",
            &b[..b.len() - 7],
            SMALL_SAMPLES - 1,
            format!("a 'D' message at byte {last} (110 of its 117 bytes)"),
        ),
        (
            "cut-header",
            &one_more[..],
            SMALL_SAMPLES,
            format!("a message header at byte {} (1 of its 3 bytes)", b.len()),
        ),
    ] {
        let path = tmp(&format!("{name}.ulg"));
        std::fs::write(&path, bytes).unwrap();
        let (c, summary) = read_all(&path, &quad(0.0), &small_mapping()).unwrap();
        assert_eq!(c.len() as u64, samples, "{name}");
        let note = summary.cut_off.unwrap_or_default();
        assert!(
            note.starts_with(&format!("the file ends inside {want}: the log was cut off")),
            "{name}: {note}"
        );
    }
    let path = tmp("whole.ulg");
    std::fs::write(&path, b).unwrap();
    assert_eq!(
        read_all(&path, &quad(0.0), &small_mapping())
            .unwrap()
            .1
            .cut_off,
        None
    );
}

/// The px4 mapping with rotor speeds from actuator_outputs instance 1 (PWM 1000..2000,
/// 1000 rad/s at full command, THR_MDL_FAC 1: speed linear in the command).
fn commanded_mapping(time_constant: Option<f64>) -> Mapping {
    let text = std::fs::read_to_string("examples/px4.toml").unwrap();
    let start = text.find("[signals.rotor_speeds]").unwrap();
    let mut text = text[..start].to_string();
    text += r#"
[signals.rotor_speeds]
topic = "actuator_outputs[1]"
fields = ["output[0]", "output[1]", "output[2]", "output[3]"]
unit = "rad/s"
[signals.rotor_speeds.actuator]
pwm_min = 1000
pwm_max = 2000
max_speed = 1000
thr_mdl_fac = 1.0
"#;
    if let Some(tau) = time_constant {
        text += &format!("time_constant = {tau}\n");
    }
    Mapping::from_toml_str(&text, "commanded.toml").unwrap()
}

#[test]
fn rotor_speeds_from_commanded_pwm() {
    let vehicle = quad(0.0);
    let path = tmp("commanded.ulg");
    std::fs::write(
        &path,
        px4_like_log(Px4Log {
            duration_us: 2_000_000,
            dropout_at: None,
        }),
    )
    .unwrap();
    let (got, summary) = read_all(&path, &vehicle, &commanded_mapping(None)).unwrap();
    assert!(got.len() > 450);
    assert!(
        summary
            .derived
            .iter()
            .any(|d| d.contains("commanded, not measured"))
    );
    for k in 0..got.len() {
        let t_us = got.t[k] * 1e6;
        for i in 0..4 {
            // u = (pwm − 1000)/1000, Ω = 1000 u; f32 PWM data: 1e-3 rad/s.
            let want = px4_pwm(i, t_us) - 1000.0;
            assert!(
                (got.omega[i][k] - want).abs() < 1e-3,
                "omega[{i}] at {t_us} us"
            );
        }
    }
    // A first-order motor lag of 50 ms on a command ramping at 100 rad/s^2 settles
    // 100 * 0.05 = 5 rad/s behind it (exact for the linear command, after transients).
    let (lagged, _) = read_all(&path, &vehicle, &commanded_mapping(Some(0.05))).unwrap();
    assert_eq!(lagged.len(), got.len());
    let t0 = lagged.t[0];
    let mut checked = 0;
    for k in 0..lagged.len() {
        if lagged.t[k] - t0 < 1.0 {
            continue;
        }
        for i in 0..4 {
            let lag = got.omega[i][k] - lagged.omega[i][k];
            assert!(
                (lag - 5.0).abs() < 1e-3,
                "lag {lag} of rotor {i} at {}",
                lagged.t[k]
            );
        }
        checked += 1;
    }
    assert!(checked > 200);
    // Bad maps are refused with the key named.
    let bad = std::fs::read_to_string("examples/px4.toml").unwrap()
        + "[signals.rotor_speeds.actuator]\npwm_min = 2000\npwm_max = 1000\nmax_speed = 1\n";
    let e = Mapping::from_toml_str(&bad, "bad.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("key \"signals.rotor_speeds\": actuator: give both `pwm_min` < `pwm_max`"),
        "{e}"
    );
}

/// Read speed, by hand: `cargo test --release --test io_ulog -- --ignored --nocapture`.
#[test]
#[ignore = "timing, run by hand"]
fn read_speed_of_a_large_file() {
    let vehicle = quad(0.0);
    let n = 200_000;
    let chunks: Vec<SampleChunk> = (0..n / 1000)
        .map(|c| {
            let mut ch = analytic_chunk(1000, 400.0);
            ch.t.iter_mut().for_each(|t| *t += c as f64 * 2.5);
            ch
        })
        .collect();
    let path = tmp("large.ulg");
    write_samples(&path, &chunks).unwrap();
    let bytes = std::fs::metadata(&path).unwrap().len() as f64;
    let mapping = written_mapping(4, true, true, true);
    let start = std::time::Instant::now();
    let (got, _) = read_all(&path, &vehicle, &mapping).unwrap();
    let s = start.elapsed().as_secs_f64();
    assert_eq!(got.len(), n);
    println!(
        "{n} samples ({:.1} MB, 3 data messages each) in {s:.3} s: {:.2} M samples/s, {:.0} MB/s",
        bytes / 1e6,
        n as f64 / s / 1e6,
        bytes / 1e6 / s
    );
}

#[test]
fn appended_data_after_a_cut_message_header_is_read() {
    let vehicle = quad(0.0);
    let small = small_log();
    let mut bytes = small.bytes().to_vec();
    // Half a message header, then the appended data: two more samples.
    bytes.extend_from_slice(&[0x40, 0x00]);
    let offset = bytes.len() as u64;
    let mut more = UlogWriter::new(0);
    for k in SMALL_SAMPLES..SMALL_SAMPLES + 2 {
        let mut d = (1_000_000 + 10_000 * k).to_le_bytes().to_vec();
        for x in [
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 900.0, 900.0, 900.0, 900.0, 0.0, 0.0, -11.0,
        ] {
            d.extend_from_slice(&f64::to_le_bytes(x));
        }
        more.data(7, &d);
    }
    bytes.extend_from_slice(&more.bytes()[16..]);
    bytes[19 + 8] = 1;
    bytes[19 + 16..19 + 24].copy_from_slice(&offset.to_le_bytes());
    let path = tmp("appended-header.ulg");
    std::fs::write(&path, &bytes).unwrap();
    let (got, _) = read_all(&path, &vehicle, &small_mapping()).unwrap();
    assert_eq!(got.len(), SMALL_SAMPLES as usize + 2);
}
