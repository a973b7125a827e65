//! The response-surface data kind: random steady states and rotor speeds drawn uniformly
//! over an envelope (as a wind-tunnel or CFD test matrix would be), the loads of each
//! point logged with balance noise. The points and the noise depend on the seed only,
//! so a case and the clean set of the same seed share them.

use mrsysid::Sample;
use nalgebra::{UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

use super::physics::{Airframe, LoadState};

/// Balance noise on the forces, N (standard deviation), on the reference quadrotor.
pub const FORCE_NOISE: f64 = 0.03;
/// Balance noise on the moments, N m (standard deviation), on the reference quadrotor.
pub const MOMENT_NOISE: f64 = 0.0015;

/// The envelope: |u|, |v| ≤ 12 m/s, w ∈ [−6, 2.5] m/s (climb to mild descent, far from
/// the vortex ring at ν_h ≈ 10 m/s), |p|, |q| ≤ 6 rad/s, |r| ≤ 3 rad/s, each rotor
/// independently within ±35 % of hover speed, rotor accelerations within
/// ±0.25 Ω_h/τ_motor, CG height 0.04–0.5 m (hubs 0.5–4 diameters up). On another
/// vehicle the descent limit scales with the hover induced velocity, the heights with
/// the rotor radius and the balance noise with the mass and the inertia
/// ([`super::physics::Scale`]).
pub fn response_surface(air: &Airframe, points: usize, seed: u64) -> Vec<Sample> {
    let mut draw = StdRng::seed_from_u64(seed);
    let mut noise = StdRng::seed_from_u64(seed ^ 0x5eed_ba1a);
    let n = air.hubs.len();
    let scale = air.scale;
    let hover = air.hover_omega();
    let accel = 0.25 * hover / air.rotor.motor_tau;
    let mut out = Vec::with_capacity(points);
    for k in 0..points {
        let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * draw.random::<f64>();
        let velocity = Vector3::new(
            uniform(-12.0, 12.0),
            uniform(-12.0, 12.0),
            uniform(-6.0, 2.5 * scale.induced),
        );
        let rates = Vector3::new(uniform(-6.0, 6.0), uniform(-6.0, 6.0), uniform(-3.0, 3.0));
        let omega: Vec<f64> = (0..n)
            .map(|_| uniform(0.65 * hover, 1.35 * hover))
            .collect();
        let omega_dot: Vec<f64> = (0..n).map(|_| uniform(-accel, accel)).collect();
        let height = uniform(0.04 * scale.length, 0.5 * scale.length);
        let state = LoadState {
            velocity,
            rates,
            omega: &omega,
            omega_dot: &omega_dot,
            height,
            attitude: UnitQuaternion::identity(),
        };
        let mut wrench = air.wrench(&state);
        for (j, f) in wrench.iter_mut().enumerate() {
            let sd = if j < 3 {
                FORCE_NOISE * scale.mass
            } else {
                MOMENT_NOISE * scale.inertia_sum
            };
            *f += sd * gauss(&mut noise);
        }
        out.push(Sample {
            t: k as f64,
            velocity: velocity.into(),
            rates: rates.into(),
            omega,
            omega_dot,
            wrench,
            height: Some(height),
            attitude: None,
        });
    }
    out
}

/// A standard normal draw.
pub fn gauss(rng: &mut StdRng) -> f64 {
    StandardNormal.sample(rng)
}
