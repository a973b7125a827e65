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
//! terms across the seam are added at merge time).

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
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
    theta: Vec<f64>,
    xtx_inv: Vec<f64>,
    white: Vec<f64>,
    terms: Vec<String>,
}

/// Streaming second pass over the data with the MMR estimates of a [`Fit`].
#[derive(Debug, Clone)]
pub struct ResidualPass {
    structure: ModelStructure,
    theta: Vec<f64>,
    weight: [[f64; 6]; 6],
    covariance: Vec<f64>,
    param_index: Vec<usize>,
    names: Vec<String>,
    white: Vec<f64>,
    ols: Vec<OlsModel>,
    options: DiagnosticOptions,
    p: usize,
    count: u64,
    /// (L+1) × p × p: Σ_t x_t x_{t+k}ᵀ.
    lag_xx: Vec<f64>,
    /// (L+1) × 12 × 12: Σ_t v_t v_{t+k}ᵀ over MMR and OLS residuals.
    lag_vv: Vec<f64>,
    head: Rows,
    tail: Rows,
    hist: Vec<Histogram>,
    sum: [f64; 6],
}

/// Row-major rows of regressors (width p) and residuals (width 6).
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
            theta: fit.mmr.theta.clone(),
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
                    theta: a.ols.theta.clone(),
                    xtx_inv: a.ols.xtx_inv.clone(),
                    white: a.ols.std_error.clone(),
                    terms: a.ols.terms.clone(),
                })
                .collect(),
            options: DiagnosticOptions { bins, ..options },
            p,
            count: 0,
            lag_xx: vec![0.0; (l + 1) * p * p],
            lag_vv: vec![0.0; (l + 1) * VW * VW],
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
        let n = ws.len();
        let p = self.p;
        let mut rows = Rows {
            x: vec![0.0; n * p],
            v: vec![0.0; n * VW],
        };
        for (c, col) in self.structure.columns.iter().enumerate() {
            let data = ws.column(c);
            let th = self.theta[col.param];
            let a = col.axis as usize;
            for (t, &x) in data.iter().enumerate() {
                rows.x[t * p + c] = x;
                rows.v[t * VW + a] -= th * x;
            }
        }
        for (a, model) in self.ols.iter().enumerate() {
            for (&c, &th) in model.columns.iter().zip(&model.theta) {
                for (t, &x) in ws.column(c).iter().enumerate() {
                    rows.v[t * VW + 6 + a] -= th * x;
                }
            }
        }
        for (a, &axis) in Axis::ALL.iter().enumerate() {
            for (t, &z) in ws.output(axis).iter().enumerate() {
                rows.v[t * VW + a] += z;
                rows.v[t * VW + 6 + a] += z;
            }
        }
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
        self.tail = last_rows(joined, l, self.p);
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
        let p = self.p;
        let k = model.columns.len();
        let mut middle = vec![0.0; k * k];
        for lag in 0..=self.options.max_lag {
            let r = self.lag_vv[lag * VW * VW + (6 + a) * VW + 6 + a] / n;
            let s = &self.lag_xx[lag * p * p..(lag + 1) * p * p];
            for (i, &ci) in model.columns.iter().enumerate() {
                for (j, &cj) in model.columns.iter().enumerate() {
                    let mut v = s[ci * p + cj];
                    if lag > 0 {
                        v += s[cj * p + ci];
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
        let p = self.p;
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
            let s = &self.lag_xx[k * p * p..(k + 1) * p * p];
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
                    let v = m[ci.axis as usize][cj.axis as usize] * s[i * p + j];
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

    /// Lag products of rows within one segment: for each lag k, Xᵀ\[0..n−k\] X\[k..n\] (and
    /// the same for the residuals) as one matrix product (faer), not n outer products.
    fn add_within(&mut self, rows: &Rows) {
        let n = rows.len();
        let p = self.p;
        let x = Mat::from_fn(n, p, |t, i| rows.x[t * p + i]);
        let v = Mat::from_fn(n, VW, |t, i| rows.v[t * VW + i]);
        let mut sx = Mat::<f64>::zeros(p, p);
        let mut sv = Mat::<f64>::zeros(VW, VW);
        for k in 0..=self.options.max_lag.min(n.saturating_sub(1)) {
            let len = n - k;
            matmul(
                sx.as_mut(),
                Accum::Replace,
                x.as_ref().subrows(0, len).transpose(),
                x.as_ref().subrows(k, len),
                1.0,
                Par::Seq,
            );
            matmul(
                sv.as_mut(),
                Accum::Replace,
                v.as_ref().subrows(0, len).transpose(),
                v.as_ref().subrows(k, len),
                1.0,
                Par::Seq,
            );
            let dst = &mut self.lag_xx[k * p * p..(k + 1) * p * p];
            for (i, row) in dst.chunks_exact_mut(p).enumerate() {
                row.iter_mut()
                    .enumerate()
                    .for_each(|(j, d)| *d += sx[(i, j)]);
            }
            let dst = &mut self.lag_vv[k * VW * VW..(k + 1) * VW * VW];
            for (i, row) in dst.chunks_exact_mut(VW).enumerate() {
                row.iter_mut()
                    .enumerate()
                    .for_each(|(j, d)| *d += sv[(i, j)]);
            }
        }
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

    /// S_k += x_s x_tᵀ and Γ-sum_k += v_s v_tᵀ.
    fn outer(&mut self, k: usize, a: &Rows, s: usize, b: &Rows, t: usize) {
        let p = self.p;
        let xs = &a.x[s * p..(s + 1) * p];
        let xt = &b.x[t * p..(t + 1) * p];
        let dst = &mut self.lag_xx[k * p * p..(k + 1) * p * p];
        for (row, &xi) in dst.chunks_exact_mut(p).zip(xs) {
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
            .extend_from_slice(&rows.x[rows.x.len() - rows.len().min(l) * self.p..]);
        joined
            .v
            .extend_from_slice(&rows.v[rows.v.len() - rows.len().min(l) * VW..]);
        self.tail = last_rows(joined, l, self.p);
        self.count += n;
    }

    fn extend_head(&mut self, rows: &Rows) {
        let take = (self.options.max_lag - self.head.len()).min(rows.len());
        self.head.x.extend_from_slice(&rows.x[..take * self.p]);
        self.head.v.extend_from_slice(&rows.v[..take * VW]);
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

/// The last `l` rows of `rows`.
fn last_rows(rows: Rows, l: usize, p: usize) -> Rows {
    let n = rows.len();
    if n <= l {
        return rows;
    }
    Rows {
        x: rows.x[(n - l) * p..].to_vec(),
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
    let normal = Normal::new(0.0, 1.0).expect("standard normal");
    let n = count as f64;
    let cells = h.cells();
    let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut rank = 0u64;
    for (lo, hi, c) in cells {
        for i in 0..c {
            rank += 1;
            let x = lo + (hi - lo) * (i as f64 + 0.5) / c as f64;
            let y = normal.inverse_cdf((rank as f64 - 0.375) / (n + 0.25));
            sx += x;
            sy += y;
            sxx += x * x;
            syy += y * y;
            sxy += x * y;
        }
    }
    let cov = sxy - sx * sy / n;
    cov / ((sxx - sx * sx / n) * (syy - sy * sy / n)).sqrt()
}
