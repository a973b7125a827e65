//! Accumulation throughput (one streaming pass, quad× full Eq. 22 model: 38 columns +
//! 6 outputs): assembly of the regressors, the TSQR fold, and both together, on 1e6
//! samples per iteration (64 distinct chunks of `CHUNK_SAMPLES` cycled, so memory stays
//! small while the work per sample is that of a 1e6-sample log).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mrsysid::CHUNK_SAMPLES;
use mrsysid::internals::stats::Accumulator;
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};
use mrsysid::{ModelOptions, ModelStructure, Workspace};
use mrsysid::{Sample, SampleChunk};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

const SAMPLES: usize = 1_000_000;

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

fn chunks(rng: &mut StdRng) -> Vec<SampleChunk> {
    (0..64)
        .map(|_| {
            let mut c = SampleChunk::with_capacity(4, CHUNK_SAMPLES, true);
            for i in 0..CHUNK_SAMPLES {
                c.push(&Sample {
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
            c
        })
        .collect()
}

/// Feeds `SAMPLES` samples (whole chunks) to `f`.
fn stream(chunks: &[SampleChunk], mut f: impl FnMut(&SampleChunk)) {
    let mut fed = 0;
    for c in chunks.iter().cycle() {
        if fed >= SAMPLES {
            break;
        }
        f(c);
        fed += c.len();
    }
}

fn bench(c: &mut Criterion) {
    let v = quad_x();
    let s = ModelStructure::eq22(&v, ModelOptions::default());
    let data = chunks(&mut StdRng::seed_from_u64(1));
    let mut g = c.benchmark_group("accumulate_quad_x_1e6");
    g.throughput(Throughput::Elements(SAMPLES as u64));
    g.sample_size(10);
    g.bench_function("assemble_only", |b| {
        let mut ws = Workspace::default();
        b.iter(|| stream(&data, |ch| s.assemble(ch, &mut ws).unwrap()));
    });
    g.bench_function("assemble_and_tsqr", |b| {
        let mut ws = Workspace::default();
        b.iter(|| {
            let mut acc = Accumulator::new(&s);
            stream(&data, |ch| acc.push(&s, ch, &mut ws).unwrap());
            acc.count()
        });
    });
    g.bench_function("tsqr_only", |b| {
        let mut ws = Workspace::default();
        s.assemble(&data[0], &mut ws).unwrap();
        b.iter(|| {
            let mut acc = Accumulator::new(&s);
            for _ in 0..SAMPLES.div_ceil(CHUNK_SAMPLES) {
                acc.push_assembled(&ws).unwrap();
            }
            acc.count()
        });
    });
    g.bench_function("assemble_and_tsqr_2_threads_merged", |b| {
        b.iter(|| {
            let half = data.len() / 2;
            let parts: Vec<Accumulator> = std::thread::scope(|scope| {
                let hs: Vec<_> = [&data[..half], &data[half..]]
                    .into_iter()
                    .map(|part| {
                        let s = &s;
                        scope.spawn(move || {
                            let mut ws = Workspace::default();
                            let mut acc = Accumulator::new(s);
                            let mut fed = 0;
                            for ch in part.iter().cycle() {
                                if fed >= SAMPLES / 2 {
                                    break;
                                }
                                acc.push(s, ch, &mut ws).unwrap();
                                fed += ch.len();
                            }
                            acc
                        })
                    })
                    .collect();
                hs.into_iter().map(|h| h.join().unwrap()).collect()
            });
            let mut acc = parts[0].clone();
            acc.merge(&parts[1]).unwrap();
            acc.count()
        });
    });
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
