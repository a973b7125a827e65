//! Forward selection ordering algorithm (seed Algorithm 1, Tables 2–3), on the
//! accumulated statistics.
//!
//! Each iteration scores every remaining candidate x by R²(I ∪ {x}) and adds the best.
//! Nothing is refitted: the candidates and the output live as m-vectors in the space of
//! the accumulated factor R (isometric to the data's column space), and each chosen
//! column is orthogonalised once (modified Gram–Schmidt, reorthogonalised) and swept out
//! of the rest, so the residual sum of squares with candidate x added is
//! ‖z⊥‖² − (x⊥ᵀz⊥)²/‖x⊥‖².
//!
//! Beyond the seed, each step carries the partial F statistic of the added term and
//! Morelli's predicted squared error PSE = SSE/N + σ²_max p/N, σ²_max = Σ(z − z̄)²/N
//! (Morelli & Klein 2016, stepwise regression), which mark where terms stop paying.

use serde::Serialize;
use statrs::distribution::FisherSnedecor;

use super::EstimateError;
use super::lstsq::{self, SingularValues};
use super::ols::{compressed, term_name};
use crate::model::ModelStructure;
use crate::sample::Axis;
use crate::stats::Accumulator;
use crate::util::dot;

/// A candidate whose part orthogonal to the chosen terms has norm below this fraction of
/// its own norm adds nothing the data can distinguish (aliased).
const ALIAS_TOL: f64 = 1e-10;

/// One FSOA iteration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FsoaStep {
    /// R²(I ∪ {x}) for every candidate x, indexed like [`FsoaTable::terms`]; `None` for
    /// terms already in the model.
    pub r2: Vec<Option<f64>>,
    /// Index (into [`FsoaTable::terms`]) of the term added.
    pub chosen: usize,
    /// R² after adding it (centred; may be negative).
    pub r2_chosen: f64,
    /// Partial F of the added term: (SSE_before − SSE_after)/(SSE_after/(N − j)).
    pub partial_f: f64,
    /// P-value of the partial F, F(1, N − j) survival function.
    pub partial_f_p_value: f64,
    /// Predicted squared error after adding it, (N or N m)².
    pub pse: f64,
    /// True when the term adds nothing the data can separate from earlier terms.
    pub aliased: bool,
}

/// The FSOA table of one axis (seed Tables 2–3) with the stopping rules.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FsoaTable {
    /// Output axis.
    pub axis: Axis,
    /// Candidate terms, `param (label)`, in the structure's column order.
    pub terms: Vec<String>,
    /// Column indices (into `ModelStructure::columns`) of the candidates.
    pub columns: Vec<usize>,
    /// One step per iteration.
    pub steps: Vec<FsoaStep>,
    /// Number of leading terms at the PSE minimum.
    pub pse_terms: usize,
    /// Number of leading terms whose partial F is at least F_in.
    pub f_in_terms: usize,
    /// F_in used for `f_in_terms`.
    pub f_in: f64,
}

impl FsoaTable {
    /// The table of no steps, before Algorithm 1 has run.
    pub(crate) fn empty(axis: Axis, f_in: f64) -> Self {
        Self {
            axis,
            terms: Vec::new(),
            columns: Vec::new(),
            steps: Vec::new(),
            pse_terms: 0,
            f_in_terms: 0,
            f_in,
        }
    }

    /// Candidate indices in the order chosen.
    pub fn order(&self) -> Vec<usize> {
        self.steps.iter().map(|s| s.chosen).collect()
    }
}

/// Runs Algorithm 1 for `axis` over its columns in `structure`.
pub fn fsoa(
    structure: &ModelStructure,
    acc: &Accumulator,
    axis: Axis,
    f_in: f64,
) -> Result<FsoaTable, EstimateError> {
    let columns: Vec<usize> = structure.axis_columns(axis).collect();
    let terms: Vec<String> = columns.iter().map(|&c| term_name(structure, c)).collect();
    let n = acc.count() as f64;
    if n <= columns.len() as f64 {
        return Err(EstimateError::TooFewSamples {
            samples: acc.count(),
            parameters: columns.len(),
        });
    }
    let (x, z) = compressed(acc, &columns, axis);
    let k = columns.len();
    let mut cand: Vec<Vec<f64>> = (0..k).map(|j| normalised(x.col(j).iter())).collect();
    let mut zp = z;
    let sst = acc.output_centred_ss(axis);
    let sigma2_max = sst / n;
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut remaining: Vec<usize> = (0..k).collect();
    let mut steps = Vec::new();
    let mut sse_prev = dot(&zp, &zp);
    while !remaining.is_empty() {
        let mut r2 = vec![None; k];
        let mut best: Option<(usize, f64)> = None;
        for &c in &remaining {
            let nc = dot(&cand[c], &cand[c]);
            let sse = if nc > ALIAS_TOL * ALIAS_TOL {
                (sse_prev - dot(&cand[c], &zp).powi(2) / nc).max(0.0)
            } else {
                sse_prev
            };
            r2[c] = Some(1.0 - sse / sst);
            if best.is_none_or(|(_, s)| sse < s) {
                best = Some((c, sse));
            }
        }
        let (chosen, _) = best.expect("remaining is not empty");
        remaining.retain(|&c| c != chosen);
        let mut q = cand[chosen].clone();
        let aliased = dot(&q, &q).sqrt() <= ALIAS_TOL;
        if !aliased {
            // Reorthogonalise the chosen vector against the basis ("twice is enough").
            for b in &basis {
                let proj = dot(b, &q);
                axpy(&mut q, -proj, b);
            }
            let nq = dot(&q, &q).sqrt();
            q.iter_mut().for_each(|v| *v /= nq);
            let proj = dot(&q, &zp);
            axpy(&mut zp, -proj, &q);
            for &c in &remaining {
                let proj = dot(&q, &cand[c]);
                axpy(&mut cand[c], -proj, &q);
            }
            basis.push(q);
        }
        let sse = dot(&zp, &zp);
        let j = steps.len() + 1;
        let dof = n - j as f64;
        let (partial_f, partial_f_p_value) = partial_f(sse_prev, sse, dof);
        steps.push(FsoaStep {
            r2,
            chosen,
            r2_chosen: 1.0 - sse / sst,
            partial_f,
            partial_f_p_value,
            pse: sse / n + sigma2_max * j as f64 / n,
            aliased,
        });
        sse_prev = sse;
    }
    let pse_terms = steps
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.pse.total_cmp(&b.1.pse))
        .map_or(0, |(i, _)| i + 1);
    let f_in_terms = steps.iter().take_while(|s| s.partial_f >= f_in).count();
    Ok(FsoaTable {
        axis,
        terms,
        columns,
        steps,
        pse_terms,
        f_in_terms,
        f_in,
    })
}

/// What adding one candidate column to a set of columns of one axis buys, computed from
/// an accumulator that holds the candidate (e.g. after `ModelStructure::add_parameter`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Addition {
    /// Centred R² without the candidate.
    pub r2_before: f64,
    /// Centred R² with the candidate.
    pub r2_after: f64,
    /// Partial F of the candidate.
    pub partial_f: f64,
    /// P-value of the partial F.
    pub p_value: f64,
    /// PSE without the candidate.
    pub pse_before: f64,
    /// PSE with the candidate.
    pub pse_after: f64,
}

/// Scores adding column `candidate` to columns `base` of `axis` (partial F, PSE, R²),
/// by two small QR solves on the accumulated factor.
pub fn score_addition(
    acc: &Accumulator,
    axis: Axis,
    base: &[usize],
    candidate: usize,
) -> Result<Addition, EstimateError> {
    let n = acc.count() as f64;
    let k = base.len() + 1;
    if n <= k as f64 {
        return Err(EstimateError::TooFewSamples {
            samples: acc.count(),
            parameters: k,
        });
    }
    let sse_of = |cols: &[usize]| -> Result<f64, EstimateError> {
        if cols.is_empty() {
            let z = acc.r_column(acc.output_index(axis));
            return Ok(dot(&z, &z));
        }
        let (x, z) = compressed(acc, cols, axis);
        lstsq::solve(&x, &z, ALIAS_TOL, SingularValues::Always)
            .map(|ls| ls.sse)
            .map_err(|d| EstimateError::Unidentifiable {
                problem: format!("candidate scoring {axis}"),
                parameters: d
                    .conditioning
                    .involved(ALIAS_TOL)
                    .iter()
                    .map(|&j| acc.label(cols[j]).to_string())
                    .collect(),
                condition_number: d.conditioning.condition_number(),
            })
    };
    let before = sse_of(base)?;
    let mut with: Vec<usize> = base.to_vec();
    with.push(candidate);
    let after = sse_of(&with)?;
    let sst = acc.output_centred_ss(axis);
    let (f, p) = partial_f(before, after, n - k as f64);
    Ok(Addition {
        r2_before: 1.0 - before / sst,
        r2_after: 1.0 - after / sst,
        partial_f: f,
        p_value: p,
        pse_before: before / n + sst / n * (k - 1) as f64 / n,
        pse_after: after / n + sst / n * k as f64 / n,
    })
}

/// Partial F of one added term and its P-value (F(1, dof) survival function).
fn partial_f(sse_before: f64, sse_after: f64, dof: f64) -> (f64, f64) {
    let gain = (sse_before - sse_after).max(0.0);
    if sse_after <= 0.0 {
        return if gain > 0.0 {
            (f64::INFINITY, 0.0)
        } else {
            (0.0, 1.0)
        };
    }
    let f = gain / (sse_after / dof);
    let p = FisherSnedecor::new(1.0, dof).map_or(f64::NAN, |d| crate::util::survival(&d, f));
    (f, p)
}

fn normalised<'a>(v: impl Iterator<Item = &'a f64>) -> Vec<f64> {
    let v: Vec<f64> = v.copied().collect();
    let n = dot(&v, &v).sqrt();
    if n > 0.0 {
        v.iter().map(|x| x / n).collect()
    } else {
        v
    }
}

fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    y.iter_mut().zip(x).for_each(|(y, x)| *y += a * x);
}
