//! Zero-phase Butterworth low-pass filtering of a log, the way post-processed flight data
//! are smoothed (the `smoothed_loads` effect of [`super::effects`]).
//!
//! Design: the analog Butterworth low-pass of order n with its cut-off pre-warped to
//! K = tan(π f_c / f_s), mapped by the bilinear transform s = (1 − z⁻¹)/(K (1 + z⁻¹)) and
//! kept as a cascade of sections: one second-order section per conjugate pole pair
//! p_k = exp(iπ(2k + n − 1)/(2n)), k = 1..⌊n/2⌋, with damping 2ζ_k = 2 sin(π(2k − 1)/(2n)),
//!
//! H_k(z) = K² (1 + z⁻¹)² / [(1 + 2ζ_k K + K²) + 2(K² − 1) z⁻¹ + (1 − 2ζ_k K + K²) z⁻²],
//!
//! and for odd n the first-order section K (1 + z⁻¹) / [(1 + K) + (K − 1) z⁻¹]. Each
//! section has DC gain 1, and the cascade's |H(e^{iω})|² = 1 / (1 + (tan(ω/2)/K)^{2n}):
//! exactly 1/2 at f_c for every order.
//!
//! [`Butterworth::filtfilt`] runs the cascade forward, then backward over the reversed
//! output, so the result has zero phase and the magnitude |H|² (−6 dB at f_c). Edge
//! treatment, as SciPy's `filtfilt` with odd padding: each end is extended by an odd
//! reflection x₋ⱼ = 2 x₀ − xⱼ (j = 1..P, P = min(len − 1, ⌈3 f_s / f_c⌉), three periods
//! of the cut-off), every section starts in its steady state for the first padded value
//! (a constant input passes without transient), and the padding is dropped at the end.

use std::f64::consts::PI;

/// One second-order section b₀ + b₁ z⁻¹ + b₂ z⁻² over 1 + a₁ z⁻¹ + a₂ z⁻² (a first-order
/// section has b₂ = a₂ = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Numerator b₀, b₁, b₂.
    pub b: [f64; 3],
    /// Denominator a₁, a₂ (a₀ = 1).
    pub a: [f64; 2],
}

/// A low-pass that cannot be designed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FilterError {
    /// An order outside 1..=8.
    #[error("Butterworth order {order}: must be 1 to 8")]
    Order {
        /// The order asked for.
        order: usize,
    },
    /// A cut-off not above 0 and below half the sample rate.
    #[error(
        "Butterworth cut-off {cutoff} Hz: must be above 0 and below half the sample rate ({} Hz)",
        0.5 * rate
    )]
    CutOff {
        /// The cut-off asked for, Hz.
        cutoff: f64,
        /// The sample rate, Hz.
        rate: f64,
    },
}

/// A digital Butterworth low-pass as a cascade of [`Section`]s.
#[derive(Debug, Clone, PartialEq)]
pub struct Butterworth {
    /// Sections, applied in order.
    pub sections: Vec<Section>,
    /// Padding of [`Self::filtfilt`] at each end, samples: ⌈3 f_s / f_c⌉.
    pub pad: usize,
}

impl Butterworth {
    /// The order-`order` low-pass with cut-off `cutoff` (Hz) at sample rate `rate` (Hz),
    /// by the bilinear transform with pre-warping (module documentation). Refuses an
    /// order outside 1..=8 and a cut-off outside (0, rate/2).
    pub fn low_pass(order: usize, cutoff: f64, rate: f64) -> Result<Self, FilterError> {
        if !(1..=8).contains(&order) {
            return Err(FilterError::Order { order });
        }
        if !(cutoff > 0.0 && cutoff < 0.5 * rate) {
            return Err(FilterError::CutOff { cutoff, rate });
        }
        let k = (PI * cutoff / rate).tan();
        let k2 = k * k;
        let mut sections = Vec::with_capacity(order.div_ceil(2));
        if order % 2 == 1 {
            let n = 1.0 / (1.0 + k);
            sections.push(Section {
                b: [k * n, k * n, 0.0],
                a: [(k - 1.0) * n, 0.0],
            });
        }
        for j in 1..=order / 2 {
            let two_zeta = 2.0 * (PI * (2 * j - 1) as f64 / (2 * order) as f64).sin();
            let n = 1.0 / (1.0 + two_zeta * k + k2);
            sections.push(Section {
                b: [k2 * n, 2.0 * k2 * n, k2 * n],
                a: [2.0 * (k2 - 1.0) * n, (1.0 - two_zeta * k + k2) * n],
            });
        }
        Ok(Self {
            sections,
            pad: (3.0 * rate / cutoff).ceil() as usize,
        })
    }

    /// Runs the cascade causally over `x` in place (direct form II transposed), every
    /// section starting in the steady state of a constant input equal to `x[0]`.
    pub fn filter_in_place(&self, x: &mut [f64]) {
        let Some(&first) = x.first() else {
            return;
        };
        for s in &self.sections {
            let [b0, b1, b2] = s.b;
            let [a1, a2] = s.a;
            // Steady state of a constant input u (output u, DC gain 1).
            let mut z2 = (b2 - a2) * first;
            let mut z1 = (b1 - a1) * first + z2;
            for v in x.iter_mut() {
                let u = *v;
                let y = b0 * u + z1;
                z1 = b1 * u - a1 * y + z2;
                z2 = b2 * u - a2 * y;
                *v = y;
            }
        }
    }

    /// Zero-phase filtering of `x` (forward and backward, module documentation); returns
    /// a series of the same length. A series of fewer than two samples is returned as is.
    pub fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        let len = x.len();
        if len < 2 {
            return x.to_vec();
        }
        let pad = self.pad.min(len - 1);
        let mut ext = Vec::with_capacity(len + 2 * pad);
        ext.extend((1..=pad).rev().map(|j| 2.0 * x[0] - x[j]));
        ext.extend_from_slice(x);
        ext.extend((1..=pad).map(|j| 2.0 * x[len - 1] - x[len - 1 - j]));
        self.filter_in_place(&mut ext);
        ext.reverse();
        self.filter_in_place(&mut ext);
        ext.reverse();
        ext[pad..pad + len].to_vec()
    }
}

/// Zero-phase Butterworth low-pass of `x` sampled at `rate` (Hz): order `order`, cut-off
/// `cutoff` (Hz), see [`Butterworth::filtfilt`].
pub fn smooth(x: &[f64], order: usize, cutoff: f64, rate: f64) -> Result<Vec<f64>, FilterError> {
    Ok(Butterworth::low_pass(order, cutoff, rate)?.filtfilt(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Amplitude and phase (rad) of `y` against sin(2π f t) over the samples `range`,
    /// by projection on sin and cos (whole periods in the range).
    fn amplitude_phase(y: &[f64], f: f64, rate: f64, range: std::ops::Range<usize>) -> (f64, f64) {
        let (mut s, mut c) = (0.0, 0.0);
        let n = range.len() as f64;
        for k in range {
            let arg = 2.0 * PI * f * k as f64 / rate;
            s += y[k] * arg.sin();
            c += y[k] * arg.cos();
        }
        let (s, c) = (2.0 * s / n, 2.0 * c / n);
        (s.hypot(c), c.atan2(s))
    }

    fn sine(f: f64, rate: f64, len: usize) -> Vec<f64> {
        (0..len)
            .map(|k| (2.0 * PI * f * k as f64 / rate).sin())
            .collect()
    }

    /// The second-order section equals the closed form b = K²n (1, 2, 1),
    /// a = (2(K² − 1)n, (1 − √2 K + K²)n), n = 1/(1 + √2 K + K²) (tolerance: round-off).
    #[test]
    fn order_two_matches_the_closed_form() {
        let f = Butterworth::low_pass(2, 28.85, 400.0).unwrap();
        let k = (PI * 28.85 / 400.0).tan();
        let n = 1.0 / (1.0 + 2f64.sqrt() * k + k * k);
        let s = f.sections[0];
        let want_b = [k * k * n, 2.0 * k * k * n, k * k * n];
        let want_a = [2.0 * (k * k - 1.0) * n, (1.0 - 2f64.sqrt() * k + k * k) * n];
        assert_eq!(f.sections.len(), 1);
        for (got, want) in s.b.iter().zip(want_b).chain(s.a.iter().zip(want_a)) {
            assert!((got - want).abs() < 1e-15, "{got} vs {want}");
        }
    }

    /// A constant passes unchanged (DC gain 1, steady-state start, odd padding): error
    /// below 1e-12 for orders 1–4, also for a log shorter than the padding.
    #[test]
    fn constant_passes_unchanged() {
        for order in 1..=4 {
            for len in [5, 400] {
                let y = smooth(&vec![3.25; len], order, 5.0, 100.0).unwrap();
                assert!(y.iter().all(|v| (v - 3.25).abs() < 1e-12), "order {order}");
            }
        }
        // A ramp is odd about both ends, so the odd reflection continues it exactly and
        // the two passes' lags cancel: it too passes unchanged, up to what is left of
        // the start transient after the padding, e^(−ζ 2π f_c · 3/f_c) = 1.6e-6 of the
        // lag (order 2, ζ = 1/√2): 1e-6 of the ramp's range.
        let ramp: Vec<f64> = (0..300).map(|k| 0.01 * k as f64).collect();
        let y = smooth(&ramp, 2, 5.0, 100.0).unwrap();
        for (a, b) in y.iter().zip(&ramp) {
            assert!((a - b).abs() < 1e-6 * 3.0, "{a} vs {b}");
        }
    }

    /// Filtfilt of a sinusoid: amplitude |H|² = 1/(1 + (tan(πf/fs)/tan(πf_c/fs))^{2n})
    /// (1/2 at f_c for every order) and phase zero. Measured over the middle half of a
    /// 40 s log at 100 Hz, away from the ends: amplitude within 1e-4, phase within 1e-4
    /// rad (the ends' transients have decayed by far more than that at three periods
    /// of the cut-off from the padding and 10 s of signal).
    #[test]
    fn sinusoids_pass_with_the_squared_butterworth_gain_and_zero_phase() {
        let rate = 100.0;
        let fc = 5.0;
        let len = 4000;
        for order in 1..=4 {
            for f in [0.5, 2.5, 5.0, 7.5] {
                let y = smooth(&sine(f, rate, len), order, fc, rate).unwrap();
                let (amp, phase) = amplitude_phase(&y, f, rate, 1000..3000);
                let ratio = (PI * f / rate).tan() / (PI * fc / rate).tan();
                let want = 1.0 / (1.0 + ratio.powi(2 * order as i32));
                assert!(
                    (amp - want).abs() < 1e-4,
                    "order {order}, {f} Hz: {amp} vs {want}"
                );
                assert!(phase.abs() < 1e-4, "order {order}, {f} Hz: phase {phase}");
                if f == fc {
                    assert!((amp - 0.5).abs() < 1e-4);
                }
            }
        }
    }

    /// Causal filtering keeps the one-way response: a single pass of the order-2 filter
    /// at f_c has |H| = 1/√2 and lags by π/2 (the Butterworth phase at cut-off is −nπ/4),
    /// which the backward pass of filtfilt cancels (tolerance 1e-3).
    #[test]
    fn one_pass_lags_by_the_butterworth_phase() {
        let rate = 100.0;
        let fc = 5.0;
        let f = Butterworth::low_pass(2, fc, rate).unwrap();
        let mut y = sine(fc, rate, 4000);
        f.filter_in_place(&mut y);
        let (amp, phase) = amplitude_phase(&y, fc, rate, 1000..3000);
        assert!((amp - 0.5f64.sqrt()).abs() < 1e-3, "{amp}");
        assert!((phase + PI / 2.0).abs() < 1e-3, "{phase}");
    }

    #[test]
    fn bad_designs_are_refused() {
        assert_eq!(
            Butterworth::low_pass(0, 5.0, 100.0),
            Err(FilterError::Order { order: 0 })
        );
        let e = Butterworth::low_pass(2, 50.0, 100.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "Butterworth cut-off 50 Hz: must be above 0 and below half the sample rate (50 Hz)"
        );
        assert!(Butterworth::low_pass(2, 0.0, 100.0).is_err());
    }
}
