//! Identifiability: which parameters the data cannot separate, found from the SVD of the
//! equilibrated design, and what was done about them (refuse, or drop them explicitly).
//! No estimate is ever computed from a system whose equilibrated design has
//! σ_min ≤ `rank_tol` σ_max.

use faer::Mat;
use serde::Serialize;

use super::lstsq::{self, LeastSquares};
use super::{EstimateError, FitOptions, UnidentifiablePolicy};

/// Conditioning of one least-squares problem (a per-axis OLS or the MMR).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProblemConditioning {
    /// Which problem: `OLS Fx` … `OLS Mz`, or `MMR`.
    pub problem: String,
    /// Condition number σ_max/σ_min of the equilibrated design (unit-norm columns) of
    /// the terms finally kept (NaN when none is kept).
    pub condition_number: f64,
    /// Uncentred variance-inflation factor of each kept term, in term order.
    pub vif: Vec<(String, f64)>,
    /// Terms dropped because the data could not separate them, in drop order, each with
    /// the other terms of the near-null direction it was dropped from.
    pub dropped: Vec<DroppedTerm>,
}

/// A term removed because the data cannot identify it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DroppedTerm {
    /// The removed term.
    pub name: String,
    /// All terms with weight ≥ 0.1 in the near-null singular directions at the time.
    pub aliased_with: Vec<String>,
    /// Condition number of the equilibrated design before dropping.
    pub condition_number: f64,
}

/// Solves min ‖X θ − z‖ over the columns of `x` named `names`. When the equilibrated
/// design is numerically singular, either refuses (error naming the involved terms) or
/// drops the term with the largest weight in the weakest direction and retries, per
/// `options`. Returns the solution, the indices of the kept columns and the report.
pub(crate) fn solve_identifiable(
    problem: &str,
    x: &Mat<f64>,
    z: &[f64],
    names: &[String],
    options: &FitOptions,
) -> Result<(LeastSquares, Vec<usize>, ProblemConditioning), EstimateError> {
    let mut kept: Vec<usize> = (0..x.ncols()).collect();
    let mut dropped = Vec::new();
    loop {
        if kept.is_empty() {
            // Every term was dropped: the model of this problem is empty.
            let ls = LeastSquares {
                theta: Vec::new(),
                sse: z.iter().map(|v| v * v).sum(),
                xtx_inv: Vec::new(),
                conditioning: lstsq::conditioning_of(&Mat::zeros(0, 0)),
            };
            let report = ProblemConditioning {
                problem: problem.into(),
                condition_number: f64::NAN,
                vif: Vec::new(),
                dropped,
            };
            return Ok((ls, kept, report));
        }
        let sub = Mat::from_fn(x.nrows(), kept.len(), |i, j| x[(i, kept[j])]);
        match lstsq::solve(&sub, z, options.rank_tol) {
            Ok(ls) => {
                let report = ProblemConditioning {
                    problem: problem.into(),
                    condition_number: ls.conditioning.condition_number(),
                    vif: kept
                        .iter()
                        .zip(&ls.conditioning.vif)
                        .map(|(&j, &v)| (names[j].clone(), v))
                        .collect(),
                    dropped,
                };
                return Ok((ls, kept, report));
            }
            Err(deficient) => {
                let c = &deficient.conditioning;
                let involved: Vec<String> = c
                    .involved(options.rank_tol)
                    .iter()
                    .map(|&j| names[kept[j]].clone())
                    .collect();
                if options.unidentifiable == UnidentifiablePolicy::Refuse {
                    return Err(EstimateError::Unidentifiable {
                        problem: problem.into(),
                        parameters: involved,
                        condition_number: c.condition_number(),
                    });
                }
                let worst = c.worst().expect("non-empty design");
                dropped.push(DroppedTerm {
                    name: names[kept[worst]].clone(),
                    aliased_with: involved,
                    condition_number: c.condition_number(),
                });
                kept.remove(worst);
            }
        }
    }
}
