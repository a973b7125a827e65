//! Assembly: the regressor columns and the known-term-corrected outputs of a chunk, for
//! all columns, the wanted ones, or the wanted ones reusing earlier columns
//! ([`super::reuse`]).

use super::evaluate::signal_slice;
use super::kernels::{AssembleColumns, apply_term};
use super::reuse::{self, Reuse};
use super::{ModelError, ModelStructure, Signal, Workspace};
use crate::sample::{Axis, SampleChunk};
use crate::util::range_of_slice;

impl ModelStructure {
    /// Assembles all regressor columns and the known-term-corrected outputs of `chunk`
    /// into `ws` (column-major, reused across chunks; allocates only when a chunk is
    /// longer than any before).
    pub fn assemble(&self, chunk: &SampleChunk, ws: &mut Workspace) -> Result<(), ModelError> {
        self.assemble_columns(chunk, ws, None, &[])
    }

    /// [`Self::assemble`] of the columns j with `wanted[j]` only (and all outputs); the
    /// other columns of `ws` are left unspecified. For an accumulator, which reads one
    /// column of each shape (`wanted` shorter than the columns assembles them all).
    pub(crate) fn assemble_wanted(
        &self,
        chunk: &SampleChunk,
        ws: &mut Workspace,
        wanted: &[bool],
    ) -> Result<(), ModelError> {
        let wanted = (wanted.len() == self.columns.len()).then_some(wanted);
        self.assemble_columns(chunk, ws, wanted, &[])
    }

    /// How [`Self::assemble_reusing`] computes the columns j with `wanted[j]` (one entry
    /// per column): runs of terms that are an earlier wanted column's terms, as they are
    /// or times one more signal (a rotor's thrust terms times its wake factor), as one
    /// product each.
    pub(crate) fn reuse_plan(&self, wanted: &[bool]) -> Vec<Option<Reuse>> {
        reuse::plan(&self.columns, wanted)
    }

    /// [`Self::assemble_wanted`] by `plan` ([`Self::reuse_plan`] of the same `wanted`):
    /// the same columns to rounding, with fewer products.
    pub(crate) fn assemble_reusing(
        &self,
        chunk: &SampleChunk,
        ws: &mut Workspace,
        wanted: &[bool],
        plan: &[Option<Reuse>],
    ) -> Result<(), ModelError> {
        assert!(
            wanted.len() == self.columns.len() && plan.len() == wanted.len(),
            "a reuse plan of this structure"
        );
        self.assemble_columns(chunk, ws, Some(wanted), plan)
    }

    /// The regressor columns of `chunk` into `ws`, its signals read from `from`, where
    /// `source` last assembled `chunk`, rather than computed again (the same values, so
    /// the same columns as [`Self::assemble`]); only the columns are written (outputs,
    /// measured and motion ranges of `ws` are left unspecified). `None` (nothing
    /// written) unless every signal this structure computes is one `source` computed
    /// (the signals read from the chunk itself are always at hand).
    pub(crate) fn assemble_columns_from(
        &self,
        chunk: &SampleChunk,
        source: &ModelStructure,
        from: &Workspace,
        ws: &mut Workspace,
    ) -> Option<()> {
        let n = chunk.len();
        let slots: Vec<usize> = self
            .required
            .iter()
            .map(|s| match s.is_direct() {
                // Read from the chunk itself.
                true => Some(0),
                false => source.required.binary_search(s).ok(),
            })
            .collect::<Option<_>>()?;
        if from.len() != n {
            return None;
        }
        ws.prepare(n, self.columns.len(), 0);
        let cap = ws.capacity;
        let from_cap = from.capacity;
        let required = &self.required;
        let lookup = |s: Signal| {
            let at = required.binary_search(&s).expect("required signal");
            signal_slice(s, chunk, &from.signals, slots[at] * from_cap, n)
        };
        crate::util::vectorized(AssembleColumns {
            columns: &self.columns,
            wanted: None,
            plan: &[],
            dst: &mut ws.columns,
            cap,
            n,
            lookup: &lookup,
        });
        Some(())
    }

    fn assemble_columns(
        &self,
        chunk: &SampleChunk,
        ws: &mut Workspace,
        wanted: Option<&[bool]>,
        plan: &[Option<Reuse>],
    ) -> Result<(), ModelError> {
        self.check_chunk(chunk)?;
        let n = chunk.len();
        ws.prepare(n, self.columns.len(), self.required.len());
        let cap = ws.capacity;
        for (slot, &s) in self.required.iter().enumerate() {
            if !s.is_direct() {
                let dst = &mut ws.signals[slot * cap..slot * cap + n];
                self.constants.compute(s, chunk, dst);
            }
        }
        let Workspace {
            signals,
            columns,
            outputs,
            measured,
            motion,
            ..
        } = ws;
        let range = |v: &[f64]| range_of_slice(&v[..n.min(v.len())]);
        for k in 0..3 {
            motion[k] = range(&chunk.velocity[k]);
            motion[3 + k] = range(&chunk.rates[k]);
        }
        let required = &self.required;
        let lookup = |s: Signal| {
            let slot = required.binary_search(&s).expect("required signal");
            signal_slice(s, chunk, signals, slot * cap, n)
        };
        crate::util::vectorized(AssembleColumns {
            columns: &self.columns,
            wanted,
            plan,
            dst: columns,
            cap,
            n,
            lookup: &lookup,
        });
        for axis in Axis::ALL {
            let a = axis as usize;
            let dst = &mut outputs[a * cap..a * cap + n];
            // A chunk without measured outputs (prediction only) counts them as zero.
            match chunk.wrench[a].get(..n) {
                Some(z) => dst.copy_from_slice(z),
                None => dst.fill(0.0),
            }
            measured[a] = range_of_slice(dst);
            for t in &self.known[a] {
                apply_term(dst, t, false, -1.0, &lookup);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::model::{
        Column, ModelOptions, ModelStructure, ParamId, Parameter, Signal, Workspace, term,
    };
    use crate::sample::{Axis, Sample, SampleChunk};

    /// Three-factor terms are summed in one pass with the products of the pairwise fold
    /// ((c·x)·y)·z, bit for bit; an assembly of the wanted columns gives the same bits in
    /// those columns and the same outputs.
    #[test]
    fn three_factor_terms_and_wanted_columns_assemble_exactly() {
        use Signal::*;
        let v = crate::model::test_quad();
        let mut s = ModelStructure::eq22(&v, ModelOptions::default());
        let param = s.add_parameter(
            Parameter {
                name: "x".into(),
                unit: "-".into(),
            },
            vec![Column {
                axis: Axis::Fz,
                param: ParamId::default(),
                label: "u*v*w + 3 p*q*W1".into(),
                terms: vec![term(0.7, &[U, V, W]), term(3.0, &[P, Q, RotorSpeed(0)])],
            }],
        );
        let p = (0..s.columns.len())
            .find(|&j| s.columns[j].param == param)
            .expect("the added column");
        let mut chunk = SampleChunk::with_capacity(4, 64, true);
        for k in 0..64 {
            let f = k as f64;
            chunk.push(&Sample {
                velocity: [0.3 * f - 7.1, 1.0 / (f + 3.0), (0.1 * f).sin()],
                rates: [0.01 * f, (0.2 * f).cos(), -0.5],
                omega: vec![400.0 + 3.7 * f; 4],
                omega_dot: vec![1.0; 4],
                ..Sample::default()
            });
        }
        let mut ws = Workspace::default();
        s.assemble(&chunk, &mut ws).unwrap();
        for k in 0..64 {
            let u: [f64; 3] = std::array::from_fn(|a| chunk.velocity[a][k]);
            let r: [f64; 3] = std::array::from_fn(|a| chunk.rates[a][k]);
            let first = 0.7 * u[0] * u[1] * u[2];
            let expected = first + 3.0 * r[0] * r[1] * chunk.omega[0][k];
            assert_eq!(ws.column(p)[k].to_bits(), expected.to_bits(), "sample {k}");
        }
        let wanted: Vec<bool> = (0..s.columns.len()).map(|j| j % 3 != 1).collect();
        let mut part = Workspace::default();
        s.assemble_wanted(&chunk, &mut part, &wanted).unwrap();
        for (j, _) in wanted.iter().enumerate().filter(|(_, w)| **w) {
            assert_eq!(part.column(j), ws.column(j), "column {j}");
        }
        for axis in Axis::ALL {
            assert_eq!(part.output(axis), ws.output(axis));
        }
    }

    /// Columns assembled from another structure's signals are those assembled from the
    /// chunk, bit for bit; without those signals nothing is assembled.
    #[test]
    fn columns_from_another_assembly_s_signals_are_the_same_columns() {
        let v = crate::model::test_quad();
        let s = ModelStructure::eq22(&v, ModelOptions::default());
        let mut chunk = SampleChunk::with_capacity(4, 40, true);
        for k in 0..40 {
            let f = k as f64;
            chunk.push(&Sample {
                velocity: [0.2 * f - 3.0, (0.3 * f).cos(), 0.1 * f],
                rates: [0.02 * f, -0.1, (0.1 * f).sin()],
                omega: vec![500.0 + 2.0 * f; 4],
                omega_dot: vec![3.0 - 0.1 * f; 4],
                ..Sample::default()
            });
        }
        let mut ws = Workspace::default();
        s.assemble(&chunk, &mut ws).unwrap();
        // Every other column of eq22 as a parameter of its own, no known terms: only
        // signals eq22 computes.
        let mut part = s.select_columns(&[]);
        part.known = Default::default();
        for (j, c) in s.columns.iter().enumerate().step_by(2) {
            let p = Parameter {
                name: format!("c{j}"),
                unit: "-".into(),
            };
            part.add_parameter(p, vec![c.clone()]);
        }
        let (mut direct, mut reused) = (Workspace::default(), Workspace::default());
        part.assemble(&chunk, &mut direct).unwrap();
        assert!(
            part.assemble_columns_from(&chunk, &s, &ws, &mut reused)
                .is_some()
        );
        for j in 0..part.columns.len() {
            let bits = |w: &Workspace| w.column(j).iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&reused), bits(&direct), "column {j}");
        }
        // A structure of no computed signals has none of eq22's to lend.
        let mut bare = s.select_columns(&[]);
        bare.known = Default::default();
        let u = Column {
            axis: Axis::Fx,
            param: ParamId::default(),
            label: "u".into(),
            terms: vec![term(1.0, &[Signal::U])],
        };
        let p = Parameter {
            name: "u".into(),
            unit: "-".into(),
        };
        bare.add_parameter(p, vec![u]);
        bare.assemble(&chunk, &mut direct).unwrap();
        assert!(
            s.assemble_columns_from(&chunk, &bare, &direct, &mut reused)
                .is_none()
        );
    }
}
