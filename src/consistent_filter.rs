//! Consistent filtering: when a log's loads were smoothed as the log was made (forces
//! and moments from accelerations through a zero-phase low-pass, or a smoothing spline),
//! the signals the regressors are built from — air-relative velocity, body rates, rotor
//! speeds and accelerations — pass through the same kind of filter, so that the model
//! y = X θ is fitted as L[y] ≈ L[X] θ rather than against loads whose fast content was
//! removed while the regressors' was not (the output-error practice of SIDPAC's
//! consistent filtering). The filter is the crate's zero-phase low-pass
//! ([`crate::smooth::LowPass`], −3 dB at the cut-off the log's processing used). For
//! the regressors that are products of signals (Ω², u·Ω, …) filtering the signals
//! rather than each product differs by the fast content's own products, small where the
//! signals' content above the cut-off is small.

use crate::held::HeldChunks;
use crate::sample::SampleChunk;
use crate::smooth::LowPass;

/// Low-passes the regressor signals of a stream of chunks in place: chunks are held until
/// the filter has passed their last sample (1.5 windows of samples later), then handed on
/// in order.
pub(crate) struct ConsistentFilter {
    cutoff: f64,
    /// The low-pass once the first chunk has said how many channels there are.
    lp: Option<LowPass>,
    held: HeldChunks,
    /// The channels of the sample being pushed.
    values: Vec<f64>,
}

/// The filtered signals of `chunk`: velocity, rates, rotor speeds, rotor accelerations
/// (when logged or derived), in that order.
fn channels(chunk: &mut SampleChunk) -> impl Iterator<Item = &mut Vec<f64>> {
    chunk
        .velocity
        .iter_mut()
        .chain(chunk.rates.iter_mut())
        .chain(chunk.omega.iter_mut())
        .chain(chunk.omega_dot.iter_mut().flatten())
}

impl ConsistentFilter {
    /// A stage low-passing at `cutoff` Hz (> 0, finite).
    pub(crate) fn new(cutoff: f64) -> Self {
        Self {
            cutoff,
            lp: None,
            held: HeldChunks::new(1),
            values: Vec::new(),
        }
    }

    /// Takes `chunk` in, and hands every chunk now complete to `out`, in order.
    pub(crate) fn push<E>(
        &mut self,
        mut chunk: SampleChunk,
        out: impl FnMut(SampleChunk) -> Result<(), E>,
    ) -> Result<(), E> {
        let n = chunk.len();
        let width = channels(&mut chunk).count();
        let lp = self
            .lp
            .get_or_insert_with(|| LowPass::new(self.cutoff, width));
        self.held.push(chunk);
        for k in 0..n {
            self.values.clear();
            let newest = self.held.newest();
            self.values.extend(
                newest
                    .velocity
                    .iter()
                    .chain(&newest.rates)
                    .chain(&newest.omega)
                    .chain(newest.omega_dot.iter().flatten())
                    .map(|v| v[k]),
            );
            let t = newest.t[k];
            let held = &mut self.held;
            lp.push(t, &self.values, |_, y| store(held, y));
        }
        self.held.hand_on(false, out)
    }

    /// The stream ended: completes and hands on every chunk held.
    pub(crate) fn finish<E>(
        &mut self,
        out: impl FnMut(SampleChunk) -> Result<(), E>,
    ) -> Result<(), E> {
        if let Some(lp) = self.lp.as_mut() {
            let held = &mut self.held;
            lp.finish(|_, y| store(held, y));
        }
        self.held.hand_on(true, out)
    }
}

/// Writes one filtered sample `y` (one value per channel) into its place in `held`.
fn store(held: &mut HeldChunks, y: &[f64]) {
    let (chunk, k) = held.next_slot(0);
    for (signal, &v) in channels(chunk).zip(y) {
        signal[k] = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::Sample;

    /// 10 s at 400 Hz, 2 rotors: u a 1 Hz sine with 60 Hz noise on top, Ω constant.
    fn stream() -> SampleChunk {
        let mut c = SampleChunk::with_capacity(2, 4000, false);
        let tau = 2.0 * std::f64::consts::PI;
        for k in 0..4000 {
            let t = k as f64 / 400.0;
            c.push(&Sample {
                t,
                velocity: [(tau * t).sin() + 0.3 * (tau * 60.0 * t).sin(), 0.0, 0.0],
                omega: vec![1000.0, 1100.0],
                wrench: [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                ..Sample::default()
            });
        }
        c
    }

    fn through(cut: usize) -> SampleChunk {
        let all = stream();
        let mut stage = ConsistentFilter::new(20.0);
        let mut out = SampleChunk::with_capacity(2, 0, false);
        let mut take = |c: SampleChunk| -> Result<(), ()> {
            out.extend_from(&c, 0..c.len());
            Ok(())
        };
        for c in crate::held::cut(&all, cut) {
            stage.push(c, &mut take).unwrap();
        }
        stage.finish(&mut take).unwrap();
        out
    }

    #[test]
    fn the_regressor_signals_lose_their_fast_content_and_the_loads_are_untouched() {
        let (a, b) = (through(1024), through(13));
        // Bit for bit however the stream is cut: the filter sees the samples alone.
        assert_eq!(a.velocity, b.velocity);
        assert_eq!(a.t, stream().t);
        // The loads are not filtered (they already were, when the log was made).
        assert_eq!(a.wrench, stream().wrench);
        // Constant rotor speeds stay constant to rounding.
        assert!(a.omega[1].iter().all(|&w| (w - 1100.0).abs() < 1e-9));
        // At 20 Hz the 60 Hz part (0.3) is gone to < 1 % of it (sinc³ at 3 f_c ~ 1e-3)
        // and the 1 Hz sine passes within 1 % (sinc³ ≈ 0.997), away from the ends.
        let tau = 2.0 * std::f64::consts::PI;
        for k in (400..3600).step_by(37) {
            let expected = (tau * a.t[k]).sin();
            assert!(
                (a.velocity[0][k] - expected).abs() < 0.01 + 0.003,
                "{k}: {} vs {expected}",
                a.velocity[0][k]
            );
        }
    }
}
