//! Residual diagnostics of the MMR model: a streaming, mergeable second pass.
//!
//! Per axis: a histogram with its fitted Gaussian and the linearity of ordered residuals
//! against the inverse normal CDF (seed Figure 3), and the residual autocorrelation up to
//! lag L. For the estimates: coloured-residual corrected standard errors after Morelli
//! (Morelli & Klein 2016, §5.2), generalised to the six-output weighted fit of Eq. 24:
//!
//! Cov(θ̂) = B⁻¹ [Σ_{k=−L}^{L} Σ_t Σ_ab H_{t,a}ᵀ (W Γ(k) W)_ab H_{t+k,b}] B⁻¹,
//!
//! with B = Hᵀ(R⁻¹⊗I)H, W = R⁻¹, and Γ(k)_ab = (1/N) Σ_t v_{t,a} v_{t+k,b} the residual
//! cross-correlation at lag k (the stationary R_vv of Morelli's formula). For white
//! residuals (Γ(k) = 0, k ≠ 0, Γ(0) = R) it reduces to B⁻¹. Lags beyond L are taken as
//! zero (rectangular window), so the pass costs O(N·L·p²) for p regressor columns
//! (computed per chunk as L matrix products): linear in N, never O(N²).
//!
//! The per-axis OLS estimates get Morelli's formula itself,
//! Cov(θ̂_i) = (X_iᵀX_i)⁻¹ [Σ_{k=−L}^{L} r_i(k) Σ_t x_t x_{t+k}ᵀ] (X_iᵀX_i)⁻¹, with r_i the
//! autocorrelation of that axis' OLS residuals.
//!
//! The pass keeps the lag products Σ_t x_t x_{t+k}ᵀ and Σ_t v_t v_{t+k}ᵀ and the first and
//! last L rows it saw, so two passes over consecutive segments merge exactly (the cross
//! terms across the seam are added at merge time). The regressors' lag products are kept
//! over the distinct column shapes, as the accumulator keeps its factor: a column that is
//! a constant multiple f of another (`u*dt` of F_x and `h*u*dt` of M_y) has lag products
//! f × those of the other, so quadrotor× needs 30 of its 38 columns (0.6× the flops).

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal};

use super::Fit;
use crate::model::{ModelStructure, Workspace};
use crate::sample::{Axis, SampleChunk};
use crate::stats::AccumulateError;

/// Options of the residual pass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DiagnosticOptions {
    /// Largest lag L (samples) of the autocorrelation and of the coloured-residual
    /// correction. Choose it past the lag where the residual autocorrelation dies out.
    pub max_lag: usize,
    /// Histogram bins per axis.
    pub bins: usize,
    /// Histogram range ± this many residual standard deviations (σ̂ from the fit);
    /// residuals outside are counted in under/overflow cells.
    pub range_sigmas: f64,
}

impl Default for DiagnosticOptions {
    fn default() -> Self {
        Self {
            max_lag: 10,
            bins: 60,
            range_sigmas: 6.0,
        }
    }
}

/// Histogram of one axis' residuals.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Histogram {
    /// Lower edge of the first bin, N or N m.
    pub lo: f64,
    /// Upper edge of the last bin, N or N m.
    pub hi: f64,
    /// Counts per equal-width bin.
    pub counts: Vec<u64>,
    /// Residuals below `lo`.
    pub below: u64,
    /// Residuals at or above `hi`.
    pub above: u64,
    /// Smallest residual.
    pub min: f64,
    /// Largest residual.
    pub max: f64,
}

impl Histogram {
    /// `(lower edge, upper edge, count)` of every cell in order, the underflow cell
    /// spanning min..lo and the overflow cell hi..max (N or N m).
    pub fn cells(&self) -> Vec<(f64, f64, u64)> {
        let width = (self.hi - self.lo) / self.counts.len().max(1) as f64;
        let mut cells = Vec::with_capacity(self.counts.len() + 2);
        cells.push((self.min, self.lo, self.below));
        cells.extend(self.counts.iter().enumerate().map(|(b, &c)| {
            let lo = self.lo + b as f64 * width;
            (lo, lo + width, c)
        }));
        cells.push((self.hi, self.max, self.above));
        cells
    }
}

/// Residual diagnostics of one axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisResiduals {
    /// Output axis.
    pub axis: Axis,
    /// Mean of the fitted Gaussian (residual mean), N or N m.
    pub mean: f64,
    /// Standard deviation of the fitted Gaussian, N or N m.
    pub std_dev: f64,
    /// Histogram.
    pub histogram: Histogram,
    /// Correlation of ordered residuals with Φ⁻¹((i − 3/8)/(N + 1/4)) (Blom positions);
    /// order statistics are placed uniformly within histogram bins, so the value is
    /// resolved to about the bin width.
    pub normal_probability_correlation: f64,
    /// Autocorrelation ρ(k) = Γ_aa(k)/Γ_aa(0), k = 0..=L.
    pub autocorrelation: Vec<f64>,
    /// ±1.96/√N: the 95 % band of ρ(k) for white residuals.
    pub white_band95: f64,
}

/// Standard error of one MMR estimate, white and coloured-residual corrected.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColouredStdError {
    /// Parameter name.
    pub name: String,
    /// σ(θ̂) assuming white residuals (from the fit).
    pub white: f64,
    /// σ(θ̂) corrected for coloured residuals (Morelli); NaN if the truncated estimate of
    /// the variance came out negative.
    pub coloured: f64,
}

/// Residual row width: the six MMR residuals, then the six per-axis OLS residuals.
const VW: usize = 12;

/// Result of the residual pass.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ResidualDiagnostics {
    /// Samples seen.
    pub samples: u64,
    /// Lag L used.
    pub max_lag: usize,
    /// Per axis, [`Axis`] order.
    pub axes: Vec<AxisResiduals>,
    /// Per estimated MMR parameter.
    pub std_errors: Vec<ColouredStdError>,
    /// Per axis ([`Axis`] order), per kept OLS term (named `param (label)`).
    pub ols_std_errors: Vec<Vec<ColouredStdError>>,
}

/// The per-axis OLS model the pass evaluates alongside the MMR.
#[derive(Debug, Clone)]
struct OlsModel {
    columns: Vec<usize>,
    xtx_inv: Vec<f64>,
    white: Vec<f64>,
    terms: Vec<String>,
}

/// Streaming second pass over the data with the MMR estimates of a [`Fit`].
#[derive(Debug, Clone)]
pub struct ResidualPass {
    structure: ModelStructure,
    /// p × 12: the coefficient of each regressor column in the MMR prediction of each
    /// axis (columns 0–5) and in the per-axis OLS predictions (columns 6–11).
    prediction: Mat<f64>,
    weight: [[f64; 6]; 6],
    covariance: Vec<f64>,
    param_index: Vec<usize>,
    names: Vec<String>,
    white: Vec<f64>,
    ols: Vec<OlsModel>,
    options: DiagnosticOptions,
    p: usize,
    /// For each structure column: its shape and the factor f with column = f × shape.
    shapes: Vec<(usize, f64)>,
    /// The structure column holding each shape's data.
    representatives: Vec<usize>,
    count: u64,
    /// (L+1) × q × q over the q column shapes u: Σ_t u_t u_{t+k}ᵀ.
    lag_xx: Vec<f64>,
    /// (L+1) × 12 × 12: Σ_t v_t v_{t+k}ᵀ over MMR and OLS residuals.
    lag_vv: Vec<f64>,
    /// A chunk's lag products before they are added ([`add_lag_products`]): reused.
    lag_scratch: Vec<f64>,
    head: Rows,
    tail: Rows,
    hist: Vec<Histogram>,
    sum: [f64; 6],
}

/// Row-major rows of regressor column shapes (width q) and residuals (width 12).
#[derive(Debug, Clone, Default)]
struct Rows {
    x: Vec<f64>,
    v: Vec<f64>,
}

impl Rows {
    fn len(&self) -> usize {
        self.v.len() / VW
    }
}

impl ResidualPass {
    /// A pass for the MMR model of `fit` (θ̂, R⁻¹, parameter covariance).
    pub fn new(structure: &ModelStructure, fit: &Fit, options: DiagnosticOptions) -> Self {
        let p = structure.columns.len();
        let (shapes, representatives) = crate::stats::column_shapes(&structure.columns);
        let q = representatives.len();
        let l = options.max_lag;
        let bins = options.bins.max(1);
        let hist = (0..6)
            .map(|a| {
                // The MMR residuals (shared parameters) can be wider than the per-axis
                // OLS residuals of R: take the larger spread.
                let s = fit.residual_covariance[a][a]
                    .sqrt()
                    .max(fit.metrics[a].rmse);
                let half = if s > 0.0 {
                    options.range_sigmas * s
                } else {
                    1.0
                };
                Histogram {
                    lo: -half,
                    hi: half,
                    counts: vec![0; bins],
                    below: 0,
                    above: 0,
                    min: f64::INFINITY,
                    max: f64::NEG_INFINITY,
                }
            })
            .collect();
        Self {
            structure: structure.clone(),
            prediction: prediction_coefficients(structure, fit),
            weight: fit.mmr.weight,
            covariance: fit.mmr.covariance.clone(),
            param_index: fit.mmr.param_index.clone(),
            names: fit.mmr.parameters.iter().map(|e| e.name.clone()).collect(),
            white: fit.mmr.parameters.iter().map(|e| e.std_error).collect(),
            ols: fit
                .axes
                .iter()
                .map(|a| OlsModel {
                    columns: a.ols.columns.clone(),
                    xtx_inv: a.ols.xtx_inv.clone(),
                    white: a.ols.std_error.clone(),
                    terms: a.ols.terms.clone(),
                })
                .collect(),
            options: DiagnosticOptions { bins, ..options },
            p,
            shapes,
            representatives,
            count: 0,
            lag_xx: vec![0.0; (l + 1) * q * q],
            lag_vv: vec![0.0; (l + 1) * VW * VW],
            lag_scratch: Vec::new(),
            head: Rows::default(),
            tail: Rows::default(),
            hist,
            sum: [0.0; 6],
        }
    }

    /// Folds in the next chunk of the stream (chunks must come in time order; use
    /// [`ResidualPass::merge`] for segments processed elsewhere).
    pub fn push(&mut self, chunk: &SampleChunk, ws: &mut Workspace) -> Result<(), AccumulateError> {
        self.structure.assemble(chunk, ws)?;
        let rows = self.rows(ws);
        let n = rows.len();
        if let Some(i) = rows.v.iter().position(|v| !v.is_finite()) {
            return Err(AccumulateError::NonFinite {
                field: format!("residual {}", Axis::ALL[i % VW % 6]),
                sample: self.count + (i / VW) as u64,
            });
        }
        for t in 0..n {
            for a in 0..6 {
                self.bin(a, rows.v[t * VW + a]);
            }
        }
        let tail = std::mem::take(&mut self.tail);
        self.add_cross(&tail, &rows);
        self.tail = tail;
        self.add_within(&rows);
        self.append(&rows, n as u64);
        Ok(())
    }

    /// Number of distinct column shapes q.
    fn q(&self) -> usize {
        self.representatives.len()
    }

    /// The assembled chunk's column shapes as rows, and its MMR and OLS residuals
    /// z − X θ̂ (one matrix product over all columns).
    fn rows(&self, ws: &Workspace) -> Rows {
        let n = ws.len();
        let p = self.p;
        let x = row_major(ws, p);
        let q = self.q();
        let mut rows = Rows {
            x: vec![0.0; n * q],
            v: vec![0.0; n * VW],
        };
        for (shapes, row) in rows.x.chunks_exact_mut(q).zip(x.chunks_exact(p)) {
            for (dst, &c) in shapes.iter_mut().zip(&self.representatives) {
                *dst = row[c];
            }
        }
        for (a, &axis) in Axis::ALL.iter().enumerate() {
            for (t, &z) in ws.output(axis).iter().enumerate() {
                rows.v[t * VW + a] = z;
                rows.v[t * VW + 6 + a] = z;
            }
        }
        if n > 0 {
            let x = MatRef::from_row_major_slice(&x, n, p);
            let v = MatMut::from_row_major_slice_mut(&mut rows.v, n, VW);
            matmul(v, Accum::Add, x, self.prediction.as_ref(), -1.0, Par::Seq);
        }
        rows
    }

    /// Merges `later`, the pass over the segment of the stream that directly follows
    /// this one's. The result equals one pass over both segments in order.
    pub fn merge(&mut self, later: &ResidualPass) {
        let tail = std::mem::take(&mut self.tail);
        self.add_cross(&tail, &later.head);
        self.tail = tail;
        self.lag_xx
            .iter_mut()
            .zip(&later.lag_xx)
            .for_each(|(a, b)| *a += b);
        self.lag_vv
            .iter_mut()
            .zip(&later.lag_vv)
            .for_each(|(a, b)| *a += b);
        for (h, o) in self.hist.iter_mut().zip(&later.hist) {
            h.counts
                .iter_mut()
                .zip(&o.counts)
                .for_each(|(a, b)| *a += b);
            h.below += o.below;
            h.above += o.above;
            h.min = h.min.min(o.min);
            h.max = h.max.max(o.max);
        }
        self.sum
            .iter_mut()
            .zip(&later.sum)
            .for_each(|(a, b)| *a += b);
        let head_rows = later.head.clone();
        let mut tail_rows = later.tail.clone();
        // `append` extends head/tail with `later`'s rows: head only needs its first rows,
        // tail its last rows.
        let l = self.options.max_lag;
        if self.head.len() < l {
            self.extend_head(&head_rows);
        }
        let mut joined = std::mem::take(&mut self.tail);
        joined.x.append(&mut tail_rows.x);
        joined.v.append(&mut tail_rows.v);
        self.tail = last_rows(joined, l, self.q());
        self.count += later.count;
    }

    /// The diagnostics of all samples seen.
    pub fn finish(&self) -> ResidualDiagnostics {
        let n = self.count as f64;
        let l = self.options.max_lag;
        let axes = (0..6)
            .map(|a| {
                let g0 = self.lag_vv[a * VW + a];
                let mean = self.sum[a] / n;
                let var = (g0 / n - mean * mean).max(0.0);
                AxisResiduals {
                    axis: Axis::ALL[a],
                    mean,
                    std_dev: var.sqrt(),
                    histogram: self.hist[a].clone(),
                    normal_probability_correlation: normal_probability_correlation(
                        &self.hist[a],
                        self.count,
                    ),
                    autocorrelation: (0..=l)
                        .map(|k| self.lag_vv[k * VW * VW + a * VW + a] / g0)
                        .collect(),
                    white_band95: 1.96 / n.sqrt(),
                }
            })
            .collect();
        ResidualDiagnostics {
            samples: self.count,
            max_lag: l,
            axes,
            std_errors: self.coloured_std_errors(),
            ols_std_errors: (0..6).map(|a| self.ols_coloured_std_errors(a)).collect(),
        }
    }

    /// Morelli's (XᵀX)⁻¹ [Σ_k r(k) (S_k + S_kᵀ [k > 0])] (XᵀX)⁻¹ for the OLS of axis `a`.
    fn ols_coloured_std_errors(&self, a: usize) -> Vec<ColouredStdError> {
        let model = &self.ols[a];
        let n = self.count as f64;
        let k = model.columns.len();
        let mut middle = vec![0.0; k * k];
        for lag in 0..=self.options.max_lag {
            let r = self.lag_vv[lag * VW * VW + (6 + a) * VW + 6 + a] / n;
            for (i, &ci) in model.columns.iter().enumerate() {
                for (j, &cj) in model.columns.iter().enumerate() {
                    let mut v = self.column_lag_product(lag, ci, cj);
                    if lag > 0 {
                        v += self.column_lag_product(lag, cj, ci);
                    }
                    middle[i * k + j] += r * v;
                }
            }
        }
        let b = &model.xtx_inv;
        (0..k)
            .map(|d| {
                let var = quadratic_diagonal(b, &middle, k, d);
                ColouredStdError {
                    name: model.terms[d].clone(),
                    white: model.white[d],
                    coloured: if var >= 0.0 { var.sqrt() } else { f64::NAN },
                }
            })
            .collect()
    }

    /// B⁻¹ [T_0 + Σ_{k≥1} (T_k + T_kᵀ)] B⁻¹ with T_k[p,q] = Σ_ij (W Γ(k) W)_{a(i) a(j)}
    /// S_k[i,j] over columns i, j of parameters p, q.
    fn coloured_std_errors(&self) -> Vec<ColouredStdError> {
        let n = self.count as f64;
        let np = self.param_index.len();
        let mut pos = vec![usize::MAX; self.structure.params.len()];
        for (j, &p) in self.param_index.iter().enumerate() {
            pos[p] = j;
        }
        let cols = &self.structure.columns;
        let mut middle = vec![0.0; np * np];
        for k in 0..=self.options.max_lag {
            let mut gamma = [[0.0; 6]; 6];
            for (a, row) in gamma.iter_mut().enumerate() {
                for (b, g) in row.iter_mut().enumerate() {
                    *g = self.lag_vv[k * VW * VW + a * VW + b] / n;
                }
            }
            let m = sandwich6(&self.weight, &gamma);
            for (i, ci) in cols.iter().enumerate() {
                let pi = pos[ci.param];
                if pi == usize::MAX {
                    continue;
                }
                for (j, cj) in cols.iter().enumerate() {
                    let pj = pos[cj.param];
                    if pj == usize::MAX {
                        continue;
                    }
                    let v =
                        m[ci.axis as usize][cj.axis as usize] * self.column_lag_product(k, i, j);
                    middle[pi * np + pj] += v;
                    if k > 0 {
                        middle[pj * np + pi] += v;
                    }
                }
            }
        }
        let b = &self.covariance;
        (0..np)
            .map(|d| {
                let var = quadratic_diagonal(b, &middle, np, d);
                ColouredStdError {
                    name: self.names[d].clone(),
                    white: self.white[d],
                    coloured: if var >= 0.0 { var.sqrt() } else { f64::NAN },
                }
            })
            .collect()
    }

    /// S_k\[i, j\] = Σ_t x_{t,i} x_{t+k,j} of structure columns i and j, from their
    /// shapes' lag products.
    fn column_lag_product(&self, k: usize, i: usize, j: usize) -> f64 {
        let q = self.q();
        let ((si, fi), (sj, fj)) = (self.shapes[i], self.shapes[j]);
        fi * fj * self.lag_xx[k * q * q + si * q + sj]
    }

    fn bin(&mut self, a: usize, v: f64) {
        self.sum[a] += v;
        let h = &mut self.hist[a];
        h.min = h.min.min(v);
        h.max = h.max.max(v);
        if v < h.lo {
            h.below += 1;
        } else if v >= h.hi {
            h.above += 1;
        } else {
            let bins = h.counts.len();
            let b = ((v - h.lo) / (h.hi - h.lo) * bins as f64) as usize;
            h.counts[b.min(bins - 1)] += 1;
        }
    }

    /// Lag products of rows within one segment, Σ_t x_t x_{t+k}ᵀ for every lag k ≤ L
    /// (and the same for the residuals).
    fn add_within(&mut self, rows: &Rows) {
        let n = rows.len();
        let l = self.options.max_lag.min(n.saturating_sub(1));
        let (q, scratch) = (self.q(), &mut self.lag_scratch);
        add_lag_products(&rows.x, q, n, l, &mut self.lag_xx, scratch);
        add_lag_products(&rows.v, VW, n, l, &mut self.lag_vv, scratch);
    }

    /// Lag products between the last rows of a segment (`earlier`) and the first rows of
    /// the segment that follows it (`later`).
    fn add_cross(&mut self, earlier: &Rows, later: &Rows) {
        let (ne, nl) = (earlier.len(), later.len());
        let l = self.options.max_lag;
        for j in 0..nl.min(l) {
            for i in 0..ne {
                let k = (ne - i) + j;
                if k <= l {
                    self.outer(k, earlier, i, later, j);
                }
            }
        }
    }

    /// S_k += u_s u_tᵀ and Γ-sum_k += v_s v_tᵀ.
    fn outer(&mut self, k: usize, a: &Rows, s: usize, b: &Rows, t: usize) {
        let q = self.q();
        let xs = &a.x[s * q..(s + 1) * q];
        let xt = &b.x[t * q..(t + 1) * q];
        let dst = &mut self.lag_xx[k * q * q..(k + 1) * q * q];
        for (row, &xi) in dst.chunks_exact_mut(q).zip(xs) {
            row.iter_mut().zip(xt).for_each(|(d, &xj)| *d += xi * xj);
        }
        let vs = &a.v[s * VW..(s + 1) * VW];
        let vt = &b.v[t * VW..(t + 1) * VW];
        let dst = &mut self.lag_vv[k * VW * VW..(k + 1) * VW * VW];
        for (row, &vi) in dst.chunks_exact_mut(VW).zip(vs) {
            row.iter_mut().zip(vt).for_each(|(d, &vj)| *d += vi * vj);
        }
    }

    fn append(&mut self, rows: &Rows, n: u64) {
        let l = self.options.max_lag;
        if self.head.len() < l {
            self.extend_head(rows);
        }
        let mut joined = std::mem::take(&mut self.tail);
        joined
            .x
            .extend_from_slice(&rows.x[rows.x.len() - rows.len().min(l) * self.q()..]);
        joined
            .v
            .extend_from_slice(&rows.v[rows.v.len() - rows.len().min(l) * VW..]);
        self.tail = last_rows(joined, l, self.q());
        self.count += n;
    }

    fn extend_head(&mut self, rows: &Rows) {
        let take = (self.options.max_lag - self.head.len()).min(rows.len());
        self.head.x.extend_from_slice(&rows.x[..take * self.q()]);
        self.head.v.extend_from_slice(&rows.v[..take * VW]);
    }
}

/// The p × 12 prediction coefficients of [`ResidualPass`]: θ̂ of each column's parameter
/// on its axis (MMR), and each axis' OLS estimates.
fn prediction_coefficients(structure: &ModelStructure, fit: &Fit) -> Mat<f64> {
    let mut m = Mat::zeros(structure.columns.len(), VW);
    for (c, col) in structure.columns.iter().enumerate() {
        m[(c, col.axis as usize)] = fit.mmr.theta[col.param];
    }
    for (a, axis) in fit.axes.iter().enumerate() {
        for (&c, &th) in axis.ols.columns.iter().zip(&axis.ols.theta) {
            m[(c, 6 + a)] = th;
        }
    }
    m
}

/// Adds S_k = Σ_{t+k<n} x_t x_{t+k}ᵀ, k = 0..=l (l < n), of the `n` row-major rows of
/// width `w` in `rows` to `dst` ((l+1) blocks of w × w, row-major).
///
/// All lags are one matrix product (faer): the rows t < n − l, transposed, times the
/// w × (l+1)w view whose row t is x_t, x_{t+1}, …, x_{t+l} side by side. In row-major
/// storage that row is the contiguous slice starting at x_t, so the view shares the
/// rows' memory (row stride w, overlapping rows) and nothing is copied. The last l rows'
/// lags, which run past the end, are added as outer products.
fn add_lag_products(
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
fn quadratic_diagonal(b: &[f64], m: &[f64], k: usize, d: usize) -> f64 {
    let mut var = 0.0;
    for p in 0..k {
        for q in 0..k {
            var += b[d * k + p] * m[p * k + q] * b[q * k + d];
        }
    }
    var
}

/// The first `w` columns of the chunk assembled in `ws` as row-major rows.
fn row_major(ws: &Workspace, w: usize) -> Vec<f64> {
    let n = ws.len();
    let mut rows = vec![0.0; n * w];
    // Transposed in blocks of samples, so the rows written stay in L1.
    const BLOCK: usize = 16;
    for t0 in (0..n).step_by(BLOCK) {
        let t1 = (t0 + BLOCK).min(n);
        for c in 0..w {
            for (t, &x) in (t0..t1).zip(&ws.column(c)[t0..t1]) {
                rows[t * w + c] = x;
            }
        }
    }
    rows
}

/// The last `l` rows of `rows`.
fn last_rows(rows: Rows, l: usize, q: usize) -> Rows {
    let n = rows.len();
    if n <= l {
        return rows;
    }
    Rows {
        x: rows.x[(n - l) * q..].to_vec(),
        v: rows.v[(n - l) * VW..].to_vec(),
    }
}

/// W Γ W for 6 × 6 matrices.
fn sandwich6(w: &[[f64; 6]; 6], g: &[[f64; 6]; 6]) -> [[f64; 6]; 6] {
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

/// Pearson correlation of ordered residuals with Blom normal scores, order statistics
/// spread uniformly within each histogram cell (under/overflow cells span min..lo and
/// hi..max).
fn normal_probability_correlation(h: &Histogram, count: u64) -> f64 {
    let n = count as f64;
    let mut sums = ScoreSums::default();
    let mut before = 0u64;
    for (lo, hi, c) in h.cells() {
        // The cell in pieces: ranks among the first or last EXACT_CELL, where the normal
        // scores are too curved for the integrals, and the ones between.
        let head = EXACT_CELL.saturating_sub(before).min(c);
        let tail = (count.saturating_sub(EXACT_CELL + before)).clamp(head, c);
        for (piece, (i0, i1)) in [(0, head), (head, tail), (tail, c)].into_iter().enumerate() {
            let m = i1 - i0;
            let at = |i: u64| lo + (hi - lo) * i as f64 / c as f64;
            let (a, b) = (at(i0), at(i1));
            if piece == 1 && m > EXACT_CELL {
                sums.add_integrated(a, b, m, before + i0, n);
            } else {
                sums.add_exact(a, b, m, before + i0, n);
            }
        }
        before += c;
    }
    sums.correlation(n)
}

/// Pieces of a cell of at most this many residuals, and the ranks this close to either
/// end, get their normal scores one by one; the rest by the integrals of the scores
/// over their span of plotting positions.
const EXACT_CELL: u64 = 64;

/// Σx, Σy, Σx², Σy², Σxy of residuals x and their Blom normal scores y.
#[derive(Default)]
struct ScoreSums {
    x: f64,
    y: f64,
    xx: f64,
    yy: f64,
    xy: f64,
}

impl ScoreSums {
    /// The cell's `c` residuals, spread uniformly over lo..hi, after `before` smaller
    /// ones: ranks before + 1 ..= before + c of `n`, scores y = Φ⁻¹((rank − 3/8)/(n + 1/4)).
    fn add_exact(&mut self, lo: f64, hi: f64, c: u64, before: u64, n: f64) {
        let normal = Normal::new(0.0, 1.0).expect("standard normal");
        for i in 0..c {
            let x = lo + (hi - lo) * (i as f64 + 0.5) / c as f64;
            let y = normal.inverse_cdf(((before + i + 1) as f64 - 0.375) / (n + 0.25));
            self.add(x, y);
        }
    }

    fn add(&mut self, x: f64, y: f64) {
        self.x += x;
        self.y += y;
        self.xx += x * x;
        self.yy += y * y;
        self.xy += x * y;
    }

    /// The same sums as [`ScoreSums::add_exact`], the scores' by the midpoint rule read
    /// backwards: the plotting positions p_i are spaced h = 1/(n + 1/4) apart, so
    /// Σ g(p_i) ≈ (1/h) ∫ g(p) dp over the cell's positions ± h/2, with closed forms in
    /// u = Φ⁻¹(p) (φ the normal density): ∫ Φ⁻¹ dp = −φ(u), ∫ (Φ⁻¹)² dp = p − uφ(u),
    /// ∫ p Φ⁻¹ dp = −pφ(u) + Φ(u√2)/(2√π). The residual x is linear in p over the cell.
    /// With the Euler–Maclaurin correction of the cell's ends the rule's error is
    /// O(h⁴ g⁗) per score (test below).
    fn add_integrated(&mut self, lo: f64, hi: f64, c: u64, before: u64, n: f64) {
        let normal = Normal::new(0.0, 1.0).expect("standard normal");
        let scale = n + 0.25;
        let (pa, pb) = (
            (before as f64 + 0.125) / scale,
            ((before + c) as f64 + 0.125) / scale,
        );
        let (ua, ub) = (normal.inverse_cdf(pa), normal.inverse_cdf(pb));
        let density = |u: f64| (-0.5 * u * u).exp() / (2.0 * std::f64::consts::PI).sqrt();
        let (fa, fb) = (density(ua), density(ub));
        let second = |p: f64, u: f64, f: f64| {
            -p * f + normal.cdf(u * std::f64::consts::SQRT_2) / (2.0 * std::f64::consts::PI.sqrt())
        };
        let y1 = fa - fb;
        let y2 = (pb - pa) - (ub * fb - ua * fa);
        let yp = second(pb, ub, fb) - second(pa, ua, fa);
        // x(p) = mid + slope (p − pm) over the cell, pm its middle position.
        let slope = (hi - lo) / (pb - pa);
        let pm = 0.5 * (pa + pb);
        let c = c as f64;
        let mid = 0.5 * (lo + hi);
        self.x += c * mid;
        self.xx += c * mid * mid + (hi - lo).powi(2) * (c * c - 1.0) / (12.0 * c);
        // Euler–Maclaurin's next term, −(h/24)[g′] over the cell, with (Φ⁻¹)′ = 1/φ(u).
        let edge = 1.0 / (24.0 * scale);
        self.y += scale * y1 - edge * (1.0 / fb - 1.0 / fa);
        self.yy += scale * y2 - edge * 2.0 * (ub / fb - ua / fa);
        self.xy += scale * (mid * y1 + slope * (yp - pm * y1))
            - edge * (slope * (ub - ua) + hi / fb - lo / fa);
    }

    fn correlation(&self, n: f64) -> f64 {
        let cov = self.xy - self.x * self.y / n;
        cov / ((self.xx - self.x * self.x / n) * (self.yy - self.y * self.y / n)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The regressors' lag products kept over column shapes give every column pair's
    /// Σ_t x_{t,i} x_{t+k,j}, seams between chunks and segments included: against the
    /// direct sum over the assembled columns of a quad× sweep (38 columns, 30 shapes), to
    /// 1e-12 of √(S_0[i,i] S_0[j,j]) (the Cauchy–Schwarz bound of the sum; only the
    /// rounding of the shape factor and the summation order differ).
    #[test]
    fn lag_products_over_shapes_equal_the_direct_sums_of_all_columns() {
        use crate::estimate::{FitOptions, fit};
        use crate::model::ModelOptions;
        use crate::sim::test_matrix::{Design, Ranges, sweep};
        use crate::sim::{Effects, RotorFile, TruthModel};
        use crate::stats::Accumulator;
        use crate::vehicle::Vehicle;

        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let v = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).unwrap();
        let truth = TruthModel::new(
            &v,
            &RotorFile::default(),
            Effects::new(Vec::new(), &v).unwrap(),
        )
        .unwrap();
        let n = 700;
        let all = sweep(
            &truth,
            &Ranges::scaled_to(&truth),
            Design::LatinHypercube,
            n,
            3,
        );
        let s = ModelStructure::eq22(&v, ModelOptions::default());
        let mut ws = Workspace::default();
        let mut acc = Accumulator::new(&s);
        acc.push(&s, &all, &mut ws).unwrap();
        let f = fit(&s, &acc, &FitOptions::default()).unwrap();
        let o = DiagnosticOptions::default();
        // Chunks of 5 (shorter than L) and 300 samples; the second half a segment of its own.
        let mut first = ResidualPass::new(&s, &f, o);
        let mut second = ResidualPass::new(&s, &f, o);
        for (i, start) in (0..n).step_by(50).enumerate() {
            for part in [start..start + 5, start + 5..start + 50] {
                let mut c = SampleChunk::default();
                c.extend_from(&all, part);
                let pass = if i < 7 { &mut first } else { &mut second };
                pass.push(&c, &mut ws).unwrap();
            }
        }
        first.merge(&second);
        let p = s.columns.len();
        assert!(
            first.q() < p,
            "quad× has proportional columns: {} of {p}",
            first.q()
        );
        s.assemble(&all, &mut ws).unwrap();
        let direct = |k: usize, i: usize, j: usize| -> f64 {
            (0..n - k)
                .map(|t| ws.column(i)[t] * ws.column(j)[t + k])
                .sum()
        };
        for k in 0..=o.max_lag {
            for i in 0..p {
                for j in 0..p {
                    let bound = (direct(0, i, i) * direct(0, j, j)).sqrt();
                    let d = first.column_lag_product(k, i, j) - direct(k, i, j);
                    assert!(
                        d.abs() <= 1e-12 * bound,
                        "S_{k}[{i},{j}] off by {d:e} of {bound:e}"
                    );
                }
            }
        }
    }

    /// Σ over every residual of the cell, as [`ScoreSums::add_exact`] does for small ones.
    fn exact(h: &Histogram, count: u64) -> f64 {
        let mut sums = ScoreSums::default();
        let mut rank = 0;
        for (lo, hi, c) in h.cells() {
            sums.add_exact(lo, hi, c, rank, count as f64);
            rank += c;
        }
        sums.correlation(count as f64)
    }

    fn histogram(counts: Vec<u64>, below: u64, above: u64) -> Histogram {
        let bins = counts.len() as f64;
        Histogram {
            lo: -3.0,
            hi: 3.0,
            counts,
            below,
            above,
            min: -3.0 - 6.0 / bins * 2.0,
            max: 3.0 + 6.0 / bins * 5.0,
        }
    }

    /// Integrating the normal scores over large cells gives the per-residual sum's
    /// correlation to 1e-10 (7e-12 and 5e-12 measured; 1e-9 off before the ranks
    /// nearest the ends were summed one by one and the Euler–Maclaurin term added): Gaussian counts of 2e5 residuals in 60 bins with tails in
    /// the overflow cells, and a skewed histogram of 1e6 whose tail cells hold more than
    /// [`EXACT_CELL`] residuals each (integrated too) — 1 − r, what a reader compares,
    /// there ~1e-3 to 1e-1.
    #[test]
    fn integrated_scores_match_the_per_residual_sum() {
        let gauss: Vec<u64> = (0..60)
            .map(|b| {
                let x = -3.0 + (b as f64 + 0.5) * 0.1;
                (2e5 * 0.1 * (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()) as u64
            })
            .collect();
        let skew: Vec<u64> = (0..60).map(|b| 100 + (b * b * b) as u64 / 10).collect();
        for h in [histogram(gauss, 30, 40), histogram(skew, 500, 80)] {
            let count = h.counts.iter().sum::<u64>() + h.below + h.above;
            let (fast, slow) = (normal_probability_correlation(&h, count), exact(&h, count));
            assert!((fast - slow).abs() < 1e-10, "{fast} vs {slow}");
            assert!(slow < 0.9999, "a case that tests something: {slow}");
        }
    }
}
