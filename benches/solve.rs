//! Solve time of the estimation from accumulated statistics (quad× full model): FSOA of
//! one axis, and the whole fit (6 OLS + 6 FSOA + R + MMR + inference + metrics), for
//! accumulators of 1e4 and 1e5 samples. The solve works on the m × m factor only, so
//! the time must not depend on N.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use mrsysid::CHUNK_SAMPLES;
use mrsysid::internals::estimate::{FitOptions, fit, fsoa};
use mrsysid::internals::stats::Accumulator;
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};
use mrsysid::{Axis, Sample, SampleChunk};
use mrsysid::{ModelOptions, ModelStructure, Workspace};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

fn quad_x() -> Vehicle {
    let props = MassAndRotorProperties {
        mass: 1.2,
        inertia: [[0.01, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.02]],
        air_density: 1.225,
        rotor_radius: 0.12,
        hub_height: 0.04,
        rotor_inertia: 3e-5,
    };
    Vehicle::preset("bench quad x", Preset::QuadX, 0.25, 1.0, props).expect("valid preset")
}

/// Accumulator over `n` random samples with outputs from a random θ plus noise.
fn accumulator(s: &ModelStructure, n: usize, rng: &mut StdRng) -> Accumulator {
    let theta: Vec<f64> = s
        .params
        .iter()
        .map(|_| rng.random_range(0.01..0.1))
        .collect();
    let mut acc = Accumulator::new(s);
    let mut ws = Workspace::default();
    let mut left = n;
    while left > 0 {
        let len = left.min(CHUNK_SAMPLES);
        let mut c = SampleChunk::with_capacity(4, len, true);
        for i in 0..len {
            let mut smp = Sample {
                t: i as f64 * 0.01,
                velocity: std::array::from_fn(|_| rng.random_range(-10.0..10.0)),
                rates: std::array::from_fn(|_| rng.random_range(-3.0..3.0)),
                omega: (0..4).map(|_| rng.random_range(400.0..1100.0)).collect(),
                omega_dot: (0..4).map(|_| rng.random_range(-500.0..500.0)).collect(),
                wrench: [0.0; 6],
                height: None,
                attitude: None,
            };
            let y = s.predict(&theta, &smp).unwrap();
            smp.wrench = std::array::from_fn(|a| y[a] + rng.random_range(-0.1..0.1));
            c.push(&smp);
        }
        acc.push(s, &c, &mut ws).unwrap();
        left -= len;
    }
    acc
}

fn bench(c: &mut Criterion) {
    let v = quad_x();
    let s = ModelStructure::eq22(&v, ModelOptions::default());
    let mut rng = StdRng::seed_from_u64(2);
    let mut g = c.benchmark_group("solve_quad_x");
    for n in [10_000usize, 100_000] {
        let acc = accumulator(&s, n, &mut rng);
        g.bench_with_input(BenchmarkId::new("fsoa_Mx", n), &acc, |b, acc| {
            b.iter(|| fsoa(&s, acc, Axis::Mx, 4.0).unwrap());
        });
        g.bench_with_input(BenchmarkId::new("fit", n), &acc, |b, acc| {
            b.iter(|| fit(&s, acc, &FitOptions::default()).unwrap());
        });
    }
    g.finish();
}

// Plots off: the crate enables plotters' bundled-font backend (`ab_glyph`), under which
// criterion's own plots find no font; the numbers are what matter.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
