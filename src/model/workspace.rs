//! The reusable buffers of an assembly: signal values, regressor columns and outputs of
//! one chunk, column-major.

use crate::sample::{Axis, SampleChunk};
use crate::util::range_of;

/// Reusable column-major buffers for [`super::ModelStructure::assemble`].
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    /// Computed signal values, one block of `capacity` per required signal.
    pub(super) signals: Vec<f64>,
    /// Regressor columns, column j at `j * capacity`.
    pub(super) columns: Vec<f64>,
    /// Known-term-corrected outputs, axis a at `a * capacity`.
    pub(super) outputs: Vec<f64>,
    /// Smallest and largest measured output per axis (before the known terms).
    pub(super) measured: [(f64, f64); 6],
    /// Smallest and largest u, v, w, p, q, r.
    pub(super) motion: [(f64, f64); 6],
    /// Samples each column block has room for.
    pub(super) capacity: usize,
    len: usize,
    n_columns: usize,
    n_signals: usize,
}

impl Workspace {
    /// A workspace with room for `capacity` samples of a structure with `n_columns`
    /// columns.
    pub fn new(capacity: usize, n_columns: usize) -> Self {
        let mut ws = Self::default();
        ws.prepare(capacity, n_columns, 32);
        ws.len = 0;
        ws
    }

    /// Room for `n` samples of `n_columns` columns and `n_signals` signals (grown, never
    /// shrunk); the chunk in the buffers is then `n` samples long.
    pub(super) fn prepare(&mut self, n: usize, n_columns: usize, n_signals: usize) {
        if n > self.capacity || n_columns > self.n_columns || n_signals > self.n_signals {
            self.capacity = self.capacity.max(n);
            self.n_columns = self.n_columns.max(n_columns);
            self.n_signals = self.n_signals.max(n_signals);
            self.signals.resize(self.n_signals * self.capacity, 0.0);
            self.columns.resize(self.n_columns * self.capacity, 0.0);
            self.outputs.resize(6 * self.capacity, 0.0);
        }
        self.len = n;
    }

    /// Samples in the last assembled chunk.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the last assembled chunk was empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Regressor column `j` of the last assembled chunk.
    pub fn column(&self, j: usize) -> &[f64] {
        &self.columns[j * self.capacity..j * self.capacity + self.len]
    }

    /// Smallest and largest measured output of `axis` (before subtracting the known
    /// terms) in the last assembled chunk.
    pub fn measured_range(&self, axis: Axis) -> (f64, f64) {
        self.measured[axis as usize]
    }

    /// Smallest and largest of u, v, w, p, q, r (index 0..6) in the last assembled chunk.
    pub fn motion_range(&self, k: usize) -> (f64, f64) {
        self.motion[k]
    }

    /// Rows `rows` (ascending sample indices) of `chunk`, last assembled into `self` with
    /// `wanted.len()` columns, copied into `into` as if that part of `chunk` alone had
    /// been assembled: the regressor columns j with `wanted[j]` (the others are left
    /// unspecified), outputs, and the measured and motion ranges (signals are not
    /// copied).
    pub fn gather(&self, chunk: &SampleChunk, rows: &[usize], wanted: &[bool], into: &mut Self) {
        let m = rows.len();
        into.prepare(m, wanted.len(), 0);
        let cap = into.capacity;
        let pick = |src: &[f64], dst: &mut [f64]| {
            dst.iter_mut().zip(rows).for_each(|(d, &i)| *d = src[i]);
        };
        for j in (0..wanted.len()).filter(|&j| wanted[j]) {
            pick(self.column(j), &mut into.columns[j * cap..j * cap + m]);
        }
        for axis in Axis::ALL {
            let a = axis as usize;
            pick(self.output(axis), &mut into.outputs[a * cap..a * cap + m]);
        }
        (into.measured, into.motion) = row_ranges(chunk, rows);
    }

    /// Measured output of `axis` minus the known terms, for the last assembled chunk.
    pub fn output(&self, axis: Axis) -> &[f64] {
        let a = axis as usize;
        &self.outputs[a * self.capacity..a * self.capacity + self.len]
    }
}

/// Smallest and largest value of six signals.
pub(crate) type Ranges = [(f64, f64); 6];

/// The measured output ranges (per axis; (0, 0) without measured outputs) and the motion
/// ranges (u, v, w, p, q, r) of the rows `rows` of `chunk`, as [`Workspace::gather`]
/// gives them.
pub(crate) fn row_ranges(chunk: &SampleChunk, rows: &[usize]) -> (Ranges, Ranges) {
    let measured = Axis::ALL.map(
        |axis| match chunk.wrench[axis as usize].get(..chunk.len()) {
            Some(z) => range_of(rows.iter().map(|&i| z[i])),
            None => (0.0, 0.0),
        },
    );
    let mut motion = [(0.0, 0.0); 6];
    for k in 0..3 {
        motion[k] = range_of(rows.iter().map(|&i| chunk.velocity[k][i]));
        motion[3 + k] = range_of(rows.iter().map(|&i| chunk.rates[k][i]));
    }
    (measured, motion)
}
