//! A saved model on logs it was not fitted to: its prediction per chunk
//! ([`IdentifiedModel::predict_log`], `mrsysid predict`) and its fit metrics
//! ([`Validation`], `mrsysid validate`). Both read a log as the fit read its own
//! ([`crate::pipeline::stream_for_model`]).

use std::path::Path;

use crate::error::Error;
use crate::estimate::{self, AxisMetrics};
use crate::identified::IdentifiedModel;
use crate::io::Mapping;
use crate::model::Workspace;
use crate::pipeline::stream_for_model;
use crate::sample::SampleChunk;
use crate::stats::Accumulator;

impl IdentifiedModel {
    /// Predicts the log file at `log` (read with `mapping`) chunk by chunk: `each` gets
    /// every chunk in order with the model's force (N) and moment (N m) per sample, one
    /// column per [`crate::Axis`].
    pub fn predict_log(
        &self,
        log: &Path,
        mapping: Option<&Mapping>,
        mut each: impl FnMut(&SampleChunk, &[Vec<f64>; 6]),
    ) -> Result<(), Error> {
        let mut ws = Workspace::default();
        stream_for_model(self, log, mapping, |chunk| {
            let y = self.predict_chunk(chunk, &mut ws)?;
            each(chunk, &y);
            Ok(())
        })
    }
}

/// The fit metrics (NRMSE, TIC, R², RMSE per axis) of a saved model on logs added one by
/// one, from the one-pass statistics of their regressors and outputs.
pub struct Validation<'a> {
    model: &'a IdentifiedModel,
    acc: Accumulator,
    ws: Workspace,
}

impl<'a> Validation<'a> {
    /// No log yet.
    pub fn new(model: &'a IdentifiedModel) -> Self {
        Self {
            model,
            acc: Accumulator::new(&model.structure),
            ws: Workspace::default(),
        }
    }

    /// Adds the samples of the log file at `log`, read with `mapping`.
    pub fn add_log(&mut self, log: &Path, mapping: Option<&Mapping>) -> Result<(), Error> {
        let (model, acc, ws) = (self.model, &mut self.acc, &mut self.ws);
        stream_for_model(model, log, mapping, |chunk| {
            acc.push(&model.structure, chunk, ws)
                .map_err(|e| Error::Accumulate {
                    log: log.display().to_string(),
                    source: e,
                })
        })
    }

    /// Samples added so far.
    pub fn samples(&self) -> u64 {
        self.acc.count()
    }

    /// The model's metrics per axis on the samples added.
    pub fn metrics(&self) -> Result<[AxisMetrics; 6], Error> {
        Ok(estimate::evaluate(
            &self.model.structure,
            &self.model.theta(),
            &self.acc,
        )?)
    }
}
