//! Multivariate multiple regression (seed Eq. 24): one θ over all six axes, weighted by
//! the inverse residual covariance R⁻¹ of the per-axis fits,
//! θ̂ = (Hᵀ(R⁻¹⊗I)H)⁻¹ Hᵀ(R⁻¹⊗I)Z.
//!
//! R ⊗ I_N is never formed. With R⁻¹ = L Lᵀ (L = C⁻ᵀ for the Cholesky factor C of R),
//! Hᵀ(R⁻¹⊗I)H = Σ_k (A C_k)ᵀ(A C_k) where A = [X | Z] is the augmented data and
//! C_k maps augmented column c of axis i to parameter `param(c)` with weight L\[i,k\]
//! (and output i to the right-hand side). AᵀA = RᵀR for the accumulated factor R, so the
//! same normal equations belong to the small stacked matrix [R C_0; …; R C_5]
//! (6m × (n_θ + 1)), solved by equilibrated Householder QR: Σ_ij R⁻¹_ij X_iᵀX_j and
//! Σ_ij R⁻¹_ij X_iᵀz_j are never formed either, which keeps QR-grade accuracy.

use faer::Mat;

use super::identifiability::{
    DesignTerms, ProblemConditioning, solve_identifiable, zero_column_cause,
};
use super::lstsq::{LeastSquares, SingularValues};
use super::{EstimateError, FitOptions};
use crate::model::{ModelStructure, ParamId};
use crate::stats::Accumulator;

/// How the six outputs were weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Weighting {
    /// Full R⁻¹, as Eq. 24.
    Full,
    /// R was numerically singular (e.g. exact data); only its diagonal was used.
    Diagonal,
}

/// Result of the weighted solve, before inference.
pub(crate) struct MmrSolution {
    pub ls: LeastSquares,
    /// The estimated parameters.
    pub params: Vec<ParamId>,
    pub conditioning: ProblemConditioning,
    pub weight: [[f64; 6]; 6],
    pub weighting: Weighting,
}

/// W = R⁻¹ and its factor L (W = L Lᵀ); falls back to the diagonal of R when R is not
/// numerically positive definite. `floor` bounds each variance from below.
pub(crate) fn weights(
    r: &[[f64; 6]; 6],
    floor: &[f64; 6],
) -> ([[f64; 6]; 6], [[f64; 6]; 6], Weighting) {
    let d: Vec<f64> = (0..6).map(|i| r[i][i].max(floor[i]).sqrt()).collect();
    let mut corr = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            corr[i][j] = if i == j { 1.0 } else { r[i][j] / (d[i] * d[j]) };
        }
    }
    let (c, weighting) = match cholesky(&corr) {
        Some(c) => (c, Weighting::Full),
        None => {
            let mut id = [[0.0; 6]; 6];
            (0..6).for_each(|i| id[i][i] = 1.0);
            (id, Weighting::Diagonal)
        }
    };
    // corr = C Cᵀ; R = D C Cᵀ D; R⁻¹ = D⁻¹ C⁻ᵀ C⁻¹ D⁻¹ = L Lᵀ with L = D⁻¹ C⁻ᵀ.
    let cinv = lower_inverse(&c);
    let mut l = [[0.0; 6]; 6];
    for i in 0..6 {
        for k in 0..6 {
            l[i][k] = cinv[k][i] / d[i];
        }
    }
    let mut w = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            w[i][j] = (0..6).map(|k| l[i][k] * l[j][k]).sum();
        }
    }
    (w, l, weighting)
}

/// Solves Eq. 24 for all parameters of `structure` with weights from `r`, computing the
/// singular values of the design as `singular_values` says.
pub(crate) fn solve(
    structure: &ModelStructure,
    acc: &Accumulator,
    r: &[[f64; 6]; 6],
    floor: &[f64; 6],
    options: &FitOptions,
    singular_values: SingularValues,
) -> Result<MmrSolution, EstimateError> {
    let (weight, l, weighting) = weights(r, floor);
    let np = structure.params.len();
    let m = acc.rows();
    let mut g = Mat::<f64>::zeros(6 * m, np);
    let mut rhs = vec![0.0; 6 * m];
    let mut r_col = vec![0.0; m];
    for k in 0..6 {
        for (c, col) in structure.columns.iter().enumerate() {
            let lik = l[col.axis as usize][k];
            if lik != 0.0 {
                acc.write_r_column(c, &mut r_col);
                for (i, &rv) in r_col.iter().enumerate() {
                    g[(k * m + i, col.param.index())] += lik * rv;
                }
            }
        }
        for (a, &axis) in crate::sample::Axis::ALL.iter().enumerate() {
            let lak = l[a][k];
            let zc = acc.output_index(axis);
            for (i, rv) in acc.r_column(zc).into_iter().enumerate() {
                rhs[k * m + i] += lak * rv;
            }
        }
    }
    let names: Vec<String> = structure.params.iter().map(|p| p.name.clone()).collect();
    let cause = |p: usize| {
        let cols: Vec<usize> = (0..structure.columns.len())
            .filter(|&c| structure.columns[c].param.index() == p)
            .collect();
        zero_column_cause(structure, acc, &cols)
    };
    let terms = DesignTerms::distinct(names, &cause);
    let (ls, params, conditioning) =
        solve_identifiable("MMR", &g, &rhs, &terms, options, singular_values)?;
    Ok(MmrSolution {
        ls,
        // The design's columns are the parameters.
        params: params.into_iter().map(ParamId::new).collect(),
        conditioning,
        weight,
        weighting,
    })
}

fn cholesky(a: &[[f64; 6]; 6]) -> Option<[[f64; 6]; 6]> {
    let mut c = [[0.0; 6]; 6];
    for j in 0..6 {
        let d = a[j][j] - (0..j).map(|k| c[j][k] * c[j][k]).sum::<f64>();
        // A correlation matrix with a pivot this small is singular to working accuracy.
        if d.is_nan() || d <= 1e-12 {
            return None;
        }
        c[j][j] = d.sqrt();
        for i in (j + 1)..6 {
            c[i][j] = (a[i][j] - (0..j).map(|k| c[i][k] * c[j][k]).sum::<f64>()) / c[j][j];
        }
    }
    Some(c)
}

#[allow(clippy::needless_range_loop)] // triangular index arithmetic reads clearest
fn lower_inverse(c: &[[f64; 6]; 6]) -> [[f64; 6]; 6] {
    let mut inv = [[0.0; 6]; 6];
    for j in 0..6 {
        for i in j..6 {
            let e = if i == j { 1.0 } else { 0.0 };
            let s: f64 = (j..i).map(|k| c[i][k] * inv[k][j]).sum();
            inv[i][j] = (e - s) / c[i][i];
        }
    }
    inv
}
