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

/// Whether a solve computes the singular values of its design.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SingularValues {
    /// Always: the condition number is reported.
    Always,
    /// Only when the bound κ ≤ ‖R‖_F ‖R⁻¹‖_F (R⁻¹ is computed anyway) leaves the rank in
    /// doubt, i.e. exceeds 10⁻³/`rank_tol`: below that the SVD could only find full
    /// rank, so the estimates are those of [`SingularValues::Always`] bit for bit and
    /// only the condition number is missing (NaN). For refits whose conditioning
    /// nobody reads (cross-validation folds, diagnosis trials); the SVD is ~¼ of them.
    WhenRankInDoubt,
}

/// Conditioning of an equilibrated design (every column scaled to unit norm).
#[derive(Debug, Clone)]
pub(crate) struct Conditioning {
    /// Singular values, largest first; empty when [`SingularValues::WhenRankInDoubt`]
    /// skipped them (the design has columns but no singular values).
    pub singular_values: Vec<f64>,
    /// Right singular vectors, `vectors[i]` belongs to `singular_values[i]` (empty in the
    /// conditioning of a successful [`solve`]: only a rank-deficient design needs them).
    pub vectors: Vec<Vec<f64>>,
    /// Variance-inflation factors (uncentred: diagonal of (CᵀC)⁻¹ for unit-norm columns);
    /// infinite for a rank-deficient design.
    pub vif: Vec<f64>,
}

impl Conditioning {
    /// σ_max / σ_min (infinite when σ_min = 0; NaN when the singular values were
    /// skipped).
    pub fn condition_number(&self) -> f64 {
        if self.singular_values.is_empty() && !self.vif.is_empty() {
            return f64::NAN;
        }
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
/// X has σ_min ≤ `rank_tol` σ_max. `singular_values` says whether the conditioning
/// reports them when they decide nothing.
pub(crate) fn solve(
    x: &Mat<f64>,
    z: &[f64],
    rank_tol: f64,
    singular_values: SingularValues,
) -> Result<LeastSquares, RankDeficient> {
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
    let vif = variance_inflation(&rinv);
    let skip = singular_values == SingularValues::WhenRankInDoubt
        && proven_full_rank(&r11, &vif, rank_tol);
    let conditioning = if skip {
        Conditioning {
            singular_values: Vec::new(),
            vectors: Vec::new(),
            vif,
        }
    } else {
        conditioning_with(&r11, false, vif)
    };
    if !conditioning.weak_directions(rank_tol).is_empty() {
        // The singular vectors name the aliased columns: worth their cost only here. The
        // values stay those the rank was decided on, so the weak directions are the ones
        // found (a second SVD may round σ_min to the other side of the tolerance).
        let Conditioning {
            singular_values,
            vif,
            ..
        } = conditioning;
        let mut deficient = conditioning_with(&r11, true, vif);
        deficient.singular_values = singular_values;
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

/// Whether ‖R‖_F ‖R⁻¹‖_F ≥ σ_max/σ_min (from ‖R⁻¹‖²_F = Σ `vif`) proves σ_min/σ_max
/// ≥ 10³ `rank_tol`: then a computed SVD, accurate to ~kε σ_max, cannot put σ_min at or
/// below `rank_tol` σ_max. False for NaN (the SVD decides).
fn proven_full_rank(r11: &Mat<f64>, vif: &[f64], rank_tol: f64) -> bool {
    let k = r11.ncols();
    let r_norm2: f64 = (0..k)
        .flat_map(|j| (0..=j).map(move |i| (i, j)))
        .map(|(i, j)| r11[(i, j)].powi(2))
        .sum();
    let bound = (r_norm2 * vif.iter().sum::<f64>()).sqrt();
    bound * rank_tol < 1e-3
}

/// Uncentred VIFs of an equilibrated design from `rinv` = R11⁻¹: the row sums of squares
/// of R11⁻¹ (the diagonal of (CᵀC)⁻¹).
fn variance_inflation(rinv: &Mat<f64>) -> Vec<f64> {
    let k = rinv.ncols();
    (0..k)
        .map(|i| (i..k).map(|l| rinv[(i, l)].powi(2)).sum())
        .collect()
}

/// Singular values, right singular vectors and VIFs of an equilibrated triangular factor.
pub(crate) fn conditioning_of(r11: &Mat<f64>) -> Conditioning {
    conditioning_with(r11, true, variance_inflation(&upper_inverse(r11)))
}

/// [`conditioning_of`] with the VIFs `vif` of R11 (infinite instead when σ_min = 0), and
/// the singular vectors only when `with_vectors` (else `vectors` is empty: the solve of
/// a design of full rank needs its singular values and VIFs only).
fn conditioning_with(r11: &Mat<f64>, with_vectors: bool, vif: Vec<f64>) -> Conditioning {
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
        vif
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
    thread_local! {
        static SCRATCH: std::cell::RefCell<FoldScratch> =
            const { std::cell::RefCell::new(FoldScratch::new()) };
    }
    let n = a.ncols();
    let mut r = Mat::zeros(n, n);
    SCRATCH.with_borrow_mut(|s| fold_rows(r.as_mut(), a.as_mut(), s));
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
    let mut x = b.to_vec();
    back_substitute_in_place(u, &mut x);
    x
}

/// Overwrites b with x solving U x = b for upper-triangular U.
fn back_substitute_in_place(u: &Mat<f64>, x: &mut [f64]) {
    let k = x.len();
    for i in (0..k).rev() {
        let s: f64 = ((i + 1)..k).map(|j| u[(i, j)] * x[j]).sum();
        x[i] = (x[i] - s) / u[(i, i)];
    }
}

/// U⁻¹ for upper-triangular U (upper triangular), column j solving U x = eⱼ.
fn upper_inverse(u: &Mat<f64>) -> Mat<f64> {
    let k = u.ncols();
    let mut inv = Mat::<f64>::zeros(k, k);
    for j in 0..k {
        let col = inv.col_as_slice_mut(j);
        col[j] = 1.0;
        back_substitute_in_place(u, col);
    }
    inv
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `rows` × 4 design whose last column is the first plus `eps` times a fourth
    /// independent direction (condition number ~1/`eps`), and a target.
    fn design(rows: usize, eps: f64) -> (Mat<f64>, Vec<f64>) {
        let t = |i: usize| i as f64 / rows as f64;
        let x = Mat::from_fn(rows, 4, |i, j| {
            let s = t(i);
            match j {
                0 => 1.0 + s,
                1 => (7.0 * s).sin(),
                2 => s * s,
                _ => 1.0 + s + eps * (13.0 * s).cos(),
            }
        });
        let z = (0..rows).map(|i| 2.0 - t(i) + (3.0 * t(i)).cos()).collect();
        (x, z)
    }

    #[test]
    fn skipping_the_singular_values_of_a_full_rank_design_changes_no_estimate() {
        let (x, z) = design(200, 0.5);
        let all = solve(&x, &z, 1e-10, SingularValues::Always).unwrap();
        let lean = solve(&x, &z, 1e-10, SingularValues::WhenRankInDoubt).unwrap();
        assert_eq!(lean.theta, all.theta);
        assert_eq!(lean.sse.to_bits(), all.sse.to_bits());
        assert_eq!(lean.xtx_inv, all.xtx_inv);
        assert_eq!(lean.conditioning.vif, all.conditioning.vif);
        assert!(lean.conditioning.singular_values.is_empty());
        assert!(lean.conditioning.condition_number().is_nan());
        let kappa = all.conditioning.condition_number();
        assert!(kappa.is_finite() && kappa > 1.0, "κ = {kappa}");
    }

    #[test]
    fn a_design_near_the_rank_tolerance_still_gets_its_svd() {
        // κ ~ 1e9: below 1/rank_tol = 1e10, but above the bound's 1e7 margin, so the
        // SVD decides (and reports) as it always does.
        let (x, z) = design(200, 1e-9);
        let all = solve(&x, &z, 1e-10, SingularValues::Always).unwrap();
        let lean = solve(&x, &z, 1e-10, SingularValues::WhenRankInDoubt).unwrap();
        assert_eq!(
            lean.conditioning.singular_values,
            all.conditioning.singular_values
        );
        assert!(all.conditioning.condition_number() > 1e7);
        // Past the tolerance both refuse with the same weak direction.
        let (x, z) = design(200, 1e-13);
        let a = solve(&x, &z, 1e-10, SingularValues::Always).unwrap_err();
        let b = solve(&x, &z, 1e-10, SingularValues::WhenRankInDoubt).unwrap_err();
        assert_eq!(a.conditioning.worst(), b.conditioning.worst());
        assert_eq!(a.conditioning.involved(1e-10), vec![0, 3]);
        assert_eq!(b.conditioning.involved(1e-10), vec![0, 3]);
    }
}
