//! Zero-phase low-pass of sampled signals, streamed: three centred moving averages in
//! time (a box cascade, close to a Gaussian).
//!
//! One pass of the cascade averages every sample with its neighbours within ± h seconds
//! (h = T/2); three passes give the response H(f) = sinc³(π f T), which is real and
//! positive up to f = 1/T, so it shifts no phase. Its −3 dB frequency is
//! f_c = 0.26194 / T (sinc(x) = 2^(−1/6) at x = 0.82290): [`LowPass::new`] takes f_c.
//!
//! Windows are defined in time, not in samples, so irregular sampling needs no special
//! case and a gap in the data longer than a window separates its two sides (near a gap
//! or an end the window holds only the samples on one side: the average shrinks to
//! them). Window sums are differences of running sums over the whole stream (Neumaier
//! compensated), so every output depends on the samples alone, never on how the
//! stream was cut into pushes, and each sample costs the same whatever the window.

use std::collections::VecDeque;

/// sin(x)/x = 2^(−1/6) at x = `SINC_CUBE_HALF_POWER`: the −3 dB point of sinc³.
const SINC_CUBE_HALF_POWER: f64 = 0.822_903_030_482_375_6;

/// Passes of the box cascade.
const PASSES: usize = 3;

/// A running sum with Neumaier's compensation: `sum + comp` is the sum of every value
/// added, to about one rounding of the result.
#[derive(Clone, Copy, Default)]
struct Compensated {
    sum: f64,
    comp: f64,
}

impl Compensated {
    fn add(&mut self, x: f64) {
        let s = self.sum + x;
        self.comp += if self.sum.abs() >= x.abs() {
            (self.sum - s) + x
        } else {
            (x - s) + self.sum
        };
        self.sum = s;
    }

    /// The sum of the values added after `earlier` was taken, up to this one.
    fn since(self, earlier: Compensated) -> f64 {
        (self.sum - earlier.sum) + (self.comp - earlier.comp)
    }
}

/// One centred moving average over ± `half` seconds of `channels` signals sampled
/// together.
struct BoxPass {
    half: f64,
    channels: usize,
    /// Times of the samples still in some window, oldest first.
    t: VecDeque<f64>,
    /// For each sample in `t`, the running sums of every channel before it (channel-major
    /// within a sample).
    before: VecDeque<Compensated>,
    /// Running sums of every channel over all samples pushed.
    total: Vec<Compensated>,
    /// Index in `t` of the next sample to average.
    next: usize,
    /// Index in `t` of the first sample in the next sample's window.
    lo: usize,
    /// Index in `t` one past the last sample known to be in the next sample's window.
    hi: usize,
    /// One average per channel, handed to `drain`'s `out` (reused, not reallocated per
    /// sample).
    y: Vec<f64>,
}

impl BoxPass {
    fn new(half: f64, channels: usize) -> Self {
        Self {
            half,
            channels,
            t: VecDeque::new(),
            before: VecDeque::new(),
            total: vec![Compensated::default(); channels],
            next: 0,
            lo: 0,
            hi: 0,
            y: vec![0.0; channels],
        }
    }

    fn push(&mut self, t: f64, x: &[f64]) {
        self.t.push_back(t);
        self.before.extend(self.total.iter().copied());
        for (sum, &v) in self.total.iter_mut().zip(x) {
            sum.add(v);
        }
    }

    /// Averages every sample whose window is complete (all of it when `end`), handing
    /// each time and its averages to `out` in order.
    fn drain(&mut self, end: bool, mut out: impl FnMut(f64, &[f64])) {
        let mut y = std::mem::take(&mut self.y);
        while self.next < self.t.len() {
            let tk = self.t[self.next];
            while self.hi < self.t.len() && self.t[self.hi] <= tk + self.half {
                self.hi += 1;
            }
            // The window is complete once a later sample lies beyond it.
            if self.hi == self.t.len() && !end {
                break;
            }
            while self.t[self.lo] < tk - self.half {
                self.lo += 1;
            }
            let count = (self.hi - self.lo) as f64;
            for (c, yc) in y.iter_mut().enumerate() {
                let upper = if self.hi == self.t.len() {
                    self.total[c]
                } else {
                    self.before[self.hi * self.channels + c]
                };
                *yc = upper.since(self.before[self.lo * self.channels + c]) / count;
            }
            out(tk, &y);
            self.next += 1;
            // Samples before the window of the next one are no longer needed.
            let drop = self.lo;
            self.t.drain(..drop);
            self.before.drain(..drop * self.channels);
            self.next -= drop;
            self.hi -= drop;
            self.lo = 0;
        }
        self.y = y;
    }
}

/// Zero-phase low-pass of `channels` signals sampled at the same times, fed sample by
/// sample and read back in order: a sample's output is complete once a sample more than
/// three half windows (1.5 T) later has come in, or at the end.
pub(crate) struct LowPass {
    passes: [BoxPass; PASSES],
}

impl LowPass {
    /// A low-pass with −3 dB frequency `cutoff` (Hz, > 0) for `channels` signals.
    pub(crate) fn new(cutoff: f64, channels: usize) -> Self {
        let half = 0.5 * SINC_CUBE_HALF_POWER / (std::f64::consts::PI * cutoff);
        Self {
            passes: std::array::from_fn(|_| BoxPass::new(half, channels)),
        }
    }

    /// Adds the sample at time `t` (s, increasing) with one value per channel, then hands
    /// every output now complete to `out` (its time and one value per channel), in order.
    pub(crate) fn push(&mut self, t: f64, x: &[f64], out: impl FnMut(f64, &[f64])) {
        self.passes[0].push(t, x);
        self.cascade(false, out);
    }

    /// The stream ended: hands every remaining output to `out`, in order.
    pub(crate) fn finish(&mut self, out: impl FnMut(f64, &[f64])) {
        self.cascade(true, out);
    }

    fn cascade(&mut self, end: bool, mut out: impl FnMut(f64, &[f64])) {
        let [first, second, third] = &mut self.passes;
        first.drain(end, |t, y| second.push(t, y));
        second.drain(end, |t, y| third.push(t, y));
        third.drain(end, &mut out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs `x` (one channel) through a low-pass at `cutoff` Hz.
    fn filter(t: &[f64], x: &[f64], cutoff: f64) -> Vec<f64> {
        let mut lp = LowPass::new(cutoff, 1);
        let mut y = Vec::new();
        for (&tk, &xk) in t.iter().zip(x) {
            lp.push(tk, &[xk], |_, v| y.push(v[0]));
        }
        lp.finish(|_, v| y.push(v[0]));
        y
    }

    fn times(n: usize, rate: f64) -> Vec<f64> {
        (0..n).map(|k| k as f64 / rate).collect()
    }

    #[test]
    fn a_sinusoid_at_the_cutoff_keeps_half_its_power_and_its_phase() {
        // 400 Hz, 1 Hz cut-off: the box windows hold ~105 samples, so the sampled
        // response is within ~1e-4 of sinc³; the amplitude is read at the centre sample's
        // peak, far from both ends.
        let rate = 400.0;
        let t = times(8000, rate);
        let x: Vec<f64> = t
            .iter()
            .map(|&t| (2.0 * std::f64::consts::PI * t).cos())
            .collect();
        let y = filter(&t, &x, 1.0);
        assert_eq!(y.len(), x.len());
        // t = 10 s is a peak of cos(2π t): zero phase leaves the peak where it was.
        let peak = y[4000];
        assert!((peak - 0.5f64.sqrt()).abs() < 2e-3, "{peak}");
        let (k_max, _) = y[3800..4200]
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        assert_eq!(3800 + k_max, 4000, "no phase shift");
    }

    #[test]
    fn ten_times_the_cutoff_is_removed_and_a_ramp_passes_unchanged() {
        let rate = 400.0;
        let t = times(8000, rate);
        // sinc³ at 10 f_c is below 2e-3 (its envelope 1/(π f T)³ ≈ 1/(8.2)^3).
        let x: Vec<f64> = t
            .iter()
            .map(|&t| (2.0 * std::f64::consts::PI * 10.0 * t).sin())
            .collect();
        let y = filter(&t, &x, 1.0);
        let interior = &y[400..7600];
        assert!(interior.iter().all(|v| v.abs() < 2e-3));
        // A symmetric window averages a straight line to itself, away from the ends.
        let ramp: Vec<f64> = t.iter().map(|&t| 3.0 * t - 1.0).collect();
        let y = filter(&t, &ramp, 1.0);
        for k in 400..7600 {
            assert!(
                (y[k] - ramp[k]).abs() < 1e-9,
                "{k}: {} vs {}",
                y[k],
                ramp[k]
            );
        }
    }

    #[test]
    fn a_gap_longer_than_the_windows_separates_its_sides() {
        // Two runs at 400 Hz, 5 s apart, constant 1 and constant 7: no output mixes them.
        let mut t = times(800, 400.0);
        t.extend(times(800, 400.0).iter().map(|t| t + 7.0));
        let x: Vec<f64> = (0..1600).map(|k| if k < 800 { 1.0 } else { 7.0 }).collect();
        let y = filter(&t, &x, 1.0);
        assert!(y[..800].iter().all(|&v| (v - 1.0).abs() < 1e-12));
        assert!(y[800..].iter().all(|&v| (v - 7.0).abs() < 1e-12));
    }

    #[test]
    fn outputs_do_not_depend_on_the_channels_beside_them_or_on_when_they_are_read() {
        // Two channels through one filter equal each channel alone, bit for bit, and a
        // long stream with large values keeps every bit whatever the values before it.
        let rate = 250.0;
        let t = times(20_000, rate);
        let a: Vec<f64> = t
            .iter()
            .map(|&t| 1e6 * (1.0 + 0.1 * (7.0 * t).sin()))
            .collect();
        let b: Vec<f64> = t.iter().map(|&t| (3.0 * t).cos()).collect();
        let mut lp = LowPass::new(0.5, 2);
        let (mut ya, mut yb) = (Vec::new(), Vec::new());
        let mut take = |_: f64, v: &[f64]| {
            ya.push(v[0]);
            yb.push(v[1]);
        };
        for k in 0..t.len() {
            lp.push(t[k], &[a[k], b[k]], &mut take);
        }
        lp.finish(&mut take);
        assert_eq!(ya, filter(&t, &a, 0.5));
        assert_eq!(yb, filter(&t, &b, 0.5));
        // Outputs trail the inputs by the delay, and no more: after each push, every
        // sample older than the delay plus one interval per pass has its output.
        let mut lp = LowPass::new(0.5, 1);
        // Three half windows of T = 0.82290/(π f_c).
        let delay = 3.0 * 0.5 * SINC_CUBE_HALF_POWER / (std::f64::consts::PI * 0.5);
        let mut newest = f64::NEG_INFINITY;
        for k in 0..t.len() {
            lp.push(t[k], &[b[k]], |tk, _| newest = tk);
            if t[k] > delay + 1.0 {
                assert!(newest >= t[k] - delay - PASSES as f64 / rate, "{k}");
                assert!(newest < t[k] - delay, "{k}");
            }
        }
    }
}
