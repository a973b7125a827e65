//! Where a candidate acts: effects confined to part of the envelope (near the ground, in
//! the wake of other rotors, in descent near the hover inflow speed) are judged on the
//! held-out samples where they act, not diluted over a whole log.
//!
//! A candidate with an [`Activity`](super::Activity) gets a second set of held-out statistics, accumulated
//! over only the samples where its activity signal reaches the threshold; its validation
//! gain is then measured there ([`LocalFolds`]), with the training statistics of the
//! ordinary folds.

use crate::estimate::Folds;
use crate::model::{Column, ModelStructure, ParamId, Parameter, Workspace};
use crate::sample::{Axis, SampleChunk};
use crate::stats::{AccumulateError, Accumulator};

use super::candidate::Candidate;

/// The local candidates of a candidate set and the structure that evaluates their
/// activity signals (one column each).
#[derive(Debug, Clone)]
pub struct LocalRegions {
    /// Candidate index (into the candidate set) of each region.
    pub candidates: Vec<usize>,
    thresholds: Vec<f64>,
    activity: ModelStructure,
}

impl LocalRegions {
    /// The regions of the candidates with an activity; `base` supplies the vehicle's
    /// geometry for the signals. At most 64 (a bit each in an activity pattern; the
    /// candidate library has five).
    pub fn new(base: &ModelStructure, candidates: &[Candidate]) -> Self {
        // Only the activity columns are read: no known terms, so assembling them
        // computes no outputs' known terms and none of their signals.
        let mut activity = base.select_columns(&[]);
        activity.known = Default::default();
        let mut regions = Vec::new();
        let mut thresholds = Vec::new();
        for (c, cand) in candidates.iter().enumerate() {
            let Some(a) = &cand.activity else { continue };
            let column = Column {
                axis: Axis::Fx,
                param: ParamId::default(),
                label: format!("activity of {}", cand.name),
                terms: a.terms.clone(),
            };
            let param = Parameter {
                name: format!("activity_{c}"),
                unit: "-".into(),
            };
            activity.add_parameter(param, vec![column]);
            regions.push(c);
            thresholds.push(a.threshold);
        }
        assert!(regions.len() <= 64, "at most 64 local candidates");
        Self {
            candidates: regions,
            thresholds,
            activity,
        }
    }

    /// Number of regions.
    pub fn len(&self) -> usize {
        self.candidates.len()
    }

    /// True without local candidates.
    pub fn is_empty(&self) -> bool {
        self.candidates.is_empty()
    }

    /// Pushes the samples of `chunk` where some region's candidate acts into `into`, by
    /// activity pattern (the regions acting at the sample): a sample in several regions
    /// is folded once. `assembled` must hold `chunk` as an accumulator over `extended`
    /// assembles it: the active rows are taken from it rather than assembled again
    /// (every regressor is a function of its own sample, so this is the same as
    /// assembling the active part). `active_ws` takes the activity signals (reused
    /// across chunks).
    pub fn push(
        &self,
        chunk: &SampleChunk,
        assembled: &Workspace,
        extended: &ModelStructure,
        into: &mut ActivityParts,
        active_ws: &mut Workspace,
    ) -> Result<(), AccumulateError> {
        if self.is_empty() || chunk.is_empty() {
            return Ok(());
        }
        // The activity signals are among the candidates' (each region's candidate acts
        // through them), so they are read from the extended assembly.
        let reused = self
            .activity
            .assemble_columns_from(chunk, extended, assembled, active_ws);
        if reused.is_none() {
            self.activity
                .assemble(chunk, active_ws)
                .map_err(AccumulateError::from)?;
        }
        let signals: Vec<&[f64]> = (0..self.len()).map(|k| active_ws.column(k)).collect();
        let patterns = activity_patterns(&signals, &self.thresholds);
        // The distinct patterns that act, ascending (a handful per chunk).
        let mut acting: Vec<u64> = Vec::new();
        for &m in &patterns {
            if m != 0 && !acting.contains(&m) {
                acting.push(m);
            }
        }
        acting.sort_unstable();
        let mut rows = Vec::with_capacity(chunk.len());
        for pattern in acting {
            rows.clear();
            rows.extend((0..patterns.len()).filter(|&i| patterns[i] == pattern));
            let acc = into.part(pattern, extended);
            acc.push_rows(assembled, chunk, &rows)?;
        }
        Ok(())
    }

    /// Each region's statistics over `extended` from `parts`: the patterns it acts in,
    /// merged in pattern order.
    pub fn per_region(
        &self,
        parts: &ActivityParts,
        extended: &ModelStructure,
    ) -> Result<Vec<Accumulator>, AccumulateError> {
        (0..self.len()).map(|k| parts.region(k, extended)).collect()
    }
}

/// Each sample's activity pattern: bit k set where `signals[k]` reaches `thresholds[k]`
/// in magnitude (at most 64 regions, [`LocalRegions::new`]).
fn activity_patterns(signals: &[&[f64]], thresholds: &[f64]) -> Vec<u64> {
    let n = signals.first().map_or(0, |s| s.len());
    let mut patterns = vec![0u64; n];
    for (k, (signal, &threshold)) in signals.iter().zip(thresholds).enumerate() {
        for (m, v) in patterns.iter_mut().zip(*signal) {
            *m |= u64::from(v.abs() >= threshold) << k;
        }
    }
    patterns
}

/// Statistics of the samples where local candidates act, one accumulator per activity
/// pattern ([`LocalRegions::push`]); [`LocalRegions::per_region`] makes each region's.
#[derive(Debug, Clone, Default)]
pub struct ActivityParts {
    /// (pattern, statistics), patterns ascending.
    parts: Vec<(u64, Accumulator)>,
}

impl ActivityParts {
    /// The statistics of `pattern` (empty over `extended` when there are none yet).
    fn part(&mut self, pattern: u64, extended: &ModelStructure) -> &mut Accumulator {
        let at = match self.parts.binary_search_by_key(&pattern, |(m, _)| *m) {
            Ok(at) => at,
            Err(at) => {
                self.parts.insert(at, (pattern, Accumulator::new(extended)));
                at
            }
        };
        &mut self.parts[at].1
    }

    /// Merges `later`'s statistics (of other samples) pattern by pattern.
    pub fn merge(&mut self, later: &ActivityParts) -> Result<(), AccumulateError> {
        for (pattern, part) in &later.parts {
            match self.parts.binary_search_by_key(pattern, |(m, _)| *m) {
                Ok(at) => self.parts[at].1.merge(part)?,
                Err(at) => self.parts.insert(at, (*pattern, part.clone())),
            }
        }
        Ok(())
    }

    /// Region `k`'s statistics over `extended`: the patterns with bit k, merged in
    /// pattern order.
    fn region(&self, k: usize, extended: &ModelStructure) -> Result<Accumulator, AccumulateError> {
        let mut region = Accumulator::new(extended);
        for (_, part) in self.parts.iter().filter(|(m, _)| m >> k & 1 == 1) {
            region.merge(part)?;
        }
        Ok(region)
    }
}

/// Fewest active held-out samples per fold for a gain where a candidate acts: the NRMSE
/// there normalises by the output's range over those samples (none for one sample), and
/// an RMSE from n samples is known to about 1/√(2n) (10 % at 50).
pub const MIN_ACTIVE_SAMPLES: u64 = 50;

/// The held-out statistics of one local candidate over the cross-validation folds.
#[derive(Debug, Clone)]
pub struct LocalFolds {
    /// Candidate index.
    pub candidate: usize,
    /// The ordinary training statistics with held-out statistics of the active samples.
    pub folds: Folds,
    /// Active held-out samples over all held-out samples.
    pub share: f64,
}

impl LocalFolds {
    /// `tests[j]` the active held-out samples of fold j of `folds`. The folds with at
    /// least [`MIN_ACTIVE_SAMPLES`] of them are kept (a contiguous block of one log may
    /// lie wholly where the effect does not act, e.g. the climb-out after a low flight);
    /// `None` when no fold has that many (the gain there cannot be measured).
    pub fn new(candidate: usize, folds: &Folds, tests: Vec<Accumulator>) -> Option<Self> {
        if tests.len() != folds.len() {
            return None;
        }
        let active: u64 = tests.iter().map(Accumulator::count).sum();
        let share = active as f64 / folds.test_samples().max(1) as f64;
        let (keep, tests): (Vec<usize>, Vec<Accumulator>) = tests
            .into_iter()
            .enumerate()
            .filter(|(_, t)| t.count() >= MIN_ACTIVE_SAMPLES)
            .unzip();
        if keep.is_empty() {
            return None;
        }
        Some(Self {
            candidate,
            folds: folds.subset_with_tests(&keep, tests)?,
            share,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::ModelOptions;
    use crate::sim::test_matrix::{Design, Ranges, sweep};
    use crate::sim::{Effects, RotorFile, TruthModel};
    use crate::vehicle::Vehicle;

    /// `n` samples of a Latin-hypercube sweep of the shipped quadrotor× (no effects) and
    /// its Eq. 22 structure.
    fn quad_x_sweep(n: usize, seed: u64) -> (SampleChunk, ModelStructure) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let v = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).unwrap();
        let effects = Effects::new(Vec::new(), &v).unwrap();
        let truth = TruthModel::new(&v, &RotorFile::default(), effects).unwrap();
        let ranges = Ranges::scaled_to(&truth);
        let all = sweep(&truth, &ranges, Design::LatinHypercube, n, seed);
        (all, ModelStructure::eq22(&v, ModelOptions::default()))
    }

    #[test]
    fn a_fold_with_fewer_than_the_minimum_active_samples_has_no_local_gain() {
        let (all, s) = quad_x_sweep(200, 1);
        let first = |n: usize| {
            let mut c = SampleChunk::default();
            c.extend_from(&all, 0..n);
            let mut a = Accumulator::new(&s);
            a.push(&s, &c, &mut Workspace::default()).unwrap();
            a
        };
        let folds = Folds::holdout("held out", first(200), first(100));
        let n = MIN_ACTIVE_SAMPLES as usize;
        // One sample short: the gain where the candidate acts is not measured (a
        // single active sample gave an infinite NRMSE, range 0, before the minimum).
        assert!(LocalFolds::new(0, &folds, vec![first(n - 1)]).is_none());
        let local = LocalFolds::new(0, &folds, vec![first(n)]).expect("enough samples");
        assert_eq!(local.share, n as f64 / 100.0);
        // Two folds, the effect acting in the first only (a block of the log wholly
        // outside its region): judged on that fold alone, its share over both.
        let two = Folds::from_folds(vec![
            ("a".into(), first(200), first(100)),
            ("b".into(), first(200), first(100)),
        ]);
        let empty = Accumulator::new(&s);
        let local = LocalFolds::new(0, &two, vec![first(n), empty]).expect("one fold acts");
        assert_eq!(local.folds.len(), 1);
        assert_eq!(local.share, n as f64 / 200.0);
    }

    /// A region's statistics merged from the activity patterns it acts in equal those of
    /// its own samples pushed directly, to rounding (the same rows in another order).
    #[test]
    fn a_region_merged_from_its_patterns_equals_its_samples_pushed_directly() {
        let (all, s) = quad_x_sweep(300, 2);
        let mut ws = Workspace::default();
        s.assemble(&all, &mut ws).unwrap();
        // Three regions over the samples: even i, i a multiple of 3, i ≥ 200.
        let acts = |i: usize| [i.is_multiple_of(2), i.is_multiple_of(3), i >= 200];
        let pattern = |i: usize| (0..3).map(|k| u64::from(acts(i)[k]) << k).sum::<u64>();
        let mut parts = ActivityParts::default();
        let mut part_ws = Workspace::default();
        for m in 1..8u64 {
            let rows: Vec<usize> = (0..all.len()).filter(|&i| pattern(i) == m).collect();
            let acc = parts.part(m, &s);
            ws.gather(&all, &rows, acc.stored_columns(), &mut part_ws);
            acc.push_assembled(&part_ws).unwrap();
        }
        for k in 0..3 {
            let merged = parts.region(k, &s).unwrap();
            let rows: Vec<usize> = (0..all.len()).filter(|&i| acts(i)[k]).collect();
            let mut direct = Accumulator::new(&s);
            ws.gather(&all, &rows, direct.stored_columns(), &mut part_ws);
            direct.push_assembled(&part_ws).unwrap();
            assert_eq!(merged.count(), rows.len() as u64);
            let q = direct.rows();
            let scale = (0..q).map(|i| direct.r(i, i).abs()).fold(0.0, f64::max);
            for i in 0..q {
                for j in i..q {
                    let (a, b) = (merged.r(i, j), direct.r(i, j));
                    assert!(
                        (a - b).abs() <= 1e-12 * scale,
                        "region {k}, R[{i}, {j}]: {a} vs {b}"
                    );
                }
            }
        }
    }

    /// Rows folded straight from the assembled chunk give the statistics of the same
    /// rows gathered and pushed, bit for bit; a non-finite value is refused alike.
    #[test]
    fn rows_pushed_from_the_assembly_equal_the_rows_gathered_and_pushed() {
        let (all, s) = quad_x_sweep(300, 4);
        let mut ws = Workspace::default();
        s.assemble(&all, &mut ws).unwrap();
        let (mut gathered, mut direct) = (Accumulator::new(&s), Accumulator::new(&s));
        let mut part_ws = Workspace::default();
        for rows in [vec![0, 3, 4, 299], (10..200).step_by(3).collect(), vec![7]] {
            ws.gather(&all, &rows, gathered.stored_columns(), &mut part_ws);
            gathered.push_assembled(&part_ws).unwrap();
            direct.push_rows(&ws, &all, &rows).unwrap();
            assert_eq!(direct, gathered);
        }
        let mut bad = all.clone();
        bad.velocity[0][5] = f64::NAN;
        s.assemble(&bad, &mut ws).unwrap();
        let rows = vec![2, 5, 9];
        ws.gather(&bad, &rows, gathered.stored_columns(), &mut part_ws);
        let refused = gathered.push_assembled(&part_ws).unwrap_err();
        assert_eq!(direct.push_rows(&ws, &bad, &rows).unwrap_err(), refused);
        assert_eq!(direct, gathered, "nothing taken in");
    }

    #[test]
    fn a_sample_s_pattern_has_a_bit_for_each_region_at_or_above_its_threshold() {
        let ground = [0.0, 0.02, -0.01, 0.005, 0.0, 0.5];
        let wake = [0.3, 0.0, 0.1, 0.0, 0.0, -0.3];
        // |value| ≥ 0.01 (bit 0) and ≥ 0.1 (bit 1): the threshold itself acts.
        let patterns = activity_patterns(&[&ground, &wake], &[0.01, 0.1]);
        assert_eq!(patterns, vec![0b10, 0b01, 0b11, 0, 0, 0b11]);
    }
}
