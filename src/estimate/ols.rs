//! Per-axis ordinary least squares (seed Eq. 23): z_i = X_i θ_i + v_i, each axis on its
//! own columns, every column a separate regressor (a parameter shared between axes is
//! estimated once per axis here; the MMR joins them).

use faer::Mat;
use serde::Serialize;

use super::identifiability::{
    DesignTerms, ProblemConditioning, solve_identifiable, zero_column_cause,
};
use super::lstsq::SingularValues;
use super::{EstimateError, FitOptions};
use crate::model::ModelStructure;
use crate::sample::Axis;
use crate::stats::Accumulator;

/// The OLS fit of one axis with all its identifiable columns.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisOls {
    /// Output axis.
    pub axis: Axis,
    /// Indices into `ModelStructure::columns` of the columns kept in the fit.
    pub columns: Vec<usize>,
    /// `param (label)` of each kept column.
    pub terms: Vec<String>,
    /// Estimates, one per kept column (units of the parameter).
    pub theta: Vec<f64>,
    /// Standard errors √(σ̂² (XᵀX)⁻¹_jj), white-residual assumption.
    pub std_error: Vec<f64>,
    /// (XᵀX)⁻¹ over the kept columns, row-major; the white-residual covariance of θ̂ is
    /// σ̂² (XᵀX)⁻¹.
    pub xtx_inv: Vec<f64>,
    /// Residual sum of squares, (N or N m)².
    pub sse: f64,
    /// Residual variance σ̂² = SSE / (N − p_i), (N or N m)². The seed divides by N − 1;
    /// N − p_i is unbiased and the two agree for N ≫ p_i.
    pub residual_variance: f64,
    /// Residual degrees of freedom N − p_i.
    pub dof: f64,
    /// Centred R² = 1 − SSE/Σ(z − z̄)² (no intercept in the model; may be negative).
    pub r2: f64,
}

impl AxisOls {
    /// Weights w over the augmented columns [X | Z] with A w = residual z − X θ̂.
    pub fn residual_weights(&self, acc: &Accumulator) -> Vec<f64> {
        let mut w = vec![0.0; acc.m()];
        for (&c, &t) in self.columns.iter().zip(&self.theta) {
            w[c] = -t;
        }
        w[acc.output_index(self.axis)] = 1.0;
        w
    }
}

/// Term name used in reports: `param (label)`.
pub(crate) fn term_name(structure: &ModelStructure, column: usize) -> String {
    let c = &structure.columns[column];
    format!("{} ({})", structure.param(c.param).name, c.label)
}

/// For each of the columns `cols` (one axis), the others that span it by construction:
/// the first earlier column of its shape in `acc` (a twin, e.g. a parameter untied on
/// this axis), or, for a column of several terms, single-term columns with each of its
/// terms' factors (e.g. a centre-of-gravity offset h × the F_y model beside the h × F_y
/// terms of M_x). A column that spans others is never itself spanned, so they cannot all
/// be dropped.
fn spanned_by(structure: &ModelStructure, acc: &Accumulator, cols: &[usize]) -> Vec<Vec<usize>> {
    let twin = |j: usize| (0..j).find(|&i| acc.shape_of(cols[i]) == acc.shape_of(cols[j]));
    let terms = |j: usize| &structure.columns[cols[j]].terms;
    let single = |i: usize| twin(i).is_none() && terms(i).len() == 1;
    (0..cols.len())
        .map(|j| {
            if let Some(i) = twin(j) {
                return vec![i];
            }
            if terms(j).len() < 2 {
                return Vec::new();
            }
            let basis = |t: &crate::model::Term| {
                (0..cols.len()).find(|&i| i != j && single(i) && terms(i)[0].factors == t.factors)
            };
            let mut span: Vec<usize> = match terms(j).iter().map(basis).collect() {
                Some(span) => span,
                None => return Vec::new(),
            };
            span.sort_unstable();
            span.dedup();
            span
        })
        .collect()
}

/// The compressed design F[:, cols] (q × k) and target F[:, z_axis] of a column subset.
pub(crate) fn compressed(acc: &Accumulator, cols: &[usize], axis: Axis) -> (Mat<f64>, Vec<f64>) {
    let mut x = Mat::zeros(acc.rows(), cols.len());
    for (j, &c) in cols.iter().enumerate() {
        acc.write_r_column(c, x.col_as_slice_mut(j));
    }
    let z = acc.r_column(acc.output_index(axis));
    (x, z)
}

/// OLS of `axis` on all of its columns in `structure`, from the accumulated statistics.
pub fn axis_ols(
    structure: &ModelStructure,
    acc: &Accumulator,
    axis: Axis,
    options: &FitOptions,
) -> Result<(AxisOls, ProblemConditioning), EstimateError> {
    axis_ols_with(structure, acc, axis, options, SingularValues::Always)
}

/// [`axis_ols`], computing the singular values of the design as `singular_values` says.
pub(crate) fn axis_ols_with(
    structure: &ModelStructure,
    acc: &Accumulator,
    axis: Axis,
    options: &FitOptions,
    singular_values: SingularValues,
) -> Result<(AxisOls, ProblemConditioning), EstimateError> {
    let cols: Vec<usize> = structure.axis_columns(axis).collect();
    let names: Vec<String> = cols.iter().map(|&c| term_name(structure, c)).collect();
    let n = acc.count() as f64;
    if n <= cols.len() as f64 {
        return Err(EstimateError::TooFewSamples {
            samples: acc.count(),
            parameters: cols.len(),
        });
    }
    let (x, z) = compressed(acc, &cols, axis);
    let cause = |j: usize| zero_column_cause(structure, acc, &[cols[j]]);
    let terms = DesignTerms {
        spanned_by: spanned_by(structure, acc, &cols),
        names,
        zero_cause: &cause,
    };
    let (ls, kept, report) = solve_identifiable(
        &format!("OLS {axis}"),
        &x,
        &z,
        &terms,
        options,
        singular_values,
    )?;
    let names = terms.names;
    let k = kept.len();
    let dof = n - k as f64;
    let residual_variance = ls.sse / dof;
    let sst = acc.output_centred_ss(axis);
    Ok((
        AxisOls {
            axis,
            columns: kept.iter().map(|&j| cols[j]).collect(),
            terms: kept.iter().map(|&j| names[j].clone()).collect(),
            std_error: (0..k)
                .map(|j| (residual_variance * ls.xtx_inv[j * k + j]).sqrt())
                .collect(),
            theta: ls.theta,
            xtx_inv: ls.xtx_inv,
            sse: ls.sse,
            residual_variance,
            dof,
            r2: 1.0 - ls.sse / sst,
        },
        report,
    ))
}
