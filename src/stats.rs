//! Mergeable sufficient statistics of one streaming pass (DESIGN.md, "Architecture").
//!
//! The [`Accumulator`] holds, for the augmented data matrix A = [X | Z] (every regressor
//! column of a [`ModelStructure`] followed by the six known-term-corrected outputs):
//!
//! - the upper-triangular factor R of a QR factorisation A = QR (m × m, m = p + 6), with
//!   non-negative diagonal; AᵀA = RᵀR, so every cross product XᵢᵀXⱼ, Xᵢᵀzⱼ, zᵢᵀzⱼ the
//!   two-step pipeline of the seed (§5) needs is available, and every least-squares
//!   problem on a subset of columns is solved as a small QR of R\[:, S\] with the
//!   accuracy of a QR of the data (never via normal equations);
//! - per-column minimum and maximum and per-output mean and centred sum of squares
//!   (Chan et al.'s pairwise update), for the centred R² and NRMSE;
//! - the sample count.
//!
//! Each chunk is folded in by a blocked Householder QR (faer) of R stacked on the chunk,
//! and two accumulators merge by a QR of [R_a; R_b]: a TSQR tree, so chunks, files and
//! threads combine in any grouping with rounding-level differences only. Memory is
//! O(m²) whatever the sample count.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor::{
    qr_in_place, qr_in_place_scratch, recommended_block_size,
};
use faer::{Mat, Par};

use crate::model::{ModelError, ModelStructure, Workspace};
use crate::sample::{Axis, SampleChunk};

/// Why a chunk could not be accumulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AccumulateError {
    /// The chunk does not fit the model (rotor count, missing signals).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A regressor or output is NaN or infinite.
    #[error(
        "non-finite value in {field} at sample {sample} of the stream (0-based, counted over all chunks pushed to this accumulator)"
    )]
    NonFinite {
        /// Column label or output axis name.
        field: String,
        /// Sample index within the stream of this accumulator.
        sample: u64,
    },
    /// Two accumulators of different model structures were merged.
    #[error("cannot merge accumulators of {left} and {right} columns")]
    ShapeMismatch {
        /// Columns of the left accumulator.
        left: usize,
        /// Columns of the right accumulator.
        right: usize,
    },
}

/// One-pass, mergeable statistics of [X | Z] for a model structure.
#[derive(Debug, Clone, PartialEq)]
pub struct Accumulator {
    p: usize,
    /// Upper-triangular R, m × m, column-major.
    r: Vec<f64>,
    count: u64,
    min: Vec<f64>,
    max: Vec<f64>,
    out_mean: [f64; 6],
    out_m2: [f64; 6],
    labels: Vec<String>,
}

/// Scratch buffers for folding chunks into an [`Accumulator`].
struct Stacked {
    a: Mat<f64>,
    h: Mat<f64>,
    mem: Option<MemBuffer>,
    mem_key: (usize, usize, usize),
}

impl Accumulator {
    /// An empty accumulator sized for `structure` (all its columns and six outputs).
    pub fn new(structure: &ModelStructure) -> Self {
        let p = structure.columns.len();
        let m = p + 6;
        let mut labels: Vec<String> = structure.columns.iter().map(column_field).collect();
        labels.extend(Axis::ALL.iter().map(|a| format!("output {a}")));
        Self {
            p,
            r: vec![0.0; m * m],
            count: 0,
            min: vec![f64::INFINITY; m],
            max: vec![f64::NEG_INFINITY; m],
            out_mean: [0.0; 6],
            out_m2: [0.0; 6],
            labels,
        }
    }

    /// Assembles `chunk` with `structure` (using `ws` as scratch) and folds it in.
    pub fn push(
        &mut self,
        structure: &ModelStructure,
        chunk: &SampleChunk,
        ws: &mut Workspace,
    ) -> Result<(), AccumulateError> {
        structure.assemble(chunk, ws)?;
        self.push_assembled(ws)
    }

    /// Folds in the chunk last assembled into `ws` (by the same structure).
    pub fn push_assembled(&mut self, ws: &Workspace) -> Result<(), AccumulateError> {
        let n = ws.len();
        if n == 0 {
            return Ok(());
        }
        let m = self.m();
        for j in 0..m {
            let col = self.data_column(ws, j);
            if let Some(i) = col.iter().position(|v| !v.is_finite()) {
                return Err(AccumulateError::NonFinite {
                    field: self.labels[j].clone(),
                    sample: self.count + i as u64,
                });
            }
        }
        for j in 0..m {
            let col = self.data_column(ws, j);
            let (lo, hi) = col
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
            self.min[j] = self.min[j].min(lo);
            self.max[j] = self.max[j].max(hi);
        }
        for a in 0..6 {
            let z = ws.output(Axis::ALL[a]);
            let mean = z.iter().sum::<f64>() / n as f64;
            let m2 = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
            self.combine_moments(a, n as u64, mean, m2);
        }
        STACKED.with_borrow_mut(|s| {
            s.a.resize_with(m + n, m, |_, _| 0.0);
            for j in 0..m {
                let dst = s.a.col_as_slice_mut(j);
                dst[..m].copy_from_slice(&self.r[j * m..(j + 1) * m]);
                dst[m..].copy_from_slice(self.data_column(ws, j));
            }
            self.r = triangular_factor(s, m + n, m);
        });
        self.count += n as u64;
        Ok(())
    }

    /// Merges `other` (statistics of disjoint data) into `self`: afterwards `self` holds
    /// the statistics of the union, as if all samples had been pushed to one accumulator.
    pub fn merge(&mut self, other: &Accumulator) -> Result<(), AccumulateError> {
        if other.p != self.p {
            return Err(AccumulateError::ShapeMismatch {
                left: self.p,
                right: other.p,
            });
        }
        if other.count == 0 {
            return Ok(());
        }
        let m = self.m();
        for j in 0..m {
            self.min[j] = self.min[j].min(other.min[j]);
            self.max[j] = self.max[j].max(other.max[j]);
        }
        for a in 0..6 {
            self.combine_moments(a, other.count, other.out_mean[a], other.out_m2[a]);
        }
        STACKED.with_borrow_mut(|s| {
            s.a.resize_with(2 * m, m, |_, _| 0.0);
            for j in 0..m {
                for i in 0..m {
                    s.a[(i, j)] = self.r[j * m + i];
                    s.a[(m + i, j)] = other.r[j * m + i];
                }
            }
            self.r = triangular_factor(s, 2 * m, m);
        });
        self.count += other.count;
        Ok(())
    }

    /// Number of regressor columns p (the structure's columns).
    pub fn n_columns(&self) -> usize {
        self.p
    }

    /// Size m = p + 6 of the augmented matrix [X | Z].
    pub fn m(&self) -> usize {
        self.p + 6
    }

    /// Number of samples accumulated.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Index in the augmented matrix of the output column of `axis` (p + axis).
    pub fn output_index(&self, axis: Axis) -> usize {
        self.p + axis as usize
    }

    /// Entry (i, j) of the triangular factor R of [X | Z] (zero below the diagonal).
    pub fn r(&self, i: usize, j: usize) -> f64 {
        self.r[j * self.m() + i]
    }

    /// Column j of R (m values; entries below the diagonal are zero).
    pub fn r_column(&self, j: usize) -> &[f64] {
        let m = self.m();
        &self.r[j * m..(j + 1) * m]
    }

    /// Cross product aᵢᵀaⱼ of augmented columns i and j, from R (RᵀR = AᵀA).
    pub fn cross(&self, i: usize, j: usize) -> f64 {
        let k = i.min(j) + 1;
        self.r_column(i)[..k]
            .iter()
            .zip(&self.r_column(j)[..k])
            .map(|(a, b)| a * b)
            .sum()
    }

    /// Squared norm ‖A w‖² of a linear combination of augmented columns, computed as
    /// ‖R w‖² (exact in exact arithmetic, no cancellation from forming AᵀA).
    pub fn combination_norm2(&self, w: &[f64]) -> f64 {
        self.combination(w).iter().map(|v| v * v).sum()
    }

    /// R w, the image of a combination of augmented columns in the m-dimensional space
    /// isometric to the column space of A.
    pub fn combination(&self, w: &[f64]) -> Vec<f64> {
        let m = self.m();
        let mut out = vec![0.0; m];
        for (j, &wj) in w.iter().enumerate() {
            if wj != 0.0 {
                for (o, &rij) in out.iter_mut().zip(self.r_column(j)) {
                    *o += wj * rij;
                }
            }
        }
        out
    }

    /// Smallest value of augmented column j seen.
    pub fn min(&self, j: usize) -> f64 {
        self.min[j]
    }

    /// Largest value of augmented column j seen.
    pub fn max(&self, j: usize) -> f64 {
        self.max[j]
    }

    /// Mean of the corrected output of `axis`.
    pub fn output_mean(&self, axis: Axis) -> f64 {
        self.out_mean[axis as usize]
    }

    /// Centred sum of squares Σ(z − z̄)² of the corrected output of `axis`.
    pub fn output_centred_ss(&self, axis: Axis) -> f64 {
        self.out_m2[axis as usize]
    }

    /// Label of augmented column j (column label, or `output Fx` …).
    pub fn label(&self, j: usize) -> &str {
        &self.labels[j]
    }

    fn data_column<'w>(&self, ws: &'w Workspace, j: usize) -> &'w [f64] {
        if j < self.p {
            ws.column(j)
        } else {
            ws.output(Axis::ALL[j - self.p])
        }
    }

    /// Chan, Golub & LeVeque pairwise update of (count, mean, M2).
    fn combine_moments(&mut self, a: usize, n_b: u64, mean_b: f64, m2_b: f64) {
        let n_a = self.count as f64;
        let n_b = n_b as f64;
        let n = n_a + n_b;
        let delta = mean_b - self.out_mean[a];
        self.out_mean[a] += delta * n_b / n;
        self.out_m2[a] += m2_b + delta * delta * n_a * n_b / n;
    }
}

/// `label (axis)` of a column, for error messages.
fn column_field(c: &crate::model::Column) -> String {
    format!("regressor column {} ({})", c.label, c.axis)
}

thread_local! {
    static STACKED: std::cell::RefCell<Stacked> = const { std::cell::RefCell::new(Stacked {
        a: Mat::new(),
        h: Mat::new(),
        mem: None,
        mem_key: (0, 0, 0),
    }) };
}

/// Householder QR of the first `rows` rows of `s.a` (rows × m) in place; returns the
/// upper-triangular m × m factor (column-major) with non-negative diagonal.
fn triangular_factor(s: &mut Stacked, rows: usize, m: usize) -> Vec<f64> {
    let bs = recommended_block_size::<f64>(rows, m);
    s.h.resize_with(bs, m.min(rows), |_, _| 0.0);
    let key = (rows, m, bs);
    if s.mem.is_none() || s.mem_key != key {
        s.mem = Some(MemBuffer::new(qr_in_place_scratch::<f64>(
            rows,
            m,
            bs,
            Par::Seq,
            Default::default(),
        )));
        s.mem_key = key;
    }
    let mem = s.mem.as_mut().expect("allocated above");
    qr_in_place(
        s.a.as_mut(),
        s.h.as_mut(),
        Par::Seq,
        MemStack::new(mem),
        Default::default(),
    );
    let mut r = vec![0.0; m * m];
    for i in 0..m.min(rows) {
        let sign = if s.a[(i, i)] < 0.0 { -1.0 } else { 1.0 };
        for j in i..m {
            r[j * m + i] = sign * s.a[(i, j)];
        }
    }
    r
}

impl Accumulator {
    /// The statistics of the structure's columns `columns` only (indices into this
    /// accumulator's columns, in the order wanted), as if that smaller structure had
    /// been accumulated: R of A\[:, S\] is the triangular factor of R\[:, S\], since
    /// A\[:, S\] = Q R\[:, S\]. Outputs, count and moments carry over unchanged.
    pub fn select(&self, columns: &[usize]) -> Accumulator {
        let m = self.m();
        let keep: Vec<usize> = columns.iter().copied().chain(self.p..m).collect();
        let k = keep.len();
        let r = STACKED.with_borrow_mut(|s| {
            s.a.resize_with(m, k, |_, _| 0.0);
            for (dst, &j) in keep.iter().enumerate() {
                s.a.col_as_slice_mut(dst)
                    .copy_from_slice(&self.r[j * m..(j + 1) * m]);
            }
            triangular_factor(s, m, k)
        });
        Accumulator {
            p: columns.len(),
            r,
            count: self.count,
            min: keep.iter().map(|&j| self.min[j]).collect(),
            max: keep.iter().map(|&j| self.max[j]).collect(),
            out_mean: self.out_mean,
            out_m2: self.out_m2,
            labels: keep.iter().map(|&j| self.labels[j].clone()).collect(),
        }
    }
}
