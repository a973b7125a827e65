//! Proof of the Eq. 22 structure: regressors × lumped parameters equal the independent
//! per-rotor sum (Eq. 5 + Eq. 7 at the local hub velocity of Eq. 18, carried to the CG by
//! Eq. 11–16) for every configuration class and both spin assignments.
//!
//! Tolerance 1e-10 relative to the largest |F| or |M| of the axis over the batch: both
//! sides are a few dozen floating-point products and sums, so agreement is expected to
//! ~1e-15; any structural error (a wrong sign, a missing term) shows up at ≥ 1e-3.

use mrsysid::airframe::closed_form_wrench;
use mrsysid::model::{InflowCorrection, ModelOptions, ModelStructure, Workspace};
use mrsysid::rotor::BladeConstants;
use mrsysid::sample::{Axis, Sample, SampleChunk};
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

const STATES: usize = 1000;

fn random_vehicle(rng: &mut StdRng, preset: Preset, first_spin: f64) -> Vehicle {
    let props = MassAndRotorProperties {
        mass: rng.random_range(0.5..5.0),
        inertia: [[0.01, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.02]],
        air_density: rng.random_range(1.0..1.3),
        rotor_radius: rng.random_range(0.05..0.2),
        hub_height: rng.random_range(-0.05..0.08),
        rotor_inertia: rng.random_range(1e-6..1e-4),
    };
    let arm = rng.random_range(0.15..0.5);
    Vehicle::preset("random", preset, arm, first_spin, props).unwrap()
}

fn random_blade(rng: &mut StdRng) -> BladeConstants {
    BladeConstants {
        blades: [2.0, 3.0, 4.0][rng.random_range(0..3)],
        chord: rng.random_range(0.01..0.04),
        lift_slope: rng.random_range(4.0..6.5),
        mean_drag: rng.random_range(0.005..0.03),
        theta0: rng.random_range(0.1..0.4),
        theta_tw: rng.random_range(-0.2..0.0),
        c_nu_mu: rng.random_range(-0.3..0.1),
        c_nu_w: rng.random_range(0.1..0.6),
    }
}

fn random_sample(rng: &mut StdRng, n: usize) -> Sample {
    Sample {
        t: 0.0,
        velocity: [
            rng.random_range(-18.0..18.0),
            rng.random_range(-18.0..18.0),
            rng.random_range(-9.0..1.5),
        ],
        rates: [
            rng.random_range(-12.0..12.0),
            rng.random_range(-12.0..12.0),
            rng.random_range(-6.0..6.0),
        ],
        omega: (0..n).map(|_| rng.random_range(200.0..1500.0)).collect(),
        omega_dot: (0..n).map(|_| rng.random_range(-3000.0..3000.0)).collect(),
        wrench: [0.0; 6],
        height: None,
        attitude: None,
    }
}

/// Largest |model − reference| over the batch, relative to the largest |reference|, per axis.
fn relative_errors(
    vehicle: &Vehicle,
    options: ModelOptions,
    blade: &BladeConstants,
    samples: &[Sample],
) -> [f64; 6] {
    let model = ModelStructure::eq22(vehicle, options);
    let lumped = blade.lumped_parameters(vehicle.props.rotor_radius);
    let theta: Vec<f64> = model
        .params
        .iter()
        .map(|p| lumped.value(&p.name).expect("known parameter"))
        .collect();
    let mut chunk = SampleChunk::with_capacity(vehicle.rotor_count(), samples.len(), true);
    for s in samples {
        let mut s = s.clone();
        s.wrench = closed_form_wrench(vehicle, blade, s.velocity, s.rates, &s.omega, &s.omega_dot);
        chunk.push(&s);
    }
    let mut ws = Workspace::default();
    model.assemble(&chunk, &mut ws).unwrap();
    let mut errors = [0.0; 6];
    for axis in Axis::ALL {
        let a = axis as usize;
        // ws.output = measured − known terms; the columns must explain it exactly.
        let mut fit = vec![0.0; chunk.len()];
        for j in model.axis_columns(axis) {
            let th = theta[model.columns[j].param];
            for (f, x) in fit.iter_mut().zip(ws.column(j)) {
                *f += th * x;
            }
        }
        let scale = chunk.wrench[a].iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let err = fit
            .iter()
            .zip(ws.output(axis))
            .fold(0.0_f64, |m, (f, z)| m.max((f - z).abs()));
        errors[a] = err / scale;
    }
    errors
}

const PRESETS: [Preset; 6] = [
    Preset::QuadPlus,
    Preset::QuadX,
    Preset::HexaPlus,
    Preset::HexaX,
    Preset::OctoPlus,
    Preset::OctoX,
];

#[test]
fn derived_regressors_equal_per_rotor_sum_for_every_class_and_spin_assignment() {
    let mut rng = StdRng::seed_from_u64(22);
    for preset in PRESETS {
        for first_spin in [1.0, -1.0] {
            let vehicle = random_vehicle(&mut rng, preset, first_spin);
            let blade = random_blade(&mut rng);
            let samples: Vec<Sample> = (0..STATES)
                .map(|_| random_sample(&mut rng, vehicle.rotor_count()))
                .collect();
            let errors = relative_errors(&vehicle, ModelOptions::default(), &blade, &samples);
            for (axis, e) in Axis::ALL.iter().zip(errors) {
                assert!(
                    e <= 1e-10,
                    "{preset:?} spin {first_spin}: {axis} relative error {e:e}"
                );
            }
        }
    }
}

#[test]
fn mirror_image_is_the_same_model_with_spins_reversed() {
    // Reversing every spin changes the vehicle but the derived model stays exact.
    let mut rng = StdRng::seed_from_u64(7);
    let vehicle = random_vehicle(&mut rng, Preset::QuadX, 1.0).with_spins_reversed();
    let blade = random_blade(&mut rng);
    let samples: Vec<Sample> = (0..STATES).map(|_| random_sample(&mut rng, 4)).collect();
    let errors = relative_errors(&vehicle, ModelOptions::default(), &blade, &samples);
    assert!(errors.iter().all(|&e| e <= 1e-10), "{errors:?}");
}

#[test]
fn printed_case_table_is_not_exact_for_either_spin_assignment_of_a_quad() {
    // The seed's printed Δν table mixes the two spin assignments (see model.rs docs):
    // for quadrotor× and quadrotor+, whichever assignment we pick, one moment axis
    // misses by far more than rounding. Forces and the other moments stay exact.
    let mut rng = StdRng::seed_from_u64(8);
    let paper = ModelOptions {
        inflow: InflowCorrection::Paper,
        ..ModelOptions::default()
    };
    for preset in [Preset::QuadX, Preset::QuadPlus] {
        for first_spin in [1.0, -1.0] {
            let vehicle = random_vehicle(&mut rng, preset, first_spin);
            let blade = random_blade(&mut rng);
            let samples: Vec<Sample> = (0..STATES).map(|_| random_sample(&mut rng, 4)).collect();
            let e = relative_errors(&vehicle, paper, &blade, &samples);
            assert!(
                e[..3].iter().all(|&x| x <= 1e-10),
                "{preset:?} {first_spin}: forces {e:?}"
            );
            let worst = e[3..].iter().fold(0.0_f64, |m, &x| m.max(x));
            assert!(
                worst > 1e-4,
                "{preset:?} spin {first_spin}: printed table unexpectedly exact {e:?}"
            );
        }
    }
}

#[test]
fn printed_multirotor_table_holds_only_for_equal_rotor_speeds() {
    let mut rng = StdRng::seed_from_u64(9);
    let paper = ModelOptions {
        inflow: InflowCorrection::Paper,
        ..ModelOptions::default()
    };
    let vehicle = random_vehicle(&mut rng, Preset::HexaX, 1.0);
    let blade = random_blade(&mut rng);
    let mut samples: Vec<Sample> = (0..STATES).map(|_| random_sample(&mut rng, 6)).collect();
    let unequal = relative_errors(&vehicle, paper, &blade, &samples);
    assert!(unequal[3] > 1e-4 && unequal[4] > 1e-4, "{unequal:?}");
    for s in &mut samples {
        let mean = s.omega.iter().sum::<f64>() / 6.0;
        s.omega.iter_mut().for_each(|w| *w = mean);
    }
    let equal = relative_errors(&vehicle, paper, &blade, &samples);
    assert!(equal.iter().all(|&e| e <= 1e-10), "{equal:?}");
}

#[test]
fn every_parameter_is_visible_to_the_exactness_check() {
    // Power of the test above: a 0.1 % change of any one lumped parameter moves some axis
    // by far more than the 1e-10 tolerance.
    let mut rng = StdRng::seed_from_u64(10);
    for preset in [Preset::QuadX, Preset::HexaPlus] {
        let vehicle = random_vehicle(&mut rng, preset, 1.0);
        let blade = random_blade(&mut rng);
        let model = ModelStructure::eq22(&vehicle, ModelOptions::default());
        let lumped = blade.lumped_parameters(vehicle.props.rotor_radius);
        let theta: Vec<f64> = model
            .params
            .iter()
            .map(|p| lumped.value(&p.name).unwrap())
            .collect();
        let samples: Vec<Sample> = (0..200)
            .map(|_| random_sample(&mut rng, vehicle.rotor_count()))
            .collect();
        for (i, p) in model.params.iter().enumerate() {
            let mut worst = 0.0_f64;
            for s in &samples {
                let mut s = s.clone();
                s.wrench = closed_form_wrench(
                    &vehicle,
                    &blade,
                    s.velocity,
                    s.rates,
                    &s.omega,
                    &s.omega_dot,
                );
                let mut bumped = theta.clone();
                bumped[i] *= 1.001;
                let y = model.predict(&bumped, &s).unwrap();
                for (m, z) in y.iter().zip(&s.wrench) {
                    worst = worst.max((m - z).abs() / (1e-3 + z.abs()));
                }
            }
            assert!(
                worst > 1e-8,
                "{preset:?}: parameter {} has no visible effect ({worst:e})",
                p.name
            );
        }
    }
}
