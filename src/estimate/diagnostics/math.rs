//! Linear-algebra helpers of the residual pass: the lag products of a block of rows
//! (one matrix product), the diagonal of B M B, and W Γ W for 6 × 6 matrices.

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

/// Adds S_k = Σ_{t+k<n} x_t x_{t+k}ᵀ, k = 0..=l (l < n), of the `n` row-major rows of
/// width `w` in `rows` to `dst` ((l+1) blocks of w × w, row-major).
///
/// All lags are one matrix product (faer): the rows t < n − l, transposed, times the
/// w × (l+1)w view whose row t is x_t, x_{t+1}, …, x_{t+l} side by side. In row-major
/// storage that row is the contiguous slice starting at x_t, so the view shares the
/// rows' memory (row stride w, overlapping rows) and nothing is copied. The last l rows'
/// lags, which run past the end, are added as outer products.
pub(super) fn add_lag_products(
    rows: &[f64],
    w: usize,
    n: usize,
    l: usize,
    dst: &mut [f64],
    scratch: &mut Vec<f64>,
) {
    if n == 0 {
        return;
    }
    let m = n - l;
    // The chunk's products S, w × (l+1)w column-major in `scratch`: S[i, c] at c w + i.
    let cols = (l + 1) * w;
    scratch.resize(w * cols, 0.0);
    let xt = MatRef::from_column_major_slice_with_stride(rows, w, m, w);
    let shifted = MatRef::from_row_major_slice_with_stride(rows, m, cols, w);
    let s = MatMut::from_column_major_slice_mut(&mut scratch[..w * cols], w, cols);
    matmul(s, Accum::Replace, xt, shifted, 1.0, Par::Seq);
    for t in m..n {
        let xs = &rows[t * w..(t + 1) * w];
        for k in 0..n - t {
            let xk = &rows[(t + k) * w..(t + k + 1) * w];
            for (j, &xj) in xk.iter().enumerate() {
                let column = &mut scratch[(k * w + j) * w..(k * w + j + 1) * w];
                column.iter_mut().zip(xs).for_each(|(d, &xi)| *d += xi * xj);
            }
        }
    }
    for (k, block) in dst.chunks_exact_mut(w * w).take(l + 1).enumerate() {
        for j in 0..w {
            let column = &scratch[(k * w + j) * w..(k * w + j + 1) * w];
            for (row, &v) in block.chunks_exact_mut(w).zip(column) {
                row[j] += v;
            }
        }
    }
}

/// (B M B)_dd = Σ_pq B_dp M_pq B_qd for k × k row-major B (symmetric) and M.
pub(super) fn quadratic_diagonal(b: &[f64], m: &[f64], k: usize, d: usize) -> f64 {
    let mut var = 0.0;
    for p in 0..k {
        for q in 0..k {
            var += b[d * k + p] * m[p * k + q] * b[q * k + d];
        }
    }
    var
}

/// W Γ W for 6 × 6 matrices.
pub(super) fn sandwich6(w: &[[f64; 6]; 6], g: &[[f64; 6]; 6]) -> [[f64; 6]; 6] {
    let mut wg = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            wg[i][j] = (0..6).map(|k| w[i][k] * g[k][j]).sum();
        }
    }
    let mut out = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            out[i][j] = (0..6).map(|k| wg[i][k] * w[k][j]).sum();
        }
    }
    out
}
