//! Mergeable sufficient statistics of one streaming pass.
//!
//! The [`Accumulator`] holds, for the augmented data matrix A = [X | Z] (every regressor
//! column of a [`ModelStructure`] followed by the six known-term-corrected outputs):
//!
//! - the upper-triangular factor R of a QR factorisation A = QR (over the q ≤ p + 6
//!   distinct column shapes, see below), with non-negative diagonal; AᵀA = RᵀR, so every
//!   cross product XᵢᵀXⱼ, Xᵢᵀzⱼ, zᵢᵀzⱼ the two-step pipeline of the seed (§5) needs is
//!   available, and every least-squares problem on a subset of columns is solved as a
//!   small QR of R\[:, S\] with the accuracy of a QR of the data (never via normal
//!   equations);
//! - per-column minimum and maximum and per-output mean and centred sum of squares
//!   (Chan et al.'s pairwise update), for the centred R² and NRMSE;
//! - the sample count;
//! - the number of distinct regressor rows (states) seen, counted exactly up to
//!   [`DISTINCT_ROWS_CAP`]: a log of one repeated state, or of fewer distinct states than
//!   parameters, cannot support a fit however many samples it has.
//!
//! Columns that are constant multiples of another column (e.g. `u*dt` of F_x and
//! `h*u*dt` of M_y) are folded in once: the factor is kept over the q distinct column
//! shapes, and column j is read as `scale_j` × its shape's column of R (R of [X D] is R D
//! for diagonal D). For quadrotor× this is 30 instead of 38 columns, ~1.5× less work.
//!
//! Each chunk is folded in by a blocked Householder QR of R stacked on the chunk that
//! leaves R's zeros alone (`triangular_update`), and two accumulators merge by the same
//! QR of [R_a; R_b]: a TSQR tree, so chunks, files and threads combine in any grouping
//! with rounding-level differences only. Memory is O(q²) whatever the sample count.
//! Cost: ~2q² flops per sample (q = 36 for the quad× model), the price of QR-grade
//! accuracy over a Gram update's q².

mod triangular_update;

use std::hash::{DefaultHasher, Hasher};
use std::sync::Arc;

use faer::{Mat, MatMut};
pub(crate) use triangular_update::{FoldScratch, fold_rows};

use crate::model::{Column, ModelError, ModelStructure, Workspace};
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

impl AccumulateError {
    /// The same error for a stream that had `samples` samples before this one's first.
    pub fn after(self, samples: u64) -> Self {
        match self {
            Self::NonFinite { field, sample } => Self::NonFinite {
                field,
                sample: sample + samples,
            },
            other => other,
        }
    }
}

/// One-pass, mergeable statistics of [X | Z] for a model structure.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Accumulator {
    p: usize,
    /// For each augmented column j (structure columns, then outputs): its shape index
    /// and the factor with column j = factor × shape column.
    shape: Vec<(usize, f64)>,
    /// For each shape, the augmented column whose data it stores.
    representative: Vec<usize>,
    /// For each structure column, whether it is a shape's representative (the only
    /// columns [`Accumulator::push`] assembles).
    stored: Vec<bool>,
    /// Upper-triangular R over the shapes, q × q (q = distinct shapes), column-major.
    /// Serialised as its upper triangle only.
    #[serde(with = "upper_triangle")]
    r: Vec<f64>,
    count: u64,
    min: Vec<f64>,
    max: Vec<f64>,
    out_mean: [f64; 6],
    out_m2: [f64; 6],
    /// Label of each augmented column (shared, not copied, by [`Accumulator::select`]'s
    /// thousands of trial statistics).
    labels: Vec<Arc<str>>,
    /// Sorted hashes of the distinct regressor rows seen, at most [`DISTINCT_ROWS_CAP`]
    /// (shared with the statistics selected from these until either adds one).
    distinct: Arc<Vec<u64>>,
    /// Smallest and largest measured output per axis (before the known terms).
    measured: [(f64, f64); 6],
    /// Smallest and largest u, v, w, p, q, r.
    motion: [(f64, f64); 6],
}

/// The serialised form of a q × q column-major upper-triangular matrix: q, then the
/// entries on and above the diagonal, column by column (half the bytes of the whole;
/// the entries below the diagonal are zero), or none for the zero matrix (statistics of
/// no sample).
mod upper_triangle {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// The largest order read: beyond any model's column shapes, and refused before its
    /// q² entries are allocated.
    const MAX_ORDER: usize = 1 << 14;

    pub fn serialize<S: Serializer>(r: &[f64], s: S) -> Result<S::Ok, S::Error> {
        let q = r.len().isqrt();
        let packed: Vec<f64> = if r.iter().all(|&v| v == 0.0) {
            Vec::new()
        } else {
            (0..q)
                .flat_map(|j| &r[j * q..j * q + j + 1])
                .copied()
                .collect()
        };
        (q, packed).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let (q, packed) = <(usize, Vec<f64>)>::deserialize(d)?;
        let entries = |q: usize| q * (q + 1) / 2;
        if q > MAX_ORDER || !(packed.is_empty() || packed.len() == entries(q)) {
            return Err(D::Error::custom(format!(
                "a triangular factor of order {q} with {} entries",
                packed.len()
            )));
        }
        let mut r = vec![0.0; q * q];
        let mut entries = packed.into_iter();
        for j in 0..q {
            for (dst, v) in r[j * q..j * q + j + 1].iter_mut().zip(&mut entries) {
                *dst = v;
            }
        }
        Ok(r)
    }
}

/// Distinct regressor rows counted exactly; beyond this many the count saturates (more
/// than any model structure has parameters).
pub const DISTINCT_ROWS_CAP: usize = 1024;

/// Which of `p` structure columns are among the `representative` augmented columns.
fn stored_columns(p: usize, representative: &[usize]) -> Vec<bool> {
    let mut stored = vec![false; p];
    representative
        .iter()
        .filter(|&&j| j < p)
        .for_each(|&j| stored[j] = true);
    stored
}

/// Which columns of `structure` an [`Accumulator`] of it stores and so has
/// [`Accumulator::push`] assemble (one per shape).
pub(crate) fn stored_columns_of(structure: &ModelStructure) -> Vec<bool> {
    let (_, representative) = column_shapes(&structure.columns);
    stored_columns(structure.columns.len(), &representative)
}

/// Inserts `h` into the sorted set `set` unless it is there or the set is full.
fn insert_distinct(set: &mut Vec<u64>, h: u64) {
    if set.len() < DISTINCT_ROWS_CAP
        && let Err(at) = set.binary_search(&h)
    {
        set.insert(at, h);
    }
}

/// Scratch buffers for folding chunks into an [`Accumulator`].
struct Stacked {
    /// The rows to fold in (chunk rows, or another accumulator's R).
    a: Mat<f64>,
    fold: FoldScratch,
}

impl Accumulator {
    /// An empty accumulator sized for `structure` (all its columns and six outputs).
    pub fn new(structure: &ModelStructure) -> Self {
        let p = structure.columns.len();
        let mut labels: Vec<Arc<str>> = structure
            .columns
            .iter()
            .map(|c| column_field(c).into())
            .collect();
        labels.extend(Axis::ALL.iter().map(|a| format!("output {a}").into()));
        let (mut shape, mut representative) = column_shapes(&structure.columns);
        for a in 0..6 {
            representative.push(p + a);
            shape.push((representative.len() - 1, 1.0));
        }
        let q = representative.len();
        Self {
            p,
            shape,
            stored: stored_columns(p, &representative),
            representative,
            r: vec![0.0; q * q],
            count: 0,
            min: vec![f64::INFINITY; q],
            max: vec![f64::NEG_INFINITY; q],
            out_mean: [0.0; 6],
            out_m2: [0.0; 6],
            labels,
            distinct: Arc::default(),
            measured: [(f64::INFINITY, f64::NEG_INFINITY); 6],
            motion: [(f64::INFINITY, f64::NEG_INFINITY); 6],
        }
    }

    /// True when the accumulator has the layout of `empty` (an [`Accumulator::new`] of
    /// the structure it should belong to: columns, shapes, labels and buffer sizes) and a
    /// sorted set of distinct rows within its cap: what merging and fitting index by. An
    /// accumulator read from a file is checked with it before use.
    pub fn has_layout_of(&self, empty: &Accumulator) -> bool {
        let q = empty.representative.len();
        self.p == empty.p
            && self.shape == empty.shape
            && self.representative == empty.representative
            && self.stored == empty.stored
            && self.labels == empty.labels
            && self.r.len() == q * q
            && self.min.len() == q
            && self.max.len() == q
            && self.distinct.len() <= DISTINCT_ROWS_CAP
            && self.distinct.windows(2).all(|w| w[0] < w[1])
    }

    /// Assembles `chunk` with `structure` (using `ws` as scratch) and folds it in.
    /// Afterwards `ws` holds the outputs and the columns this accumulator stores (one
    /// per shape); a column that is a multiple of an earlier one is not assembled.
    pub fn push(
        &mut self,
        structure: &ModelStructure,
        chunk: &SampleChunk,
        ws: &mut Workspace,
    ) -> Result<(), AccumulateError> {
        structure.assemble_wanted(chunk, ws, &self.stored)?;
        self.push_assembled(ws)
    }

    /// Folds in the chunk last assembled into `ws` (by the same structure).
    pub fn push_assembled(&mut self, ws: &Workspace) -> Result<(), AccumulateError> {
        let n = ws.len();
        if n == 0 {
            return Ok(());
        }
        let q = self.rows();
        let columns: Vec<&[f64]> = (0..q).map(|u| self.data_column(ws, u)).collect();
        let measured = Axis::ALL.map(|axis| ws.measured_range(axis));
        let motion = std::array::from_fn(|k| ws.motion_range(k));
        self.take_in(&columns, measured, motion)?;
        STACKED.with_borrow_mut(|s| {
            s.a.resize_with(n, q, |_, _| 0.0);
            for (j, col) in columns.iter().enumerate() {
                s.a.col_as_slice_mut(j).copy_from_slice(col);
            }
            fold_into(&mut self.r, s);
        });
        self.count += n as u64;
        Ok(())
    }

    /// Folds in the rows `rows` (ascending) of `chunk`, last assembled into `ws` by the
    /// same structure: the same statistics as [`Accumulator::push_assembled`] of those
    /// rows gathered ([`Workspace::gather`]), the rows copied straight into the fold.
    pub(crate) fn push_rows(
        &mut self,
        ws: &Workspace,
        chunk: &SampleChunk,
        rows: &[usize],
    ) -> Result<(), AccumulateError> {
        let n = rows.len();
        if n == 0 {
            return Ok(());
        }
        let q = self.rows();
        let (measured, motion) = crate::model::row_ranges(chunk, rows);
        STACKED.with_borrow_mut(|s| {
            s.a.resize_with(n, q, |_, _| 0.0);
            for u in 0..q {
                let src = self.data_column(ws, u);
                for (d, &i) in s.a.col_as_slice_mut(u).iter_mut().zip(rows) {
                    *d = src[i];
                }
            }
            let columns: Vec<&[f64]> = (0..q).map(|u| s.a.col_as_slice(u)).collect();
            self.take_in(&columns, measured, motion)?;
            fold_into(&mut self.r, s);
            Ok::<(), AccumulateError>(())
        })?;
        self.count += n as u64;
        Ok(())
    }

    /// Checks the data of `n` new samples, `columns[u]` of shape u, and takes in all but
    /// their factor: column ranges, output moments, distinct rows, the measured and
    /// motion ranges. Nothing changes when a value is not finite.
    fn take_in(
        &mut self,
        columns: &[&[f64]],
        measured: [(f64, f64); 6],
        motion: [(f64, f64); 6],
    ) -> Result<(), AccumulateError> {
        for (u, col) in columns.iter().enumerate() {
            if !crate::util::all_finite(col) {
                let i = col.iter().position(|v| !v.is_finite()).unwrap_or(0);
                return Err(AccumulateError::NonFinite {
                    field: self.labels[self.representative[u]].to_string(),
                    sample: self.count + i as u64,
                });
            }
        }
        for (j, col) in columns.iter().enumerate() {
            let (lo, hi) = crate::util::range_of_slice(col);
            self.min[j] = self.min[j].min(lo);
            self.max[j] = self.max[j].max(hi);
        }
        for a in 0..6 {
            let z = columns[self.output_shape(a)];
            let n = z.len();
            let mean = z.iter().sum::<f64>() / n as f64;
            let m2 = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
            self.combine_moments(a, n as u64, mean, m2);
        }
        self.count_distinct_rows(columns);
        for (m, (lo, hi)) in self.measured.iter_mut().zip(measured) {
            *m = (m.0.min(lo), m.1.max(hi));
        }
        for (m, (lo, hi)) in self.motion.iter_mut().zip(motion) {
            *m = (m.0.min(lo), m.1.max(hi));
        }
        Ok(())
    }

    /// The shape of the output of axis `a` (0..6; outputs have shapes of their own).
    fn output_shape(&self, a: usize) -> usize {
        self.shape[self.p + a].0
    }

    /// For each structure column, whether this accumulator stores its data (one column
    /// per shape; the others are multiples of a stored one).
    #[cfg(test)]
    pub(crate) fn stored_columns(&self) -> &[bool] {
        &self.stored
    }

    /// Merges `other` (statistics of disjoint data) into `self`: afterwards `self` holds
    /// the statistics of the union, as if all samples had been pushed to one accumulator.
    pub fn merge(&mut self, other: &Accumulator) -> Result<(), AccumulateError> {
        if other.p != self.p || other.shape != self.shape {
            return Err(AccumulateError::ShapeMismatch {
                left: self.p,
                right: other.p,
            });
        }
        if other.count == 0 {
            return Ok(());
        }
        if self.count == 0 {
            // Nothing to combine: the union is `other`, exactly (no refactorisation).
            *self = other.clone();
            return Ok(());
        }
        let q = self.rows();
        for j in 0..q {
            self.min[j] = self.min[j].min(other.min[j]);
            self.max[j] = self.max[j].max(other.max[j]);
        }
        for a in 0..6 {
            self.combine_moments(a, other.count, other.out_mean[a], other.out_m2[a]);
        }
        if self.distinct.len() < DISTINCT_ROWS_CAP {
            let set = Arc::make_mut(&mut self.distinct);
            for &h in other.distinct.iter() {
                insert_distinct(set, h);
            }
        }
        for (m, o) in self
            .measured
            .iter_mut()
            .zip(&other.measured)
            .chain(self.motion.iter_mut().zip(&other.motion))
        {
            *m = (m.0.min(o.0), m.1.max(o.1));
        }
        STACKED.with_borrow_mut(|s| {
            s.a.resize_with(q, q, |_, _| 0.0);
            for j in 0..q {
                s.a.col_as_slice_mut(j)
                    .copy_from_slice(&other.r[j * q..(j + 1) * q]);
            }
            fold_into(&mut self.r, s);
        });
        self.count += other.count;
        Ok(())
    }

    /// Number of regressor columns p (the structure's columns).
    pub fn n_columns(&self) -> usize {
        self.p
    }

    /// Number m = p + 6 of augmented columns [X | Z].
    pub fn m(&self) -> usize {
        self.p + 6
    }

    /// Number of rows of the factor: the distinct column shapes q ≤ m.
    pub fn rows(&self) -> usize {
        self.representative.len()
    }

    /// Number of samples accumulated.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Distinct regressor rows (states as the model sees them) among the samples:
    /// `Some(d)` when exact, `None` when at least [`DISTINCT_ROWS_CAP`] were seen. Rows
    /// are compared bit for bit (−0 = +0) through a 64-bit hash. After
    /// [`select`](Self::select) this is the count over the parent's columns, an upper
    /// bound for the subset.
    pub fn distinct_rows(&self) -> Option<usize> {
        (self.distinct.len() < DISTINCT_ROWS_CAP).then_some(self.distinct.len())
    }

    /// Smallest and largest measured output of `axis` (as logged, before subtracting
    /// the known terms).
    pub fn measured_range(&self, axis: Axis) -> (f64, f64) {
        self.measured[axis as usize]
    }

    /// Smallest and largest of the motion variable `k` (0..6: u, v, w, p, q, r).
    pub fn motion_range(&self, k: usize) -> (f64, f64) {
        self.motion[k]
    }

    /// Hashes the regressor rows of new samples (`columns[u]` the data of shape u) into
    /// the distinct-row set until it is full (then nothing more is hashed).
    fn count_distinct_rows(&mut self, columns: &[&[f64]]) {
        if self.distinct.len() >= DISTINCT_ROWS_CAP {
            return;
        }
        let cols: Vec<&[f64]> = (0..self.rows())
            .filter(|&u| self.representative[u] < self.p)
            .map(|u| columns[u])
            .collect();
        let n = columns.first().map_or(0, |c| c.len());
        let set = Arc::make_mut(&mut self.distinct);
        for i in 0..n {
            let mut h = DefaultHasher::new();
            for c in &cols {
                // + 0.0 maps −0 to +0.
                h.write_u64((c[i] + 0.0).to_bits());
            }
            insert_distinct(set, h.finish());
            if set.len() >= DISTINCT_ROWS_CAP {
                return;
            }
        }
    }

    /// Index in the augmented matrix of the output column of `axis` (p + axis).
    pub fn output_index(&self, axis: Axis) -> usize {
        self.p + axis as usize
    }

    /// Entry i (row of the factor, i < `rows()`) of the factor column of augmented
    /// column j: with F the q × m matrix of these columns, FᵀF = AᵀA.
    pub fn r(&self, i: usize, j: usize) -> f64 {
        let (u, f) = self.shape[j];
        f * self.r[u * self.rows() + i]
    }

    /// The column shape of augmented column j: columns of one shape are constant
    /// multiples of each other, here and in every statistic derived from this one.
    pub(crate) fn shape_of(&self, j: usize) -> usize {
        self.shape[j].0
    }

    /// Writes the factor column of augmented column j into `dst` (`rows()` values):
    /// [`Accumulator::r_column`] without allocating.
    pub(crate) fn write_r_column(&self, j: usize, dst: &mut [f64]) {
        let (u, f) = self.shape[j];
        let q = self.rows();
        for (d, v) in dst.iter_mut().zip(&self.r[u * q..(u + 1) * q]) {
            *d = f * v;
        }
    }

    /// Factor column of augmented column j (`rows()` values).
    pub fn r_column(&self, j: usize) -> Vec<f64> {
        let (u, f) = self.shape[j];
        let q = self.rows();
        self.r[u * q..(u + 1) * q].iter().map(|v| f * v).collect()
    }

    /// Cross product aᵢᵀaⱼ of augmented columns i and j, from the factor.
    pub fn cross(&self, i: usize, j: usize) -> f64 {
        let (ui, fi) = self.shape[i];
        let (uj, fj) = self.shape[j];
        let q = self.rows();
        let k = ui.min(uj) + 1;
        let s: f64 = self.r[ui * q..ui * q + k]
            .iter()
            .zip(&self.r[uj * q..uj * q + k])
            .map(|(a, b)| a * b)
            .sum();
        fi * fj * s
    }

    /// Squared norm ‖A w‖² of a linear combination of augmented columns, computed as
    /// ‖F w‖² (no cancellation from forming AᵀA).
    pub fn combination_norm2(&self, w: &[f64]) -> f64 {
        self.combination(w).iter().map(|v| v * v).sum()
    }

    /// F w: the image of a combination of augmented columns in the q-dimensional space
    /// isometric to the column space of A.
    pub fn combination(&self, w: &[f64]) -> Vec<f64> {
        let q = self.rows();
        let mut out = vec![0.0; q];
        for (j, &wj) in w.iter().enumerate() {
            if wj != 0.0 {
                let (u, f) = self.shape[j];
                for (o, &rij) in out.iter_mut().zip(&self.r[u * q..(u + 1) * q]) {
                    *o += wj * f * rij;
                }
            }
        }
        out
    }

    /// Smallest value of augmented column j seen.
    pub fn min(&self, j: usize) -> f64 {
        let (u, f) = self.shape[j];
        if f >= 0.0 {
            f * self.min[u]
        } else {
            f * self.max[u]
        }
    }

    /// Largest value of augmented column j seen.
    pub fn max(&self, j: usize) -> f64 {
        let (u, f) = self.shape[j];
        if f >= 0.0 {
            f * self.max[u]
        } else {
            f * self.min[u]
        }
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

    /// Data of shape u (its representative column).
    fn data_column<'w>(&self, ws: &'w Workspace, u: usize) -> &'w [f64] {
        let j = self.representative[u];
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

/// The distinct shapes of `columns`: for each column its shape index and the factor f
/// with column = f × the shape's representative column, and the representative (first
/// column) of each shape in order.
pub(crate) fn column_shapes(columns: &[Column]) -> (Vec<(usize, f64)>, Vec<usize>) {
    let mut shape = Vec::with_capacity(columns.len() + 6);
    let mut representative: Vec<usize> = Vec::new();
    for (j, col) in columns.iter().enumerate() {
        let found = representative
            .iter()
            .enumerate()
            .find_map(|(u, &rep)| proportion(&columns[rep], col).map(|f| (u, f)));
        shape.push(found.unwrap_or_else(|| {
            representative.push(j);
            (representative.len() - 1, 1.0)
        }));
    }
    (shape, representative)
}

/// f with `col` = f × `rep` for every sample, when the two columns have the same
/// factors term by term and proportional coefficients (to rounding).
fn proportion(rep: &Column, col: &Column) -> Option<f64> {
    if rep.terms.len() != col.terms.len() {
        return None;
    }
    let f = col.terms.first()?.coef / rep.terms[0].coef;
    let same = rep.terms.iter().zip(&col.terms).all(|(a, b)| {
        a.factors == b.factors && (b.coef - f * a.coef).abs() <= 1e-14 * b.coef.abs()
    });
    (same && f.is_finite() && f != 0.0).then_some(f)
}

/// `label (axis)` of a column, for error messages.
fn column_field(c: &Column) -> String {
    format!("regressor column {} ({})", c.label, c.axis)
}

thread_local! {
    static STACKED: std::cell::RefCell<Stacked> = const { std::cell::RefCell::new(Stacked {
        a: Mat::new(),
        fold: FoldScratch::new(),
    }) };
}

/// Replaces `r` (q × q upper triangular, column-major, q = the columns of `s.a`) by the
/// triangular factor, with non-negative diagonal, of `r` stacked on the rows of `s.a`
/// (which are overwritten).
fn fold_into(r: &mut [f64], s: &mut Stacked) {
    let q = s.a.ncols();
    let r = MatMut::from_column_major_slice_mut(r, q, q);
    fold_rows(r, s.a.as_mut(), &mut s.fold);
}

impl Accumulator {
    /// The statistics of the structure's columns `columns` only (indices into this
    /// accumulator's columns, in the order wanted), as if that smaller structure had
    /// been accumulated: R of A\[:, S\] is the triangular factor of R\[:, S\], since
    /// A\[:, S\] = Q R\[:, S\]. Outputs, count and moments carry over unchanged.
    pub fn select(&self, columns: &[usize]) -> Accumulator {
        let m = self.m();
        let q = self.rows();
        let keep: Vec<usize> = columns.iter().copied().chain(self.p..m).collect();
        // New shapes: the old shapes the kept columns use, each stored as the data of the
        // first kept column with that shape (its factor f0 rescales the old shape).
        let mut old_of_new: Vec<(usize, f64)> = Vec::new();
        let mut representative = Vec::new();
        let shape: Vec<(usize, f64)> = keep
            .iter()
            .enumerate()
            .map(|(new_j, &j)| {
                let (u, f) = self.shape[j];
                match old_of_new.iter().position(|&(ou, _)| ou == u) {
                    Some(v) => (v, f / old_of_new[v].1),
                    None => {
                        old_of_new.push((u, f));
                        representative.push(new_j);
                        (old_of_new.len() - 1, 1.0)
                    }
                }
            })
            .collect();
        let k = old_of_new.len();
        let r = STACKED.with_borrow_mut(|s| {
            s.a.resize_with(q, k, |_, _| 0.0);
            for (dst, &(u, f0)) in old_of_new.iter().enumerate() {
                let src = &self.r[u * q..(u + 1) * q];
                for (d, v) in s.a.col_as_slice_mut(dst).iter_mut().zip(src) {
                    *d = f0 * v;
                }
            }
            // The QR of R[:, S] alone: folded into a zero factor.
            let mut r = vec![0.0; k * k];
            fold_into(&mut r, s);
            r
        });
        let scaled = |u: usize, f0: f64, lower: bool| {
            let (lo, hi) = (f0 * self.min[u], f0 * self.max[u]);
            if (f0 >= 0.0) == lower { lo } else { hi }
        };
        Accumulator {
            p: columns.len(),
            shape,
            stored: stored_columns(columns.len(), &representative),
            representative,
            r,
            count: self.count,
            min: old_of_new
                .iter()
                .map(|&(u, f0)| scaled(u, f0, true))
                .collect(),
            max: old_of_new
                .iter()
                .map(|&(u, f0)| scaled(u, f0, false))
                .collect(),
            out_mean: self.out_mean,
            out_m2: self.out_m2,
            labels: keep.iter().map(|&j| Arc::clone(&self.labels[j])).collect(),
            distinct: Arc::clone(&self.distinct),
            measured: self.measured,
            motion: self.motion,
        }
    }
}

#[cfg(test)]
mod tests {
    use serde::{Deserialize, Serialize};

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Factor(#[serde(with = "super::upper_triangle")] Vec<f64>);

    #[test]
    fn triangular_factors_round_trip_and_an_absurd_order_is_refused() {
        let upper = Factor(vec![1.0, 0.0, 2.0, 3.0]);
        let bytes = postcard::to_stdvec(&upper).unwrap();
        assert_eq!(postcard::from_bytes::<Factor>(&bytes).unwrap(), upper);
        // The zero matrix is its order alone: 1 byte of q, 1 of an empty entry list.
        let zero = Factor(vec![0.0; 9]);
        let bytes = postcard::to_stdvec(&zero).unwrap();
        assert_eq!(bytes.len(), 2);
        assert_eq!(postcard::from_bytes::<Factor>(&bytes).unwrap(), zero);
        // An order of 2^40 with no entries would ask for 2^80 values: refused, not
        // allocated.
        let absurd = postcard::to_stdvec(&(1usize << 40, Vec::<f64>::new())).unwrap();
        let e = postcard::from_bytes::<Factor>(&absurd).unwrap_err();
        assert!(!e.to_string().is_empty());
        let short = postcard::to_stdvec(&(2usize, vec![1.0])).unwrap();
        assert!(postcard::from_bytes::<Factor>(&short).is_err());
    }
}
