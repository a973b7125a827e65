//! MCAP: CSV → samples → MCAP (JSON) → samples identical; asynchronous topics aligned by
//! interpolation within max_gap and split into segments beyond it; malformed files.

mod io_support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use io_support::{analytic_chunk, assert_same, concat, quad};
use mrsysid::io::contract_csv::write_contract_csv;
use mrsysid::io::mcap_write::{Encoding, write_samples, written_mapping};
use mrsysid::io::{Mapping, ReadOptions, open_log};
use mrsysid::sample::SampleChunk;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mrsysid-mcap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn read_all(
    path: &Path,
    mapping: Option<&Mapping>,
) -> (SampleChunk, mrsysid::io::Summary, Vec<usize>) {
    let vehicle = quad(3e-5);
    let mut reader = open_log(path, &vehicle, mapping, &ReadOptions::default()).unwrap();
    let mut chunks = Vec::new();
    let mut segments = Vec::new();
    while let Some(c) = reader.next() {
        chunks.push(c.unwrap());
        segments.push(reader.segment_index());
    }
    (concat(&chunks), reader.summary().clone(), segments)
}

#[test]
fn csv_to_mcap_json_to_samples_is_identical() {
    let vehicle = quad(3e-5);
    let src = analytic_chunk(2100, 250.0);
    let csv = tmp("rt.csv");
    write_contract_csv(&csv, [&src]).unwrap();
    let (from_csv, _, _) = read_all(&csv, None);
    let mcap = tmp("rt.mcap");
    write_samples(&mcap, &vehicle, [&from_csv], Encoding::Json).unwrap();
    let mapping = written_mapping(4, true, true, true);
    let (from_mcap, summary, segments) = read_all(&mcap, Some(&mapping));
    // JSON numbers are written with shortest round-trip formatting: bit-identical.
    assert_same(&from_mcap, &from_csv);
    assert_same(&from_mcap, &src);
    assert_eq!(summary.segments, 1);
    assert_eq!(segments, vec![0, 0, 0]);
}

/// Writes an MCAP file with an IMU topic at `imu_hz` and a rotor topic at `rotor_hz`
/// (offset by half a rotor period), with a wrench on the IMU topic; rotor speed is
/// linear in time so interpolation is exact. Rotor messages in (hole_from, hole_to)
/// are left out.
fn write_async(path: &Path, seconds: f64, hole: (f64, f64)) {
    use mcap::records::MessageHeader;
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(path).unwrap(),
    ))
    .unwrap();
    let meta = BTreeMap::new();
    let imu = w.add_channel(0, "/imu", "json", &meta).unwrap();
    let esc = w.add_channel(0, "/esc", "json", &meta).unwrap();
    let mut seq = 0;
    let mut events: Vec<(u64, u16, String)> = Vec::new();
    let n_imu = (seconds * 200.0) as u64;
    for k in 0..n_imu {
        let ns = k * 5_000_000;
        let msg = format!(
            r#"{{"header":{{"stamp":{{"sec":{},"nanosec":{}}}}},"gyro":[0.1,0.2,0.3],"vel":{{"x":1,"y":0,"z":0}},"f":[0,0,-11.7],"m":[0,0,0]}}"#,
            ns / 1_000_000_000,
            ns % 1_000_000_000
        );
        events.push((ns, imu, msg));
    }
    let n_esc = (seconds * 100.0) as u64;
    for k in 0..n_esc {
        let ns = 5_000_000 + k * 10_000_000;
        let t = ns as f64 * 1e-9;
        if t > hole.0 && t < hole.1 {
            continue;
        }
        let rpm = 6000.0 + 1000.0 * t;
        let msg = format!(
            r#"{{"header":{{"stamp":{{"sec":{},"nanosec":{}}}}},"esc":[{{"rpm":{rpm}}},{{"rpm":{rpm}}},{{"rpm":{rpm}}},{{"rpm":{rpm}}}]}}"#,
            ns / 1_000_000_000,
            ns % 1_000_000_000
        );
        events.push((ns, esc, msg));
    }
    events.sort_by_key(|e| e.0);
    for (ns, ch, msg) in events {
        let header = MessageHeader {
            channel_id: ch,
            sequence: seq,
            log_time: ns,
            publish_time: ns,
        };
        seq += 1;
        w.write_to_known_channel(&header, msg.as_bytes()).unwrap();
    }
    w.finish().unwrap();
}

fn async_mapping() -> Mapping {
    Mapping::from_toml_str(
        r#"
        [time]
        fields = ["header.stamp"]
        [mcap]
        time_base = "/imu"
        [signals.rates]
        topic = "/imu"
        fields = ["gyro[0]", "gyro[1]", "gyro[2]"]
        [signals.velocity_body]
        topic = "/imu"
        fields = ["vel.x", "vel.y", "vel.z"]
        [signals.force]
        topic = "/imu"
        fields = ["f[0]", "f[1]", "f[2]"]
        [signals.moment]
        topic = "/imu"
        fields = ["m[0]", "m[1]", "m[2]"]
        [signals.rotor_speeds]
        topic = "/esc"
        fields = ["esc[0].rpm", "esc[1].rpm", "esc[2].rpm", "esc[3].rpm"]
        unit = "rpm"
        "#,
        "async.toml",
    )
    .unwrap()
}

#[test]
fn asynchronous_topics_are_interpolated_within_max_gap() {
    let path = tmp("async.mcap");
    write_async(&path, 2.0, (10.0, 10.0));
    let (c, s, _) = read_all(&path, Some(&async_mapping()));
    // IMU at 0, 5, …, 1995 ms; ESC at 5, 15, …, 1995 ms: the first IMU sample (t = 0)
    // precedes every ESC message and the last ESC message is at 1995 ms, so 399 samples
    // from 5 ms on are aligned and 1 is dropped.
    assert_eq!(c.len(), 399);
    assert_eq!(s.dropped.get("topic not aligned within max_gap"), Some(&1));
    for k in 0..c.len() {
        // Rotor speed linear in t: interpolation is exact up to rounding, 1e-9 rad/s.
        let want = (6000.0 + 1000.0 * c.t[k]) * std::f64::consts::PI / 30.0;
        assert!(
            (c.omega[2][k] - want).abs() < 1e-9,
            "k={k}: {} vs {want}",
            c.omega[2][k]
        );
    }
}

#[test]
fn a_hole_in_one_topic_splits_segments_never_bridged() {
    let path = tmp("hole.mcap");
    write_async(&path, 2.0, (0.8, 1.2)); // ESC silent for 0.4 s > max_gap 0.1 s
    let (c, s, segments) = read_all(&path, Some(&async_mapping()));
    assert_eq!(s.segments, 2);
    assert_eq!(segments, vec![0, 1]);
    assert!(
        s.dropped["topic not aligned within max_gap"] > 70,
        "{:?}",
        s.dropped
    );
    assert!(c.t.windows(2).all(|w| w[1] > w[0]));
    assert_eq!(s.gaps.len(), 1);
    assert!(s.gaps[0].to - s.gaps[0].from > 0.3);
}

fn first_error(path: &Path, mapping: &Mapping) -> String {
    let vehicle = quad(0.0);
    match open_log(path, &vehicle, Some(mapping), &ReadOptions::default()) {
        Err(e) => e.to_string(),
        Ok(r) => r
            .filter_map(Result::err)
            .next()
            .map(|e| e.to_string())
            .expect("an error"),
    }
}

#[test]
fn malformed_mcap_inputs_get_specific_errors() {
    let path = tmp("good.mcap");
    write_async(&path, 0.5, (10.0, 10.0));
    let bytes = std::fs::read(&path).unwrap();
    // Truncated in the middle of the data section.
    let cut = tmp("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = first_error(&cut, &async_mapping());
    assert!(e.starts_with("cut.mcap: message "), "{e}");
    assert!(e.contains("MCAP"), "{e}");
    // A mapped topic absent from the file.
    let mut m = async_mapping();
    m.signals.rotor_speeds.as_mut().unwrap().topic = Some("/motors".into());
    assert_eq!(
        first_error(&path, &m),
        "good.mcap: field \"/motors\": topic not in the file"
    );
    // A mapped field absent from the messages.
    let mut m = async_mapping();
    m.signals.rates.as_mut().unwrap().fields[1] = "gyro[7]".into();
    assert_eq!(
        first_error(&path, &m),
        "good.mcap: message 0, field \"/imu.gyro[7]\": field not in the message"
    );
    // MCAP without a mapping file.
    let e = open_log(&path, &quad(0.0), None, &ReadOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert_eq!(
        e,
        "good.mcap: an MCAP log needs a mapping file naming topics and fields"
    );
}
