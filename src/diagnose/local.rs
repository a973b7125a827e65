//! Where a candidate acts: effects confined to part of the envelope (near the ground, in
//! the wake of other rotors, in descent near the hover inflow speed) are judged on the
//! held-out samples where they act, not diluted over a whole log.
//!
//! A candidate with an [`Activity`] gets a second set of held-out statistics, accumulated
//! over only the samples where its activity signal reaches the threshold; its validation
//! gain is then measured there ([`LocalFolds`]), with the training statistics of the
//! ordinary folds.

use crate::estimate::Folds;
use crate::model::{Column, ModelStructure, Parameter, Term, Workspace};
use crate::sample::{Axis, SampleChunk};
use crate::stats::{AccumulateError, Accumulator};

use super::candidates::Candidate;

/// The part of the envelope where a candidate acts: samples whose activity (a sum of
/// signal products, dimensionless) reaches `threshold`.
#[derive(Debug, Clone, PartialEq)]
pub struct Activity {
    /// Activity signal of one sample, e.g. the Cheeseman–Bennett thrust gain.
    pub terms: Vec<Term>,
    /// Smallest activity that counts as acting.
    pub threshold: f64,
}

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
    /// geometry for the signals.
    pub fn new(base: &ModelStructure, candidates: &[Candidate]) -> Self {
        let mut activity = base.select_columns(&[]);
        let mut regions = Vec::new();
        let mut thresholds = Vec::new();
        for (c, cand) in candidates.iter().enumerate() {
            let Some(a) = &cand.activity else { continue };
            let column = Column {
                axis: Axis::Fx,
                param: 0,
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

    /// One empty accumulator over `extended` per region.
    pub fn accumulators(&self, extended: &ModelStructure) -> Vec<Accumulator> {
        self.candidates
            .iter()
            .map(|_| Accumulator::new(extended))
            .collect()
    }

    /// Pushes the samples of `chunk` where each region's candidate acts into that
    /// region's accumulator in `into` (one per region, from [`Self::accumulators`]).
    /// `assembled` must hold `chunk` as those accumulators' `push` assembles it: the active rows are gathered from it rather
    /// than assembled again (every regressor is a function of its own sample, so this is
    /// the same as assembling the active part). `active_ws` takes the activity signals,
    /// `part_ws` the gathered rows (both reused across chunks).
    pub fn push(
        &self,
        chunk: &SampleChunk,
        assembled: &Workspace,
        into: &mut [Accumulator],
        active_ws: &mut Workspace,
        part_ws: &mut Workspace,
    ) -> Result<(), AccumulateError> {
        if self.is_empty() || chunk.is_empty() {
            return Ok(());
        }
        self.activity
            .assemble(chunk, active_ws)
            .map_err(AccumulateError::from)?;
        let mut rows = Vec::with_capacity(chunk.len());
        for (k, acc) in into.iter_mut().enumerate() {
            active_rows(active_ws.column(k), self.thresholds[k], &mut rows);
            if !rows.is_empty() {
                assembled.gather(chunk, &rows, acc.stored_columns(), part_ws);
                acc.push_assembled(part_ws)?;
            }
        }
        Ok(())
    }
}

/// The indices (in order) of the samples whose activity `values` reach `threshold`.
fn active_rows(values: &[f64], threshold: f64, rows: &mut Vec<usize>) {
    rows.clear();
    rows.extend((0..values.len()).filter(|&i| values[i].abs() >= threshold));
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
    /// `tests[j]` the active held-out samples of fold j of `folds`; `None` when a fold
    /// has fewer than [`MIN_ACTIVE_SAMPLES`] (the gain there cannot be measured).
    pub fn new(candidate: usize, folds: &Folds, tests: Vec<Accumulator>) -> Option<Self> {
        if tests.iter().any(|t| t.count() < MIN_ACTIVE_SAMPLES) {
            return None;
        }
        let active: u64 = tests.iter().map(Accumulator::count).sum();
        let share = active as f64 / folds.test_samples().max(1) as f64;
        Some(Self {
            candidate,
            folds: folds.with_tests(tests)?,
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

    #[test]
    fn a_fold_with_fewer_than_the_minimum_active_samples_has_no_local_gain() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let v = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).unwrap();
        let effects = Effects::new(Vec::new(), &v).unwrap();
        let truth = TruthModel::new(&v, &RotorFile::default(), effects).unwrap();
        let all = sweep(
            &truth,
            &Ranges::scaled_to(&truth),
            Design::LatinHypercube,
            200,
            1,
        );
        let s = ModelStructure::eq22(&v, ModelOptions::default());
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
    }

    #[test]
    fn the_active_rows_are_the_samples_at_or_above_the_threshold_in_order() {
        let values = [0.0, 0.02, -0.01, 0.005, 0.0, 0.5];
        let mut rows = vec![9];
        active_rows(&values, 0.01, &mut rows);
        // |value| ≥ 0.01: samples 1, 2 (a run) and 5 (at the end).
        assert_eq!(rows, vec![1, 2, 5]);
        active_rows(&values, 1.0, &mut rows);
        assert!(rows.is_empty());
    }
}
