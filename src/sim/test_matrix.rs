//! Response-surface test matrices (seed §5, Table 1): states and rotor speeds sampled over
//! ranges scaled to the vehicle, the truth wrench evaluated at each point, as if querying
//! a wind-tunnel database.
//!
//! Table 1 of the seed (|u|, |v| ≤ 60 ft/s, w ∈ [−30, +5] ft/s, |p|, |q| ≤ 720 °/s,
//! |r| ≤ 360 °/s) is scaled by Froude similarity with the arm length ℓ relative to a
//! reference ℓ_ref = 0.225 m (speeds × √(ℓ/ℓ_ref), rates × √(ℓ_ref/ℓ)); the upper bound of w
//! stays below half the hover inflow ν0 (no vortex-ring state) unless the `vortex_ring`
//! effect is on, when it extends to 1.6 ν0; rotor speeds span hover ± 40 % independently,
//! rotor accelerations ± 0.2 Ω_h / τ_m. With ground effect on, the hub height above ground
//! spans [R/2, 4R] and the `height` column is written.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::truth::{TruthInput, TruthModel};
use crate::sample::{Sample, SampleChunk};

/// Reference arm length of the Froude scaling, m.
pub const REFERENCE_ARM: f64 = 0.225;

/// How points fill the ranges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Design {
    /// Independent uniform draws.
    Uniform,
    /// Latin hypercube: each variable's range cut into n strata, one point per stratum,
    /// strata paired by independent random permutations.
    LatinHypercube,
}

/// Closed intervals `(min, max)` of every sampled variable (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct Ranges {
    /// u, v, w, m/s.
    pub velocity: [(f64, f64); 3],
    /// p, q, r, rad/s.
    pub rates: [(f64, f64); 3],
    /// Rotor speed, rad/s (each rotor independently).
    pub omega: (f64, f64),
    /// Rotor acceleration, rad/s².
    pub omega_dot: (f64, f64),
    /// CG height above ground, m, when ground effect is on.
    pub height: Option<(f64, f64)>,
}

impl Ranges {
    /// Table 1 scaled to the model's vehicle (see the module documentation).
    pub fn scaled_to(model: &TruthModel) -> Self {
        let v = &model.vehicle;
        let speed = (v.arm_length() / REFERENCE_ARM).sqrt();
        let rate = 1.0 / speed;
        let vuv = 18.0 * speed;
        let nu0 = v.hover_induced_velocity();
        let w_max = if model.effects.vortex_ring().is_some() {
            1.6 * nu0
        } else {
            (1.5 * speed).min(0.45 * nu0)
        };
        let wh = model.hover_omega;
        let r = v.props.rotor_radius;
        let h = v.props.hub_height;
        Self {
            velocity: [(-vuv, vuv), (-vuv, vuv), (-9.0 * speed, w_max)],
            rates: [
                (-12.0 * rate, 12.0 * rate),
                (-12.0 * rate, 12.0 * rate),
                (-6.0 * rate, 6.0 * rate),
            ],
            omega: (0.6 * wh, 1.4 * wh),
            omega_dot: (
                -0.2 * wh / model.motor_time_constant,
                0.2 * wh / model.motor_time_constant,
            ),
            height: model
                .effects
                .ground_effect()
                .map(|_| (0.5 * r - h, 4.0 * r - h)),
        }
    }
}

/// Samples `points` test points with `design` and seed `seed`, and evaluates the truth
/// wrench at each. The chunk carries Ω̇ (and `height` with ground effect); `t` is the
/// test-point number (s, 0, 1, 2, …) so the file satisfies the strictly increasing time
/// of the data contract. Points are drawn sequentially from the seed, then evaluated on
/// all available cores; the output does not depend on the core count.
pub fn sweep(
    model: &TruthModel,
    ranges: &Ranges,
    design: Design,
    points: usize,
    seed: u64,
) -> SampleChunk {
    let n_rotors = model.vehicle.rotor_count();
    let mut intervals: Vec<(f64, f64)> = Vec::new();
    intervals.extend(ranges.velocity);
    intervals.extend(ranges.rates);
    intervals.extend(std::iter::repeat_n(ranges.omega, n_rotors));
    intervals.extend(std::iter::repeat_n(ranges.omega_dot, n_rotors));
    if let Some(h) = ranges.height {
        intervals.push(h);
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = match design {
        Design::Uniform => uniform_unit(&mut rng, points, intervals.len()),
        Design::LatinHypercube => latin_hypercube(&mut rng, points, intervals.len()),
    };
    let dims = intervals.len();
    let scaled: Vec<f64> = unit
        .chunks_exact(dims)
        .flat_map(|row| {
            row.iter()
                .zip(&intervals)
                .map(|(u, (lo, hi))| lo + u * (hi - lo))
        })
        .collect();
    let has_height = ranges.height.is_some();
    let wrenches = evaluate_parallel(model, &scaled, dims, has_height);
    let mut chunk = SampleChunk::with_capacity(n_rotors, points, true);
    let mut s = Sample {
        omega: vec![0.0; n_rotors],
        omega_dot: vec![0.0; n_rotors],
        ..Default::default()
    };
    for (k, (x, wrench)) in scaled.chunks_exact(dims).zip(wrenches).enumerate() {
        fill_sample(&mut s, x, n_rotors, has_height);
        s.t = k as f64;
        s.wrench = wrench;
        chunk.push(&s);
    }
    chunk
}

/// Unpacks one row of scaled variables [u, v, w, p, q, r, Ω.., Ω̇.., (height)] into `s`.
fn fill_sample(s: &mut Sample, x: &[f64], n_rotors: usize, has_height: bool) {
    s.velocity = [x[0], x[1], x[2]];
    s.rates = [x[3], x[4], x[5]];
    s.omega.copy_from_slice(&x[6..6 + n_rotors]);
    s.omega_dot
        .copy_from_slice(&x[6 + n_rotors..6 + 2 * n_rotors]);
    s.height = has_height.then(|| x[6 + 2 * n_rotors]);
}

/// Truth wrench of every row, split over the available cores. Rows are independent (no
/// inflow warm start is carried between them), so the result does not depend on the
/// split.
fn evaluate_parallel(
    model: &TruthModel,
    rows: &[f64],
    dims: usize,
    has_height: bool,
) -> Vec<[f64; 6]> {
    let n_rows = rows.len() / dims;
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(n_rows.max(1));
    let per = n_rows.div_ceil(threads.max(1)).max(1);
    let n_rotors = model.vehicle.rotor_count();
    let mut out = vec![[0.0; 6]; n_rows];
    std::thread::scope(|scope| {
        for (block, dst) in rows.chunks(per * dims).zip(out.chunks_mut(per)) {
            scope.spawn(move || {
                let mut inflow = model.inflow_states();
                let mut s = Sample {
                    omega: vec![0.0; n_rotors],
                    omega_dot: vec![0.0; n_rotors],
                    ..Default::default()
                };
                for (x, w) in block.chunks_exact(dims).zip(dst) {
                    fill_sample(&mut s, x, n_rotors, has_height);
                    inflow.iter_mut().for_each(|st| st.nu = None);
                    *w = model.wrench(
                        &TruthInput {
                            velocity: s.velocity,
                            rates: s.rates,
                            omega: &s.omega,
                            omega_dot: &s.omega_dot,
                            height: s.height,
                            down_row: None,
                        },
                        &mut inflow,
                    );
                }
            });
        }
    });
    out
}

/// `points × dims` independent U(0, 1) draws, row-major.
fn uniform_unit(rng: &mut StdRng, points: usize, dims: usize) -> Vec<f64> {
    (0..points * dims).map(|_| rng.random::<f64>()).collect()
}

/// Latin hypercube in the unit cube, row-major `points × dims`.
pub fn latin_hypercube(rng: &mut StdRng, points: usize, dims: usize) -> Vec<f64> {
    let mut out = vec![0.0; points * dims];
    let mut perm: Vec<usize> = (0..points).collect();
    for d in 0..dims {
        // Fisher–Yates shuffle.
        for i in (1..points).rev() {
            let j = rng.random_range(0..=i);
            perm.swap(i, j);
        }
        for (k, &stratum) in perm.iter().enumerate() {
            out[k * dims + d] = (stratum as f64 + rng.random::<f64>()) / points as f64;
        }
    }
    out
}
