//! Batch regressor assembly throughput (Eq. 22 columns + known-term outputs), in chunks of
//! `CHUNK_SAMPLES` into one reused workspace, for quad× and hexa× at 1e3, 1e5, 1e6 samples.
//! Goal: ≥ 50 million samples/s on one core for quad×.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use mrsysid::CHUNK_SAMPLES;
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};
use mrsysid::{ModelOptions, ModelStructure, Workspace};
use mrsysid::{Sample, SampleChunk};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

fn vehicle(preset: Preset) -> Vehicle {
    let props = MassAndRotorProperties {
        mass: 1.2,
        inertia: [[0.011, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.021]],
        air_density: 1.225,
        rotor_radius: 0.0635,
        hub_height: 0.02,
        rotor_inertia: 3e-5,
    };
    Vehicle::preset("bench", preset, 0.225, 1.0, props).unwrap()
}

fn chunks(n_rotors: usize, samples: usize) -> Vec<SampleChunk> {
    let mut rng = StdRng::seed_from_u64(1);
    let mut out = Vec::new();
    let mut left = samples;
    while left > 0 {
        let n = left.min(CHUNK_SAMPLES);
        let mut c = SampleChunk::with_capacity(n_rotors, n, true);
        for _ in 0..n {
            c.push(&Sample {
                velocity: [
                    rng.random_range(-15.0..15.0),
                    rng.random_range(-15.0..15.0),
                    rng.random_range(-8.0..1.0),
                ],
                rates: [
                    rng.random_range(-10.0..10.0),
                    rng.random_range(-10.0..10.0),
                    rng.random_range(-5.0..5.0),
                ],
                omega: (0..n_rotors)
                    .map(|_| rng.random_range(400.0..1200.0))
                    .collect(),
                omega_dot: (0..n_rotors)
                    .map(|_| rng.random_range(-2000.0..2000.0))
                    .collect(),
                wrench: [1.0; 6],
                ..Sample::default()
            });
        }
        out.push(c);
        left -= n;
    }
    out
}

fn assembly(c: &mut Criterion) {
    let mut group = c.benchmark_group("regressors");
    for (name, preset) in [("quad_x", Preset::QuadX), ("hexa_x", Preset::HexaX)] {
        let v = vehicle(preset);
        let model = ModelStructure::eq22(&v, ModelOptions::default());
        for samples in [1_000, 100_000, 1_000_000] {
            let data = chunks(v.rotor_count(), samples);
            let mut ws = Workspace::new(CHUNK_SAMPLES, model.columns.len());
            group.throughput(Throughput::Elements(samples as u64));
            group.bench_with_input(BenchmarkId::new(name, samples), &data, |b, data| {
                b.iter(|| {
                    let mut acc = 0.0;
                    for chunk in data {
                        model.assemble(chunk, &mut ws).unwrap();
                        acc += ws.column(0)[0];
                    }
                    acc
                })
            });
        }
    }
    group.finish();
}

// Plots off: the crate enables plotters' bundled-font backend (`ab_glyph`), under which
// criterion's own plots find no font; the numbers are what matter.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = assembly
}
criterion_main!(benches);
