//! The streaming residual pass ([`ResidualPass`]): per chunk the residuals of the MMR
//! and per-axis OLS models, their histograms and the lag products of regressors and
//! residuals, merged across segments, and at the end the coloured-residual corrected
//! standard errors.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};

use super::math::{add_lag_products, quadratic_diagonal, sandwich6};
use super::scores::normal_probability_correlation;
use super::{AxisResiduals, ColouredStdError, DiagnosticOptions, Histogram, ResidualDiagnostics};
use crate::estimate::Fit;
use crate::model::{ModelStructure, ParamId, Workspace};
use crate::sample::{Axis, SampleChunk};
use crate::stats::AccumulateError;

/// Residual row width: the six MMR residuals, then the six per-axis OLS residuals.
const VW: usize = 12;

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
    param_index: Vec<ParamId>,
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
    /// A chunk's rows ([`ResidualPass::rows`]) and its regressor columns as row-major
    /// rows: buffers reused from chunk to chunk.
    chunk_rows: Rows,
    row_major: Vec<f64>,
    hist: Vec<Histogram>,
    sum: [f64; 6],
}

/// What a residual pass gathered from its samples, without what it was set up with from
/// its fit: the part of a pass one process sends another ([`ResidualPass::sums`],
/// [`ResidualPass::with_sums`]).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ResidualSums {
    count: u64,
    lag_xx: Vec<f64>,
    lag_vv: Vec<f64>,
    head: Rows,
    tail: Rows,
    hist: Vec<Histogram>,
    sum: [f64; 6],
}

/// Row-major rows of regressor column shapes (width q) and residuals (width 12).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
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
            chunk_rows: Rows::default(),
            row_major: Vec::new(),
            hist,
            sum: [0.0; 6],
        }
    }

    /// The sums gathered so far.
    pub fn sums(&self) -> ResidualSums {
        ResidualSums {
            count: self.count,
            lag_xx: self.lag_xx.clone(),
            lag_vv: self.lag_vv.clone(),
            head: self.head.clone(),
            tail: self.tail.clone(),
            hist: self.hist.clone(),
            sum: self.sum,
        }
    }

    /// This pass, as set up from its fit, holding `sums` gathered by a pass set up from
    /// the same fit; `None` when `sums` are not laid out as this pass's (other
    /// options, another model, or altered bytes).
    pub fn with_sums(&self, sums: ResidualSums) -> Option<ResidualPass> {
        let (q, l) = (self.q(), self.options.max_lag);
        let rows_fit =
            |r: &Rows| r.v.len().is_multiple_of(VW) && r.len() <= l && r.x.len() == r.len() * q;
        let hist_fit = sums.hist.len() == self.hist.len()
            && (sums.hist.iter().zip(&self.hist))
                .all(|(a, b)| a.counts.len() == b.counts.len() && a.lo == b.lo && a.hi == b.hi);
        let fits = sums.lag_xx.len() == self.lag_xx.len()
            && sums.lag_vv.len() == self.lag_vv.len()
            && rows_fit(&sums.head)
            && rows_fit(&sums.tail)
            && hist_fit;
        fits.then(|| ResidualPass {
            count: sums.count,
            lag_xx: sums.lag_xx,
            lag_vv: sums.lag_vv,
            head: sums.head,
            tail: sums.tail,
            hist: sums.hist,
            sum: sums.sum,
            ..self.clone()
        })
    }

    /// Folds in the next chunk of the stream (chunks must come in time order; use
    /// [`ResidualPass::merge`] for segments processed elsewhere).
    pub fn push(&mut self, chunk: &SampleChunk, ws: &mut Workspace) -> Result<(), AccumulateError> {
        self.structure.assemble(chunk, ws)?;
        let mut rows = std::mem::take(&mut self.chunk_rows);
        self.rows(ws, &mut rows);
        let pushed = self.push_rows(&rows);
        self.chunk_rows = rows;
        pushed
    }

    /// Folds in a chunk's `rows` ([`ResidualPass::rows`]).
    fn push_rows(&mut self, rows: &Rows) -> Result<(), AccumulateError> {
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
        self.add_cross(&tail, rows);
        self.tail = tail;
        self.add_within(rows);
        self.append(rows, n as u64);
        Ok(())
    }

    /// Number of distinct column shapes q.
    fn q(&self) -> usize {
        self.representatives.len()
    }

    /// Writes into `rows` the assembled chunk's column shapes as rows, and its MMR and
    /// OLS residuals z − X θ̂ (one matrix product over all columns).
    fn rows(&mut self, ws: &Workspace, rows: &mut Rows) {
        let n = ws.len();
        let p = self.p;
        let mut x = std::mem::take(&mut self.row_major);
        row_major(ws, p, &mut x);
        let q = self.q();
        // Every entry is written below.
        rows.x.resize(n * q, 0.0);
        rows.v.resize(n * VW, 0.0);
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
        self.row_major = x;
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
        let q = self.q();
        self.tail.x.append(&mut tail_rows.x);
        self.tail.v.append(&mut tail_rows.v);
        keep_last_rows(&mut self.tail, l, q);
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
            pos[p.index()] = j;
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
                let pi = pos[ci.param.index()];
                if pi == usize::MAX {
                    continue;
                }
                for (j, cj) in cols.iter().enumerate() {
                    let pj = pos[cj.param.index()];
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
        let (q, tail) = (self.q(), &mut self.tail);
        tail.x
            .extend_from_slice(&rows.x[rows.x.len() - rows.len().min(l) * q..]);
        tail.v
            .extend_from_slice(&rows.v[rows.v.len() - rows.len().min(l) * VW..]);
        keep_last_rows(tail, l, q);
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
        m[(c, col.axis as usize)] = fit.mmr.theta[col.param.index()];
    }
    for (a, axis) in fit.axes.iter().enumerate() {
        for (&c, &th) in axis.ols.columns.iter().zip(&axis.ols.theta) {
            m[(c, 6 + a)] = th;
        }
    }
    m
}

/// Writes into `rows` the first `w` columns of the chunk assembled in `ws` as row-major
/// rows.
fn row_major(ws: &Workspace, w: usize, rows: &mut Vec<f64>) {
    let n = ws.len();
    // Every entry is written below.
    rows.resize(n * w, 0.0);
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
}

/// Drops all but the last `l` rows of `rows`.
fn keep_last_rows(rows: &mut Rows, l: usize, q: usize) {
    let n = rows.len();
    if n > l {
        rows.x.drain(..(n - l) * q);
        rows.v.drain(..(n - l) * VW);
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
}
