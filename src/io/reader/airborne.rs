//! Airborne segments: samples on the ground (rotors stopped or idling) are left out and
//! the log is split at them, so each flight is a segment of its own.
//!
//! The measured force cannot tell the ground from a hover: on the ground the normal
//! force balances the weight, so F_z ≈ −m g there as in the air. The rotor speeds can:
//! the thrust the rotors can at most give, k_max Σ Ω_i² with k_max = C_T,max ρ π R⁴
//! (C_T,max = [`MAX_THRUST_COEFFICIENT`], the top of the propellers' range), is compared
//! with the weight m g. A run of samples whose ceiling φ = k_max Σ Ω_i² / (m g) stays
//! below [`ENTER_GROUND`] (until it rises above [`LEAVE_GROUND`]: hysteresis) for at
//! least [`MIN_RUN_SECONDS`] inside a segment is ground; a shorter dip is kept. Likewise
//! a take-off counts once φ has stayed above [`ENTER_GROUND`] for [`MIN_RUN_SECONDS`]
//! (a shorter burst on the ground is left out). A segment of one-sample test points (a
//! sweep) never holds such a run and is kept whole.

use std::collections::VecDeque;

use super::convert::Row;
use super::plan::VehicleFacts;
use crate::io::summary::AirborneSpan;
use crate::vehicle::STANDARD_GRAVITY;

/// Largest plausible hover thrust coefficient C_T = T / (ρ π R² (Ω R)²) of a propeller
/// (propellers have about 0.005 to 0.03).
pub(super) const MAX_THRUST_COEFFICIENT: f64 = 0.03;

/// Ceiling φ below which a sample is on the ground: even at C_T,max the rotors carry
/// less than the weight.
pub(super) const ENTER_GROUND: f64 = 1.0;

/// Ceiling φ above which a run of ground samples ends (hysteresis).
pub(crate) const LEAVE_GROUND: f64 = 1.25;

/// Shortest run, s, that switches between ground and air.
pub(super) const MIN_RUN_SECONDS: f64 = 1.0;

/// What precedes a row released to the window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Break {
    /// Nothing: the row continues the segment.
    None,
    /// A time gap (or a logger dropout) from the time given, s.
    Gap(f64),
    /// Ground time was left out before it.
    Ground,
}

/// The detector between the time checks and the window.
#[derive(Debug)]
pub(super) struct Detector {
    /// Detection on (off: every row is released as it comes).
    on: bool,
    /// k_max / (m g): φ per Σ Ω_i², 1/(rad/s)².
    ceiling_per_square: f64,
    ground: bool,
    /// The candidate run that may switch the state, with the break before its first row.
    held: VecDeque<Row>,
    held_break: Break,
    rotors: f64,
    /// Largest Σ Ω_i² of a sample, (rad/s)².
    peak_square: f64,
    /// Rows for the window, with the break before each.
    pub released: VecDeque<(Row, Break)>,
    /// First kept time of the flight under way, s.
    flight_start: Option<f64>,
    last_kept: f64,
    span: AirborneSpan,
}

impl Detector {
    /// A detector for the vehicle of `facts`; `on` false keeps every sample.
    pub fn new(facts: &VehicleFacts, on: bool) -> Self {
        let k_max = MAX_THRUST_COEFFICIENT
            * facts.air_density
            * std::f64::consts::PI
            * facts.rotor_radius.powi(4);
        Self {
            on,
            ceiling_per_square: k_max / (facts.mass * STANDARD_GRAVITY),
            ground: false,
            rotors: facts.rotors as f64,
            peak_square: 0.0,
            held: VecDeque::new(),
            held_break: Break::None,
            released: VecDeque::new(),
            flight_start: None,
            last_kept: 0.0,
            span: AirborneSpan::default(),
        }
    }

    /// Takes the next row (after its time checks) with the break before it.
    pub fn push(&mut self, row: Row, brk: Break, rotors: usize) {
        if !self.on {
            self.released.push_back((row, brk));
            return;
        }
        if brk != Break::None {
            // A run never spans a gap: resolve the candidate as too short.
            self.settle();
        }
        let square = row.omega[..rotors].iter().map(|w| w * w).sum::<f64>();
        self.peak_square = self.peak_square.max(square);
        let phi = self.ceiling_per_square * square;
        let candidate = !self.held.is_empty();
        let threshold = if candidate != self.ground {
            LEAVE_GROUND
        } else {
            ENTER_GROUND
        };
        // Air: a ground candidate starts below ENTER and runs while below LEAVE.
        // Ground: an air candidate starts above LEAVE and runs while above ENTER.
        let switching = if self.ground {
            phi >= threshold
        } else {
            phi < threshold
        };
        if switching {
            if self.held.is_empty() {
                self.held_break = brk;
            }
            self.held.push_back(row);
            let run =
                self.held.back().map_or(0.0, |r| r.t) - self.held.front().map_or(0.0, |r| r.t);
            if run >= MIN_RUN_SECONDS {
                self.ground = !self.ground;
                if self.ground {
                    self.end_flight();
                    self.drop_held();
                } else {
                    self.held_break = Break::Ground;
                    self.release_held();
                }
            }
        } else {
            self.settle();
            if self.ground {
                self.span.ground_samples += 1;
            } else {
                self.release(row, brk);
            }
        }
    }

    /// Resolves the candidate run as too short to switch.
    fn settle(&mut self) {
        if self.ground {
            self.drop_held();
        } else {
            self.release_held();
        }
    }

    /// End of the log: resolves the candidate; what was kept.
    pub fn finish(&mut self) -> AirborneSpan {
        self.settle();
        self.end_flight();
        self.span.peak_speed = (self.peak_square / self.rotors).sqrt();
        self.span.lift_speed = (1.0 / (self.ceiling_per_square * self.rotors)).sqrt();
        self.span
    }

    fn drop_held(&mut self) {
        self.span.ground_samples += self.held.len() as u64;
        self.held.clear();
    }

    fn release_held(&mut self) {
        let mut brk = self.held_break;
        while let Some(row) = self.held.pop_front() {
            self.release(row, brk);
            brk = Break::None;
        }
    }

    fn release(&mut self, row: Row, brk: Break) {
        if self.flight_start.is_none() {
            self.flight_start = Some(row.t);
            self.span.flights += 1;
        }
        self.last_kept = row.t;
        self.released.push_back((row, brk));
    }

    fn end_flight(&mut self) {
        if let Some(start) = self.flight_start.take() {
            self.span.airborne_seconds += self.last_kept - start;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// quad_x: 1.2 kg, R = 0.0635 m, ρ = 1.225: φ = 1 at Ω = 1252 rad/s on every rotor
    /// (its simulated hover, 2167.7 rad/s at C_T = 0.01, is φ = 3.0).
    fn detector() -> Detector {
        let facts = VehicleFacts {
            rotors: 4,
            mass: 1.2,
            inertia: [[0.0; 3]; 3],
            rotor_inertia: 0.0,
            arm: 0.225,
            rotor_radius: 0.0635,
            air_density: 1.225,
        };
        Detector::new(&facts, true)
    }

    fn row(t: f64, omega: f64) -> Row {
        let mut r = Row {
            t,
            ..Row::default()
        };
        r.omega[..4].fill(omega);
        r
    }

    /// Pushes `omega` (rad/s) at 100 Hz from `t0` for `seconds`; returns the next time.
    fn run(d: &mut Detector, t0: f64, seconds: f64, omega: f64) -> f64 {
        let n = (seconds * 100.0).round() as usize;
        for k in 0..n {
            d.push(row(t0 + k as f64 * 0.01, omega), Break::None, 4);
        }
        t0 + n as f64 * 0.01
    }

    fn breaks(d: &Detector) -> Vec<(usize, Break)> {
        d.released
            .iter()
            .enumerate()
            .filter(|(_, (_, b))| *b != Break::None)
            .map(|(i, (_, b))| (i, *b))
            .collect()
    }

    #[test]
    fn ceiling_is_one_at_the_thrust_of_the_top_coefficient() {
        let d = detector();
        let phi = |w: f64| d.ceiling_per_square * 4.0 * w * w;
        assert!((phi(1252.0) - 1.0).abs() < 1e-3, "{}", phi(1252.0));
        // Hover at C_T = 0.01 is a third of the ceiling (to the rounding of 2167.7).
        assert!((phi(2167.7) - 3.0).abs() < 1e-2, "{}", phi(2167.7));
    }

    /// Idle 3 s, fly 5 s with a 0.5 s dip to idle inside, idle 2 s: the idle runs are
    /// left out (500 samples), the dip is kept, one flight of 4.99 s, no break inside.
    #[test]
    fn short_dips_are_kept_and_ground_runs_left_out() {
        let mut d = detector();
        let t = run(&mut d, 0.0, 3.0, 650.0);
        let t = run(&mut d, t, 2.0, 2167.7);
        let t = run(&mut d, t, 0.5, 650.0);
        let t = run(&mut d, t, 2.5, 2167.7);
        run(&mut d, t, 2.0, 650.0);
        let span = d.finish();
        assert_eq!(span.ground_samples, 500);
        assert_eq!(span.flights, 1);
        assert!((span.airborne_seconds - 4.99).abs() < 1e-9, "{span:?}");
        assert_eq!(d.released.len(), 500);
        assert_eq!(breaks(&d), vec![(0, Break::Ground)]);
    }

    /// Between the thresholds the state holds (hysteresis): φ = 1.1 (Ω = 1312 rad/s)
    /// keeps a flight airborne and a landed vehicle on the ground; a 0.9 s burst to
    /// hover on the ground is left out; the second flight starts a segment.
    #[test]
    fn hysteresis_and_minimum_run() {
        let mut d = detector();
        let t = run(&mut d, 0.0, 2.0, 2167.7);
        let t = run(&mut d, t, 2.0, 1312.0);
        let t = run(&mut d, t, 2.0, 0.0);
        let t = run(&mut d, t, 2.0, 1312.0);
        let t = run(&mut d, t, 0.9, 2167.7);
        let t = run(&mut d, t, 1.0, 650.0);
        run(&mut d, t, 1.5, 2167.7);
        let span = d.finish();
        assert_eq!(span.flights, 2);
        assert_eq!(span.ground_samples, 200 + 200 + 90 + 100);
        assert_eq!(d.released.len(), 400 + 150);
        assert_eq!(breaks(&d), vec![(400, Break::Ground)]);
    }

    /// One-sample segments (a sweep's test points, a gap before each) are never ground,
    /// whatever their rotor speeds; a gap ends a candidate run.
    #[test]
    fn runs_do_not_span_gaps() {
        let mut d = detector();
        for k in 0..10 {
            let t = k as f64;
            d.push(row(t, 0.0), Break::Gap(t - 1.0), 4);
        }
        let span = d.finish();
        assert_eq!(span.ground_samples, 0);
        assert_eq!(d.released.len(), 10);
    }

    #[test]
    fn off_keeps_every_row() {
        let facts = detector();
        let mut d = Detector { on: false, ..facts };
        run(&mut d, 0.0, 3.0, 0.0);
        assert_eq!(d.finish().ground_samples, 0);
        assert_eq!(d.released.len(), 300);
    }
}
