//! The triangular factor of R stacked on new rows, without touching R's zeros.
//!
//! Folding a chunk B (n × q) into the upper-triangular factor R (q × q) of the data seen
//! so far is the QR factorisation of [R; B]. A general Householder QR of that stack
//! treats the zeros below R's diagonal as data; here, as in LAPACK's `dtpqrt` (Elmroth
//! and Gustavson's triangular-pentagonal QR), the reflector of column j is built from
//! R\[j, j\] and column j of B only: v = [eⱼ; B\[:, j\] / (α − β)] touches row j of R
//! and all of B. Reflectors are applied within panels of [`PANEL`] columns by
//! vector loops and to the columns right of each panel as one block reflector
//! I − V T Vᵀ (compact WY form, two matrix products through faer), so ~2nq² flops per
//! chunk run mostly in matrix-product kernels. Standard Householder QR: the same
//! backward stability as faer's `qr_in_place`, at 3–5× its speed on these shapes
//! (measured in docs/benchmarks.md).

use faer::linalg::matmul::matmul;
use faer::prelude::*;
use faer::{Accum, Mat, MatMut, Par};

use crate::util::dot;

/// Columns per panel: reflectors within a panel are applied by vector loops, to the rest
/// of the matrix by matrix products. 8 is fastest for q = 44 and q = 147 on 1024-row
/// chunks (4 and 16 cost 15–50 % more).
const PANEL: usize = 8;

/// Scratch of [`fold_rows`], reused between calls.
#[derive(Debug)]
pub(crate) struct FoldScratch {
    /// The panel's reflectors' Gram matrix V_BᵀV_B.
    gram: Mat<f64>,
    /// Upper-triangular T of the panel's block reflector.
    t: Mat<f64>,
    /// Vᵀ C, then Tᵀ Vᵀ C, for the columns C right of the panel.
    w: Mat<f64>,
    tw: Mat<f64>,
    /// τ of each reflector of the panel.
    tau: Vec<f64>,
}

impl FoldScratch {
    /// Empty buffers (sized on first use).
    pub(crate) const fn new() -> Self {
        Self {
            gram: Mat::new(),
            t: Mat::new(),
            w: Mat::new(),
            tw: Mat::new(),
            tau: Vec::new(),
        }
    }
}

/// Replaces the upper-triangular `r` (q × q; entries below the diagonal are ignored and
/// left as they are) by the triangular factor of [R; B], with non-negative diagonal; `b`
/// (n × q, column-major) is overwritten by the reflectors. R = 0 gives the QR of B.
pub(crate) fn fold_rows(mut r: MatMut<'_, f64>, mut b: MatMut<'_, f64>, s: &mut FoldScratch) {
    let q = r.ncols();
    assert!(r.nrows() == q && b.ncols() == q, "[R; B] shapes");
    if b.nrows() > 0 {
        crate::util::vectorized(FoldPanels {
            r: r.rb_mut(),
            b: b.rb_mut(),
            s,
        });
    }
    for i in 0..q {
        if r[(i, i)] < 0.0 {
            for j in i..q {
                r[(i, j)] = -r[(i, j)];
            }
        }
    }
}

/// The reflectors of [R; B], panel by panel, as one operation for
/// [`crate::util::vectorized`].
struct FoldPanels<'a> {
    r: MatMut<'a, f64>,
    b: MatMut<'a, f64>,
    s: &'a mut FoldScratch,
}

impl pulp::WithSimd for FoldPanels<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Self { mut r, mut b, s } = self;
        let q = r.ncols();
        let mut c = 0;
        while c < q {
            let w = PANEL.min(q - c);
            factor_panel(r.rb_mut(), b.rb_mut(), c, w, &mut s.tau);
            if c + w < q {
                update_right_of_panel(r.rb_mut(), b.rb_mut(), c, w, s);
            }
            c += w;
        }
    }
}

/// Column j of `b` as a slice (faer's columns are contiguous).
fn column(b: MatMut<'_, f64>, j: usize) -> &mut [f64] {
    b.col_mut(j)
        .try_as_col_major_mut()
        .expect("contiguous column")
        .as_slice_mut()
}

/// Reflectors of columns c..c + w, applied within those columns; their τ in `tau`.
#[inline(always)]
fn factor_panel(
    mut r: MatMut<'_, f64>,
    mut b: MatMut<'_, f64>,
    c: usize,
    w: usize,
    tau: &mut Vec<f64>,
) {
    tau.clear();
    for j in c..c + w {
        let (left, mut right) = b.rb_mut().split_at_col_mut(j + 1);
        let v = column(left, j);
        let alpha = r[(j, j)];
        let x_norm = norm(v);
        if x_norm < f64::MIN_POSITIVE {
            // Column j of [R; B] is already reduced: H = I. A subnormal remainder (the
            // rounding residue of a rank-deficient factor, e.g. two merged accumulators
            // of two samples each) counts as none: 1/(α − β) would overflow to ∞ and
            // turn the rest of R into NaN.
            tau.push(0.0);
            continue;
        }
        let beta = -alpha.hypot(x_norm).copysign(alpha);
        let tau_j = (beta - alpha) / beta;
        let scale = 1.0 / (alpha - beta);
        v.iter_mut().for_each(|x| *x *= scale);
        r[(j, j)] = beta;
        for k in j + 1..c + w {
            let col = column(right.rb_mut(), k - j - 1);
            let dot = r[(j, k)] + dot(v, col);
            r[(j, k)] -= tau_j * dot;
            axpy(-tau_j * dot, v, col);
        }
        tau.push(tau_j);
    }
}

/// Applies the panel's block reflector Qᵀ = I − V Tᵀ Vᵀ to the columns right of it: rows
/// c..c + w of R (V's identity part) and all of B.
fn update_right_of_panel(
    mut r: MatMut<'_, f64>,
    b: MatMut<'_, f64>,
    c: usize,
    w: usize,
    s: &mut FoldScratch,
) {
    let q = r.ncols();
    let rest = q - c - w;
    let (left, mut right) = b.split_at_col_mut(c + w);
    let v = left.rb().subcols(c, w);
    // T (forward, column-wise): T[..j, j] = −τⱼ T[..j, ..j] Vᵀ[..j] vⱼ; the identity
    // parts of distinct reflectors are orthogonal, so VᵀV = V_BᵀV_B + I.
    s.gram.resize_with(w, w, |_, _| 0.0);
    matmul(
        s.gram.as_mut(),
        Accum::Replace,
        v.transpose(),
        v,
        1.0,
        Par::Seq,
    );
    s.t.resize_with(w, w, |_, _| 0.0);
    for j in 0..w {
        for i in 0..w {
            s.t[(i, j)] = 0.0;
        }
        s.t[(j, j)] = s.tau[j];
        for i in 0..j {
            let sum: f64 = (i..j).map(|l| s.t[(i, l)] * s.gram[(l, j)]).sum();
            s.t[(i, j)] = -s.tau[j] * sum;
        }
    }
    s.w.resize_with(w, rest, |_, _| 0.0);
    s.w.copy_from(r.rb().submatrix(c, c + w, w, rest));
    matmul(
        s.w.as_mut(),
        Accum::Add,
        v.transpose(),
        right.rb(),
        1.0,
        Par::Seq,
    );
    s.tw.resize_with(w, rest, |_, _| 0.0);
    matmul(
        s.tw.as_mut(),
        Accum::Replace,
        s.t.transpose(),
        s.w.as_ref(),
        1.0,
        Par::Seq,
    );
    let mut r_rows = r.rb_mut().submatrix_mut(c, c + w, w, rest);
    for j in 0..rest {
        for i in 0..w {
            r_rows[(i, j)] -= s.tw[(i, j)];
        }
    }
    matmul(right.rb_mut(), Accum::Add, v, s.tw.as_ref(), -1.0, Par::Seq);
}

/// ‖x‖₂: the plain sum of squares, or faer's scaled norm where that over- or underflows.
#[inline(always)]
fn norm(x: &[f64]) -> f64 {
    let ss = dot(x, x);
    if ss.is_finite() && ss > f64::MIN_POSITIVE / f64::EPSILON {
        ss.sqrt()
    } else {
        faer::ColRef::from_slice(x).norm_l2()
    }
}

/// y += a x.
#[inline(always)]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    y.iter_mut().zip(x).for_each(|(yi, xi)| *yi += a * xi);
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::qr::no_pivoting::factor::{qr_in_place, qr_in_place_scratch};

    /// Deterministic values in [−0.5, 0.5).
    fn values(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// R of [R0; B] by faer's general Householder QR of the stacked matrix, diagonal
    /// made non-negative.
    fn reference(r0: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
        let (q, n) = (r0.ncols(), b.nrows());
        let mut a = Mat::from_fn(
            q + n,
            q,
            |i, j| if i < q { r0[(i, j)] } else { b[(i - q, j)] },
        );
        let mut h = Mat::zeros(1, q);
        let scratch = qr_in_place_scratch::<f64>(q + n, q, 1, Par::Seq, Default::default());
        let mut mem = MemBuffer::new(scratch);
        let stack = MemStack::new(&mut mem);
        qr_in_place(a.as_mut(), h.as_mut(), Par::Seq, stack, Default::default());
        Mat::from_fn(q, q, |i, j| {
            if j < i {
                0.0
            } else {
                a[(i, j)] * a[(i, i)].signum()
            }
        })
    }

    /// Both factors are backward stable, so they agree to a few ulps of ‖A‖ times the
    /// conditioning of the leading columns; these designs are well conditioned (random
    /// entries, R0 with a dominant diagonal), 1e-12 relative leaves a margin of ~100.
    #[test]
    fn folded_factor_equals_the_qr_of_the_stack() {
        for (q, n, seed) in [
            (147, 1024, 1),
            (44, 1024, 2),
            (13, 5, 3),
            (9, 0, 4),
            (20, 20, 5),
            (1, 7, 6),
        ] {
            let mut rnd = values(seed);
            let r0 = Mat::from_fn(q, q, |i, j| match j.cmp(&i) {
                std::cmp::Ordering::Less => 0.0,
                std::cmp::Ordering::Equal => 3.0 + rnd(),
                std::cmp::Ordering::Greater => rnd(),
            });
            let b = Mat::from_fn(n, q, |_, _| rnd());
            let expected = reference(&r0, &b);
            let mut r = r0.clone();
            let mut work = b.clone();
            fold_rows(r.as_mut(), work.as_mut(), &mut FoldScratch::new());
            let scale = expected.norm_max();
            for j in 0..q {
                for i in 0..=j {
                    let d = (r[(i, j)] - expected[(i, j)]).abs();
                    assert!(d <= 1e-12 * scale, "q {q} n {n}: R[{i},{j}] off by {d:e}");
                }
                assert!(r[(j, j)] >= 0.0);
            }
        }
    }

    /// The AVX2 code of [`crate::util::vectorized`] and the baseline code give the same
    /// bits: no fused multiply-adds, the same order of operations (the reports' identity
    /// across machines with and without AVX2 rests on it).
    #[test]
    fn vector_and_baseline_code_fold_to_the_same_bits() {
        let (q, n) = (45, 300);
        let mut rnd = values(7);
        let r0 = Mat::from_fn(q, q, |i, j| match j.cmp(&i) {
            std::cmp::Ordering::Less => 0.0,
            std::cmp::Ordering::Equal => 2.0 + rnd(),
            std::cmp::Ordering::Greater => rnd(),
        });
        let b = Mat::from_fn(n, q, |_, _| rnd());
        let fold = |baseline: bool| {
            let (mut r, mut work, mut s) = (r0.clone(), b.clone(), FoldScratch::new());
            let op = FoldPanels {
                r: r.as_mut(),
                b: work.as_mut(),
                s: &mut s,
            };
            if baseline {
                pulp::WithSimd::with_simd(op, pulp::Scalar);
            } else {
                crate::util::vectorized(op);
            }
            (r, work)
        };
        let (vector, baseline) = (fold(false), fold(true));
        for j in 0..q {
            for i in 0..q {
                assert_eq!(
                    vector.0[(i, j)].to_bits(),
                    baseline.0[(i, j)].to_bits(),
                    "R[{i},{j}]"
                );
            }
            for i in 0..n {
                assert_eq!(
                    vector.1[(i, j)].to_bits(),
                    baseline.1[(i, j)].to_bits(),
                    "V[{i},{j}]"
                );
            }
        }
    }

    /// A zero R gives the QR of B alone; a zero column (rank deficiency) and columns of
    /// 1e200 (squares overflow) and 1e-200 (squares underflow) give the exact norms.
    #[test]
    fn degenerate_and_extreme_columns_keep_their_norms() {
        let n = 30;
        let b = Mat::from_fn(n, 3, |i, j| match j {
            0 => 1e200 * (1.0 + i as f64),
            1 => 0.0,
            _ => 1e-200 * (1.0 + i as f64),
        });
        let mut r = Mat::<f64>::zeros(3, 3);
        let mut work = b.clone();
        fold_rows(r.as_mut(), work.as_mut(), &mut FoldScratch::new());
        let sum_sq: f64 = (1..=n).map(|k| (k * k) as f64).sum();
        let expected = sum_sq.sqrt();
        assert!((r[(0, 0)] / 1e200 - expected).abs() <= 1e-14 * expected);
        assert_eq!((r[(1, 1)], r[(1, 2)]), (0.0, 0.0));
        // Column 2 is parallel to column 0: nothing left after its projection.
        assert!((r[(0, 2)] / 1e-200 - expected).abs() <= 1e-14 * expected);
        assert!(r[(2, 2)].abs() <= 1e-14 * 1e-200 * expected);
    }

    /// A column whose remainder below R is subnormal (8e-315, the residue met when the
    /// time units of a sweep merged two-sample accumulators) is taken as reduced: R stays
    /// finite (before, 1/(α − β) overflowed and R's later columns became NaN).
    #[test]
    fn a_subnormal_remainder_leaves_the_factor_finite() {
        let mut r = Mat::from_fn(3, 3, |i, j| if i == 0 { 1.0 + j as f64 } else { 0.0 });
        let mut b = Mat::from_fn(1, 3, |_, j| [0.0, 8e-315, 1.0][j]);
        fold_rows(r.as_mut(), b.as_mut(), &mut FoldScratch::new());
        for i in 0..3 {
            for j in 0..3 {
                assert!(r[(i, j)].is_finite(), "R[{i},{j}] = {}", r[(i, j)]);
            }
        }
        // Row 0 unchanged; the 1.0 in column 2 is folded in whole.
        assert_eq!((r[(0, 0)], r[(0, 1)], r[(0, 2)]), (1.0, 2.0, 3.0));
        assert!((r[(1, 2)].abs() + r[(2, 2)].abs() - 1.0).abs() < 1e-15);
    }
}
