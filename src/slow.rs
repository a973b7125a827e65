//! The slow part of each rotor's thrust signal Ω_i², derived by the fit pipeline for the
//! diagnosis's trim-moment candidates: a stage over the stream of chunks.
//!
//! Below the attitude loop's bandwidth a flying multirotor's rotor commands hold the
//! trim: when a slow moment the model lacks acts on the airframe (a fuselage or payload
//! moment, a CG that moves), the controller balances it with differential thrust, and
//! that slow band of the rotor signals produces no angular acceleration. The candidates
//! built on these signals ([`crate::model::Signal::SlowSquaredActuator`]) let the data
//! say so. The low-pass is zero-phase ([`crate::smooth`]): it is the slow part around
//! each sample, not a response to rotor speeds later than the load.

use crate::held::HeldChunks;
use crate::sample::{SampleChunk, TRIM_BANDS_HZ};
use crate::smooth::LowPass;

/// Fills [`SampleChunk::omega_squared_slow`] of a stream of chunks: chunks are held
/// until every band's low-pass has passed their last sample (1.5 windows, 0.8 s at the
/// lowest band, of samples later), then handed on in order.
pub(crate) struct SlowThrust {
    /// One low-pass per band, one channel per rotor.
    bands: Vec<LowPass>,
    rotors: usize,
    /// Chunks held; one filter per band.
    held: HeldChunks,
    /// Ω_i² of the sample being pushed.
    squares: Vec<f64>,
}

impl SlowThrust {
    /// A stage for chunks of `rotors` rotors.
    pub(crate) fn new(rotors: usize) -> Self {
        Self {
            bands: TRIM_BANDS_HZ
                .iter()
                .map(|&f| LowPass::new(f, rotors))
                .collect(),
            rotors,
            held: HeldChunks::new(TRIM_BANDS_HZ.len()),
            squares: vec![0.0; rotors],
        }
    }

    /// Takes `chunk` in, and hands every chunk now complete to `out`, in order.
    pub(crate) fn push<E>(
        &mut self,
        mut chunk: SampleChunk,
        out: impl FnMut(SampleChunk) -> Result<(), E>,
    ) -> Result<(), E> {
        let n = chunk.len();
        let slow = chunk.omega_squared_slow.get_or_insert_with(Vec::new);
        slow.resize_with(self.bands.len() * self.rotors, Vec::new);
        for v in slow.iter_mut() {
            v.clear();
            v.resize(n, 0.0);
        }
        self.held.push(chunk);
        for k in 0..n {
            let chunk = self.held.newest();
            for (sq, w) in self.squares.iter_mut().zip(&chunk.omega) {
                *sq = w[k] * w[k];
            }
            let t = chunk.t[k];
            self.filter(|lp, squares, store| lp.push(t, squares, store));
        }
        self.held.hand_on(false, out)
    }

    /// The stream ended: completes and hands on every chunk held.
    pub(crate) fn finish<E>(
        &mut self,
        out: impl FnMut(SampleChunk) -> Result<(), E>,
    ) -> Result<(), E> {
        self.filter(|lp, _, store| lp.finish(store));
        self.held.hand_on(true, out)
    }

    /// Runs `step` on each band's low-pass, storing what it outputs in the held chunks.
    fn filter(&mut self, step: impl Fn(&mut LowPass, &[f64], &mut dyn FnMut(f64, &[f64]))) {
        let Self {
            bands,
            rotors,
            held,
            squares,
        } = self;
        for (b, lp) in bands.iter_mut().enumerate() {
            let mut store = |_: f64, y: &[f64]| {
                let (chunk, k) = held.next_slot(b);
                let slow = chunk.omega_squared_slow.as_mut().expect("sized by `push`");
                for (i, &v) in y.iter().enumerate() {
                    slow[b * *rotors + i][k] = v;
                }
            };
            step(lp, squares, &mut store);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::Sample;

    /// A 20 s, 400 Hz stream of 2 rotors: Ω_1 constant, Ω_2 with a slow and a fast
    /// oscillation.
    fn stream() -> SampleChunk {
        let mut c = SampleChunk::with_capacity(2, 8000, false);
        for k in 0..8000 {
            let t = k as f64 / 400.0;
            let w2 = 1000.0
                + 50.0 * (0.4 * t).sin()
                + 30.0 * (2.0 * std::f64::consts::PI * 25.0 * t).sin();
            c.push(&Sample {
                t,
                omega: vec![900.0, w2],
                ..Sample::default()
            });
        }
        c
    }

    /// The chunks of `stream` cut every `cut` samples, through the stage.
    fn through(cut: usize) -> Vec<SampleChunk> {
        let all = stream();
        let mut stage = SlowThrust::new(2);
        let mut out = Vec::new();
        let mut take = |c: SampleChunk| -> Result<(), ()> {
            out.push(c);
            Ok(())
        };
        for c in crate::held::cut(&all, cut) {
            stage.push(c, &mut take).unwrap();
        }
        stage.finish(&mut take).unwrap();
        out
    }

    fn joined(chunks: &[SampleChunk]) -> SampleChunk {
        let mut all = SampleChunk::with_capacity(2, 0, false);
        for c in chunks {
            all.extend_from(c, 0..c.len());
        }
        all
    }

    #[test]
    fn every_chunk_comes_back_in_order_with_the_same_slow_signals_however_cut() {
        let a = through(1024);
        let b = through(7);
        assert_eq!(a.len(), 8);
        let (a, b) = (joined(&a), joined(&b));
        assert_eq!(a.t, stream().t);
        assert_eq!(a.omega, stream().omega);
        // Bit for bit: the low-pass depends on the samples alone.
        assert_eq!(a.omega_squared_slow, b.omega_squared_slow);
        let slow = a.omega_squared_slow.expect("derived");
        assert_eq!(slow.len(), 2 * TRIM_BANDS_HZ.len());
    }

    #[test]
    fn the_slow_signals_keep_the_slow_part_of_omega_squared_and_drop_the_fast() {
        let all = joined(&through(1024));
        let slow = all.omega_squared_slow.as_ref().expect("derived");
        // Rotor 1 constant: its slow Ω² is Ω² to rounding in every band.
        for b in 0..TRIM_BANDS_HZ.len() {
            assert!(slow[2 * b].iter().all(|&v| (v - 810_000.0).abs() < 1e-6));
        }
        // Rotor 2, 1 Hz band, away from the ends: the 25 Hz part (and its square's
        // 50 Hz part) is gone to < 0.1 % of its amplitude 2·1000·30 rad²/s² (sinc³ at
        // 25 f_c is ~1e-5); the 0.064 Hz part passes within 1 % (sinc³ ≈ 0.994); the
        // mean of the fast part's square, 30²/2, stays.
        let slow = &slow[2 + 1];
        for k in (800..7200).step_by(97) {
            let t = all.t[k];
            let w = 1000.0 + 50.0 * (0.4 * t).sin();
            let expected = w * w + 450.0;
            assert!(
                (slow[k] - expected).abs() < 0.01 * 2.0 * 1000.0 * 50.0 + 60.0,
                "{k}: {} vs {expected}",
                slow[k]
            );
        }
    }
}
