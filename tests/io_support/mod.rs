//! Shared helpers of the io tests: a test vehicle and analytic sample streams.
#![allow(dead_code)]

use mrsysid::sample::SampleChunk;
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};

/// A quad-x test vehicle with J_z = 0 (no rotor-acceleration derivation).
pub fn quad(rotor_inertia: f64) -> Vehicle {
    Vehicle::preset(
        "test-quad",
        Preset::QuadX,
        0.16,
        1.0,
        MassAndRotorProperties {
            mass: 1.2,
            inertia: [[0.011, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.021]],
            air_density: 1.225,
            rotor_radius: 0.0635,
            hub_height: 0.02,
            rotor_inertia,
        },
    )
    .expect("valid test vehicle")
}

/// `n` samples at `rate_hz` of smooth analytic flight signals, in one chunk, with
/// attitude and height.
pub fn analytic_chunk(n: usize, rate_hz: f64) -> SampleChunk {
    let mut c = SampleChunk::with_capacity(4, n, true);
    for k in 0..n {
        let t = 1.0 + k as f64 / rate_hz;
        c.t.push(t);
        for a in 0..3 {
            c.velocity[a].push(2.0 * (0.5 * t + a as f64).sin());
            c.rates[a].push(0.3 * (1.3 * t + a as f64).cos());
        }
        for i in 0..4 {
            c.omega[i].push(900.0 + 50.0 * (2.0 * t + i as f64).sin());
            c.omega_dot[i].push(100.0 * (2.0 * t + i as f64).cos());
        }
        for a in 0..6 {
            let base = if a == 2 { -11.8 } else { 0.0 };
            c.wrench[a].push(base + 0.1 * (0.7 * t + a as f64).sin());
        }
        c.height.push(1.5 + 0.1 * t);
        let half = 0.2 * (0.3 * t).sin();
        c.attitude[0].push(half.cos());
        c.attitude[1].push(0.0);
        c.attitude[2].push(0.0);
        c.attitude[3].push(half.sin());
    }
    c
}

/// Concatenates chunks into one.
pub fn concat(chunks: &[SampleChunk]) -> SampleChunk {
    let mut out = chunks[0].clone();
    out.clear();
    for c in chunks {
        for k in 0..c.len() {
            out.push(&c.sample(k));
        }
    }
    out
}

/// Asserts two chunks hold bit-identical values, naming the first difference.
pub fn assert_same(a: &SampleChunk, b: &SampleChunk) {
    assert_eq!(a.len(), b.len(), "sample counts");
    for k in 0..a.len() {
        let (x, y) = (a.sample(k), b.sample(k));
        assert!(x == y, "sample {k} differs:\n{x:?}\n{y:?}");
    }
}
