//! Shared test data for the estimation tests: a quadrotor× preset, physically
//! consistent lumped parameters, and chunks whose outputs follow Eq. 22 exactly (plus
//! optional noise).

#![allow(dead_code)] // each test binary uses a different subset of these helpers

use mrsysid::internals::rotor::BladeConstants;
use mrsysid::internals::stats::Accumulator;
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};
use mrsysid::{Axis, Sample, SampleChunk};
use mrsysid::{ModelOptions, ModelStructure, Workspace};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// A 1.2 kg quadrotor× with 0.25 m arms.
pub fn quad_x() -> Vehicle {
    let props = MassAndRotorProperties {
        mass: 1.2,
        inertia: [[0.01, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.02]],
        air_density: 1.225,
        rotor_radius: 0.12,
        hub_height: 0.04,
        rotor_inertia: 3e-5,
    };
    Vehicle::preset("test quad x", Preset::QuadX, 0.25, 1.0, props).expect("valid preset")
}

/// The full Eq. 22 structure (J_z known) of `vehicle`.
pub fn structure(vehicle: &Vehicle) -> ModelStructure {
    ModelStructure::eq22(vehicle, ModelOptions::default())
}

/// Physically consistent θ (one per `structure.params`) from blade constants.
pub fn true_theta(structure: &ModelStructure, vehicle: &Vehicle) -> Vec<f64> {
    let blade = BladeConstants {
        blades: 2.0,
        chord: 0.02,
        lift_slope: 5.7,
        mean_drag: 0.012,
        theta0: 0.25,
        theta_tw: -0.1,
        c_nu_mu: -0.1,
        c_nu_w: 0.35,
    };
    let lumped = blade.lumped_parameters(vehicle.props.rotor_radius);
    structure
        .params
        .iter()
        .map(|p| lumped.value(&p.name).expect("known parameter"))
        .collect()
}

/// Flight states over a response-surface-like box (scaled Table 1 ranges).
pub fn random_samples(rng: &mut StdRng, n: usize, rotors: usize) -> Vec<Sample> {
    (0..n)
        .map(|i| Sample {
            t: i as f64 * 0.01,
            velocity: [
                rng.random_range(-10.0..10.0),
                rng.random_range(-10.0..10.0),
                rng.random_range(-4.0..2.0),
            ],
            rates: [
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-2.0..2.0),
            ],
            omega: (0..rotors)
                .map(|_| rng.random_range(400.0..1100.0))
                .collect(),
            omega_dot: (0..rotors)
                .map(|_| rng.random_range(-500.0..500.0))
                .collect(),
            wrench: [0.0; 6],
            height: None,
            attitude: None,
        })
        .collect()
}

/// Splits `samples` into chunks of `size`.
pub fn chunks(samples: &[Sample], rotors: usize, size: usize) -> Vec<SampleChunk> {
    samples
        .chunks(size)
        .map(|part| {
            let mut c = SampleChunk::with_capacity(rotors, part.len(), true);
            part.iter().for_each(|s| c.push(s));
            c
        })
        .collect()
}

/// Sets each sample's wrench to the exact Eq. 22 output for `theta` (known J_z terms
/// included) plus `noise[k]` (one 6-vector per sample, or none).
pub fn set_outputs(
    structure: &ModelStructure,
    theta: &[f64],
    samples: &mut [Sample],
    noise: Option<&[[f64; 6]]>,
) {
    for (k, s) in samples.iter_mut().enumerate() {
        s.wrench = [0.0; 6];
        let y = structure.predict(theta, s).expect("assembles");
        s.wrench = y;
        if let Some(noise) = noise {
            for (w, e) in s.wrench.iter_mut().zip(&noise[k]) {
                *w += e;
            }
        }
    }
}

/// Accumulates `chunks` into one accumulator.
pub fn accumulate(structure: &ModelStructure, chunks: &[SampleChunk]) -> Accumulator {
    let mut acc = Accumulator::new(structure);
    let mut ws = Workspace::default();
    for c in chunks {
        acc.push(structure, c, &mut ws).expect("valid chunk");
    }
    acc
}

/// Correlated Gaussian noise: `n` draws of L·e with e ~ N(0, I₆) and L lower triangular.
pub fn correlated_noise(rng: &mut StdRng, n: usize, l: &[[f64; 6]; 6]) -> Vec<[f64; 6]> {
    use rand_distr::{Distribution, StandardNormal};
    (0..n)
        .map(|_| {
            let e: [f64; 6] = std::array::from_fn(|_| StandardNormal.sample(rng));
            std::array::from_fn(|i| (0..=i).map(|k| l[i][k] * e[k]).sum())
        })
        .collect()
}

/// A fixed cross-axis noise factor L (covariance L Lᵀ), N and N m: forces ~0.3 N,
/// moments ~0.02 N m, with cross-axis correlation.
pub fn noise_factor() -> [[f64; 6]; 6] {
    [
        [0.30, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.10, 0.25, 0.0, 0.0, 0.0, 0.0],
        [0.05, -0.08, 0.40, 0.0, 0.0, 0.0],
        [0.004, 0.010, 0.0, 0.020, 0.0, 0.0],
        [-0.010, 0.0, 0.003, 0.005, 0.020, 0.0],
        [0.0, 0.002, 0.001, 0.0, 0.002, 0.004],
    ]
}

/// Seeded RNG.
pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

/// Largest |a − b| / |b| over the entries.
pub fn max_rel(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| ((x - y) / y).abs())
        .fold(0.0, f64::max)
}

/// Axis index helper for readability.
pub fn axis(a: Axis) -> usize {
    a as usize
}
