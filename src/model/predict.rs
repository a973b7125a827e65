//! Prediction: the model output Σ θ x of Eq. 22 plus the known terms, for one sample or
//! for every sample of an assembled chunk.

use super::{ModelError, ModelStructure, Workspace};
use crate::sample::{Axis, Sample, SampleChunk};

impl ModelStructure {
    /// Model output ŷ = Σ `θ[param]` · column for one sample, plus the known terms:
    /// `[F_x, F_y, F_z, M_x, M_y, M_z]` in N and N m.
    pub fn predict(&self, theta: &[f64], sample: &Sample) -> Result<[f64; 6], ModelError> {
        let mut chunk =
            SampleChunk::with_capacity(sample.omega.len(), 1, !sample.omega_dot.is_empty());
        chunk.push(sample);
        let mut ws = Workspace::default();
        let y = self.predict_chunk(theta, &chunk, &mut ws)?;
        Ok(y.map(|v| v[0]))
    }

    /// Model output of every sample of `chunk` per axis (N, N m), `ws` as scratch space.
    pub fn predict_chunk(
        &self,
        theta: &[f64],
        chunk: &SampleChunk,
        ws: &mut Workspace,
    ) -> Result<[Vec<f64>; 6], ModelError> {
        self.check_theta(theta)?;
        self.assemble(chunk, ws)?;
        Ok(self.predict_assembled(theta, chunk, ws))
    }

    /// Model output of every sample of `chunk` whose regressors `ws` holds (assembled by
    /// this structure): Σ θ x over the axis' columns plus the known terms (the measured
    /// output less the known-term-corrected one). The one prediction routine of the
    /// crate.
    pub fn predict_assembled(
        &self,
        theta: &[f64],
        chunk: &SampleChunk,
        ws: &Workspace,
    ) -> [Vec<f64>; 6] {
        Axis::ALL.map(|axis| {
            let a = axis as usize;
            let mut y: Vec<f64> = chunk.wrench[a]
                .iter()
                .zip(ws.output(axis))
                .map(|(z, c)| z - c)
                .collect();
            for j in self.axis_columns(axis) {
                let th = theta[self.columns[j].param.index()];
                y.iter_mut()
                    .zip(ws.column(j))
                    .for_each(|(o, x)| *o += th * x);
            }
            y
        })
    }

    /// θ holds one value per parameter.
    fn check_theta(&self, theta: &[f64]) -> Result<(), ModelError> {
        if theta.len() == self.params.len() {
            Ok(())
        } else {
            Err(ModelError::ParameterCount {
                expected: self.params.len(),
                found: theta.len(),
            })
        }
    }
}
