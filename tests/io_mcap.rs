//! MCAP: CSV → samples → MCAP (JSON) → samples identical; asynchronous topics aligned by
//! interpolation within max_gap and split into segments beyond it; malformed files.

mod io_support;
mod scratch;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use io_support::{analytic_chunk, assert_same, concat, quad};
use mrsysid::SampleChunk;
use mrsysid::io::fixtures::mcap::{
    Encoding, Layout, write_samples, write_samples_laid_out, written_mapping,
};
use mrsysid::io::fixtures::write_contract_csv;
use mrsysid::io::{Mapping, ReadOptions, open_log};

fn tmp(name: &str) -> PathBuf {
    scratch::dir("mcap").join(name)
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
fn csv_to_mcap_json_and_cdr_to_samples_is_identical() {
    let vehicle = quad(3e-5);
    let src = analytic_chunk(2100, 250.0);
    let csv = tmp("rt.csv");
    write_contract_csv(&csv, [&src]).unwrap();
    let (from_csv, _, _) = read_all(&csv, None);
    for encoding in [Encoding::Json, Encoding::Cdr] {
        let mcap = tmp(&format!("rt-{encoding:?}.mcap"));
        write_samples(&mcap, &vehicle, [&from_csv], encoding).unwrap();
        let mapping = written_mapping(4, true, true, true);
        let (from_mcap, summary, segments) = read_all(&mcap, Some(&mapping));
        // JSON numbers use shortest round-trip formatting, CDR the raw IEEE bytes:
        // bit-identical either way.
        assert_same(&from_mcap, &from_csv);
        assert_same(&from_mcap, &src);
        assert_eq!(summary.segments, 1);
        assert_eq!(segments, vec![0, 0, 0]);
    }
}

/// MCAP need not store messages in log-time order: a file whose topics are written in
/// blocks (all state messages, then all rotor speeds, then all wrenches) in small chunks
/// that overlap in time reads back identical to the source through the chunk indexes,
/// JSON and CDR; without an index the broken order is an error saying so, and an
/// unindexed file in log-time order still reads in file order.
#[test]
fn messages_out_of_log_time_order_are_read_through_the_chunk_index() {
    let vehicle = quad(3e-5);
    let src = analytic_chunk(2100, 250.0);
    let mapping = written_mapping(4, true, true, true);
    let layout = |topic_blocks, indexed| Layout {
        topic_blocks,
        indexed,
        chunk_size: 16 << 10,
    };
    for encoding in [Encoding::Json, Encoding::Cdr] {
        let blocks = tmp(&format!("blocks-{encoding:?}.mcap"));
        write_samples_laid_out(&blocks, &vehicle, [&src], encoding, layout(true, true)).unwrap();
        let (c, summary, _) = read_all(&blocks, Some(&mapping));
        assert_same(&c, &src);
        assert_eq!(summary.segments, 1);
        assert!(summary.dropped.is_empty(), "{:?}", summary.dropped);

        let flat = tmp(&format!("flat-{encoding:?}.mcap"));
        write_samples_laid_out(&flat, &vehicle, [&src], encoding, layout(true, false)).unwrap();
        let e = first_error(&flat, &mapping);
        // Message 2100 is the first rotor message (t = 1 s), after the 2100 state messages.
        let want = format!(
            "flat-{encoding:?}.mcap: message 2100, field \"/mrsysid/rotors\": time t = 1 s"
        );
        assert!(e.starts_with(&want), "{e}");
        assert!(e.contains("not stored in log-time order"), "{e}");
        assert!(e.contains("no chunk index"), "{e}");

        let ordered = tmp(&format!("ordered-{encoding:?}.mcap"));
        write_samples_laid_out(&ordered, &vehicle, [&src], encoding, layout(false, false)).unwrap();
        assert_same(&read_all(&ordered, Some(&mapping)).0, &src);
    }
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
    assert!(
        s.first_dropped[0].ends_with("no messages within max_gap = 0.1 s around t = 0 s"),
        "{:?}",
        s.first_dropped
    );
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
    // Regression (found by tests/io_fuzz.rs, aborted with a 5.8e17-byte allocation): a
    // corrupt record length is refused, not allocated. Header record opcode at byte 8,
    // its u64 length at bytes 9..17.
    let mut huge = bytes.clone();
    huge[9..17].copy_from_slice(&(u64::MAX / 32).to_le_bytes());
    let huge_path = tmp("huge.mcap");
    std::fs::write(&huge_path, &huge).unwrap();
    let e = first_error(&huge_path, &async_mapping());
    assert!(e.starts_with("huge.mcap: message 0: MCAP: "), "{e}");
    // A mapped topic absent from the file.
    let mut m = async_mapping();
    m.signals.rotor_speeds.as_mut().unwrap().topic = Some("/motors".into());
    assert_eq!(
        first_error(&path, &m),
        "good.mcap: field \"/motors\": topic not in the file (topics in the file: /esc, /imu)"
    );
    // A mapped field absent from the messages.
    let mut m = async_mapping();
    m.signals.rates.as_mut().unwrap().fields[1] = "gyro[7]".into();
    assert_eq!(
        first_error(&path, &m),
        "good.mcap: message 0, field \"/imu.gyro[7]\": field not in the message \
         (gyro has 3 elements)"
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

/// Little-endian CDR writer for test messages of arbitrary primitive layout.
struct Cdr(Vec<u8>);

impl Cdr {
    fn new() -> Self {
        Cdr(vec![0, 1, 0, 0])
    }
    fn pad(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }
    fn u8(&mut self, x: u8) {
        self.0.push(x);
    }
    fn i32(&mut self, x: i32) {
        self.pad(4);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u32(&mut self, x: u32) {
        self.pad(4);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn f32(&mut self, x: f32) {
        self.pad(4);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.pad(8);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn f64(&mut self, x: f64) {
        self.pad(8);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
    }
}

const SEP: &str =
    "================================================================================\n";

/// sensor_msgs/Imu as ROS 2 stores it in MCAP (comments stripped).
fn imu_schema() -> String {
    format!(
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n\
         geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n\
         geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n\
         {SEP}MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
         {SEP}MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n\
         {SEP}MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n\
         {SEP}MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
    )
}

/// px4_msgs/EscStatus with a fixed array of nested EscReport (abridged field list).
fn esc_schema() -> String {
    format!(
        "uint64 timestamp\nuint8 CONNECTED_ESC_MAX = 8\nuint16 counter\nuint8 esc_count\n\
         px4_msgs/EscReport[8] esc\n{SEP}MSG: px4_msgs/EscReport\nuint64 timestamp\nint32 esc_rpm\n\
         float32 esc_voltage\nuint8 esc_state\n"
    )
}

fn imu_message(ns: u64, gyro: [f64; 3], acc: [f64; 3]) -> Vec<u8> {
    let mut c = Cdr::new();
    c.i32((ns / 1_000_000_000) as i32);
    c.u32((ns % 1_000_000_000) as u32);
    c.string("base_link");
    [0.0, 0.0, 0.0, 1.0].iter().for_each(|&x| c.f64(x));
    (0..9).for_each(|_| c.f64(0.0));
    gyro.iter().for_each(|&x| c.f64(x));
    (0..9).for_each(|_| c.f64(0.0));
    acc.iter().for_each(|&x| c.f64(x));
    (0..9).for_each(|_| c.f64(0.0));
    c.0
}

fn esc_message(ns: u64, rpm: [i32; 4]) -> Vec<u8> {
    let mut c = Cdr::new();
    c.u64(ns / 1000);
    c.0.extend_from_slice(&7u16.to_le_bytes());
    c.u8(4);
    for i in 0..8 {
        c.u64(ns / 1000);
        c.i32(rpm.get(i).copied().unwrap_or(0));
        c.f32(16.8);
        c.u8(1);
    }
    c.0
}

#[test]
fn ros2_cdr_imu_and_px4_esc_status_decode_from_their_schemas() {
    use mcap::records::MessageHeader;
    let path = tmp("ros2.mcap");
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&path).unwrap(),
    ))
    .unwrap();
    let meta = BTreeMap::new();
    let s1 = w
        .add_schema("sensor_msgs/msg/Imu", "ros2msg", imu_schema().as_bytes())
        .unwrap();
    let s2 = w
        .add_schema("px4_msgs/msg/EscStatus", "ros2msg", esc_schema().as_bytes())
        .unwrap();
    let imu = w.add_channel(s1, "/imu", "cdr", &meta).unwrap();
    let esc = w.add_channel(s2, "/esc", "cdr", &meta).unwrap();
    for k in 0..100u64 {
        let ns = 1_000_000_000 + k * 10_000_000;
        let gyro = [0.01 * k as f64, -0.5, 0.25];
        let h = |c| MessageHeader {
            channel_id: c,
            sequence: k as u32,
            log_time: ns,
            publish_time: ns,
        };
        w.write_to_known_channel(&h(imu), &imu_message(ns, gyro, [0.1, 0.2, -9.7]))
            .unwrap();
        let rpm = [10000 + k as i32, 10100, 10200, 10300];
        w.write_to_known_channel(&h(esc), &esc_message(ns, rpm))
            .unwrap();
    }
    w.finish().unwrap();
    let mapping = Mapping::from_toml_str(
        r#"
        [frames]
        body = "flu"
        [time]
        fields = ["header.stamp"]
        [mcap]
        time_base = "/imu"
        [mcap.topic_time."/esc"]
        field = "timestamp"
        unit = "us"
        [signals.rates]
        topic = "/imu"
        fields = ["angular_velocity.x", "angular_velocity.y", "angular_velocity.z"]
        [signals.specific_force]
        topic = "/imu"
        fields = ["linear_acceleration.x", "linear_acceleration.y", "linear_acceleration.z"]
        [signals.velocity_body]
        topic = "/imu"
        fields = ["orientation.x", "orientation.y", "orientation.z"]
        [signals.rotor_speeds]
        topic = "/esc"
        fields = ["esc[0].esc_rpm", "esc[1].esc_rpm", "esc[2].esc_rpm", "esc[3].esc_rpm"]
        unit = "erpm"
        pole_pairs = 7
        "#,
        "ros2.toml",
    )
    .unwrap();
    let (c, s, _) = read_all(&path, Some(&mapping));
    // The ESC time (µs · 1e-6) and the IMU stamp (sec + nanosec · 1e-9) of the same
    // instant may differ in the last bit; when the ESC one is earlier, the final IMU
    // sample has no later ESC message to interpolate to and is dropped (not bridged).
    assert!(c.len() >= 99 && c.len() + s.dropped.values().sum::<u64>() as usize == 100);
    // Header stamp 1 s + k·10 ms; FLU → FRD flips y and z of rates and specific force.
    assert_eq!(c.t[3], 1.0 + 30_000_000.0 * 1e-9);
    assert_eq!(c.rates[0][3], 0.03);
    assert_eq!(c.rates[1][3], 0.5);
    assert_eq!(c.rates[2][3], -0.25);
    assert_eq!(c.wrench[2][3], 1.2 * 9.7);
    // 10003 eRPM with 7 pole pairs = 10003/7 RPM; 1 ulp-level tolerance (1e-9 rad/s).
    let want = 10003.0 * (std::f64::consts::PI / 30.0 / 7.0);
    assert!((c.omega[0][3] - want).abs() < 1e-9);
}
