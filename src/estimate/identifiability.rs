//! Identifiability: which parameters the data cannot separate, found from the SVD of the
//! equilibrated design, and what was done about them (refuse, or drop them explicitly).
//! No estimate is ever computed from a system whose equilibrated design has
//! σ_min ≤ `rank_tol` σ_max.

use faer::Mat;
use serde::Serialize;

use super::lstsq::{self, LeastSquares, SingularValues};
use super::{EstimateError, FitOptions, UnidentifiablePolicy};
use crate::model::{ModelStructure, Signal};
use crate::stats::Accumulator;

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
    /// The other terms with weight ≥ 0.1 in the near-null singular directions at the
    /// time (empty when the term's own regressor is zero in every sample).
    pub aliased_with: Vec<String>,
    /// Why it cannot be identified when it is aliased with nothing: its regressor is
    /// zero in every sample, e.g. `u = v = 0 throughout: no in-plane motion`.
    pub cause: Option<String>,
    /// Condition number of the equilibrated design before dropping.
    pub condition_number: f64,
}

/// What [`solve_identifiable`] knows of the columns of a design besides their data.
pub(crate) struct DesignTerms<'a> {
    /// Name of each column.
    pub names: Vec<String>,
    /// For each column, other columns whose span holds it by construction (empty when
    /// none): the first column of its shape in the statistics, or columns whose terms
    /// are its terms one by one. It can never be separated from them.
    pub spanned_by: Vec<Vec<usize>>,
    /// Why column j is zero in every sample.
    pub zero_cause: &'a dyn Fn(usize) -> String,
}

impl<'a> DesignTerms<'a> {
    /// Terms `names`, none known to lie in the span of others.
    pub fn distinct(names: Vec<String>, zero_cause: &'a dyn Fn(usize) -> String) -> Self {
        let spanned_by = vec![Vec::new(); names.len()];
        Self {
            names,
            spanned_by,
            zero_cause,
        }
    }
}

/// Solves min ‖X θ − z‖ over the columns of `x` (described by `terms`). When the
/// equilibrated design is numerically singular, either refuses (error naming the involved
/// terms) or drops the term with the largest weight in the weakest direction and retries,
/// per `options`. When dropping, a term whose column is zero goes first, with its cause,
/// then a term in the span of others by construction, aliased with them (condition
/// number infinite, no SVD needed). Returns the solution, the indices of the kept columns and
/// the report (its condition number NaN when `singular_values` let the solve skip them).
pub(crate) fn solve_identifiable(
    problem: &str,
    x: &Mat<f64>,
    z: &[f64],
    terms: &DesignTerms,
    options: &FitOptions,
    singular_values: SingularValues,
) -> Result<(LeastSquares, Vec<usize>, ProblemConditioning), EstimateError> {
    let names = &terms.names;
    let mut kept: Vec<usize> = (0..x.ncols()).collect();
    let mut dropped = Vec::new();
    if options.unidentifiable == UnidentifiablePolicy::Drop {
        // A regressor that is zero in every sample is dropped first, with its cause: it
        // is not "aliased" with the other zero columns, it carries nothing.
        kept.retain(|&j| {
            let zero = x.col(j).iter().all(|&v| v == 0.0);
            if zero {
                dropped.push(DroppedTerm {
                    name: names[j].clone(),
                    aliased_with: Vec::new(),
                    cause: Some((terms.zero_cause)(j)),
                    condition_number: f64::INFINITY,
                });
            }
            !zero
        });
        // Zero columns dropped above are left out of a span: the rest still spans the
        // column (and a column spanned by zero columns alone is zero: dropped above).
        let is_kept = |j: usize, kept: &[usize]| kept.binary_search(&j).is_ok();
        for j in kept.clone() {
            let span: Vec<usize> = terms.spanned_by[j]
                .iter()
                .copied()
                .filter(|&i| is_kept(i, &kept))
                .collect();
            if span.is_empty() {
                continue;
            }
            dropped.push(DroppedTerm {
                name: names[j].clone(),
                aliased_with: span.iter().map(|&i| names[i].clone()).collect(),
                cause: None,
                condition_number: f64::INFINITY,
            });
            kept.retain(|&i| i != j);
        }
    }
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
        let sub;
        let design = if kept.len() == x.ncols() {
            x
        } else {
            sub = Mat::from_fn(x.nrows(), kept.len(), |i, j| x[(i, kept[j])]);
            &sub
        };
        match lstsq::solve(design, z, options.rank_tol, singular_values) {
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
                // A rank-deficient design has at least one column, so a weakest direction.
                let worst = c.worst().unwrap_or(0);
                let name = names[kept[worst]].clone();
                let aliased_with: Vec<String> =
                    involved.into_iter().filter(|n| *n != name).collect();
                let cause = aliased_with
                    .is_empty()
                    .then(|| (terms.zero_cause)(kept[worst]));
                dropped.push(DroppedTerm {
                    name,
                    aliased_with,
                    cause,
                    condition_number: c.condition_number(),
                });
                kept.remove(worst);
            }
        }
    }
}

/// Motion variables u, v, w, p, q, r, in [`Accumulator::motion_range`] order.
const MOTION: [&str; 6] = ["u", "v", "w", "p", "q", "r"];

/// The motion variables (indices into [`MOTION`]) all of which being zero makes `signal`
/// zero (V_h = 0 needs u = v = 0).
fn motion_of(signal: Signal) -> &'static [usize] {
    use Signal::*;
    match signal {
        U | AbsU => &[0],
        V | AbsV => &[1],
        Vh | UOverVh | VOverVh => &[0, 1],
        W | AbsW => &[2],
        P => &[3],
        Q => &[4],
        R => &[5],
        _ => &[],
    }
}

/// Why the regressor columns `columns` of `structure` are zero in every sample of
/// `acc`: when every term has a factor whose motion variables were zero throughout
/// (from the logged ranges), those variables and what motion was absent
/// (`u = v = 0 throughout: no in-plane motion`); else the columns themselves.
pub(crate) fn zero_column_cause(
    structure: &ModelStructure,
    acc: &Accumulator,
    columns: &[usize],
) -> String {
    let zero = |k: usize| acc.motion_range(k) == (0.0, 0.0);
    let mut vars: Vec<usize> = Vec::new();
    let explained = columns.iter().all(|&c| {
        structure.columns[c].terms.iter().all(|t| {
            let cause = t
                .factors
                .iter()
                .map(|&f| motion_of(f))
                .find(|m| !m.is_empty() && m.iter().all(|&k| zero(k)));
            if let Some(m) = cause {
                vars.extend(m);
            }
            cause.is_some()
        })
    });
    if !explained || vars.is_empty() {
        let labels: Vec<&str> = columns
            .iter()
            .map(|&c| structure.columns[c].label.as_str())
            .collect();
        return format!("regressor {} is zero in every sample", labels.join(", "));
    }
    vars.sort_unstable();
    vars.dedup();
    let what = if vars.iter().all(|&k| k < 2) {
        "no in-plane motion"
    } else if vars == [2] {
        "no vertical motion"
    } else if vars.iter().all(|&k| k >= 3) {
        "no rotation"
    } else {
        "no excitation"
    };
    let names: Vec<&str> = vars.iter().map(|&k| MOTION[k]).collect();
    format!("{} = 0 throughout: {what}", names.join(" = "))
}
