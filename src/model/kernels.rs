//! The assembly kernels: the regressor columns of one chunk from the signal values,
//! term by term, as fused pairs, or from earlier columns ([`Reuse`]), in loops written
//! for vector lanes (run under [`crate::util::vectorized`]).

use super::reuse::Reuse;
use super::signals::{Column, Signal, Term};

/// The regressor columns of one chunk, as one operation for [`crate::util::vectorized`].
pub(super) struct AssembleColumns<'c, 'a, L: Fn(Signal) -> &'a [f64]> {
    /// The structure's columns.
    pub(super) columns: &'c [Column],
    /// The columns to assemble (all when `None`).
    pub(super) wanted: Option<&'c [bool]>,
    /// How each column reuses earlier ones (none when empty).
    pub(super) plan: &'c [Option<Reuse>],
    /// Column j at `j * cap`, `n` samples.
    pub(super) dst: &'c mut [f64],
    pub(super) cap: usize,
    pub(super) n: usize,
    /// The `n` values of a signal.
    pub(super) lookup: &'c L,
}

impl<'a, L: Fn(Signal) -> &'a [f64]> pulp::WithSimd for AssembleColumns<'_, 'a, L> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let (cap, n) = (self.cap, self.n);
        for (j, col) in self.columns.iter().enumerate() {
            if self.wanted.is_some_and(|w| !w[j]) {
                continue;
            }
            let (done, todo) = self.dst.split_at_mut(j * cap);
            let dst = &mut todo[..n];
            if let Some(Some(reuse)) = self.plan.get(j) {
                let earlier = |c: usize| &done[c * cap..c * cap + n];
                apply_reuse(dst, reuse, &col.terms, earlier, self.lookup);
            } else if !apply_pair_terms(dst, &col.terms, self.lookup) {
                for (i, t) in col.terms.iter().enumerate() {
                    apply_term(dst, t, i == 0, 1.0, self.lookup);
                }
            }
        }
    }
}

/// Columns of two or three terms that are each a product of two signals (the inflow
/// corrections, the yaw-moment drag terms) in one fused pass; false when the column has
/// another shape.
#[inline(always)]
fn apply_pair_terms<'a>(
    dst: &mut [f64],
    terms: &[Term],
    lookup: &impl Fn(Signal) -> &'a [f64],
) -> bool {
    if !(2..=3).contains(&terms.len()) || terms.iter().any(|t| t.factors.len() != 2) {
        return false;
    }
    let pair = |t: &Term| (t.coef, lookup(t.factors[0]), lookup(t.factors[1]));
    let (c0, a0, b0) = pair(&terms[0]);
    let (c1, a1, b1) = pair(&terms[1]);
    let f01 = a0.iter().zip(b0).zip(a1.iter().zip(b1));
    if let Some(t2) = terms.get(2) {
        let (c2, a2, b2) = pair(t2);
        for ((d, ((x0, y0), (x1, y1))), (x2, y2)) in dst.iter_mut().zip(f01).zip(a2.iter().zip(b2))
        {
            *d = c0 * x0 * y0 + c1 * x1 * y1 + c2 * x2 * y2;
        }
    } else {
        for (d, ((x0, y0), (x1, y1))) in dst.iter_mut().zip(f01) {
            *d = c0 * x0 * y0 + c1 * x1 * y1;
        }
    }
    true
}

/// `dst = Σ runs ratio · [signal ⊙] earlier(column) + Σ other terms` ([`Reuse`] of the
/// column of `terms`; `earlier(c)` the assembled column c).
#[inline(always)]
fn apply_reuse<'a, 'e>(
    dst: &mut [f64],
    reuse: &Reuse,
    terms: &[Term],
    earlier: impl Fn(usize) -> &'e [f64],
    lookup: &impl Fn(Signal) -> &'a [f64],
) {
    for (k, run) in reuse.runs.iter().enumerate() {
        let (x, c) = (earlier(run.column), run.ratio);
        match (run.signal.map(lookup), k == 0) {
            (Some(y), true) => zip2(dst, x, y, |a, b| c * a * b),
            (Some(y), false) => zip2_add(dst, x, y, |a, b| c * a * b),
            (None, true) => zip1(dst, x, |a| c * a),
            (None, false) => zip1_add(dst, x, |a| c * a),
        }
    }
    for &t in &reuse.terms {
        apply_term(dst, &terms[t], false, 1.0, lookup);
    }
}

/// `dst (=|+=) scale · coef · Π factors`, one vectorisable loop per term.
#[inline(always)]
pub(super) fn apply_term<'a>(
    dst: &mut [f64],
    t: &Term,
    first: bool,
    scale: f64,
    lookup: &impl Fn(Signal) -> &'a [f64],
) {
    let c = scale * t.coef;
    match (t.factors.as_slice(), first) {
        ([], true) => dst.fill(c),
        ([], false) => dst.iter_mut().for_each(|d| *d += c),
        ([a], true) => zip1(dst, lookup(*a), |x| c * x),
        ([a], false) => zip1_add(dst, lookup(*a), |x| c * x),
        ([a, b], true) => zip2(dst, lookup(*a), lookup(*b), |x, y| c * x * y),
        ([a, b], false) => zip2_add(dst, lookup(*a), lookup(*b), |x, y| c * x * y),
        // Three factors (candidate effects, e.g. a rotor's thrust term times its wake
        // factor): one pass, the same products as the pairwise fold below.
        ([a, b, f], true) => zip3(dst, [lookup(*a), lookup(*b), lookup(*f)], false, c),
        ([a, b, f], false) => zip3(dst, [lookup(*a), lookup(*b), lookup(*f)], true, c),
        ([a, b, rest @ ..], _) => {
            // Four or more factors: fold pairwise (rare).
            if first {
                zip2(dst, lookup(*a), lookup(*b), |x, y| c * x * y);
                for f in rest {
                    zip1_mul(dst, lookup(*f));
                }
            } else {
                let mut tmp: Vec<f64> = lookup(*a)
                    .iter()
                    .zip(lookup(*b))
                    .map(|(x, y)| c * x * y)
                    .collect();
                for f in rest {
                    zip1_mul(&mut tmp, lookup(*f));
                }
                dst.iter_mut().zip(&tmp).for_each(|(d, t)| *d += t);
            }
        }
    }
}

#[inline(always)]
fn zip1(dst: &mut [f64], a: &[f64], f: impl Fn(f64) -> f64) {
    dst.iter_mut().zip(a).for_each(|(d, &x)| *d = f(x));
}

#[inline(always)]
fn zip1_add(dst: &mut [f64], a: &[f64], f: impl Fn(f64) -> f64) {
    dst.iter_mut().zip(a).for_each(|(d, &x)| *d += f(x));
}

#[inline(always)]
fn zip1_mul(dst: &mut [f64], a: &[f64]) {
    dst.iter_mut().zip(a).for_each(|(d, &x)| *d *= x);
}

#[inline(always)]
fn zip2(dst: &mut [f64], a: &[f64], b: &[f64], f: impl Fn(f64, f64) -> f64) {
    dst.iter_mut()
        .zip(a.iter().zip(b))
        .for_each(|(d, (&x, &y))| *d = f(x, y));
}

#[inline(always)]
fn zip2_add(dst: &mut [f64], a: &[f64], b: &[f64], f: impl Fn(f64, f64) -> f64) {
    dst.iter_mut()
        .zip(a.iter().zip(b))
        .for_each(|(d, (&x, &y))| *d += f(x, y));
}

/// `dst (=|+=) ((c·x)·y)·z` over the three factor slices.
#[inline(always)]
fn zip3(dst: &mut [f64], [a, b, f]: [&[f64]; 3], add: bool, c: f64) {
    let factors = a.iter().zip(b).zip(f);
    if add {
        for (d, ((&x, &y), &z)) in dst.iter_mut().zip(factors) {
            *d += c * x * y * z;
        }
    } else {
        for (d, ((&x, &y), &z)) in dst.iter_mut().zip(factors) {
            *d = c * x * y * z;
        }
    }
}
