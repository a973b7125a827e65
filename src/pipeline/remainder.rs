//! The third pass, after a diagnosis: the final model's moment residual on the fit logs
//! correlated with each moment axis's rotor signals over lags ([`Remainder`]), so the
//! report can say what kind of structure is left.

use super::request::FitRequest;
use super::split::Role;
use super::stream::stream_log;
use crate::diagnose::Diagnosis;
use crate::error::Error;
use crate::estimate::remainder::{AxisRemainder, Remainder};
use crate::mixing::{Mixing, VirtualActuator, mix_row};
use crate::model::{ModelStructure, Workspace};
use crate::sample::{Axis, SampleChunk};
use crate::source::LogSource;
use crate::spill::Spill;

/// Samples of each fit log the pass reads at most, from its start: the correlations
/// need thousands of samples, not a whole long log.
pub(super) const REMAINDER_SAMPLES: usize = 200_000;

/// The evidence about each moment axis's remaining residual, over the fit logs (the
/// first [`REMAINDER_SAMPLES`] of each, each log's lags counted in its own median
/// sample interval). Empty when no fit log is a time series with rotor speeds to
/// correlate with.
pub(super) fn remainder(
    req: &FitRequest,
    jobs: &[(LogSource, Role)],
    spills: &[Option<Spill>],
    diagnosis: &Diagnosis,
) -> Result<Vec<AxisRemainder>, Error> {
    let model = (&diagnosis.structure, diagnosis.theta.as_slice());
    let mut all = Remainder::default();
    for (i, (source, _)) in jobs.iter().enumerate().take(req.logs.len()) {
        all.merge(&log_remainder(req, source, spills[i].as_ref(), model)?);
    }
    Ok(all.evidence())
}

/// One log's correlation sums for [`remainder`], of the final `model` (structure, θ̂):
/// read from its `spill` when there is one.
pub(super) fn log_remainder(
    req: &FitRequest,
    source: &LogSource,
    spill: Option<&Spill>,
    model: (&ModelStructure, &[f64]),
) -> Result<Remainder, Error> {
    let mixing = Mixing::new(&req.vehicle);
    let mut log = LogRemainder {
        model,
        mixing: &mixing,
        ws: Workspace::default(),
        sums: Remainder::default(),
        seen: 0,
        scratch: Default::default(),
    };
    match spill {
        Some(spill) => {
            let chunks = spill.chunks().min(REMAINDER_SAMPLES.div_ceil(1024));
            spill.stream_chunks(0..chunks, |c| log.push(c))?;
        }
        None => {
            stream_log(source, req, 1, |c| log.push(c))?;
        }
    }
    Ok(log.sums)
}

/// One log's pass.
struct LogRemainder<'a> {
    /// The final model: its structure and θ̂.
    model: (&'a ModelStructure, &'a [f64]),
    mixing: &'a Mixing,
    ws: Workspace,
    sums: Remainder,
    seen: usize,
    /// δ² and δ̇ of the three moment rows for a chunk.
    scratch: [Vec<f64>; 6],
}

impl LogRemainder<'_> {
    fn push(&mut self, chunk: &SampleChunk) -> Result<(), Error> {
        let n = chunk.len();
        if self.seen >= REMAINDER_SAMPLES || n == 0 {
            return Ok(());
        }
        if self.seen == 0 {
            let Some(dt) = median_interval(&chunk.t) else {
                return Ok(());
            };
            self.sums.start_log(dt);
        }
        self.seen += n;
        let (structure, theta) = self.model;
        let y = structure.predict_chunk(theta, chunk, &mut self.ws)?;
        let rows = [
            VirtualActuator::Aileron,
            VirtualActuator::Elevator,
            VirtualActuator::Rudder,
        ];
        for (a, row) in rows.into_iter().enumerate() {
            let weights = self.mixing.row(row);
            let [squared, rate] = [2 * a, 2 * a + 1];
            self.scratch[squared].resize(n, 0.0);
            mix_row(weights, &chunk.omega, true, &mut self.scratch[squared]);
            self.scratch[rate].resize(n, 0.0);
            match &chunk.omega_dot {
                Some(omega_dot) => mix_row(weights, omega_dot, false, &mut self.scratch[rate]),
                None => self.scratch[rate].fill(0.0),
            }
        }
        let moments = [Axis::Mx, Axis::My, Axis::Mz];
        for (k, &tk) in chunk.t.iter().enumerate().take(n) {
            let e = moments.map(|m| chunk.wrench[m as usize][k] - y[m as usize][k]);
            let x = [0, 1, 2].map(|a| [self.scratch[2 * a][k], self.scratch[2 * a + 1][k]]);
            self.sums.push(tk, e, x);
        }
        Ok(())
    }
}

/// Median interval between consecutive times, s; `None` for fewer than two samples.
fn median_interval(t: &[f64]) -> Option<f64> {
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    Some(*d.select_nth_unstable_by(mid, f64::total_cmp).1)
}
