//! Cross-validation from mergeable statistics (beyond the seed): every modelling decision
//! is scored on data the model was not fitted on. With two or more logs each log is
//! predicted by the model fitted on the others (leave one log out, Morelli's
//! "confirmation data" applied to every log in turn); with one log, each of its contiguous
//! blocks by the model fitted on the rest of the log less a guard beside the block
//! ([`Folds::from_folds`]).
//!
//! A fold is a pair of [`Accumulator`]s (training and test statistics), so a trial model
//! is a column subset of each ([`Folds::select`]) and no trial re-reads the data. The
//! per-fold prediction errors are kept as [`ErrorSums`], which pool into the metrics of
//! all held-out predictions laid end to end.

use super::inference::{ErrorSums, error_sums};
use super::{AxisMetrics, EstimateError, FitOptions, SingularValues, theta_only};
use crate::model::ModelStructure;
use crate::sample::Axis;
use crate::stats::{AccumulateError, Accumulator};

/// Training and test statistics of each fold.
#[derive(Debug, Clone)]
pub struct Folds {
    /// Name of each fold's test data (a log's file name, or a block of a single log).
    pub names: Vec<String>,
    train: Vec<Accumulator>,
    test: Vec<Accumulator>,
}

impl Folds {
    /// Leave one out over `parts` (one named accumulator per log, at least two): fold j
    /// tests on part j and trains on all the others merged in order.
    pub fn leave_one_out(parts: &[(String, Accumulator)]) -> Result<Self, AccumulateError> {
        let mut train = Vec::with_capacity(parts.len());
        for j in 0..parts.len() {
            let mut others = parts.iter().enumerate().filter(|(i, _)| *i != j);
            let Some((_, first)) = others.next() else {
                continue;
            };
            let mut acc = first.1.clone();
            for (_, (_, a)) in others {
                acc.merge(a)?;
            }
            train.push(acc);
        }
        Ok(Self {
            names: parts.iter().map(|(n, _)| n.clone()).collect(),
            train,
            test: parts.iter().map(|(_, a)| a.clone()).collect(),
        })
    }

    /// One fold: train on `train`, test on `test` (e.g. a sweep's last points).
    pub fn holdout(name: &str, train: Accumulator, test: Accumulator) -> Self {
        Self {
            names: vec![name.to_string()],
            train: vec![train],
            test: vec![test],
        }
    }

    /// Folds of their own (name, training, test) statistics each: e.g. the contiguous
    /// blocks of a single log, each tested on its block and trained on the rest of the
    /// log less the guards beside it.
    pub fn from_folds(folds: Vec<(String, Accumulator, Accumulator)>) -> Self {
        let mut out = Self {
            names: Vec::with_capacity(folds.len()),
            train: Vec::with_capacity(folds.len()),
            test: Vec::with_capacity(folds.len()),
        };
        for (name, train, test) in folds {
            out.names.push(name);
            out.train.push(train);
            out.test.push(test);
        }
        out
    }

    /// Number of folds.
    pub fn len(&self) -> usize {
        self.test.len()
    }

    /// True without folds.
    pub fn is_empty(&self) -> bool {
        self.test.is_empty()
    }

    /// The folds over the structure's columns `columns` only (see [`Accumulator::select`]).
    pub fn select(&self, columns: &[usize]) -> Folds {
        Folds {
            names: self.names.clone(),
            train: self.train.iter().map(|a| a.select(columns)).collect(),
            test: self.test.iter().map(|a| a.select(columns)).collect(),
        }
    }

    /// The folds whose indices are in `keep` (in that order), other test statistics
    /// `test` (one per kept fold): the folds where a local effect acts.
    pub fn subset_with_tests(&self, keep: &[usize], test: Vec<Accumulator>) -> Option<Folds> {
        (test.len() == keep.len() && keep.iter().all(|&j| j < self.len())).then(|| Folds {
            names: keep.iter().map(|&j| self.names[j].clone()).collect(),
            train: keep.iter().map(|&j| self.train[j].clone()).collect(),
            test,
        })
    }

    /// Training samples of all folds.
    pub fn train_samples(&self) -> u64 {
        self.train.iter().map(Accumulator::count).sum()
    }

    /// Test samples of all folds.
    pub fn test_samples(&self) -> u64 {
        self.test.iter().map(Accumulator::count).sum()
    }
}

/// Held-out prediction errors of one structure over the folds.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossValidation {
    /// Per fold, per axis.
    pub folds: Vec<[ErrorSums; 6]>,
    /// All folds pooled, per axis.
    pub pooled: [ErrorSums; 6],
}

impl CrossValidation {
    /// Metrics of all held-out predictions pooled.
    pub fn pooled_metrics(&self) -> [AxisMetrics; 6] {
        self.pooled.map(|s| s.metrics())
    }

    /// Metrics of fold `j`.
    pub fn fold_metrics(&self, j: usize) -> [AxisMetrics; 6] {
        self.folds[j].map(|s| s.metrics())
    }

    /// Per axis, the mean over folds of each fold's NRMSE: every held-out log counts
    /// the same, whatever its length and the size of its loads (a pooled figure is
    /// dominated by the most aggressive log).
    pub fn balanced_nrmse(&self) -> [f64; 6] {
        let k = self.folds.len().max(1) as f64;
        std::array::from_fn(|a| self.folds.iter().map(|f| f[a].metrics().nrmse).sum::<f64>() / k)
    }
}

/// Fits `structure` on each fold's training statistics and scores it on the fold's test
/// statistics.
pub fn cross_validate(
    structure: &ModelStructure,
    folds: &Folds,
    options: &FitOptions,
) -> Result<CrossValidation, EstimateError> {
    let mut pooled = Axis::ALL.map(ErrorSums::empty);
    let mut per_fold = Vec::with_capacity(folds.len());
    for (train, test) in folds.train.iter().zip(&folds.test) {
        // Only the estimates are used: no condition numbers, no t-tests.
        let theta = theta_only(structure, train, options, SingularValues::WhenRankInDoubt)?;
        let sums = error_sums(structure, &theta, test)?;
        for (p, s) in pooled.iter_mut().zip(&sums) {
            p.add(s);
        }
        per_fold.push(sums);
    }
    Ok(CrossValidation {
        folds: per_fold,
        pooled,
    })
}
