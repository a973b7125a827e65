//! A slowly varying airframe moment the Eq. 22 model lacks (the `trim_moment` effect of
//! [`super::effects`]): a fuselage or payload aerodynamic moment, a shifting battery — the
//! controller trims it with differential rotor thrust.
//!
//! Form: per body axis k, a sum of [`TONES`] sinusoids
//!
//! M_k(t) = A_k Σ_j sin(2π f_kj t + φ_kj), A_k = M_k,rms √(2 / TONES),
//!
//! with frequencies f_kj drawn uniformly in [[`LOWEST_FREQUENCY`], f_max] Hz and phases
//! uniformly in [0, 2π), from a generator seeded by the flight's seed (a stream of its
//! own, so the flight's other random draws do not change when the effect is added).
//! The moment therefore has content only in [0.05, f_max] Hz, and its long-run RMS is
//! M_k,rms (the tones have distinct frequencies almost surely; over a finite flight the
//! RMS differs from it by the beat of nearby tones).

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// Sinusoids per axis.
pub const TONES: usize = 8;
/// Lowest tone frequency, Hz.
pub const LOWEST_FREQUENCY: f64 = 0.05;
/// Added to the flight's seed for the trim moment's own random stream.
const SEED_OFFSET: u64 = 0x7472_696d;

/// A band-limited random moment on the airframe, body axes.
#[derive(Debug, Clone, PartialEq)]
pub struct TrimMoment {
    /// Per axis and tone: (amplitude N m, angular frequency rad/s, phase rad).
    tones: [[(f64, f64, f64); TONES]; 3],
}

impl TrimMoment {
    /// The moment of RMS `rms` (N m, body x, y, z) with content up to `max_frequency`
    /// (Hz, above [`LOWEST_FREQUENCY`]) for the flight seeded `seed`.
    pub fn new(rms: [f64; 3], max_frequency: f64, seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed.wrapping_add(SEED_OFFSET));
        let tau = std::f64::consts::TAU;
        let tones = rms.map(|m| {
            let amplitude = m * (2.0 / TONES as f64).sqrt();
            [(); TONES].map(|_| {
                let f = rng.random_range(LOWEST_FREQUENCY..=max_frequency);
                let phase = rng.random_range(0.0..tau);
                (amplitude, tau * f, phase)
            })
        });
        Self { tones }
    }

    /// The moment at time `t` (s), N m, body axes.
    pub fn at(&self, t: f64) -> [f64; 3] {
        self.tones
            .map(|axis| axis.iter().map(|(a, w, p)| a * (w * t + p).sin()).sum())
    }

    /// The tone frequencies of body axis `axis` (0, 1, 2), Hz.
    pub fn frequencies(&self, axis: usize) -> [f64; TONES] {
        self.tones[axis].map(|(_, w, _)| w / std::f64::consts::TAU)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Same seed, same moment; the tones lie in [0.05, f_max]; over 2000 s (≥ 100
    /// periods of the slowest tone) the RMS of each axis is its parameter within 5 %
    /// (the leftover is the finite-time beat of nearby tones, ≲ 1/(2π Δf T)).
    #[test]
    fn moment_has_its_rms_and_band() {
        let rms = [0.02, 0.01, 0.005];
        let m = TrimMoment::new(rms, 0.5, 3);
        assert_eq!(m, TrimMoment::new(rms, 0.5, 3));
        assert_ne!(m, TrimMoment::new(rms, 0.5, 4));
        for k in 0..3 {
            for f in m.frequencies(k) {
                assert!((LOWEST_FREQUENCY..=0.5).contains(&f), "{f}");
            }
        }
        let n = 200_000;
        let mut sum = [0.0; 3];
        for i in 0..n {
            let v = m.at(i as f64 * 0.01);
            for k in 0..3 {
                sum[k] += v[k] * v[k];
            }
        }
        for k in 0..3 {
            let r = (sum[k] / n as f64).sqrt();
            assert!((r / rms[k] - 1.0).abs() < 0.05, "axis {k}: {r}");
        }
    }
}
