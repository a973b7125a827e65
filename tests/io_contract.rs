//! Contract CSV: write → stream back, identical values, chunking and segments.

mod io_support;
mod scratch;

use std::path::PathBuf;

use io_support::{analytic_chunk, assert_same, concat, quad};
use mrsysid::CHUNK_SAMPLES;
use mrsysid::io::fixtures::write_contract_csv;
use mrsysid::io::{ReadOptions, open_log};

fn tmp(name: &str) -> PathBuf {
    scratch::dir("io").join(name)
}

#[test]
fn contract_csv_round_trips_exactly_in_bounded_chunks() {
    let vehicle = quad(3e-5);
    let src = analytic_chunk(2500, 200.0);
    let path = tmp("round_trip.csv");
    write_contract_csv(&path, [&src]).unwrap();
    let mut reader = open_log(&path, &vehicle, None, &ReadOptions::default()).unwrap();
    let mut chunks = Vec::new();
    for c in reader.by_ref() {
        let c = c.unwrap();
        assert!(c.len() <= CHUNK_SAMPLES);
        chunks.push(c);
    }
    assert_eq!(chunks.len(), 3, "2500 samples = 1024 + 1024 + 452");
    let back = concat(&chunks);
    // Shortest round-trip formatting: bit-identical values, compared with ==.
    assert_same(&back, &src);
    let s = reader.summary();
    assert_eq!((s.rows_read, s.samples, s.segments), (2500, 2500, 1));
    assert!(s.dropped.is_empty() && s.gaps.is_empty());
}

#[test]
fn a_gap_splits_the_log_into_segments_never_bridged() {
    let vehicle = quad(0.0);
    let mut src = analytic_chunk(300, 100.0);
    for t in src.t.iter_mut().skip(120) {
        *t += 5.0; // a 5 s hole after sample 120
    }
    let path = tmp("gap.csv");
    write_contract_csv(&path, [&src]).unwrap();
    let mut reader = open_log(&path, &vehicle, None, &ReadOptions::default()).unwrap();
    let mut seen = Vec::new();
    while let Some(c) = reader.next() {
        let c = c.unwrap();
        seen.push((reader.segment_index(), c.len(), c.t[0]));
    }
    assert_eq!(seen, vec![(0, 120, 1.0), (1, 180, src.t[120])]);
    let s = reader.summary();
    assert_eq!(s.segments, 2);
    assert_eq!(s.gaps.len(), 1);
    assert_eq!(s.gaps[0].from, src.t[119]);
}

/// Joined chunks carry the same samples and summary as per-segment chunks, cut only
/// every CHUNK_SAMPLES samples: 40 segments of 60 samples (2400) make 1024 + 1024 + 352,
/// and segment_index names the segment of each chunk's last sample.
#[test]
fn joined_chunks_run_across_segments_with_the_same_samples() {
    let vehicle = quad(0.0);
    let mut src = analytic_chunk(2400, 100.0);
    for (k, t) in src.t.iter_mut().enumerate() {
        *t += 5.0 * (k / 60) as f64; // a 5 s hole every 60 samples
    }
    let path = tmp("joined.csv");
    write_contract_csv(&path, [&src]).unwrap();
    let opts = ReadOptions::default();
    let mut by_segment = open_log(&path, &vehicle, None, &opts).unwrap();
    let segmented: Vec<_> = by_segment.by_ref().map(Result::unwrap).collect();
    assert_eq!(segmented.len(), 40);
    let mut joined = open_log(&path, &vehicle, None, &opts).unwrap();
    joined.join_segments();
    let mut chunks = Vec::new();
    let mut last_segments = Vec::new();
    while let Some(c) = joined.next() {
        chunks.push(c.unwrap());
        last_segments.push(joined.segment_index());
    }
    let lens: Vec<usize> = chunks.iter().map(|c| c.len()).collect();
    assert_eq!(lens, vec![1024, 1024, 352]);
    // Samples 1023 and 2047 lie in segments 17 and 34; the last in segment 39.
    assert_eq!(last_segments, vec![17, 34, 39]);
    assert_same(&concat(&chunks), &concat(&segmented));
    let (a, b) = (joined.summary(), by_segment.summary());
    assert_eq!((a.samples, a.segments, a.gaps.len()), (2400, 40, 39));
    assert_eq!((b.samples, b.segments, b.gaps.len()), (2400, 40, 39));
}

#[test]
fn a_byte_order_mark_before_the_header_is_ignored() {
    let path = tmp("bom.csv");
    let text = "\u{feff}t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz\n\
                0,1,0,0,0,0,0,900,900,900,900,0,0,-11.8,0,0,0\n\
                0.01,1,0,0,0,0,0,900,900,900,900,0,0,-11.8,0,0,0\n";
    std::fs::write(&path, text).unwrap();
    let n: usize = open_log(&path, &quad(0.0), None, &ReadOptions::default())
        .unwrap()
        .map(|c| c.unwrap().len())
        .sum();
    assert_eq!(n, 2);
}

#[test]
fn implausible_units_and_spikes_are_reported() {
    // Accelerometer logged in g but mapped as m/s² (|a| ≈ 1), rates in deg/s mapped as
    // rad/s (up to 60), and one 400 rad/s rotor-speed spike at row 50.
    let path = tmp("units.csv");
    let mut text = String::from("t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,ax,ay,az\n");
    for k in 0..100 {
        let t = k as f64 * 0.01;
        let w1 = if k == 50 { 1300.0 } else { 900.0 + 10.0 * t };
        text += &format!(
            "{t},1,0,0,{},0,0,{w1},900,900,900,0,0,-1.0\n",
            60.0 * (3.0 * t).sin()
        );
    }
    std::fs::write(&path, text).unwrap();
    let mut reader = open_log(&path, &quad(0.0), None, &ReadOptions::default()).unwrap();
    for c in reader.by_ref() {
        c.unwrap();
    }
    let s = reader.summary();
    assert_eq!(s.unit_warnings.len(), 2, "{:?}", s.unit_warnings);
    assert!(s.unit_warnings[0].starts_with("mean |F|/m = 1.000 m/s^2 is far from g"));
    assert!(s.unit_warnings[1].starts_with("max |body rate| = 60.0 rad/s"));
    assert_eq!(s.spikes.get("rotor_speeds"), Some(&1));
    assert_eq!(s.spikes.get("rates"), None, "a smooth sine is no spike");
}
