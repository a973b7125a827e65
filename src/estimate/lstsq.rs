//! Small dense least squares by equilibrated Householder QR, with the rank and
//! conditioning information the identifiability report needs.
//!
//! Every estimator of this module works on a compressed design: rows of the accumulated
//! factor R (m ≲ 60 rows), never on the N samples, so these problems are tiny.
//!
//! They run on the calling thread (`Par::Seq`): faer's convenience `Mat::qr` and
//! `Mat::svd` take its global parallelism, a rayon pool on every core, whose idle workers
//! spin between the thousands of small solves of a diagnosis (2–4 CPU-s per fit, taken
//! from the parse workers), ignore `--threads`, and round differently with the core count.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::svd::{ComputeSvdVectors, svd, svd_scratch};
use faer::{Mat, Par};

use crate::stats::{FoldScratch, fold_rows};

/// Solution of min ‖X θ − z‖ for a small dense X of full column rank.
#[derive(Debug, Clone)]
pub(crate) struct LeastSquares {
    /// θ̂ in the units of the original columns.
    pub theta: Vec<f64>,
    /// Residual sum of squares ‖X θ̂ − z‖².
    pub sse: f64,
    /// (XᵀX)⁻¹, k × k row-major, in the units of the original columns.
    pub xtx_inv: Vec<f64>,
    /// Conditioning of the equilibrated X (unit-norm columns).
    pub conditioning: Conditioning,
}

/// Conditioning of an equilibrated design (every column scaled to unit norm).
#[derive(Debug, Clone)]
pub(crate) struct Conditioning {
    /// Singular values, largest first.
    pub singular_values: Vec<f64>,
    /// Right singular vectors, `vectors[i]` belongs to `singular_values[i]` (empty in the
    /// conditioning of a successful [`solve`]: only a rank-deficient design needs them).
    pub vectors: Vec<Vec<f64>>,
    /// Variance-inflation factors (uncentred: diagonal of (CᵀC)⁻¹ for unit-norm columns);
    /// infinite for a rank-deficient design.
    pub vif: Vec<f64>,
}

impl Conditioning {
    /// σ_max / σ_min (infinite when σ_min = 0).
    pub fn condition_number(&self) -> f64 {
        let max = self.singular_values.first().copied().unwrap_or(0.0);
        let min = self.singular_values.last().copied().unwrap_or(0.0);
        if min > 0.0 { max / min } else { f64::INFINITY }
    }

    /// Indices whose singular value is below `rank_tol · σ_max`, weakest first.
    pub fn weak_directions(&self, rank_tol: f64) -> Vec<usize> {
        let max = self.singular_values.first().copied().unwrap_or(0.0);
        (0..self.singular_values.len())
            .rev()
            .filter(|&i| {
                self.singular_values[i].partial_cmp(&(rank_tol * max))
                    != Some(std::cmp::Ordering::Greater)
            })
            .collect()
    }

    /// Columns taking part in the weak directions: |v_j| ≥ 0.1 in any of them.
    pub fn involved(&self, rank_tol: f64) -> Vec<usize> {
        let mut out: Vec<usize> = Vec::new();
        for d in self.weak_directions(rank_tol) {
            for (j, v) in self.vectors[d].iter().enumerate() {
                if v.abs() >= 0.1 && !out.contains(&j) {
                    out.push(j);
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// The column with the largest weight in the weakest direction.
    pub fn worst(&self) -> Option<usize> {
        let v = self.vectors.last()?;
        (0..v.len()).max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
    }
}

/// Rank deficiency found while solving (σ_min/σ_max below the tolerance).
#[derive(Debug, Clone)]
pub(crate) struct RankDeficient {
    pub conditioning: Conditioning,
}

/// Solves min ‖X θ − z‖ for `x` (rows × k) and `z` (rows), equilibrating the columns of
/// X to unit norm before a Householder QR of [X D⁻¹ | z]. Fails when the equilibrated
/// X has σ_min ≤ `rank_tol` σ_max.
pub(crate) fn solve(x: &Mat<f64>, z: &[f64], rank_tol: f64) -> Result<LeastSquares, RankDeficient> {
    let (rows, k) = (x.nrows(), x.ncols());
    let scale: Vec<f64> = (0..k)
        .map(|j| {
            let n = x.col(j).norm_l2();
            if n > 0.0 { n } else { 1.0 }
        })
        .collect();
    let mut a = Mat::<f64>::zeros(rows.max(k + 1), k + 1);
    for j in 0..k {
        for i in 0..rows {
            a[(i, j)] = x[(i, j)] / scale[j];
        }
    }
    for (i, &zi) in z.iter().enumerate() {
        a[(i, k)] = zi;
    }
    let r = triangular_factor(a);
    let r11 = Mat::from_fn(k, k, |i, j| if j >= i { r[(i, j)] } else { 0.0 });
    let rinv = upper_inverse(&r11);
    let conditioning = conditioning_with(&r11, false, &rinv);
    if !conditioning.weak_directions(rank_tol).is_empty() {
        // The singular vectors name the aliased columns: worth their cost only here. The
        // values stay those the rank was decided on, so the weak directions are the ones
        // found (a second SVD may round σ_min to the other side of the tolerance).
        let mut deficient = conditioning_with(&r11, true, &rinv);
        deficient.singular_values = conditioning.singular_values;
        return Err(RankDeficient {
            conditioning: deficient,
        });
    }
    let rhs: Vec<f64> = (0..k).map(|i| r[(i, k)]).collect();
    let theta_s = back_substitute(&r11, &rhs);
    let theta = theta_s.iter().zip(&scale).map(|(t, d)| t / d).collect();
    let sse = r[(k, k)].powi(2);
    // Symmetric: entry (j, i) is the same sum of the same products.
    let mut xtx_inv = vec![0.0; k * k];
    for i in 0..k {
        for j in i..k {
            let s: f64 = (j..k).map(|l| rinv[(i, l)] * rinv[(j, l)]).sum();
            xtx_inv[i * k + j] = s / (scale[i] * scale[j]);
            xtx_inv[j * k + i] = s / (scale[j] * scale[i]);
        }
    }
    Ok(LeastSquares {
        theta,
        sse,
        xtx_inv,
        conditioning,
    })
}

/// Singular values, right singular vectors and VIFs of an equilibrated triangular factor.
pub(crate) fn conditioning_of(r11: &Mat<f64>) -> Conditioning {
    conditioning_with(r11, true, &upper_inverse(r11))
}

/// [`conditioning_of`] with `rinv` = R11⁻¹, and the singular vectors only when
/// `with_vectors` (else `vectors` is empty: the solve of a design of full rank needs its
/// singular values and VIFs only).
fn conditioning_with(r11: &Mat<f64>, with_vectors: bool, rinv: &Mat<f64>) -> Conditioning {
    let k = r11.ncols();
    let (singular_values, vectors) = match singular_value_decomposition(r11, with_vectors) {
        Ok((s, v)) => {
            let mut idx: Vec<usize> = (0..k).collect();
            idx.sort_by(|&a, &b| s[b].total_cmp(&s[a]));
            let vectors = match v {
                Some(v) => idx
                    .iter()
                    .map(|&i| (0..k).map(|j| v[(j, i)]).collect())
                    .collect(),
                None => Vec::new(),
            };
            (idx.iter().map(|&i| s[i].abs()).collect(), vectors)
        }
        // SVD did not converge: report the design as unusable.
        Err(_) => (vec![0.0; k], vec![vec![1.0 / (k as f64).sqrt(); k]; k]),
    };
    let singular = singular_values.last().is_none_or(|&s| s == 0.0);
    let vif = if singular {
        vec![f64::INFINITY; k]
    } else {
        (0..k)
            .map(|i| (i..k).map(|l| rinv[(i, l)].powi(2)).sum())
            .collect()
    };
    Conditioning {
        singular_values,
        vectors,
        vif,
    }
}

/// The upper-triangular factor R (non-negative diagonal) of a Householder QR of `a`
/// (rows ≥ columns), on this thread.
fn triangular_factor(mut a: Mat<f64>) -> Mat<f64> {
    let n = a.ncols();
    let mut r = Mat::zeros(n, n);
    fold_rows(r.as_mut(), a.as_mut(), &mut FoldScratch::new());
    r
}

/// Singular values (unsorted) and, when asked for, right singular vectors (columns) of
/// square `r`, on this thread.
fn singular_value_decomposition(
    r: &Mat<f64>,
    with_vectors: bool,
) -> Result<(Vec<f64>, Option<Mat<f64>>), faer::linalg::svd::SvdError> {
    let k = r.ncols();
    let mut s = Diag::zeros(k);
    let mut v = with_vectors.then(|| Mat::zeros(k, k));
    let right = if with_vectors {
        ComputeSvdVectors::Full
    } else {
        ComputeSvdVectors::No
    };
    let scratch = svd_scratch::<f64>(
        k,
        k,
        ComputeSvdVectors::No,
        right,
        Par::Seq,
        Default::default(),
    );
    svd(
        r.as_ref(),
        s.as_mut(),
        None,
        v.as_mut().map(|v| v.as_mut()),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )?;
    Ok(((0..k).map(|i| s[i]).collect(), v))
}

/// x solving U x = b for upper-triangular U.
fn back_substitute(u: &Mat<f64>, b: &[f64]) -> Vec<f64> {
    let k = b.len();
    let mut x = b.to_vec();
    for i in (0..k).rev() {
        let s: f64 = ((i + 1)..k).map(|j| u[(i, j)] * x[j]).sum();
        x[i] = (x[i] - s) / u[(i, i)];
    }
    x
}

/// U⁻¹ for upper-triangular U (upper triangular).
fn upper_inverse(u: &Mat<f64>) -> Mat<f64> {
    let k = u.ncols();
    let mut inv = Mat::<f64>::zeros(k, k);
    for j in 0..k {
        let mut e = vec![0.0; k];
        e[j] = 1.0;
        let col = back_substitute(u, &e);
        for i in 0..k {
            inv[(i, j)] = col[i];
        }
    }
    inv
}
