//! Cross-validation of a single fit log on contiguous blocks with guards (hv-block
//! cross-validation: Burman, Chow & Nolan 1994; Racine 2000).
//!
//! The log is cut into [`Holdout::blocks`] contiguous blocks of (nearly) equal sample
//! counts; fold k tests on block k and trains on the rest of the log less a guard of
//! [`Holdout::guard_seconds`] on each side of block k, which neither fits nor scores
//! in that fold. Every sample is held out once, the last block is predicted from the
//! past alone, and no held-out sample is closer in time than the guard to a fitted one.
//!
//! Why not time segments interleaved with fitted ones (every 5th 2 s segment before):
//! a held-out stretch a few seconds long between fitted ones shares the trajectory and
//! the model error of its neighbours (the Eq. 22 residual's lag-1 autocorrelation is
//! 0.99–0.9998 on the shipped flight and the NeuroBEM flights), so the held-out error
//! measured what the model interpolates, not what it predicts: on a public PX4 log the
//! diagnosis's additions were cross-validated as gains and made the last 20 % of the
//! flight worse. A held-out block of a fifth of the log is mostly far from the fitted
//! data, and the guard removes what is left of the short-range correlation: measured on
//! the Eq. 22 residuals of the shipped flight and the three NeuroBEM flights, the
//! autocorrelation falls below 0.1 within 0.02–2.2 s on 17 of their 18 axes (within
//! 3.4 s on the last, the melon flight's pitch moment), and the widest filter the
//! pipeline derives a regressor with (the slow rotor thrust at 0.5 Hz) reaches 0.8 s to
//! either side, so with a 2 s guard no held-out sample's regressors are computed from
//! fitted samples. A longer guard wastes data a short log needs: each fold fits
//! 1 − 1/K of the log less two guards.
//!
//! The blocks are placed after the first pass, when the log's length is known: the
//! first pass accumulates the statistics of short time units ([`Units`]; their length
//! doubles, adjacent pairs merged, when a log would need more than [`MAX_UNITS`]), so
//! block edges and guards fall on unit edges, and the second pass routes each sample
//! to its piece of the same plan ([`BlockPlan`]).

use super::Holdout;
use crate::estimate::Folds;
use crate::model::{ModelStructure, Workspace};
use crate::sample::SampleChunk;
use crate::stats::{AccumulateError, Accumulator};

/// Length of the first pass's time units at the start, s: a power of two, so that a
/// sample's unit ⌊(t − t0)/L⌋ is computed exactly alike in both passes after any number
/// of doublings.
const FIRST_UNIT_SECONDS: f64 = 0.0625;

/// Most time units of a log: a sample past them doubles the units' length, so memory
/// stays at most this many Eq. 22 statistics (~10 MB for a quad) however long the log,
/// and block edges and guards are placed to 1/256 of the log or finer.
const MAX_UNITS: usize = 512;

/// The unit of time `t` (s) in units of `seconds` counted from `t0` (0 before `t0`).
fn unit_of(t: f64, t0: f64, seconds: f64) -> usize {
    let u = ((t - t0) / seconds).floor();
    if u > 0.0 { u as usize } else { 0 }
}

/// First-pass statistics of a single fit log per time unit, for the blocks placed once
/// the log has been read ([`Units::plan`]).
pub(super) struct Units {
    /// The first sample's time, s.
    t0: Option<f64>,
    /// The last sample's time, s.
    t_last: f64,
    /// Unit length, s.
    seconds: f64,
    /// Statistics of each unit (`None` while it has no sample).
    stats: Vec<Option<Accumulator>>,
    /// Samples pushed so far (error positions count from the log's first sample).
    samples: u64,
    /// A run of samples of one unit, cut from a chunk.
    run: SampleChunk,
}

/// Why a single log cannot be cut into its blocks: what the error message needs.
#[derive(Debug, Clone, Copy)]
pub(super) struct TooShort {
    /// Samples of the log.
    pub(super) samples: u64,
    /// Time from its first sample to its last, s.
    pub(super) span: f64,
}

impl Units {
    /// No sample yet.
    pub(super) fn new() -> Self {
        Self {
            t0: None,
            t_last: f64::NAN,
            seconds: FIRST_UNIT_SECONDS,
            stats: Vec::new(),
            samples: 0,
            run: SampleChunk::default(),
        }
    }

    /// Samples pushed.
    pub(super) fn samples(&self) -> u64 {
        self.samples
    }

    /// Folds the samples of `chunk` into their units' statistics (over `structure`,
    /// `ws` as scratch), in runs of one unit each.
    pub(super) fn push(
        &mut self,
        chunk: &SampleChunk,
        structure: &ModelStructure,
        ws: &mut Workspace,
    ) -> Result<(), AccumulateError> {
        if chunk.is_empty() {
            return Ok(());
        }
        let t0 = *self.t0.get_or_insert(chunk.t[0]);
        self.t_last = chunk.t[chunk.len() - 1];
        let mut start = 0;
        while start < chunk.len() {
            let mut unit = unit_of(chunk.t[start], t0, self.seconds);
            while unit >= MAX_UNITS {
                self.double()?;
                unit = unit_of(chunk.t[start], t0, self.seconds);
            }
            let mut end = start + 1;
            while end < chunk.len() && unit_of(chunk.t[end], t0, self.seconds) == unit {
                end += 1;
            }
            let part = if start == 0 && end == chunk.len() {
                chunk
            } else {
                self.run.clear();
                self.run.extend_from(chunk, start..end);
                &self.run
            };
            if self.stats.len() <= unit {
                self.stats.resize_with(unit + 1, || None);
            }
            let acc = self.stats[unit].get_or_insert_with(|| Accumulator::new(structure));
            // The accumulator counts its own samples; the error names the log's.
            let offset = self.samples - acc.count();
            acc.push(structure, part, ws).map_err(|e| e.after(offset))?;
            self.samples += (end - start) as u64;
            start = end;
        }
        Ok(())
    }

    /// Doubles the unit length, merging each even unit with the next.
    fn double(&mut self) -> Result<(), AccumulateError> {
        let mut merged = Vec::with_capacity(self.stats.len().div_ceil(2));
        let mut units = std::mem::take(&mut self.stats).into_iter();
        while let Some(first) = units.next() {
            let second = units.next().flatten();
            merged.push(match (first, second) {
                (Some(mut a), Some(b)) => {
                    a.merge(&b)?;
                    Some(a)
                }
                (a, b) => a.or(b),
            });
        }
        self.stats = merged;
        self.seconds *= 2.0;
        Ok(())
    }

    /// The blocks of `holdout` over the log, or why the log is too short for them: it
    /// spans less than a guard per block (each block at least as long as a guard), or
    /// some fold would have no sample to fit or to test.
    pub(super) fn plan(&self, holdout: Holdout) -> Result<BlockPlan, TooShort> {
        let counts: Vec<u64> = self
            .stats
            .iter()
            .map(|a| a.as_ref().map_or(0, Accumulator::count))
            .collect();
        let n: u64 = counts.iter().sum();
        let t0 = self.t0.unwrap_or(0.0);
        let span = if n > 0 { self.t_last - t0 } else { 0.0 };
        let too_short = TooShort { samples: n, span };
        let k = holdout.blocks;
        if n < k as u64 || span < k as f64 * holdout.guard_seconds {
            return Err(too_short);
        }
        let edges = block_edges(&counts, k);
        let guard = (holdout.guard_seconds / self.seconds).ceil() as usize;
        let mut piece_of_unit = Vec::with_capacity(counts.len());
        let mut pieces: Vec<Piece> = Vec::new();
        let mut piece_counts: Vec<u64> = Vec::new();
        for (unit, &count) in counts.iter().enumerate() {
            let block = edges.partition_point(|&e| e <= unit) - 1;
            let piece = Piece {
                block,
                head: block > 0 && unit < edges[block] + guard,
                tail: block + 1 < k && unit + guard >= edges[block + 1],
            };
            if pieces.last() != Some(&piece) {
                pieces.push(piece);
                piece_counts.push(0);
            }
            piece_counts[pieces.len() - 1] += count;
            piece_of_unit.push(pieces.len() - 1);
        }
        let samples = |keep: &dyn Fn(&Piece) -> bool| -> u64 {
            let chosen = pieces.iter().zip(&piece_counts).filter(|(p, _)| keep(p));
            chosen.map(|(_, c)| c).sum()
        };
        let every_fold_has_data =
            (0..k).all(|j| samples(&|p| p.block == j) > 0 && samples(&|p| !p.excluded_from(j)) > 0);
        if !every_fold_has_data {
            return Err(too_short);
        }
        Ok(BlockPlan {
            t0,
            span,
            unit_seconds: self.seconds,
            piece_of_unit,
            pieces,
            edges,
            guard_units: guard,
        })
    }

    /// The statistics of each piece of `plan` (made by [`Units::plan`] from these units),
    /// over `structure`: its units' merged in time order.
    pub(super) fn into_pieces(
        self,
        plan: &BlockPlan,
        structure: &ModelStructure,
    ) -> Result<Vec<Accumulator>, AccumulateError> {
        let mut pieces: Vec<Accumulator> = plan
            .pieces
            .iter()
            .map(|_| Accumulator::new(structure))
            .collect();
        for (unit, acc) in self.stats.into_iter().enumerate() {
            if let Some(acc) = acc {
                pieces[plan.piece_of_unit[unit]].merge(&acc)?;
            }
        }
        Ok(pieces)
    }
}

/// Unit edges of `k` blocks over units holding `counts` samples: block j starts at the
/// first unit by which j/k of the samples have gone by (each block at least one unit),
/// the last block ends after the last unit.
fn block_edges(counts: &[u64], k: usize) -> Vec<usize> {
    let n: u64 = counts.iter().sum();
    let mut edges = vec![0];
    let mut before = 0u64;
    for (unit, &c) in counts.iter().enumerate() {
        let next = edges.len() as u128;
        if (edges.len() < k)
            && unit > edges[edges.len() - 1]
            && u128::from(before) * k as u128 >= next * u128::from(n)
        {
            edges.push(unit);
        }
        before += c;
    }
    while edges.len() < k {
        edges.push(counts.len());
    }
    edges.push(counts.len());
    edges
}

/// A run of units of one block in one relation to the guards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Piece {
    /// The block it belongs to (its fold tests on it).
    pub(super) block: usize,
    /// Within the guard after the previous block: that block's fold does not fit it.
    head: bool,
    /// Within the guard before the next block: that block's fold does not fit it.
    tail: bool,
}

impl Piece {
    /// True when the fold of block `j` does not fit this piece (it tests on it, or the
    /// piece is in a guard of block `j`).
    fn excluded_from(&self, j: usize) -> bool {
        self.block == j || (self.head && self.block == j + 1) || (self.tail && self.block + 1 == j)
    }
}

/// Where the blocks of a single fit log lie: its time units and their pieces.
#[derive(Debug, Clone)]
pub(super) struct BlockPlan {
    /// The first sample's time, s.
    t0: f64,
    /// Time from the first sample to the last, s.
    span: f64,
    /// Unit length, s.
    unit_seconds: f64,
    /// The piece of each unit.
    piece_of_unit: Vec<usize>,
    /// The pieces in time order.
    pub(super) pieces: Vec<Piece>,
    /// Unit edges of the blocks (k + 1, the last after the last unit).
    edges: Vec<usize>,
    /// Guard on each side of a held-out block, units.
    guard_units: usize,
}

impl BlockPlan {
    /// Number of blocks (and folds).
    pub(super) fn blocks(&self) -> usize {
        self.edges.len() - 1
    }

    /// Guard on each side of a held-out block, s (the requested guard rounded up to
    /// whole units).
    pub(super) fn guard_seconds(&self) -> f64 {
        self.guard_units as f64 * self.unit_seconds
    }

    /// The piece of the sample at time `t` (s).
    fn piece_at(&self, t: f64) -> usize {
        let unit = unit_of(t, self.t0, self.unit_seconds);
        let last = self.piece_of_unit.len() - 1;
        self.piece_of_unit[unit.min(last)]
    }

    /// Hands the runs of `chunk` that lie in one piece each to `sink(rows, piece)`, in
    /// order.
    pub(super) fn route<E>(
        &self,
        chunk: &SampleChunk,
        mut sink: impl FnMut(std::ops::Range<usize>, usize) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut start = 0;
        while start < chunk.len() {
            let piece = self.piece_at(chunk.t[start]);
            let mut end = start + 1;
            while end < chunk.len() && self.piece_at(chunk.t[end]) == piece {
                end += 1;
            }
            sink(start..end, piece)?;
            start = end;
        }
        Ok(())
    }

    /// The folds over the pieces' statistics `pieces` (one per piece, in order): fold j
    /// tests on block j and trains on every piece its guards leave, each merged in time
    /// order; and the final fit data, all pieces merged.
    pub(super) fn folds(
        &self,
        structure: &ModelStructure,
        pieces: &[Accumulator],
    ) -> Result<(Folds, Accumulator), AccumulateError> {
        let merged = |keep: &dyn Fn(&Piece) -> bool| -> Result<Accumulator, AccumulateError> {
            // The first merge into an empty accumulator is an exact copy.
            let mut acc = Accumulator::new(structure);
            for (_, a) in self.pieces.iter().zip(pieces).filter(|(p, _)| keep(p)) {
                acc.merge(a)?;
            }
            Ok(acc)
        };
        let mut folds = Vec::with_capacity(self.blocks());
        for j in 0..self.blocks() {
            let train = merged(&|p| !p.excluded_from(j))?;
            let test = merged(&|p| p.block == j)?;
            folds.push((self.block_name(j), train, test));
        }
        Ok((Folds::from_folds(folds), merged(&|_| true)?))
    }

    /// The name of block `j` in the report: its place and time from the log's first
    /// sample.
    fn block_name(&self, j: usize) -> String {
        let at = |e: usize| (e as f64 * self.unit_seconds).min(self.span);
        format!(
            "block {}/{} ({:.1}-{:.1} s)",
            j + 1,
            self.blocks(),
            at(self.edges[j]),
            at(self.edges[j + 1])
        )
    }

    /// Which of the local-statistics groups of the log a piece's samples go to: its block
    /// (the held-out data of its fold).
    pub(super) fn group_of(&self, piece: usize) -> usize {
        self.pieces[piece].block
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::ModelOptions;
    use crate::sim::test_matrix::{Design, Ranges, sweep};
    use crate::sim::{Effects, RotorFile, TruthModel};
    use crate::vehicle::Vehicle;

    /// `n` samples of a sweep of the shipped quadrotor×, logged at `rate` Hz from t = 3 s
    /// (a log that does not start at zero), and its Eq. 22 structure.
    fn log(n: usize, rate: f64) -> (SampleChunk, ModelStructure) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let v = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).unwrap();
        let effects = Effects::new(Vec::new(), &v).unwrap();
        let truth = TruthModel::new(&v, &RotorFile::default(), effects).unwrap();
        let mut all = sweep(
            &truth,
            &Ranges::scaled_to(&truth),
            Design::LatinHypercube,
            n,
            7,
        );
        all.t = (0..n).map(|i| 3.0 + i as f64 / rate).collect();
        (all, ModelStructure::eq22(&v, ModelOptions::default()))
    }

    /// The first pass's units of `all`, pushed in chunks of `chunk` samples.
    fn units(all: &SampleChunk, s: &ModelStructure, chunk: usize) -> Units {
        let mut units = Units::new();
        let mut ws = Workspace::default();
        for start in (0..all.len()).step_by(chunk) {
            let mut c = SampleChunk::default();
            c.extend_from(all, start..(start + chunk).min(all.len()));
            units.push(&c, s, &mut ws).unwrap();
        }
        units
    }

    #[test]
    fn blocks_hold_equal_sample_counts_to_a_unit() {
        assert_eq!(block_edges(&[10; 100], 5), vec![0, 20, 40, 60, 80, 100]);
        // Empty units (a sweep's points 1 s apart in 1/4 s units) count for nothing.
        let sparse: Vec<u64> = (0..40).map(|u| u64::from(u % 4 == 0)).collect();
        assert_eq!(block_edges(&sparse, 2), vec![0, 17, 40]);
        // Fewer non-empty units than blocks: the last blocks are empty (refused later).
        assert_eq!(block_edges(&[5, 0, 5], 5), vec![0, 1, 2, 3, 3, 3]);
    }

    /// A 30 s log at 100 Hz in 5 blocks of 6 s with 2 s guards: each fold tests on its
    /// 600 samples and trains on the rest less 200 samples beside its block on each side
    /// (one side for the first and last block), so the training counts are exact.
    #[test]
    fn each_fold_trains_on_the_log_less_its_block_and_the_guards_beside_it() {
        let (all, s) = log(3000, 100.0);
        let units = units(&all, &s, 1024);
        let plan = units.plan(Holdout::DEFAULT).expect("30 s is long enough");
        assert_eq!((plan.blocks(), plan.guard_seconds()), (5, 2.0));
        let pieces = units.into_pieces(&plan, &s).unwrap();
        let (folds, fit) = plan.folds(&s, &pieces).unwrap();
        assert_eq!(fit.count(), 3000);
        assert_eq!(folds.test_samples(), 3000);
        assert_eq!(folds.train_samples(), 2 * 2200 + 3 * 2000);
        assert_eq!(folds.names[0], "block 1/5 (0.0-6.0 s)");
        assert_eq!(folds.names[4], "block 5/5 (24.0-30.0 s)");
        // The second pass routes every sample to the piece the first pass put it in.
        let mut routed = vec![0u64; plan.pieces.len()];
        plan.route(&all, |rows, piece| {
            routed[piece] += rows.len() as u64;
            Ok::<(), ()>(())
        })
        .unwrap();
        let counted: Vec<u64> = pieces.iter().map(Accumulator::count).collect();
        assert_eq!(routed, counted);
    }

    /// A log longer than the unit limit: the units double (pairs merged) and the pieces
    /// hold the same statistics as the samples pushed directly, to rounding (1e-12 of
    /// R's largest entry: the same rows folded in another grouping); the chunking of the
    /// input does not change them.
    #[test]
    fn doubled_units_hold_the_statistics_of_their_samples() {
        let (all, s) = log(2000, 10.0);
        let units = units(&all, &s, 300);
        assert_eq!(units.seconds, 0.5);
        let plan = units.plan(Holdout::DEFAULT).unwrap();
        // The guard is whole units: 2 s of 0.5 s units.
        assert_eq!(plan.guard_seconds(), 2.0);
        let pieces = units.into_pieces(&plan, &s).unwrap();
        let (_, fit) = plan.folds(&s, &pieces).unwrap();
        let mut direct = Accumulator::new(&s);
        direct.push(&s, &all, &mut Workspace::default()).unwrap();
        assert_eq!(fit.count(), direct.count());
        let q = direct.rows();
        let scale = (0..q).map(|i| direct.r(i, i).abs()).fold(0.0, f64::max);
        for i in 0..q {
            for j in i..q {
                let (a, b) = (fit.r(i, j).abs(), direct.r(i, j).abs());
                assert!((a - b).abs() <= 1e-12 * scale, "R[{i}, {j}]: {a} vs {b}");
            }
        }
        let other = units_pieces(&all, &s, 1024);
        for (a, b) in pieces.iter().zip(&other) {
            assert_eq!(a.count(), b.count());
        }
    }

    fn units_pieces(all: &SampleChunk, s: &ModelStructure, chunk: usize) -> Vec<Accumulator> {
        let units = units(all, s, chunk);
        let plan = units.plan(Holdout::DEFAULT).unwrap();
        units.into_pieces(&plan, s).unwrap()
    }

    /// A log shorter than a guard per block, or with fewer samples than blocks, cannot be
    /// cut into its blocks; without a guard a short log can.
    #[test]
    fn a_log_shorter_than_a_guard_per_block_is_too_short() {
        let (all, s) = log(999, 100.0);
        let short = units(&all, &s, 1024).plan(Holdout::DEFAULT).unwrap_err();
        assert_eq!(short.samples, 999);
        assert!((short.span - 9.98).abs() < 1e-9);
        let no_guard = Holdout {
            blocks: 5,
            guard_seconds: 0.0,
        };
        assert!(units(&all, &s, 1024).plan(no_guard).is_ok());
        let (four, s) = log(4, 0.01);
        assert_eq!(
            units(&four, &s, 1024).plan(no_guard).unwrap_err().samples,
            4
        );
    }
}
