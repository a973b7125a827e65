//! The generic pool: residual structure that no named effect explains.
//!
//! The pool holds every monomial of degree 0 to 3 in the body velocities u, v, w, the
//! rates p, q, r and the virtual actuators δt, δa, δe, δr (Eq. 21), and the rotor-local
//! products s · Σ_i w_i Ω_i² and s · Σ_i w_i Ω̇_i, s ∈ {1, u, v, w, p, q, r} and w_i a row of
//! the mixing matrix (Eq. 20: 1/N, −y_i, x_i, −σ_i; Ω̇ only when the data has it): 286 +
//! 56 = 342 monomials per axis, 2052 hypotheses in all. (Σ_i w_i s Ω_i is s times a
//! virtual actuator, already in the first part.) Accumulating them all next to the named
//! candidates would
//! multiply the cost of the streaming statistics by ~50, so the pool is *screened* on a
//! decimated sample of the fit data held in memory:
//!
//! 1. per axis, the Eq. 22 columns and every named candidate's columns are
//!    orthonormalised (Gram–Schmidt, twice) and the output is projected off them;
//! 2. each monomial g is scored by the residual-sum-of-squares drop it would bring,
//!    (gᵀr)² / ‖g − QQᵀg‖² (a partial F with one degree of freedom);
//! 3. the best monomial is kept when it is significant at α over the whole pool
//!    (Bonferroni over 1716 tests) and cuts the residual sum of squares by at least
//!    `min_drop`; it joins the basis, and the axis is screened again, up to
//!    `per_axis` monomials.
//!
//! Survivors become ordinary candidates of kind [`EffectKind::Generic`] (role
//! [`Role::Generic`]): they are accumulated over the full data with the named candidates
//! and must pass the same significance, plausibility and validation tests, after every
//! named candidate that passes (named effects are preferred whenever they explain as
//! much).
//!
//! Each survivor's column is the monomial divided by its RMS on the screening sample, so
//! its parameter reads in the axis unit: the load at one RMS of the monomial.

use super::candidate::{Candidate, CandidateParameter, EffectKind, Role};
use crate::model::{
    Column, ModelError, ModelStructure, ParamId, Parameter, Signal, Workspace, term,
};
use crate::sample::{Axis, SampleChunk};
use crate::util::{dot, map_on_threads};

/// The pool's variables: states and virtual actuators.
const VARIABLES: [(Signal, &str); 10] = [
    (Signal::U, "u"),
    (Signal::V, "v"),
    (Signal::W, "w"),
    (Signal::P, "p"),
    (Signal::Q, "q"),
    (Signal::R, "r"),
    (Signal::Dt, "dt"),
    (Signal::Da, "da"),
    (Signal::De, "de"),
    (Signal::Dr, "dr"),
];

/// Rotor-local sums: δ² (Eq. 19, Σ w_i Ω_i²) and δ̇ (Σ w_i Ω̇_i) of each mixing row.
const ROTOR_SUMS: [(Signal, &str); 8] = [
    (Signal::D2t, "d2t"),
    (Signal::D2a, "d2a"),
    (Signal::D2e, "d2e"),
    (Signal::D2r, "d2r"),
    (Signal::ActuatorRate(0), "dt_dot"),
    (Signal::ActuatorRate(1), "da_dot"),
    (Signal::ActuatorRate(2), "de_dot"),
    (Signal::ActuatorRate(3), "dr_dot"),
];

/// Samples of the fit data the pipeline keeps in memory for screening (~4 MB for a quad).
pub const SCREENING_SAMPLES: usize = 20_000;

/// Highest monomial degree in the pool.
pub const MAX_DEGREE: usize = 3;

/// Thresholds of the screening.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScreeningOptions {
    /// Family-wise significance level over the whole pool (all axes).
    pub alpha: f64,
    /// Smallest relative drop of the axis's residual sum of squares worth keeping.
    pub min_drop: f64,
    /// Most monomials kept per axis.
    pub per_axis: usize,
    /// Threads the axes are screened on (the survivors do not depend on it).
    pub threads: usize,
}

impl Default for ScreeningOptions {
    fn default() -> Self {
        Self {
            alpha: 0.01,
            min_drop: 0.05,
            per_axis: 2,
            threads: 1,
        }
    }
}

/// Every monomial of the pool as its factors: the polynomial part (degree ≤
/// [`MAX_DEGREE`], variables in non-decreasing order, the constant first), then the
/// rotor-local products.
pub fn monomials() -> Vec<Vec<Signal>> {
    let mut out = vec![Vec::new()];
    let mut frontier: Vec<Vec<usize>> = vec![Vec::new()];
    for _ in 0..MAX_DEGREE {
        let mut next = Vec::new();
        for m in &frontier {
            let start = m.last().copied().unwrap_or(0);
            for v in start..VARIABLES.len() {
                let mut n: Vec<usize> = m.clone();
                n.push(v);
                next.push(n);
            }
        }
        out.extend(
            next.iter()
                .map(|m| m.iter().map(|&v| VARIABLES[v].0).collect()),
        );
        frontier = next;
    }
    for (sum, _) in ROTOR_SUMS {
        out.push(vec![sum]);
        out.extend(VARIABLES[..6].iter().map(|&(s, _)| vec![s, sum]));
    }
    out
}

/// Number of hypotheses the pool tests (monomials × axes): the Bonferroni divisor.
pub fn pool_size() -> usize {
    monomials().len() * Axis::ALL.len()
}

fn label(m: &[Signal]) -> String {
    if m.is_empty() {
        return "1".into();
    }
    m.iter()
        .map(|s| {
            VARIABLES
                .iter()
                .chain(&ROTOR_SUMS)
                .find(|(v, _)| v == s)
                .map_or("?", |(_, name)| name)
        })
        .collect::<Vec<_>>()
        .join("*")
}

/// Monomials evaluated at once while screening: memory holds this many columns of the
/// screening sample (at most 16 × 20 000 × 8 B = 2.6 MB), not the whole pool (342
/// columns: up to 55 MB).
const MONOMIAL_BLOCK: usize = 16;

/// The pool evaluated on the screening sample one block of monomials at a time (each
/// column is assembled on its own, so a block gives the values the whole pool would).
struct MonomialBlocks<'d> {
    /// One structure per block, with one column per monomial.
    blocks: Vec<ModelStructure>,
    data: &'d SampleChunk,
    ws: Workspace,
}

impl<'d> MonomialBlocks<'d> {
    fn new(like: &ModelStructure, pool: &[Vec<Signal>], data: &'d SampleChunk) -> Self {
        let blocks = pool
            .chunks(MONOMIAL_BLOCK)
            .map(|block| {
                let (mut s, _) = like.subset(&[]);
                for m in block {
                    let column = Column {
                        axis: Axis::Fx,
                        param: ParamId::default(),
                        label: label(m),
                        terms: vec![term(1.0, m)],
                    };
                    let name = format!("m{}", s.params.len());
                    let unit = "-".into();
                    s.add_parameter(Parameter { name, unit }, vec![column]);
                }
                s
            })
            .collect();
        Self {
            blocks,
            data,
            ws: Workspace::default(),
        }
    }

    /// Calls `f(j, values of monomial j)` for every monomial, in pool order.
    fn for_each(&mut self, mut f: impl FnMut(usize, &[f64])) -> Result<(), ModelError> {
        for (b, block) in self.blocks.iter().enumerate() {
            block.assemble(self.data, &mut self.ws)?;
            for k in 0..block.columns.len() {
                f(b * MONOMIAL_BLOCK + k, self.ws.column(k));
            }
        }
        Ok(())
    }

    /// The values of monomial `j`.
    fn values(&mut self, j: usize) -> Result<Vec<f64>, ModelError> {
        let block = &self.blocks[j / MONOMIAL_BLOCK];
        block.assemble(self.data, &mut self.ws)?;
        Ok(self.ws.column(j % MONOMIAL_BLOCK).to_vec())
    }
}

/// Orthonormal basis of columns added one at a time (Gram–Schmidt, applied twice).
struct Basis {
    q: Vec<Vec<f64>>,
}

impl Basis {
    /// Adds `x`'s component orthogonal to the basis, unless it is (numerically) inside.
    fn add(&mut self, x: &[f64]) {
        let norm0 = dot(x, x).sqrt();
        if norm0 == 0.0 || !norm0.is_finite() {
            return;
        }
        let mut v = x.to_vec();
        for _ in 0..2 {
            for q in &self.q {
                let c = dot(q, &v);
                v.iter_mut().zip(q).for_each(|(a, b)| *a -= c * b);
            }
        }
        let norm = dot(&v, &v).sqrt();
        if norm > 1e-9 * norm0 {
            v.iter_mut().for_each(|a| *a /= norm);
            self.q.push(v);
        }
    }

    /// `x` minus its projection on the basis.
    fn residual(&self, x: &[f64]) -> Vec<f64> {
        let mut v = x.to_vec();
        for _ in 0..2 {
            for q in &self.q {
                let c = dot(q, &v);
                v.iter_mut().zip(q).for_each(|(a, b)| *a -= c * b);
            }
        }
        v
    }

    /// ‖x − QQᵀx‖² computed as ‖x‖² − ‖Qᵀx‖², floored at zero, and ‖x‖², for the `x`
    /// whose [`Projection`] is `known`: only the basis vectors added since `known` was
    /// last brought up to date are projected on (the sum of squares keeps its order, so
    /// the value is that of projecting on the whole basis at once).
    fn orthogonal_norm2(&self, x: &[f64], known: &mut Projection) -> (f64, f64) {
        let xx = *known.xx.get_or_insert_with(|| dot(x, x));
        for q in &self.q[known.basis..] {
            known.sum += dot(q, x).powi(2);
        }
        known.basis = self.q.len();
        ((xx - known.sum).max(0.0), xx)
    }
}

/// What [`Basis::orthogonal_norm2`] has computed of one vector x: ‖x‖² and ‖Qᵀx‖² over
/// the first `basis` vectors of the basis.
#[derive(Debug, Clone, Copy)]
struct Projection {
    xx: Option<f64>,
    /// Σ (qᵀx)² in basis order, from −0 as `f64`'s `Sum` starts.
    sum: f64,
    basis: usize,
}

impl Projection {
    const NONE: Self = Self {
        xx: None,
        sum: -0.0,
        basis: 0,
    };
}

/// One monomial kept by the screening.
#[derive(Debug, Clone, PartialEq)]
pub struct Screened {
    /// Axis it acts on.
    pub axis: Axis,
    /// The monomial, e.g. `u*q*dt`.
    pub label: String,
    /// Relative drop of the axis's residual sum of squares on the screening sample.
    pub drop: f64,
    /// Bonferroni-corrected P-value of the partial F test on the screening sample.
    pub p: f64,
    /// RMS of the monomial on the screening sample (its column is divided by it).
    pub rms: f64,
    factors: Vec<Signal>,
}

/// Screens the pool against the residual of `extended` (the base structure with every
/// named candidate added) on `data`; returns the survivors, best first per axis.
pub fn screen(
    extended: &ModelStructure,
    data: &SampleChunk,
    options: &ScreeningOptions,
) -> Result<Vec<Screened>, ModelError> {
    let needs_omega_dot = |m: &Vec<Signal>| m.iter().any(|s| matches!(s, Signal::ActuatorRate(_)));
    let pool: Vec<Vec<Signal>> = monomials()
        .into_iter()
        .filter(|m| data.omega_dot.is_some() || !needs_omega_dot(m))
        .collect();
    let tests = (pool.len() * Axis::ALL.len()) as f64;
    let per_axis = map_on_threads(&Axis::ALL, options.threads, |&axis| {
        screen_axis(extended, data, &pool, axis, tests, options)
    });
    let mut out = Vec::new();
    for survivors in per_axis {
        out.extend(survivors?);
    }
    Ok(out)
}

/// The screening of one axis: up to [`ScreeningOptions::per_axis`] monomials of `pool`,
/// chosen one at a time by the largest drop of the residual sum of squares of the axis's
/// own columns and the monomials before, while significant over `tests` tests.
fn screen_axis(
    extended: &ModelStructure,
    data: &SampleChunk,
    pool: &[Vec<Signal>],
    axis: Axis,
    tests: f64,
    options: &ScreeningOptions,
) -> Result<Vec<Screened>, ModelError> {
    let n = data.len();
    let mut ws = Workspace::default();
    let mut monomials = MonomialBlocks::new(extended, pool, data);
    let mut out = Vec::new();
    // This axis's columns only: memory holds one axis's share of the regressors.
    let columns: Vec<usize> = extended.axis_columns(axis).collect();
    let on_axis = extended.select_columns(&columns);
    on_axis.assemble(data, &mut ws)?;
    let mut basis = Basis { q: Vec::new() };
    for j in 0..columns.len() {
        basis.add(ws.column(j));
    }
    let mut r = basis.residual(ws.output(axis));
    // The basis only grows: each monomial's projection is extended, never recomputed.
    let mut known = vec![Projection::NONE; pool.len()];
    for _ in 0..options.per_axis {
        let sse = dot(&r, &r);
        let dof = n as f64 - basis.q.len() as f64 - 1.0;
        if dof < 1.0 || sse <= 0.0 {
            break;
        }
        // The largest gain (the last of equal ones), over monomials that are not
        // already in the span of the basis.
        let mut best: Option<(usize, f64)> = None;
        monomials.for_each(|j, g| {
            let (g2, gg) = basis.orthogonal_norm2(g, &mut known[j]);
            if g2 > 1e-9 * gg {
                let gain = dot(g, &r).powi(2) / g2;
                if best.is_none_or(|(_, b)| gain.total_cmp(&b).is_ge()) {
                    best = Some((j, gain));
                }
            }
        })?;
        let Some((j, gain)) = best else { break };
        let f = gain / ((sse - gain).max(f64::MIN_POSITIVE) / dof);
        let p = (f_survival(f, dof) * tests).min(1.0);
        let drop = gain / sse;
        if !(p < options.alpha && drop >= options.min_drop) {
            break;
        }
        let g = &monomials.values(j)?;
        out.push(Screened {
            axis,
            label: label(&pool[j]),
            drop,
            p,
            rms: (dot(g, g) / n as f64).sqrt(),
            factors: pool[j].clone(),
        });
        basis.add(g);
        r = basis.residual(&r);
    }
    Ok(out)
}

/// P(F(1, dof) > f).
fn f_survival(f: f64, dof: f64) -> f64 {
    use statrs::distribution::FisherSnedecor;
    FisherSnedecor::new(1.0, dof).map_or(1.0, |d| crate::util::survival(&d, f))
}

impl Screened {
    /// The survivor as a candidate effect of kind [`EffectKind::Generic`].
    pub fn candidate(&self) -> Candidate {
        let name = format!("generic {} {}", self.axis, self.label);
        let parameter = CandidateParameter::new(
            format!("g_{}_{}", self.axis, self.label.replace('*', "_")),
            self.axis.unit(),
            vec![Column {
                axis: self.axis,
                param: ParamId::default(),
                label: format!("{}/{:.4e}", self.label, self.rms),
                terms: vec![term(1.0 / self.rms, &self.factors)],
            }],
        );
        Candidate::new(
            EffectKind::Generic,
            Role::Generic,
            name,
            "Residual structure no named effect explains: a product of states, virtual actuators and rotor-local sums, estimated as the load at one RMS of the product.",
            vec![parameter],
        )
    }
}

/// Keeps every `stride`-th sample of a stream, at most about `cap`: when the kept set
/// outgrows `cap` every other kept sample is dropped and the stride doubles, so the
/// sample stays evenly spread over the whole stream whatever its length.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Thinned {
    chunk: SampleChunk,
    cap: usize,
    stride: u64,
    seen: u64,
}

impl Thinned {
    /// An empty sample holding at most `cap` (≥ 2) samples.
    pub fn new(cap: usize) -> Self {
        Self {
            chunk: SampleChunk::default(),
            cap: cap.max(2),
            stride: 1,
            seen: 0,
        }
    }

    /// Offers every sample of `c` in order.
    pub fn push(&mut self, c: &SampleChunk) {
        // The samples kept, gathered at once (one copy per signal, not per sample) up to
        // the one that overfills the set, which is thinned before the next is kept.
        let mut rows = Vec::new();
        for k in 0..c.len() {
            if self.seen.is_multiple_of(self.stride) {
                rows.push(k);
                if self.chunk.len() + rows.len() > self.cap {
                    self.keep(c, &mut rows);
                    self.halve();
                }
            }
            self.seen += 1;
        }
        self.keep(c, &mut rows);
    }

    /// Appends the samples `rows` of `c` (emptied).
    fn keep(&mut self, c: &SampleChunk, rows: &mut Vec<usize>) {
        if rows.is_empty() {
            return;
        }
        if self.chunk.is_empty() {
            self.chunk = SampleChunk::with_capacity(c.rotor_count(), 0, false);
        }
        self.chunk.extend_from_rows(c, rows);
        rows.clear();
    }

    fn halve(&mut self) {
        self.chunk = keep_every(&self.chunk, 2);
        self.stride *= 2;
    }

    /// Appends `later` (a later stream) at a common stride, then thins to `cap`.
    pub fn merge(&mut self, later: &Thinned) {
        if later.chunk.is_empty() {
            return;
        }
        let mut later = later.clone();
        while later.stride < self.stride {
            later.halve();
        }
        while self.stride < later.stride {
            self.halve();
        }
        if self.chunk.is_empty() {
            self.chunk = later.chunk;
        } else {
            self.chunk.extend_from(&later.chunk, 0..later.chunk.len());
        }
        self.seen += later.seen;
        while self.chunk.len() > self.cap {
            self.halve();
        }
    }

    /// True when it could have been made by [`Thinned::new`] with `cap` and pushes of
    /// samples of `rotors` rotors (a deserialised one may not be: a zero stride or cap
    /// would never finish thinning).
    pub fn is_consistent(&self, cap: usize, rotors: usize) -> bool {
        self.cap == cap
            && self.stride.is_power_of_two()
            && self.chunk.len() <= cap
            && self.chunk.check_lengths().is_ok()
            && (self.chunk.is_empty() || self.chunk.rotor_count() == rotors)
    }

    /// The kept samples.
    pub fn samples(&self) -> &SampleChunk {
        &self.chunk
    }
}

fn keep_every(c: &SampleChunk, every: usize) -> SampleChunk {
    let mut out = SampleChunk::with_capacity(c.rotor_count(), 0, false);
    let rows: Vec<usize> = (0..c.len()).step_by(every).collect();
    out.extend_from_rows(c, &rows);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pool_counts_every_monomial_of_degree_three_or_less() {
        // C(10 + 3, 3) = 286 monomials of degree ≤ 3 in 10 variables, then 8 rotor-local
        // sums alone and times each of the 6 states.
        let m = monomials();
        assert_eq!(m.len(), 286 + 8 * 7);
        assert_eq!(pool_size(), 6 * 342);
        let mut sorted = m.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), 342, "no monomial twice");
    }

    #[test]
    fn a_thinned_sample_with_a_zero_stride_or_another_cap_is_not_consistent() {
        // A zero stride never doubles and a zero cap never stops halving: a
        // deserialised sample like that would hang the merge, so parts refuse it.
        let mut t = Thinned::new(8);
        t.push(&ramp(20, 0));
        assert!(t.is_consistent(8, 4));
        assert!(!t.is_consistent(16, 4), "another cap");
        assert!(!t.is_consistent(8, 6), "another rotor count");
        let zero = Thinned {
            stride: 0,
            ..t.clone()
        };
        assert!(!zero.is_consistent(8, 4));
    }

    fn ramp(n: usize, offset: usize) -> SampleChunk {
        let mut c = SampleChunk::with_capacity(4, n, false);
        for k in 0..n {
            c.t.push((offset + k) as f64);
            for a in 0..3 {
                c.velocity[a].push(0.0);
                c.rates[a].push(0.0);
                c.wrench[a].push(0.0);
                c.wrench[a + 3].push(0.0);
            }
            for w in &mut c.omega {
                w.push(0.0);
            }
        }
        c
    }

    #[test]
    fn thinning_keeps_an_even_spread_within_the_cap() {
        let mut t = Thinned::new(100);
        for c in 0..10 {
            t.push(&ramp(97, c * 97));
        }
        // 970 samples, cap 100: stride 16 keeps 61 samples, at times 0, 16, 32, …
        let s = t.samples();
        assert_eq!(s.len(), 61);
        assert!(s.t.iter().enumerate().all(|(i, &x)| x == (16 * i) as f64));
        // Merging a second stream at its own stride brings both to the coarser one.
        let mut u = Thinned::new(100);
        u.push(&ramp(40, 970));
        t.merge(&u);
        assert_eq!(t.samples().len(), 61 + 3);
        assert_eq!(t.samples().t[61..], [970.0, 986.0, 1002.0]);
        // An empty stream (a validation-only log) leaves the sample as it is.
        t.merge(&Thinned::new(100));
        assert_eq!((t.samples().len(), t.samples().rotor_count()), (64, 4));
    }
}
