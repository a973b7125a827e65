//! What is left in the final model's moment residual: its correlation with the rotor
//! signals that drive each moment axis, over time lags.
//!
//! For each moment axis a, the residual e_a(t) of the final model and two reference
//! signals of that axis — the control moment's signal δ²_a = M_ix,a Ω² (Eq. 19–20) and
//! its rate δ̇_a = M_ix,a Ω̇ — are correlated at lags L (positive L: the reference earlier
//! than the residual, ρ(L) = corr(e(t), x(t − L))). A residual that still holds rotor
//! structure shows it here: a peak at L > 0 is load following the rotors with a lag the
//! model lacks, at L < 0 load leading the logged rotor speeds (a measurement lag of the
//! rotor speed, or the controller acting on the measured rates), near L = 0 a gain the
//! model has wrong; |ρ| small at every lag says the rest is not rotor-driven (noise, or
//! states the model does not use). Pairs are taken within runs of samples without a gap
//! (an interval over three nominal ones), so a lag never spans a hole in the log.

use serde::{Deserialize, Serialize};

use crate::sample::Axis;

/// Lags of the correlations, ms (positive: reference earlier than the residual).
pub const REMAINDER_LAGS_MS: [f64; 11] = [
    -100.0, -50.0, -20.0, -10.0, -5.0, 0.0, 5.0, 10.0, 20.0, 50.0, 100.0,
];

/// The moment axes, and the names of their reference signals.
const AXES: [(Axis, [&str; 2]); 3] = [
    (Axis::Mx, ["da2", "da_dot"]),
    (Axis::My, ["de2", "de_dot"]),
    (Axis::Mz, ["dr2", "dr_dot"]),
];

/// Sums of one (residual, reference) pair at one lag.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
struct PairSums {
    n: f64,
    e: f64,
    e2: f64,
    x: f64,
    x2: f64,
    ex: f64,
}

impl PairSums {
    fn add(&mut self, e: f64, x: f64) {
        self.n += 1.0;
        self.e += e;
        self.e2 += e * e;
        self.x += x;
        self.x2 += x * x;
        self.ex += e * x;
    }

    fn merge(&mut self, o: &PairSums) {
        self.n += o.n;
        self.e += o.e;
        self.e2 += o.e2;
        self.x += o.x;
        self.x2 += o.x2;
        self.ex += o.ex;
    }

    /// Pearson correlation; 0 when either side is constant.
    fn correlation(&self) -> f64 {
        let n = self.n;
        let cov = self.ex / n - (self.e / n) * (self.x / n);
        let ve = self.e2 / n - (self.e / n).powi(2);
        let vx = self.x2 / n - (self.x / n).powi(2);
        if n < 2.0 || ve <= 0.0 || vx <= 0.0 {
            0.0
        } else {
            cov / (ve * vx).sqrt()
        }
    }
}

/// One sample's residuals and references, kept for the lags.
#[derive(Debug, Clone, Copy)]
struct Row {
    e: [f64; 3],
    x: [[f64; 2]; 3],
}

/// Streaming correlation sums of one log (or the merge of several): feed it the samples
/// in time order with [`Remainder::push`]. Serialised, it carries its sums alone (what
/// [`Remainder::merge`] adds), not the state of a log's pass.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Remainder {
    /// Lags in samples, one per [`REMAINDER_LAGS_MS`] (from the log's sample interval).
    #[serde(skip)]
    lags: Vec<isize>,
    /// Nominal sample interval, s (the first interval seen until a log sets it).
    #[serde(skip)]
    interval: Option<f64>,
    /// Sums per axis, reference and lag.
    sums: Vec<PairSums>,
    /// The last samples (time, row), as many as the longest lag.
    #[serde(skip)]
    history: std::collections::VecDeque<(f64, Row)>,
}

impl Default for Remainder {
    fn default() -> Self {
        Self {
            lags: Vec::new(),
            interval: None,
            sums: vec![PairSums::default(); AXES.len() * 2 * REMAINDER_LAGS_MS.len()],
            history: Default::default(),
        }
    }
}

impl Remainder {
    /// Sets the log's nominal sample interval `dt` (s) and starts a new log: lags are
    /// counted in its samples, and no pair spans two logs.
    pub fn start_log(&mut self, dt: f64) {
        self.interval = Some(dt);
        self.lags = REMAINDER_LAGS_MS
            .iter()
            .map(|ms| (ms * 1e-3 / dt).round() as isize)
            .collect();
        self.history.clear();
    }

    /// Adds a sample at time `t` (s): residuals `e` of M_x, M_y, M_z (N m) and, per
    /// axis, the two reference signals.
    pub fn push(&mut self, t: f64, e: [f64; 3], x: [[f64; 2]; 3]) {
        let Some(dt) = self.interval else {
            return;
        };
        if self.history.back().is_some_and(|(t0, _)| t - t0 > 3.0 * dt) {
            self.history.clear();
        }
        let row = Row { e, x };
        let longest = self
            .lags
            .iter()
            .map(|l| l.unsigned_abs())
            .max()
            .unwrap_or(0);
        let n = self.history.len();
        let lag_count = REMAINDER_LAGS_MS.len();
        for (k, &lag) in self.lags.iter().enumerate() {
            let back = lag.unsigned_abs();
            if back > n {
                continue;
            }
            // Lag ≥ 0: this residual with the reference `back` samples earlier; lag < 0:
            // the residual `back` samples earlier with this reference.
            let earlier = if back == 0 {
                row
            } else {
                self.history[n - back].1
            };
            for a in 0..AXES.len() {
                for r in 0..2 {
                    let (ev, xv) = if lag >= 0 {
                        (row.e[a], earlier.x[a][r])
                    } else {
                        (earlier.e[a], row.x[a][r])
                    };
                    self.sums[(a * 2 + r) * lag_count + k].add(ev, xv);
                }
            }
        }
        self.history.push_back((t, row));
        while self.history.len() > longest {
            self.history.pop_front();
        }
    }

    /// True when its sums are laid out as this crate's (a deserialised one may not be).
    pub fn has_layout(&self) -> bool {
        self.sums.len() == AXES.len() * 2 * REMAINDER_LAGS_MS.len()
    }

    /// Adds the sums of another log's pass.
    pub fn merge(&mut self, other: &Remainder) {
        for (s, o) in self.sums.iter_mut().zip(&other.sums) {
            s.merge(o);
        }
    }

    /// The correlations per moment axis, and what they say.
    pub fn evidence(&self) -> Vec<AxisRemainder> {
        let lag_count = REMAINDER_LAGS_MS.len();
        AXES.iter()
            .enumerate()
            .map(|(a, (axis, names))| {
                let references = (0..2)
                    .map(|r| {
                        let rho: Vec<f64> = (0..lag_count)
                            .map(|k| self.sums[(a * 2 + r) * lag_count + k].correlation())
                            .collect();
                        ReferenceCorrelation {
                            signal: names[r].to_string(),
                            lags_ms: REMAINDER_LAGS_MS.to_vec(),
                            correlation: rho,
                        }
                    })
                    .collect();
                AxisRemainder {
                    axis: *axis,
                    references,
                }
            })
            .collect()
    }
}

/// Correlation of one axis' residual with one reference signal over the lags.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceCorrelation {
    /// The reference: `da2` (δ²a = M_ix,a Ω²), `da_dot` (δ̇a = M_ix,a Ω̇), and so on.
    pub signal: String,
    /// Lags, ms (positive: the reference earlier than the residual).
    pub lags_ms: Vec<f64>,
    /// Pearson correlation at each lag, in [−1, 1].
    pub correlation: Vec<f64>,
}

impl ReferenceCorrelation {
    /// The lag (ms) and value of the largest |correlation|.
    pub fn peak(&self) -> (f64, f64) {
        self.lags_ms
            .iter()
            .zip(&self.correlation)
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map_or((0.0, 0.0), |(l, r)| (*l, *r))
    }
}

/// The evidence about one moment axis' remaining residual.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AxisRemainder {
    /// The moment axis.
    pub axis: Axis,
    /// Its reference signals' correlations with the residual.
    pub references: Vec<ReferenceCorrelation>,
}

impl AxisRemainder {
    /// One sentence: where the residual still correlates with the rotor signals, and
    /// what that suggests.
    pub fn sentence(&self) -> String {
        let peaks: Vec<(String, f64, f64)> = self
            .references
            .iter()
            .map(|r| {
                let (lag, rho) = r.peak();
                (r.signal.clone(), lag, rho)
            })
            .collect();
        let (signal, lag, rho) = peaks
            .iter()
            .max_by(|a, b| a.2.abs().total_cmp(&b.2.abs()))
            .cloned()
            .unwrap_or_default();
        let listed = peaks
            .iter()
            .map(|(s, l, r)| format!("{s} {r:+.2} at {l:+.0} ms"))
            .collect::<Vec<_>>()
            .join(", ");
        let widest = REMAINDER_LAGS_MS[REMAINDER_LAGS_MS.len() - 1];
        let reading = if rho.abs() < 0.1 {
            "little rotor-driven structure is left (noise, or states the model does not use)"
                .to_string()
        } else if lag.abs() >= widest {
            format!(
                "it peaks at the edge of the ±{widest:.0} ms window: slow structure (below a few Hz) the model lacks, not a lag"
            )
        } else if lag.abs() <= 5.0 {
            format!("the model's gain on {signal} is off")
        } else if lag > 0.0 {
            format!("the load follows {signal} about {lag:.0} ms later than the model has it")
        } else {
            format!(
                "the load leads the logged {signal} by about {:.0} ms (a rotor-speed measurement lag, or the controller acting on the measured rates)",
                -lag
            )
        };
        format!(
            "{} residual, peak correlation with the rotor signals over ±100 ms: {listed}: {reading}",
            self.axis.name()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A residual that is a reference signal delayed by 20 ms (plus an independent
    /// part) peaks at +20 ms with the correlation the construction gives.
    #[test]
    fn a_residual_lagging_its_reference_peaks_at_that_lag() {
        let dt = 0.0025;
        let mut r = Remainder::default();
        r.start_log(dt);
        // A broadband reference (a sum of incommensurate sines) and, on M_y, residual =
        // reference 8 samples (20 ms) earlier plus an equal-power independent signal.
        let x = |k: i64| {
            let t = k as f64 * dt;
            (37.0 * t).sin() + (91.0 * t).cos() + (153.0 * t).sin()
        };
        let noise = |k: i64| {
            let t = k as f64 * dt;
            (41.0 * t).cos() + (107.0 * t).sin() + (173.0 * t).cos()
        };
        for k in 0..40_000i64 {
            let e = [0.0, x(k - 8) + noise(k), 0.0];
            let refs = [[0.0, 0.0], [x(k), 1.0], [0.0, 0.0]];
            r.push(k as f64 * dt, e, refs);
        }
        let ev = r.evidence();
        let my = &ev[1].references[0];
        let (lag, rho) = my.peak();
        assert_eq!(lag, 20.0);
        // corr(x + n, x) = 1/√2 for equal powers (within 0.02: finite record).
        assert!((rho - 0.5f64.sqrt()).abs() < 0.02, "{rho}");
        // A constant reference and a zero residual correlate with nothing.
        assert!(ev[1].references[1].correlation.iter().all(|&c| c == 0.0));
        assert!(ev[0].references[0].correlation.iter().all(|&c| c == 0.0));
        assert!(
            ev[1].sentence().contains("20 ms later"),
            "{}",
            ev[1].sentence()
        );
    }

    #[test]
    fn no_pair_spans_a_gap_and_logs_merge_by_their_sums() {
        let dt = 0.01;
        // Two runs 10 s apart: a residual equal to the reference shifted by one run's
        // length would correlate across the gap if pairs spanned it.
        let mut a = Remainder::default();
        a.start_log(dt);
        for k in 0..500 {
            let v = (k as f64 * 0.3).sin();
            a.push(k as f64 * dt, [v, 0.0, 0.0], [[v, 0.0], [0.0; 2], [0.0; 2]]);
        }
        for k in 0..500 {
            let v = (k as f64 * 0.3).sin();
            a.push(
                15.0 + k as f64 * dt,
                [v, 0.0, 0.0],
                [[v, 0.0], [0.0; 2], [0.0; 2]],
            );
        }
        let zero = a.evidence()[0].references[0].correlation[5];
        assert!((zero - 1.0).abs() < 1e-12, "{zero}");
        // Two halves pushed to separate passes and merged equal one pass at lag 0.
        let mut b = Remainder::default();
        b.start_log(dt);
        for k in 0..500 {
            let v = (k as f64 * 0.3).sin();
            b.push(k as f64 * dt, [v, 0.0, 0.0], [[v, 0.0], [0.0; 2], [0.0; 2]]);
        }
        let mut c = b.clone();
        c.merge(&b);
        let merged = c.evidence()[0].references[0].correlation[5];
        assert!((merged - 1.0).abs() < 1e-12);
    }
}
