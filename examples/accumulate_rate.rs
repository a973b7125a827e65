//! Accumulates 1e6 quad× samples (full Eq. 22 model) on one thread, fits, and runs the
//! residual pass (L = 10) over the same samples, printing the wall time of each. Run
//! under `/usr/bin/time` to relate it to CPU time on a shared machine:
//! `cargo run --release --example accumulate_rate`.

use mrsysid::CHUNK_SAMPLES;
use mrsysid::internals::estimate::{DiagnosticOptions, FitOptions, ResidualPass, fit};
use mrsysid::internals::stats::Accumulator;
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};
use mrsysid::{ModelOptions, ModelStructure, Workspace};
use mrsysid::{Sample, SampleChunk};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

fn main() {
    let props = MassAndRotorProperties {
        mass: 1.2,
        inertia: [[0.01, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.02]],
        air_density: 1.225,
        rotor_radius: 0.12,
        hub_height: 0.04,
        rotor_inertia: 3e-5,
    };
    let v = Vehicle::preset("quad x", Preset::QuadX, 0.25, 1.0, props).expect("valid preset");
    let s = ModelStructure::eq22(&v, ModelOptions::default());
    let mut rng = StdRng::seed_from_u64(1);
    let size: usize = std::env::var("CHUNK")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(CHUNK_SAMPLES);
    let mut chunk = SampleChunk::with_capacity(4, size, true);
    for i in 0..size {
        chunk.push(&Sample {
            t: i as f64 * 0.01,
            velocity: std::array::from_fn(|_| rng.random_range(-10.0..10.0)),
            rates: std::array::from_fn(|_| rng.random_range(-3.0..3.0)),
            omega: (0..4).map(|_| rng.random_range(400.0..1100.0)).collect(),
            omega_dot: (0..4).map(|_| rng.random_range(-500.0..500.0)).collect(),
            wrench: std::array::from_fn(|_| rng.random_range(-10.0..10.0)),
            height: None,
            attitude: None,
        });
    }
    let mut acc = Accumulator::new(&s);
    let mut ws = Workspace::default();
    let start = std::time::Instant::now();
    let chunks = 1_000_000usize.div_ceil(size);
    for _ in 0..chunks {
        acc.push(&s, &chunk, &mut ws).expect("valid chunk");
    }
    let secs = start.elapsed().as_secs_f64();
    println!(
        "{} samples, {} columns folded as {} factor columns, {:.3} s wall, {:.2} M samples/s",
        acc.count(),
        acc.m(),
        acc.rows(),
        secs,
        acc.count() as f64 / secs / 1e6
    );
    let start = std::time::Instant::now();
    let f = fit(&s, &acc, &FitOptions::default()).expect("identifiable");
    println!("fit: {:.3} ms", start.elapsed().as_secs_f64() * 1e3);
    let mut pass = ResidualPass::new(&s, &f, DiagnosticOptions::default());
    let start = std::time::Instant::now();
    for _ in 0..chunks {
        pass.push(&chunk, &mut ws).expect("valid chunk");
    }
    let d = pass.finish();
    let secs = start.elapsed().as_secs_f64();
    println!(
        "residual pass: {} samples, {:.3} s wall, {:.2} M samples/s",
        d.samples,
        secs,
        d.samples as f64 / secs / 1e6
    );
}
