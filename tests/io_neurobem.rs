//! The real NeuroBEM segments (gzip-compressed CSV) through the shipped mapping: FLU →
//! FRD conversion, derived F and M, layout inference, and agreement with the contract CSV
//! path and with the uncompressed text.

mod io_support;
mod scratch;

use std::path::Path;

use mrsysid::SampleChunk;
use mrsysid::io::fixtures::write_contract_csv;
use mrsysid::io::{Mapping, ReadOptions, open_log};
use mrsysid::vehicle::Vehicle;

const FILES: [&str; 3] = [
    "data/neurobem/figure8_1_20210218170320seg2.csv.gz",
    "data/neurobem/melon_1_20210223114138seg3.csv.gz",
    "data/neurobem/racetrack_1_20210218171908seg2.csv.gz",
];

/// Data rows of each file (the dataset's 400 Hz segments, whole).
const ROWS: [usize; 3] = [14306, 11431, 12724];

fn read(
    path: &Path,
    vehicle: &Vehicle,
    mapping: Option<&Mapping>,
) -> (SampleChunk, mrsysid::io::Summary) {
    let mut reader = open_log(path, vehicle, mapping, &ReadOptions::default()).unwrap();
    let chunks: Vec<SampleChunk> = reader.by_ref().map(Result::unwrap).collect();
    (io_support::concat(&chunks), reader.summary().clone())
}

#[test]
fn neurobem_vehicle_passes_assumption_2() {
    let v = Vehicle::from_toml_file(Path::new("data/vehicles/neurobem.toml")).unwrap();
    assert_eq!(v.rotor_count(), 4);
    // 0.11 m arm stated in the file; 1e-12 covers the 16-digit coordinates.
    assert!((v.arm_length() - 0.11).abs() < 1e-12);
}

#[test]
fn neurobem_segments_map_to_frd_with_derived_wrench() {
    let vehicle = Vehicle::from_toml_file(Path::new("data/vehicles/neurobem.toml")).unwrap();
    let mapping = Mapping::from_toml_file(Path::new("examples/neurobem.toml")).unwrap();
    for (file, rows) in FILES.into_iter().zip(ROWS) {
        let (c, s) = read(Path::new(file), &vehicle, Some(&mapping));
        assert_eq!(
            (c.len(), s.segments),
            (rows, 1),
            "{file}: every row at 400 Hz, no gap"
        );
        assert!(s.unit_warnings.is_empty(), "{file}: {:?}", s.unit_warnings);
        // First data row of figure8 (line 2 of the file): acc z = 9.742806 m/s² (FLU up)
        // → F_z = -0.772 · 9.742806 N in FRD; ang vel y = -0.017711 → q = +0.017711.
        if file.contains("figure8") {
            assert_eq!(c.t[0], 9.33);
            assert_eq!(c.wrench[2][0], -0.772 * 9.742806);
            assert_eq!(c.rates[1][0], 0.017711);
            assert_eq!(c.omega[0][0], 1111.54285);
            assert_eq!(c.height.as_ref().expect("height logged")[0], 2.113231);
            // M = I ω̇ + ω × Iω with ω̇ = (0.454176, -0.203798, 0.790547) FRD; the
            // gyroscopic part is < 1e-6 N m here, so 1e-6 bounds the difference.
            assert!((c.wrench[3][0] - 0.0025 * 0.454176).abs() < 1e-6);
            assert!((c.wrench[5][0] - 0.0043 * 0.790547).abs() < 1e-6);
        }
        // Thrust along -z in FRD: in level-on-average flight the mean body-z force carries
        // at least the weight (it exceeds it when banked), and stays under 2 m g here.
        let mean_fz = c.wrench[2].iter().sum::<f64>() / c.len() as f64;
        let mg = 0.772 * 9.80665;
        assert!(
            (-2.0 * mg..-0.9 * mg).contains(&mean_fz),
            "{file}: {mean_fz}"
        );
        // Attitude converted to body FRD → NED stays a unit quaternion (1e-6: the logged
        // quaternion has 6 decimals).
        let attitude = c.attitude.as_ref().expect("attitude logged");
        let q: Vec<f64> = attitude.iter().map(|a| a[0]).collect();
        assert!((q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-5);
        // The layout regression runs and reports (tests/io_derive.rs checks exact
        // recovery on synthetic data).
        assert_eq!(
            s.layout.expect("layout regression solvable").samples,
            rows as u64
        );
    }
}

#[test]
fn mapped_and_contract_paths_give_identical_samples() {
    let vehicle = Vehicle::from_toml_file(Path::new("data/vehicles/neurobem.toml")).unwrap();
    let mapping = Mapping::from_toml_file(Path::new("examples/neurobem.toml")).unwrap();
    let (mapped, _) = read(Path::new(FILES[2]), &vehicle, Some(&mapping));
    let out = scratch::dir("neurobem").join("contract.csv");
    write_contract_csv(&out, [&mapped]).unwrap();
    let (contract, _) = read(&out, &vehicle, None);
    io_support::assert_same(&contract, &mapped);
}

#[test]
fn gzip_and_plain_text_give_identical_samples() {
    // The reader recognises gzip by its magic bytes: the decompressed text, written
    // plain, reads to the same samples bit for bit.
    let vehicle = Vehicle::from_toml_file(Path::new("data/vehicles/neurobem.toml")).unwrap();
    let mapping = Mapping::from_toml_file(Path::new("examples/neurobem.toml")).unwrap();
    let (packed, _) = read(Path::new(FILES[1]), &vehicle, Some(&mapping));
    let mut text = Vec::new();
    let file = std::fs::File::open(FILES[1]).unwrap();
    std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(file), &mut text).unwrap();
    let out = scratch::dir("neurobem").join("plain.csv");
    std::fs::write(&out, text).unwrap();
    let (plain, _) = read(&out, &vehicle, Some(&mapping));
    assert_eq!(plain.len(), ROWS[1]);
    io_support::assert_same(&plain, &packed);
}

#[test]
fn corrupt_gzip_is_an_error_naming_the_file() {
    // A gzip stream cut in the middle: a read error, never a panic or a silent end.
    let bytes = std::fs::read(FILES[0]).unwrap();
    let out = scratch::dir("neurobem").join("neurobem-cut.csv.gz");
    std::fs::write(&out, &bytes[..bytes.len() / 2]).unwrap();
    let vehicle = Vehicle::from_toml_file(Path::new("data/vehicles/neurobem.toml")).unwrap();
    let mapping = Mapping::from_toml_file(Path::new("examples/neurobem.toml")).unwrap();
    let err = open_log(&out, &vehicle, Some(&mapping), &ReadOptions::default())
        .and_then(|mut r| r.by_ref().find_map(Result::err).map_or(Ok(()), Err))
        .expect_err("a truncated gzip stream is an error")
        .to_string();
    assert!(err.contains("neurobem-cut.csv.gz"), "{err}");
}
