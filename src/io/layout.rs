//! Motor-layout inference from data: regress the body moments on the individual rotor
//! "thrust proxies" Ω_i² (and M_z also on Ω̇_i), and read positions, spins and the arm
//! length off the coefficients.
//!
//! With thrust T_i = k Ω_i² along −z at hub (x_i, y_i) (FRD): M_x = −Σ y_i k Ω_i²,
//! M_y = Σ x_i k Ω_i², F_z = −k Σ Ω_i², and the reaction torque M_z = −Σ σ_i (k_Q Ω_i² +
//! J_z Ω̇_i) (seed Eq. 16 sign convention, as in `airframe::closed_form_wrench`). So
//! x_i = b_i / k, y_i = −a_i / k, σ_i = −sign(c_i) and J_z ≈ −σ_i d_i.

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use serde::Serialize;

/// Observations a [`NormalEquations`] keeps before it adds them to its sums as two
/// matrix products (one rank-1 update per observation cost ~90 ns at 9 regressors).
const BLOCK_ROWS: usize = 256;

/// Running normal equations of small least-squares problems y_k ≈ X β_k that share
/// their regressors: XᵀX is summed once for all outputs y_k, and a problem may use the
/// leading columns of X only (its XᵀX is the leading block, the same sums).
#[derive(Debug, Clone)]
pub struct NormalEquations {
    n: usize,
    xtx: Vec<f64>,
    /// Xᵀy_k at `k * n`.
    xty: Vec<f64>,
    yty: Vec<f64>,
    sum_y: Vec<f64>,
    count: u64,
    /// Observations not yet in the sums, row after row: n regressors, then the outputs.
    pending: Vec<f64>,
}

impl NormalEquations {
    /// Empty accumulator for `n` regressors and `outputs` outputs.
    pub fn new(n: usize, outputs: usize) -> Self {
        Self {
            n,
            xtx: vec![0.0; n * n],
            xty: vec![0.0; n * outputs],
            yty: vec![0.0; outputs],
            sum_y: vec![0.0; outputs],
            count: 0,
            pending: Vec::new(),
        }
    }

    /// Adds one observation: regressors `x` (at least n) and one value per output.
    pub fn push(&mut self, x: &[f64], y: &[f64]) {
        let outputs = self.yty.len();
        self.pending.extend_from_slice(&x[..self.n]);
        self.pending.extend_from_slice(&y[..outputs]);
        self.count += 1;
        if self.pending.len() == BLOCK_ROWS * (self.n + outputs) {
            self.add_pending();
        }
    }

    /// Adds the kept observations to the sums: XᵀX and XᵀY as matrix products (the
    /// whole XᵀX square, though only its upper triangle is read), yᵀy and Σy in order.
    fn add_pending(&mut self) {
        let (n, m) = (self.n, self.yty.len());
        let width = n + m;
        let rows = self.pending.len() / width;
        if rows == 0 {
            return;
        }
        let x = MatRef::from_row_major_slice_with_stride(&self.pending, rows, n, width);
        let y = MatRef::from_row_major_slice_with_stride(&self.pending[n..], rows, m, width);
        let xtx = MatMut::from_row_major_slice_mut(&mut self.xtx, n, n);
        matmul(xtx, Accum::Add, x.transpose(), x, 1.0, Par::Seq);
        let xty = MatMut::from_column_major_slice_mut(&mut self.xty, n, m);
        matmul(xty, Accum::Add, x.transpose(), y, 1.0, Par::Seq);
        for row in self.pending.chunks_exact(width) {
            for (k, &yk) in row[n..].iter().enumerate() {
                self.yty[k] += yk * yk;
                self.sum_y[k] += yk;
            }
        }
        self.pending.clear();
    }

    /// Least-squares coefficients (columns equilibrated) of output `output` on the first
    /// `columns` regressors, and R² about the mean; `None` when singular or empty.
    pub fn solve(&self, output: usize, columns: usize) -> Option<(Vec<f64>, f64)> {
        if !self.pending.is_empty() {
            let mut summed = self.clone();
            summed.add_pending();
            return summed.solve(output, columns);
        }
        let (stride, n) = (self.n, columns.min(self.n));
        if self.count <= n as u64 {
            return None;
        }
        let xtx = |r: usize, c: usize| self.xtx[r * stride + c];
        let xty = &self.xty[output * stride..output * stride + n];
        let scale: Vec<f64> = (0..n).map(|i| xtx(i, i).sqrt().max(1e-300)).collect();
        let mut a = vec![0.0; n * n];
        for r in 0..n {
            for c in 0..n {
                let v = if c >= r { xtx(r, c) } else { xtx(c, r) };
                a[r * n + c] = v / (scale[r] * scale[c]);
            }
        }
        let mut b: Vec<f64> = (0..n).map(|i| xty[i] / scale[i]).collect();
        // Cholesky solve of the equilibrated system.
        for j in 0..n {
            let mut d = a[j * n + j];
            for k in 0..j {
                d -= a[j * n + k] * a[j * n + k];
            }
            if d <= 1e-12 {
                return None;
            }
            let d = d.sqrt();
            a[j * n + j] = d;
            for i in j + 1..n {
                let mut s = a[i * n + j];
                for k in 0..j {
                    s -= a[i * n + k] * a[j * n + k];
                }
                a[i * n + j] = s / d;
            }
        }
        for i in 0..n {
            let mut s = b[i];
            for k in 0..i {
                s -= a[i * n + k] * b[k];
            }
            b[i] = s / a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for k in i + 1..n {
                s -= a[k * n + i] * b[k];
            }
            b[i] = s / a[i * n + i];
        }
        let beta: Vec<f64> = (0..n).map(|i| b[i] / scale[i]).collect();
        let explained: f64 = beta.iter().zip(xty).map(|(b, xy)| b * xy).sum();
        let yty = self.yty[output];
        let sse = (yty - explained).max(0.0);
        let mean = self.sum_y[output] / self.count as f64;
        let sst = yty - self.count as f64 * mean * mean;
        let r2 = if sst > 0.0 { 1.0 - sse / sst } else { 0.0 };
        Some((beta, r2))
    }
}

/// What the data say about the motor layout.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct LayoutReport {
    /// Samples used.
    pub samples: u64,
    /// Thrust coefficient k from F_z = −k Σ Ω_i², N s².
    pub thrust_coefficient: f64,
    /// Inferred hub position (x_i, y_i) per rotor, body FRD, m.
    pub positions: Vec<[f64; 2]>,
    /// Inferred spin σ_i (+1: angular velocity along body +z).
    pub spins: Vec<f64>,
    /// Mean inferred arm length, m.
    pub arm_length: f64,
    /// Rotor inertia estimate from the Ω̇ terms of M_z, kg m², when Ω̇ is available.
    pub rotor_inertia: Option<f64>,
    /// R² of the M_x, M_y, M_z and F_z regressions.
    pub r_squared: [f64; 4],
}

/// Streaming accumulator of the layout regressions.
#[derive(Debug, Clone)]
pub struct LayoutAccumulator {
    rotors: usize,
    with_omega_dot: bool,
    /// M_x, M_y on [1, Ω_i²] and M_z on [1, Ω_i², Ω̇_i] (the leading columns are shared).
    moments: NormalEquations,
    fz: NormalEquations,
    x: Vec<f64>,
}

impl LayoutAccumulator {
    /// Accumulator for `rotors` rotors; `with_omega_dot` adds the Ω̇_i terms to M_z.
    pub fn new(rotors: usize, with_omega_dot: bool) -> Self {
        let nz = 1 + rotors + if with_omega_dot { rotors } else { 0 };
        Self {
            rotors,
            with_omega_dot,
            moments: NormalEquations::new(nz, 3),
            fz: NormalEquations::new(1, 1),
            x: vec![0.0; nz],
        }
    }

    /// Adds one sample: rotor speeds (rad/s), rotor accelerations (rad/s², ignored
    /// unless enabled) and wrench [F; M] (N, N m).
    pub fn push(&mut self, omega: &[f64], omega_dot: &[f64], wrench: &[f64; 6]) {
        let n = self.rotors;
        self.x[0] = 1.0;
        let mut sum_sq = 0.0;
        for (dst, w) in self.x[1..=n].iter_mut().zip(omega) {
            *dst = w * w;
            sum_sq += *dst;
        }
        if self.with_omega_dot {
            self.x[1 + n..1 + 2 * n].copy_from_slice(&omega_dot[..n]);
        }
        self.moments.push(&self.x, &wrench[3..6]);
        self.fz.push(&[sum_sq], &[wrench[2]]);
    }

    /// The inferred layout, `None` when a regression is singular (e.g. constant speeds).
    pub fn finish(&self) -> Option<LayoutReport> {
        let n = self.rotors;
        let (kfz, r2f) = self.fz.solve(0, 1)?;
        let k = -kfz[0];
        if k <= 0.0 {
            return None;
        }
        let (a, r2x) = self.moments.solve(0, n + 1)?;
        let (b, r2y) = self.moments.solve(1, n + 1)?;
        let (c, r2z) = self.moments.solve(2, self.x.len())?;
        let positions: Vec<[f64; 2]> = (0..n).map(|i| [b[1 + i] / k, -a[1 + i] / k]).collect();
        let spins: Vec<f64> = (0..n)
            .map(|i| if c[1 + i] > 0.0 { -1.0 } else { 1.0 })
            .collect();
        let arm_length = positions.iter().map(|p| p[0].hypot(p[1])).sum::<f64>() / n as f64;
        let rotor_inertia = self
            .with_omega_dot
            .then(|| (0..n).map(|i| -spins[i] * c[1 + n + i]).sum::<f64>() / n as f64);
        Some(LayoutReport {
            samples: self.fz.count,
            thrust_coefficient: k,
            positions,
            spins,
            arm_length,
            rotor_inertia,
            r_squared: [r2x, r2y, r2z, r2f],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sharing XᵀX between outputs, and solving on its leading columns, gives what a
    /// separate accumulator of those columns alone gives: the same sums, up to the order
    /// in which the matrix products add them (1e-12 relative on this well-conditioned
    /// random design). 400 observations: one block summed, 144 still kept when solved.
    #[test]
    fn shared_normal_equations_solve_as_separate_ones() {
        let (n, lead, samples) = (9, 5, 400);
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut shared = NormalEquations::new(n, 2);
        let mut short = NormalEquations::new(lead, 1);
        let mut full = NormalEquations::new(n, 1);
        for _ in 0..samples {
            let x: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let y = [rnd(), rnd()];
            shared.push(&x, &y);
            short.push(&x[..lead], &y[..1]);
            full.push(&x, &y[1..]);
        }
        let close = |a: Option<(Vec<f64>, f64)>, b: Option<(Vec<f64>, f64)>| {
            let ((a, ra), (b, rb)) = (a.expect("regular"), b.expect("regular"));
            assert_eq!(a.len(), b.len());
            for (x, y) in a.iter().zip(&b).chain([(&ra, &rb)]) {
                assert!((x - y).abs() <= 1e-12 * y.abs(), "{x} vs {y}");
            }
        };
        close(shared.solve(0, lead), short.solve(0, lead));
        close(shared.solve(1, n), full.solve(0, n));
        // Fewer samples than regressors: no solution.
        assert!(NormalEquations::new(3, 1).solve(0, 3).is_none());
    }

    #[test]
    fn layout_regression_recovers_positions_spins_and_rotor_inertia_exactly() {
        // Synthetic noiseless loads of a quad-x (ℓ = 0.11 m) numbered like NeuroBEM:
        // T = k Ω², Q = k_Q Ω², M_z = -Σ σ (Q + J Ω̇). Least squares recovers them to rounding.
        let (k, kq, jz) = (1.5e-6, 2.0e-8, 8e-7);
        let a = 0.11 / 2f64.sqrt();
        let pos = [[-a, a], [a, a], [-a, -a], [a, -a]];
        let spin = [1.0, -1.0, -1.0, 1.0];
        let mut acc = LayoutAccumulator::new(4, true);
        for n in 0..2000 {
            let t = n as f64 * 0.0025;
            let w: Vec<f64> = (0..4)
                .map(|i| 1000.0 + 300.0 * (1.1 * t * (i + 1) as f64 + i as f64).sin())
                .collect();
            let wd: Vec<f64> = (0..4)
                .map(|i| 500.0 * (0.7 * t * (i + 2) as f64).cos())
                .collect();
            let mut wrench = [0.0; 6];
            for i in 0..4 {
                let thrust = k * w[i] * w[i];
                wrench[2] -= thrust;
                wrench[3] -= pos[i][1] * thrust;
                wrench[4] += pos[i][0] * thrust;
                wrench[5] -= spin[i] * (kq * w[i] * w[i] + jz * wd[i]);
            }
            acc.push(&w, &wd, &wrench);
        }
        let r = acc.finish().unwrap();
        assert_eq!(r.spins, spin.to_vec());
        // Noiseless data: errors are rounding in the normal equations, 1e-6 relative.
        assert!((r.thrust_coefficient - k).abs() < 1e-6 * k);
        assert!((r.arm_length - 0.11).abs() < 1e-6);
        for (got, want) in r.positions.iter().zip(pos) {
            assert!((got[0] - want[0]).abs() < 1e-6 && (got[1] - want[1]).abs() < 1e-6);
        }
        assert!((r.rotor_inertia.unwrap() - jz).abs() < 1e-6 * jz * 100.0);
    }
}
