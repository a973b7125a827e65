//! Columns assembled from columns assembled before them.
//!
//! A candidate effect that scales each rotor's thrust by a signal (its wake, vortex-ring
//! or ground factor) has, rotor by rotor, the terms of that rotor's thrust column with
//! one more factor: seven products of three signals per rotor where one product of two
//! does, `ratio · signal ⊙ (thrust column)`. A rotor's in-plane force on M_z is its
//! F_x and F_y columns times the lever arms: two scaled columns instead of 24 terms.
//! [`plan`] finds such runs of terms once per structure;
//! [`super::ModelStructure::assemble_reusing`] then computes each run as one product.
//! The value is the same sum, added in another order: it differs from the term-by-term
//! assembly by rounding only.

use std::collections::HashMap;

use super::{Column, Signal, Term};

/// A run of a column's terms that equals `ratio · signal ⊙ column` (an earlier column),
/// or `ratio · column` without a signal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Run {
    /// The earlier column (index into the structure's columns).
    pub column: usize,
    /// The factor every term of the run has after that column's factors, if any.
    pub signal: Option<Signal>,
    /// The run's coefficients over that column's.
    pub ratio: f64,
}

/// How a column is assembled from earlier columns: the sum of its runs, plus the terms no
/// run covers.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Reuse {
    /// At least one run.
    pub runs: Vec<Run>,
    /// Indices of the column's terms outside every run.
    pub terms: Vec<usize>,
}

/// For each of `columns`: how it reuses earlier columns, or `None` (assembled term by
/// term). Only columns with `wanted[j]` are planned or reused, so that an assembly of the
/// wanted columns has every column it reads.
pub(crate) fn plan(columns: &[Column], wanted: &[bool]) -> Vec<Option<Reuse>> {
    // Earlier wanted columns of two or more terms, by the factors of their first term.
    let mut by_first: HashMap<&[Signal], Vec<usize>> = HashMap::new();
    columns
        .iter()
        .enumerate()
        .map(|(j, col)| {
            if !wanted[j] {
                return None;
            }
            let reuse = reuse_of(&col.terms, columns, &by_first);
            if col.terms.len() >= 2 {
                by_first.entry(&col.terms[0].factors).or_default().push(j);
            }
            reuse
        })
        .collect()
}

/// The runs of `terms` over earlier columns (`by_first`), when there is one.
fn reuse_of(
    terms: &[Term],
    columns: &[Column],
    by_first: &HashMap<&[Signal], Vec<usize>>,
) -> Option<Reuse> {
    let (mut runs, mut rest) = (Vec::new(), Vec::new());
    let mut pos = 0;
    while pos < terms.len() {
        match run_at(terms, pos, columns, by_first) {
            Some((run, len)) => {
                runs.push(run);
                pos += len;
            }
            None => {
                rest.push(pos);
                pos += 1;
            }
        }
    }
    (!runs.is_empty()).then_some(Reuse { runs, terms: rest })
}

/// The run starting at `terms[pos]` and its length: the terms of an earlier column, as
/// they are or each times the last factor of `terms[pos]`, with proportional
/// coefficients (to rounding, as [`crate::stats`] tells columns of one shape).
fn run_at(
    terms: &[Term],
    pos: usize,
    columns: &[Column],
    by_first: &HashMap<&[Signal], Vec<usize>>,
) -> Option<(Run, usize)> {
    let factors = &terms[pos].factors;
    let as_they_are = (None, factors.as_slice());
    let times_last = factors.split_last().map(|(&s, head)| (Some(s), head));
    [Some(as_they_are), times_last]
        .into_iter()
        .flatten()
        .find_map(|(signal, head)| {
            by_first.get(head)?.iter().find_map(|&r| {
                let base = &columns[r].terms;
                let ratio = proportional(terms.get(pos..pos + base.len())?, base, signal)?;
                let run = Run {
                    column: r,
                    signal,
                    ratio,
                };
                Some((run, base.len()))
            })
        })
}

/// f with `run[k]` = f · `base[k]` · `signal` for every k (to rounding).
fn proportional(run: &[Term], base: &[Term], signal: Option<Signal>) -> Option<f64> {
    let ratio = run[0].coef / base[0].coef;
    let same = run.iter().zip(base).all(|(t, b)| {
        let factors = match signal {
            Some(s) => t.factors.split_last() == Some((&s, b.factors.as_slice())),
            None => t.factors == b.factors,
        };
        factors && (t.coef - ratio * b.coef).abs() <= 1e-14 * t.coef.abs()
    });
    (same && ratio.is_finite() && ratio != 0.0).then_some(ratio)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{ModelOptions, ModelStructure, ParamId, Parameter, Workspace, term};
    use crate::sample::{Axis, Sample, SampleChunk};

    /// A column made of an earlier column's terms times a signal (a rotor's thrust times
    /// its wake factor), or of an earlier column's terms as they are (M_z from the F_x and
    /// F_y in-plane force columns), is assembled from that column, with the same values to
    /// rounding; a run whose coefficients are not proportional, or an earlier column not
    /// assembled, is not reused.
    #[test]
    fn columns_reusing_earlier_columns_assemble_to_rounding() {
        use Signal::*;
        let v = crate::model::test_quad();
        let mut s = ModelStructure::eq22(&v, ModelOptions::default());
        let column = |label: &str, terms: Vec<Term>| Column {
            axis: Axis::Fz,
            param: ParamId::default(),
            label: label.into(),
            terms,
        };
        let a = vec![term(2.0, &[U, W]), term(3.0, &[V])];
        let times_p = vec![term(4.0, &[U, W, P]), term(6.0, &[V, P]), term(1.5, &[Q])];
        let scaled = vec![term(0.7, &[R]), term(-1.0, &[U, W]), term(-1.5, &[V])];
        let not_proportional = vec![term(4.0, &[U, W, P]), term(7.0, &[V, P])];
        let param = s.add_parameter(
            Parameter {
                name: "x".into(),
                unit: "-".into(),
            },
            vec![
                column("a", a),
                column("a*p + q", times_p),
                column("r - a/2", scaled),
                column("not a*p", not_proportional),
            ],
        );
        let first = (0..s.columns.len())
            .find(|&j| s.columns[j].param == param)
            .expect("the added columns");
        let all = vec![true; s.columns.len()];
        let plan = s.reuse_plan(&all);
        let run = |signal, ratio| Run {
            column: first,
            signal,
            ratio,
        };
        let reuse = |runs, terms| {
            Some(Reuse {
                runs: vec![runs],
                terms,
            })
        };
        assert_eq!(plan[first + 1], reuse(run(Some(P), 2.0), vec![2]));
        assert_eq!(plan[first + 2], reuse(run(None, -0.5), vec![0]));
        assert_eq!(plan[first + 3], None);
        let mut without_a = all.clone();
        without_a[first] = false;
        assert_eq!(s.reuse_plan(&without_a)[first + 1], None);

        let mut chunk = SampleChunk::with_capacity(4, 64, true);
        for k in 0..64 {
            let f = k as f64;
            chunk.push(&Sample {
                velocity: [0.3 * f - 7.1, 1.0 / (f + 3.0), (0.1 * f).sin()],
                rates: [0.01 * f - 0.2, (0.2 * f).cos(), -0.5],
                omega: vec![400.0 + 3.7 * f; 4],
                omega_dot: vec![1.0; 4],
                ..Sample::default()
            });
        }
        let (mut terms, mut reused) = (Workspace::default(), Workspace::default());
        s.assemble(&chunk, &mut terms).unwrap();
        s.assemble_reusing(&chunk, &mut reused, &all, &plan)
            .unwrap();
        for (j, how) in plan.iter().enumerate() {
            let (x, y) = (terms.column(j), reused.column(j));
            // The same terms summed in another order: a few roundings of the largest.
            let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..64 {
                assert!(
                    (x[k] - y[k]).abs() <= 8.0 * f64::EPSILON * scale,
                    "column {j}, sample {k}"
                );
            }
            if how.is_none() {
                assert_eq!(x, y, "column {j} is assembled term by term");
            }
        }
    }
}
