//! Signals derived when a log lacks them: the local-polynomial (Savitzky–Golay)
//! derivative on possibly non-uniform time stamps, the rigid-body force F = m a and moment
//! M = I ω̇ + ω × I ω (Euler's equation), the IMU lever-arm correction, and body velocity
//! from world velocity and attitude.

use serde::Deserialize;

use crate::sample::SampleChunk;
use crate::util::{cross, quat_to_matrix};

/// Options of the derivations.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeriveOptions {
    /// Savitzky–Golay window length, samples (odd, ≥ order + 2).
    #[serde(default = "default_window")]
    pub sg_window: usize,
    /// Savitzky–Golay polynomial order (1..=5).
    #[serde(default = "default_order")]
    pub sg_order: usize,
    /// IMU position relative to the CG in body FRD axes, m; the accelerometer reading is
    /// carried to the CG with a_cg = a_imu − ω̇ × r − ω × (ω × r).
    pub imu_lever_arm: Option<[f64; 3]>,
}

fn default_window() -> usize {
    11
}

fn default_order() -> usize {
    2
}

impl Default for DeriveOptions {
    fn default() -> Self {
        Self {
            sg_window: default_window(),
            sg_order: default_order(),
            imu_lever_arm: None,
        }
    }
}

/// Derivation options that cannot be used; the error names the option.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeriveOptionsError {
    /// A polynomial order outside 1..=5.
    #[error("sg_order = {sg_order} must be in 1..=5")]
    Order {
        /// The order given.
        sg_order: usize,
    },
    /// A window that is even, shorter than the order + 2, or longer than 201 samples.
    #[error(
        "sg_window = {sg_window} must be odd, at least sg_order + 2 = {} and at most 201",
        sg_order + 2
    )]
    Window {
        /// The window given, samples.
        sg_window: usize,
        /// The order it goes with.
        sg_order: usize,
    },
    /// A lever arm with a component not finite or beyond 10 m.
    #[error("imu_lever_arm = {imu_lever_arm:?} must be finite and within 10 m")]
    LeverArm {
        /// The lever arm given, m.
        imu_lever_arm: [f64; 3],
    },
}

impl DeriveOptions {
    /// Checks window, order and lever arm.
    pub(crate) fn check(&self) -> Result<(), DeriveOptionsError> {
        if !(1..=5).contains(&self.sg_order) {
            return Err(DeriveOptionsError::Order {
                sg_order: self.sg_order,
            });
        }
        if self.sg_window.is_multiple_of(2)
            || self.sg_window < self.sg_order + 2
            || self.sg_window > 201
        {
            return Err(DeriveOptionsError::Window {
                sg_window: self.sg_window,
                sg_order: self.sg_order,
            });
        }
        if let Some(r) = self.imu_lever_arm
            && r.iter().any(|c| !c.is_finite() || c.abs() > 10.0)
        {
            return Err(DeriveOptionsError::LeverArm { imu_lever_arm: r });
        }
        Ok(())
    }
}

/// Weights `w` such that Σ_j w_j x(t_j) is the derivative at `t_k` of the least-squares
/// polynomial of degree `order` through the samples at `times` (Savitzky–Golay on
/// non-uniform stamps). `k` indexes `times`. Near the ends of a segment the window is
/// one-sided. Returns `false` (weights untouched) when the fit is singular, i.e. fewer
/// distinct times than `order + 1`.
pub fn sg_derivative_weights(times: &[f64], k: usize, order: usize, w: &mut Vec<f64>) -> bool {
    let n = order + 1;
    if times.len() < n {
        return false;
    }
    let t0 = times[k];
    let span = times.iter().map(|t| (t - t0).abs()).fold(0.0, f64::max);
    if span <= 0.0 {
        return false;
    }
    // Normal equations in scaled time s = (t − t0)/span for conditioning.
    let mut a = [[0.0; 6]; 6];
    for &t in times {
        let s = (t - t0) / span;
        let mut pi = 1.0;
        let mut pow = [0.0; 11];
        for p in pow.iter_mut().take(2 * n - 1) {
            *p = pi;
            pi *= s;
        }
        for (r, row) in a.iter_mut().enumerate().take(n) {
            for (c, v) in row.iter_mut().enumerate().take(n) {
                *v += pow[r + c];
            }
        }
    }
    // Solve A g = e_1 (derivative of the fitted polynomial at s = 0 is coefficient 1).
    let mut g = [0.0; 6];
    g[1] = 1.0;
    if !solve_spd(&mut a, &mut g, n) {
        return false;
    }
    w.clear();
    for &t in times {
        let s = (t - t0) / span;
        let mut pi = 1.0;
        let mut acc = 0.0;
        for gi in g.iter().take(n) {
            acc += gi * pi;
            pi *= s;
        }
        w.push(acc / span);
    }
    true
}

/// A window reuses the weights of the window they were last computed for when each of
/// its time offsets from its centre sample lies within this fraction of that window's
/// largest offset of the corresponding one ([`SgWeights`]).
pub const SG_REUSE_TOLERANCE: f64 = 1e-9;

/// Savitzky–Golay derivative weights ([`sg_derivative_weights`]) with the last ones
/// kept for the next window of the same shape. On a uniformly sampled log every window
/// is the same up to the rounding of its time stamps (parsed decimal times jitter by an
/// ulp of t: 4e-12 s at t = 2.5e4 s, 3e-10 of the half-width of an 11-sample window at
/// 400 Hz), so the weights are computed at segment ends and reused in between instead
/// of a normal-equation solve per sample (12 % of a `fit --no-diagnose` profile).
/// Reuse is judged against the window the weights were computed for, never a reused
/// one, so the difference cannot drift: a reused weight differs from a recomputed one
/// by about [`SG_REUSE_TOLERANCE`] of its size at most.
#[derive(Debug, Default, Clone)]
pub struct SgWeights {
    /// t_j − t_k of the window the weights were computed for, s.
    offsets: Vec<f64>,
    /// Its largest |t_j − t_k|, s.
    span: f64,
    /// Its centre index k and polynomial order.
    centre: usize,
    order: usize,
    weights: Vec<f64>,
}

impl SgWeights {
    /// The weights of the derivative at `times[k]` (see [`sg_derivative_weights`]), or
    /// `None` when that fit is singular.
    pub fn get(&mut self, times: &[f64], k: usize, order: usize) -> Option<&[f64]> {
        let t0 = times[k];
        let same = !self.weights.is_empty()
            && self.centre == k
            && self.order == order
            && self.offsets.len() == times.len()
            && times
                .iter()
                .zip(&self.offsets)
                .all(|(t, o)| ((t - t0) - o).abs() <= SG_REUSE_TOLERANCE * self.span);
        if !same {
            if !sg_derivative_weights(times, k, order, &mut self.weights) {
                self.weights.clear();
                return None;
            }
            self.offsets.clear();
            self.offsets.extend(times.iter().map(|t| t - t0));
            self.span = self.offsets.iter().fold(0.0, |m, o| o.abs().max(m));
            (self.centre, self.order) = (k, order);
        }
        Some(&self.weights)
    }

    /// Forgets the kept weights (the next window computes its own).
    pub fn clear(&mut self) {
        self.weights.clear();
    }
}

/// A sample interval longer than this many times a chunk's median interval is a gap (a
/// join of the reader's segments): Ω̈ is never differentiated across it.
const JERK_GAP_FACTOR: f64 = 3.0;

/// Reusable buffers of [`rotor_jerk`].
#[derive(Debug, Default)]
pub struct JerkScratch {
    intervals: Vec<f64>,
    weights: SgWeights,
}

/// Fills `chunk.omega_ddot` with Ω̈_i, rad/s³: the Savitzky–Golay derivative (window
/// and order of `options`) of each Ω̇_i series, one-sided at the chunk's ends and at
/// time gaps, so that Ω̈ is a function of the chunk alone (the fit pipeline's chunks
/// are the same from a file and from memory). `None` when the chunk has no Ω̇; 0 on a
/// stretch too short to differentiate.
pub fn rotor_jerk(chunk: &mut SampleChunk, options: &DeriveOptions, scratch: &mut JerkScratch) {
    let SampleChunk {
        t,
        omega_dot,
        omega_ddot,
        ..
    } = chunk;
    let Some(omega_dot) = omega_dot else {
        *omega_ddot = None;
        return;
    };
    let n = t.len();
    let omega_ddot = omega_ddot.get_or_insert_with(Vec::new);
    omega_ddot.resize_with(omega_dot.len(), Vec::new);
    for v in omega_ddot.iter_mut() {
        v.clear();
        v.resize(n, 0.0);
    }
    if n < 2 {
        return;
    }
    let JerkScratch { intervals, weights } = scratch;
    // Ω̈ stays a function of the chunk alone: no weights carried over from the last one.
    weights.clear();
    intervals.clear();
    intervals.extend(t.windows(2).map(|w| w[1] - w[0]));
    let mid = intervals.len() / 2;
    let gap = JERK_GAP_FACTOR * *intervals.select_nth_unstable_by(mid, f64::total_cmp).1;
    let mut start = 0;
    for end in 1..=n {
        if end < n && t[end] - t[end - 1] <= gap {
            continue;
        }
        let width = options.sg_window.min(end - start);
        for k in start..end {
            let lo = k
                .saturating_sub(options.sg_window / 2)
                .clamp(start, end - width);
            let times = &t[lo..lo + width];
            let Some(weights) = weights.get(times, k - lo, options.sg_order) else {
                continue;
            };
            for (dst, src) in omega_ddot.iter_mut().zip(omega_dot.iter()) {
                dst[k] = weights.iter().zip(&src[lo..]).map(|(w, x)| w * x).sum();
            }
        }
        start = end;
    }
}

/// Gaussian elimination with partial pivoting on the leading `n`×`n` block; false when
/// singular.
fn solve_spd(a: &mut [[f64; 6]; 6], b: &mut [f64; 6], n: usize) -> bool {
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .unwrap_or(col);
        if a[piv][col].abs() < 1e-13 * a[0][0].abs().max(1e-300) {
            return false;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for r in col + 1..n {
            let f = a[r][col] / a[col][col];
            let pivot_row = a[col];
            for (dst, src) in a[r][col..n].iter_mut().zip(&pivot_row[col..n]) {
                *dst -= f * src;
            }
            b[r] -= f * b[col];
        }
    }
    for col in (0..n).rev() {
        let mut s = b[col];
        for c in col + 1..n {
            s -= a[col][c] * b[c];
        }
        b[col] = s / a[col][col];
    }
    true
}

/// I · v for a 3×3 inertia matrix.
pub fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// Moment on the rigid body from Euler's equation, M = I ω̇ + ω × I ω (N m), for
/// inertia `inertia` (kg m²), rates `omega` (rad/s) and angular acceleration `omega_dot`
/// (rad/s²), body axes.
pub fn euler_moment(inertia: &[[f64; 3]; 3], omega: [f64; 3], omega_dot: [f64; 3]) -> [f64; 3] {
    let i_wd = mat_vec(inertia, omega_dot);
    let gyro = cross(omega, mat_vec(inertia, omega));
    [0, 1, 2].map(|k| i_wd[k] + gyro[k])
}

/// Specific force at the CG from an accelerometer at `lever` (m, body) from the CG:
/// a_cg = a_imu − ω̇ × r − ω × (ω × r).
pub fn specific_force_at_cg(
    a_imu: [f64; 3],
    lever: [f64; 3],
    omega: [f64; 3],
    omega_dot: [f64; 3],
) -> [f64; 3] {
    let tangential = cross(omega_dot, lever);
    let centripetal = cross(omega, cross(omega, lever));
    [0, 1, 2].map(|k| a_imu[k] - tangential[k] - centripetal[k])
}

/// Unit quaternion `[w, x, y, z]` with w ≥ 0 of a rotation matrix (Shepperd's method).
pub fn matrix_to_quat(m: &[[f64; 3]; 3]) -> [f64; 4] {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let q = if tr > 0.0 {
        let s = 2.0 * (1.0 + tr).sqrt();
        [
            s / 4.0,
            (m[2][1] - m[1][2]) / s,
            (m[0][2] - m[2][0]) / s,
            (m[1][0] - m[0][1]) / s,
        ]
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt();
        [
            (m[2][1] - m[1][2]) / s,
            s / 4.0,
            (m[0][1] + m[1][0]) / s,
            (m[0][2] + m[2][0]) / s,
        ]
    } else if m[1][1] > m[2][2] {
        let s = 2.0 * (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt();
        [
            (m[0][2] - m[2][0]) / s,
            (m[0][1] + m[1][0]) / s,
            s / 4.0,
            (m[1][2] + m[2][1]) / s,
        ]
    } else {
        let s = 2.0 * (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt();
        [
            (m[1][0] - m[0][1]) / s,
            (m[0][2] + m[2][0]) / s,
            (m[1][2] + m[2][1]) / s,
            s / 4.0,
        ]
    };
    if q[0] < 0.0 { q.map(|c| -c) } else { q }
}

/// Body-axes velocity from world-axes velocity `v_world` and the body→world attitude `q`:
/// v_body = Rᵀ v_world.
pub fn body_velocity(q: [f64; 4], v_world: [f64; 3]) -> [f64; 3] {
    let r = quat_to_matrix(q);
    [0, 1, 2].map(|c| r[0][c] * v_world[0] + r[1][c] * v_world[1] + r[2][c] * v_world[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each refused option is named with its value, in the words the reader reports.
    #[test]
    fn bad_options_are_named() {
        let check = |sg_window, sg_order, imu_lever_arm| {
            DeriveOptions {
                sg_window,
                sg_order,
                imu_lever_arm,
            }
            .check()
            .map_err(|e| e.to_string())
        };
        assert_eq!(check(11, 2, Some([0.1, 0.0, -0.05])), Ok(()));
        assert_eq!(
            check(11, 6, None),
            Err("sg_order = 6 must be in 1..=5".into())
        );
        assert_eq!(
            check(4, 3, None),
            Err("sg_window = 4 must be odd, at least sg_order + 2 = 5 and at most 201".into())
        );
        assert_eq!(
            check(11, 2, Some([0.0, 11.0, 0.0])),
            Err("imu_lever_arm = [0.0, 11.0, 0.0] must be finite and within 10 m".into())
        );
    }

    /// A chunk of `n` samples at 100 Hz with Ω̇_1 = f(t), Ω̇_2 = −f(t), a time gap of 1 s
    /// after sample `gap_after` (if any).
    fn accelerations(n: usize, gap_after: Option<usize>, f: impl Fn(f64) -> f64) -> SampleChunk {
        let mut c = SampleChunk::with_capacity(2, n, true);
        for k in 0..n {
            let t = 0.01 * k as f64 + gap_after.map_or(0.0, |g| if k > g { 1.0 } else { 0.0 });
            c.t.push(t);
            c.omega.iter_mut().for_each(|w| w.push(700.0));
            let omega_dot = c.omega_dot.as_mut().expect("made with Ω̇");
            omega_dot[0].push(f(t));
            omega_dot[1].push(-f(t));
        }
        c
    }

    #[test]
    fn rotor_jerk_is_exact_on_quadratics_and_never_crosses_a_gap() {
        // Order-2 fits differentiate a quadratic exactly, one-sided windows too: Ω̈ =
        // 2 a t + b to rounding (1e-9 relative to values of ~50 rad/s³).
        let (a, b) = (40.0, -3.0);
        let quad = |t: f64| a * t * t + b * t + 5.0;
        let mut c = accelerations(50, None, quad);
        rotor_jerk(
            &mut c,
            &DeriveOptions::default(),
            &mut JerkScratch::default(),
        );
        for (k, &t) in c.t.iter().enumerate() {
            let jerk = c.omega_ddot.as_ref().expect("Ω̈ of Ω̇");
            assert!((jerk[0][k] - (2.0 * a * t + b)).abs() < 1e-9, "{k}");
            assert_eq!(jerk[1][k], -jerk[0][k]);
        }
        // A step in Ω̇ across a 1 s gap: differentiated across it, the samples next to
        // the gap would see a slope of ~100 rad/s² over the window; each side is
        // constant, so Ω̈ is 0 on both (to rounding).
        let mut g = accelerations(40, Some(19), |t| if t < 0.5 { 10.0 } else { 90.0 });
        rotor_jerk(
            &mut g,
            &DeriveOptions::default(),
            &mut JerkScratch::default(),
        );
        let jerk = &g.omega_ddot.as_ref().expect("Ω̈ of Ω̇")[0];
        assert!(jerk.iter().all(|x| x.abs() < 1e-9), "{jerk:?}");
        // No Ω̇, no Ω̈.
        let mut none = SampleChunk::with_capacity(2, 3, false);
        none.t.extend([0.0, 0.01, 0.02]);
        rotor_jerk(
            &mut none,
            &DeriveOptions::default(),
            &mut JerkScratch::default(),
        );
        assert_eq!(none.omega_ddot, None);
    }

    #[test]
    fn sg_is_exact_on_polynomials_of_its_order_even_non_uniform() {
        // Degree-2 polynomial, order-2 fit on jittered stamps: exact up to rounding
        // (tolerance 1e-9 covers the conditioning of an 11-point fit).
        let times: Vec<f64> = (0..11)
            .map(|j| 0.01 * j as f64 + 0.002 * ((j * 7 % 5) as f64))
            .collect();
        let x: Vec<f64> = times.iter().map(|t| 3.0 - 2.0 * t + 5.0 * t * t).collect();
        let mut w = Vec::new();
        for k in [0, 5, 10] {
            assert!(sg_derivative_weights(&times, k, 2, &mut w));
            let d: f64 = w.iter().zip(&x).map(|(a, b)| a * b).sum();
            assert!((d - (-2.0 + 10.0 * times[k])).abs() < 1e-9, "k={k}: {d}");
        }
    }

    #[test]
    fn euler_moment_matches_hand_computation() {
        // I = diag(1,2,3), ω = (1,0,1), ω̇ = 0: ω × Iω = (1,0,1) × (1,0,3) = (0,-2,0).
        let i = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]];
        assert_eq!(
            euler_moment(&i, [1.0, 0.0, 1.0], [0.0; 3]),
            [0.0, -2.0, 0.0]
        );
    }

    #[test]
    fn quaternion_matrix_round_trip() {
        let n = (0.3f64 * 0.3 + 0.1 * 0.1 + 0.5 * 0.5 + 0.8 * 0.8).sqrt();
        let q = [0.8 / n, 0.3 / n, -0.1 / n, 0.5 / n];
        let back = matrix_to_quat(&quat_to_matrix(q));
        for k in 0..4 {
            assert!((back[k] - q[k]).abs() < 1e-15 * 4.0, "{back:?} vs {q:?}");
        }
    }

    /// Kept weights are reused only for windows within [`SG_REUSE_TOLERANCE`] of the one
    /// they were computed for: on 400 Hz stamps parsed from 6-decimal text far into a
    /// log (jitter ~1e-12 s) every interior window reuses them and matches its own
    /// weights to 1e-8 (relative to the largest weight); a window stretched by 1e-6 of
    /// its span, or a different centre, computes its own (exactly
    /// [`sg_derivative_weights`]); and a drift of 0.6 × the tolerance per window is
    /// measured from the computed window, so the second step recomputes.
    #[test]
    fn kept_weights_serve_only_windows_of_the_same_shape() {
        let stamps: Vec<f64> = (0..200)
            .map(|i| {
                format!("{:.6}", 25_000.0 + i as f64 * 0.0025)
                    .parse()
                    .unwrap()
            })
            .collect();
        let mut kept = SgWeights::default();
        let mut own = Vec::new();
        let first = kept.get(&stamps[..11], 5, 2).unwrap().to_vec();
        for lo in 0..190 {
            let times = &stamps[lo..lo + 11];
            let w = kept.get(times, 5, 2).unwrap().to_vec();
            assert_eq!(w, first, "window {lo} reuses the weights");
            assert!(sg_derivative_weights(times, 5, 2, &mut own));
            let big = own.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            for (a, b) in w.iter().zip(&own) {
                assert!((a - b).abs() < 1e-8 * big, "{a} vs {b} at {lo}");
            }
        }

        let uniform: Vec<f64> = (0..11).map(|i| i as f64 * 0.0025).collect();
        let stretched: Vec<f64> = uniform.iter().map(|t| t * (1.0 + 1e-6)).collect();
        let mut kept = SgWeights::default();
        for (times, k) in [(&uniform, 5), (&stretched, 5), (&uniform, 4)] {
            let w = kept.get(times, k, 2).unwrap().to_vec();
            assert!(sg_derivative_weights(times, k, 2, &mut own));
            assert_eq!(w, own, "computed, not reused");
        }

        let span = 0.0125; // the largest |t_j − t_k|
        let drift = 0.6 * SG_REUSE_TOLERANCE * span;
        let mut kept = SgWeights::default();
        kept.get(&uniform, 5, 2).unwrap();
        let step = |m: f64| -> Vec<f64> {
            uniform
                .iter()
                .enumerate()
                .map(|(i, t)| if i == 10 { t + m * drift } else { *t })
                .collect()
        };
        let first = kept.get(&step(1.0), 5, 2).unwrap().to_vec();
        assert_eq!(
            kept.offsets[10],
            uniform[10] - uniform[5],
            "within tolerance: reused"
        );
        let second = kept.get(&step(2.0), 5, 2).unwrap().to_vec();
        assert_ne!(
            first, second,
            "1.2 × the tolerance from the computed window: recomputed"
        );
    }
}
