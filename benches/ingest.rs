//! Ingest throughput: a 1 M-row contract CSV through `io::open_log` against a bare
//! `csv::ByteRecord` pass over the same file, and a 100 k-sample MCAP (JSON and CDR,
//! three topics) through `open_log` against bare message iteration with the `mcap`
//! crate's linear reader, without and with decoding every message (serde_json for JSON,
//! the crate's ros2msg/CDR decoder for CDR: the decoders `open_log` uses). The CSV and
//! bare MCAP baselines read the same bytes without parsing numbers. A 100 k-sample PX4
//! ULog and a 100 k-sample ArduPilot DataFlash log (both written by the crate's test
//! writers: ULog with a state topic and two rotor-topic instances; DataFlash with two
//! IMU instances a sample, the EKF and ESC telemetry at every second) through
//! `open_log` against a bare scan of their messages: each message's header read and its
//! bytes read past through the same 64 KiB buffering, no field decoded.
//!
//! `cargo bench --bench ingest -- --warm-up-time 1 --measurement-time 3`

use std::collections::HashMap;
use std::hint::black_box;
use std::io::Read;
use std::path::{Path, PathBuf};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader};
use mrsysid::SampleChunk;
use mrsysid::io::fixtures::dataflash::write_flight;
use mrsysid::io::fixtures::mcap::{Encoding, write_samples, written_mapping};
use mrsysid::io::fixtures::{ulog, write_contract_csv};
use mrsysid::io::{ReadOptions, open_log};
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};

const CSV_ROWS: usize = 1_000_000;
const MCAP_SAMPLES: usize = 100_000;
const FLIGHT_LOG_SAMPLES: usize = 100_000;

fn vehicle() -> Vehicle {
    let props = MassAndRotorProperties {
        mass: 1.2,
        inertia: [[0.011, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.021]],
        air_density: 1.225,
        rotor_radius: 0.0635,
        hub_height: 0.02,
        rotor_inertia: 0.0,
    };
    Vehicle::preset("bench-quad", Preset::QuadX, 0.16, 1.0, props).expect("valid vehicle")
}

/// Smooth flight-like signals, chunk by chunk, 400 Hz.
fn chunks(n: usize) -> impl Iterator<Item = SampleChunk> {
    (0..n.div_ceil(4096)).map(move |c| {
        let len = 4096.min(n - c * 4096);
        let mut ch = SampleChunk::with_capacity(4, len, false);
        for j in 0..len {
            let t = (c * 4096 + j) as f64 / 400.0;
            ch.t.push(t);
            for a in 0..3 {
                ch.velocity[a].push(3.0 * (0.3 * t + a as f64).sin());
                ch.rates[a].push(0.5 * (1.7 * t + a as f64).cos());
            }
            for (i, w) in ch.omega.iter_mut().enumerate() {
                w.push(900.0 + 80.0 * (2.1 * t + i as f64).sin());
            }
            for (a, f) in ch.wrench.iter_mut().enumerate() {
                f.push(if a == 2 { -11.8 } else { 0.0 } + 0.2 * (0.9 * t + a as f64).sin());
            }
        }
        ch
    })
}

fn file(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("mrsysid-bench-{name}"))
}

fn ingest(path: &Path, v: &Vehicle, mapping: Option<&mrsysid::io::Mapping>) -> usize {
    open_log(path, v, mapping, &ReadOptions::default())
        .expect("opens")
        .map(|c| c.expect("valid").len())
        .sum()
}

fn bare_csv(path: &Path) -> usize {
    let mut r = csv::Reader::from_path(path).expect("opens");
    let mut rec = csv::ByteRecord::new();
    let mut n = 0;
    while r.read_byte_record(&mut rec).expect("valid") {
        n += rec.len();
    }
    n
}

/// Calls `f` on every record of the MCAP file at `path`, read with the `mcap` crate's
/// linear reader.
fn for_each_record(path: &Path, mut f: impl FnMut(mcap::records::Record)) {
    let mut file = std::fs::File::open(path).expect("opens");
    let mut reader = LinearReader::new();
    while let Some(ev) = reader.next_event() {
        match ev.expect("valid") {
            LinearReadEvent::ReadRequest(need) => {
                let n = file.read(reader.insert(need)).expect("reads");
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => {
                f(mcap::parse_record(opcode, data).expect("valid"));
            }
        }
    }
}

/// Bare message iteration: the payload bytes of every message.
fn bare_mcap(path: &Path) -> usize {
    let mut bytes = 0;
    for_each_record(path, |record| {
        if let mcap::records::Record::Message { data, .. } = record {
            bytes += data.len();
        }
    });
    bytes
}

/// Bare message iteration plus decoding each message with its channel's decoder; the
/// number of decoded top-level fields.
fn decoded_mcap(path: &Path) -> usize {
    use mcap::records::Record;
    use mrsysid::io::internals::{decode_cdr, parse_ros2_schema};
    let mut schemas = HashMap::new();
    let mut channels = HashMap::new();
    let mut fields = 0;
    for_each_record(path, |record| match record {
        Record::Schema { header, data } if header.encoding == "ros2msg" => {
            let text = std::str::from_utf8(&data).expect("schema text");
            let schema = parse_ros2_schema(&header.name, text).expect("schema");
            schemas.insert(header.id, schema);
        }
        Record::Channel(ch) => {
            channels.insert(ch.id, ch.schema_id);
        }
        Record::Message { header, data } => {
            let value = match schemas.get(&channels[&header.channel_id]) {
                Some(schema) => decode_cdr(schema, &data).expect("CDR"),
                None => serde_json::from_slice(&data).expect("JSON"),
            };
            fields += value.as_object().map_or(0, |o| o.len());
        }
        _ => {}
    });
    fields
}

/// A buffered reader of the file at `path`, with the readers' 64 KiB buffer.
fn buffered(path: &Path) -> std::io::BufReader<std::fs::File> {
    std::io::BufReader::with_capacity(1 << 16, std::fs::File::open(path).expect("opens"))
}

/// Bare ULog scan: the 16-byte file header, then every message's 3-byte header (size,
/// type) and its payload read past; the number of data (`D`) messages.
fn bare_ulog(path: &Path) -> usize {
    let mut r = buffered(path);
    let mut header = [0u8; 16];
    r.read_exact(&mut header).expect("header");
    let (mut payload, mut data) = (Vec::with_capacity(1 << 16), 0);
    let mut h = [0u8; 3];
    while r.read_exact(&mut h).is_ok() {
        let size = u16::from_le_bytes([h[0], h[1]]) as usize;
        payload.resize(size, 0);
        r.read_exact(&mut payload).expect("payload");
        data += usize::from(h[2] == b'D');
    }
    data
}

/// Bare DataFlash scan: every message's 3-byte head (0xA3 0x95, type) and its body read
/// past, with each type's length taken from its `FMT` message (type 128, 89 bytes; the
/// defined type and its length are its first two body bytes); the number of messages.
fn bare_dataflash(path: &Path) -> usize {
    let mut r = buffered(path);
    let mut length = [0usize; 256];
    length[128] = 89;
    let (mut body, mut messages) = (Vec::with_capacity(256), 0);
    let mut h = [0u8; 3];
    while r.read_exact(&mut h).is_ok() {
        assert_eq!(h[..2], [0xA3, 0x95], "message head");
        body.resize(length[h[2] as usize] - 3, 0);
        r.read_exact(&mut body).expect("body");
        if h[2] == 128 {
            length[body[0] as usize] = body[1] as usize;
        }
        messages += 1;
    }
    messages
}

/// Reads the flight log at `path` both ways in one benchmark group.
fn flight_log_group(c: &mut Criterion, name: &str, path: &Path, open: impl Fn() -> usize) {
    let bare = if name.starts_with("ulog") {
        bare_ulog
    } else {
        bare_dataflash
    };
    let mut g = c.benchmark_group(name);
    g.sample_size(10);
    g.throughput(Throughput::Elements(FLIGHT_LOG_SAMPLES as u64));
    g.bench_function("bare_scan", |b| b.iter(|| black_box(bare(path))));
    g.bench_function("open_log", |b| b.iter(|| black_box(open())));
    g.finish();
}

fn bench(c: &mut Criterion) {
    let v = vehicle();
    let csv_path = file("1m.csv");
    if !csv_path.exists() {
        let all: Vec<SampleChunk> = chunks(CSV_ROWS).collect();
        write_contract_csv(&csv_path, &all).expect("writes");
    }
    let mut g = c.benchmark_group("csv_1m_rows");
    g.sample_size(10);
    g.throughput(Throughput::Elements(CSV_ROWS as u64));
    g.bench_function("bare_byte_record", |b| {
        b.iter(|| black_box(bare_csv(&csv_path)))
    });
    g.bench_function("open_log", |b| {
        b.iter(|| black_box(ingest(&csv_path, &v, None)))
    });
    g.finish();

    let mapping = written_mapping(4, false, false, false);
    for encoding in [Encoding::Json, Encoding::Cdr] {
        let path = file(&format!("100k-{encoding:?}.mcap"));
        if !path.exists() {
            let all: Vec<SampleChunk> = chunks(MCAP_SAMPLES).collect();
            write_samples(&path, &v, &all, encoding).expect("writes");
        }
        let mut g = c.benchmark_group(format!("mcap_100k_{encoding:?}"));
        g.sample_size(10);
        g.throughput(Throughput::Elements(MCAP_SAMPLES as u64));
        g.bench_function("bare_messages", |b| b.iter(|| black_box(bare_mcap(&path))));
        g.bench_function("bare_messages_decoded", |b| {
            b.iter(|| black_box(decoded_mcap(&path)))
        });
        g.bench_function("open_log", |b| {
            b.iter(|| black_box(ingest(&path, &v, Some(&mapping))))
        });
        g.finish();
    }

    let path = file("100k.ulg");
    if !path.exists() {
        let all: Vec<SampleChunk> = chunks(FLIGHT_LOG_SAMPLES).collect();
        ulog::write_samples(&path, &all).expect("writes");
    }
    let mapping = ulog::written_mapping(4, false, false, false);
    flight_log_group(c, "ulog_100k", &path, || ingest(&path, &v, Some(&mapping)));

    let path = file("100k.bin");
    if !path.exists() {
        let mut all = SampleChunk::with_capacity(4, FLIGHT_LOG_SAMPLES, false);
        for chunk in chunks(FLIGHT_LOG_SAMPLES) {
            all.extend_from(&chunk, 0..chunk.len());
        }
        // Level flight: the identity attitude, and specific force = wrench / mass.
        all.attitude = Some([1.0, 0.0, 0.0, 0.0].map(|q| vec![q; FLIGHT_LOG_SAMPLES]));
        let sf = [0, 1, 2].map(|a| all.wrench[a].iter().map(|f| f / 1.2).collect());
        std::fs::write(&path, write_flight(&all, &sf, &[], None, 2)).expect("writes");
    }
    let mapping = mrsysid::io::Mapping::from_toml_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/ardupilot.toml"),
    )
    .expect("example mapping");
    flight_log_group(c, "dataflash_100k", &path, || {
        ingest(&path, &v, Some(&mapping))
    });
}

// Plots off: the crate enables plotters' bundled-font backend (`ab_glyph`), under which
// criterion's own plots find no font; the numbers are what matter.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
