//! Physical-range checks of logged values, spike flagging (Hampel filter) and unit
//! plausibility heuristics.

use super::mapping::Signal;
use crate::vehicle::STANDARD_GRAVITY;

/// Admissible range of one component of `signal` in SI units, for a vehicle of mass
/// `mass` (kg) and arm length `arm` (m); the text is shown in errors.
pub fn physical_range(signal: Signal, mass: f64, arm: f64) -> Option<(f64, f64, String)> {
    let g50 = 50.0 * STANDARD_GRAVITY;
    let sym = |m: f64, unit: &str, why: &str| Some((-m, m, format!("[-{m}, {m}] {unit} ({why})")));
    match signal {
        Signal::Time => None,
        Signal::VelocityBody | Signal::VelocityWorld => sym(150.0, "m/s", "150 m/s"),
        Signal::Rates => sym(
            100.0,
            "rad/s",
            "about 5730 deg/s; a log in deg/s needs unit \"deg/s\"",
        ),
        Signal::AngularAcceleration => sym(5000.0, "rad/s^2", "5000 rad/s^2"),
        Signal::RotorSpeeds => Some((
            0.0,
            15000.0,
            "[0, 15000] rad/s (magnitudes, about 143000 RPM; a log in RPM needs unit \"rpm\")"
                .into(),
        )),
        Signal::RotorAccelerations => sym(1.0e6, "rad/s^2", "1e6 rad/s^2"),
        Signal::Force => sym(round3(mass * g50), "N", "50 g times the vehicle mass"),
        Signal::Moment => sym(
            round3(mass * g50 * arm * 2.0),
            "N m",
            "50 g times mass times twice the arm",
        ),
        Signal::SpecificForce => sym(round3(g50), "m/s^2", "50 g"),
        Signal::Height => Some((-1000.0, 100000.0, "[-1000, 100000] m".into())),
        Signal::Attitude => sym(1.01, "", "quaternion component"),
    }
}

fn round3(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

/// Largest admissible deviation of a quaternion's norm from 1.
pub const QUATERNION_NORM_TOLERANCE: f64 = 0.01;

/// Half width of the Hampel window used to flag spikes, samples.
pub const SPIKE_HALF_WINDOW: usize = 3;

/// A sample is flagged as a spike when it departs from the median of its
/// 2·[`SPIKE_HALF_WINDOW`]+1 neighbourhood by more than this many robust standard
/// deviations (1.4826 · MAD) …
pub const SPIKE_SIGMAS: f64 = 6.0;

/// … and by more than this floor in SI units (so quantised or constant signals do not
/// count every step as a spike): rates 0.5 rad/s, rotor speeds 50 rad/s, force or
/// specific force 5 (N or m/s²).
pub fn spike_floor(signal: Signal) -> f64 {
    match signal {
        Signal::Rates => 0.5,
        Signal::RotorSpeeds => 50.0,
        _ => 5.0,
    }
}

/// Hampel test of the centre of `window` (odd length ≥ 3): true when it is a spike.
pub fn is_spike(window: &mut [f64], floor: f64) -> bool {
    let mid = window.len() / 2;
    let centre = window[mid];
    window.sort_unstable_by(f64::total_cmp);
    let median = window[mid];
    for v in window.iter_mut() {
        *v = (*v - median).abs();
    }
    window.sort_unstable_by(f64::total_cmp);
    let mad = window[mid];
    (centre - median).abs() > (SPIKE_SIGMAS * 1.4826 * mad).max(floor)
}

/// Statistics gathered while reading, to flag implausible units.
#[derive(Debug, Clone, Default)]
pub struct UnitStats {
    samples: u64,
    sum_specific_force: f64,
    max_rate: f64,
    max_omega: f64,
    sum_omega: f64,
}

impl UnitStats {
    /// Adds one sample: force (N), mass (kg), rates (rad/s), rotor speeds (rad/s).
    pub fn push(&mut self, force: [f64; 3], mass: f64, rates: [f64; 3], omega: &[f64]) {
        self.samples += 1;
        let norm = (force[0] * force[0] + force[1] * force[1] + force[2] * force[2]).sqrt();
        self.sum_specific_force += norm / mass;
        for r in rates {
            self.max_rate = self.max_rate.max(r.abs());
        }
        for &w in omega {
            self.max_omega = self.max_omega.max(w);
            self.sum_omega += w / omega.len() as f64;
        }
    }

    /// Human-readable warnings about units that look wrong.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.samples == 0 {
            return out;
        }
        let n = self.samples as f64;
        let mean_a = self.sum_specific_force / n;
        if !(0.3 * STANDARD_GRAVITY..=4.0 * STANDARD_GRAVITY).contains(&mean_a) {
            out.push(format!(
                "mean |F|/m = {mean_a:.3} m/s^2 is far from g = 9.807 m/s^2 expected of flight \
                 (force or accelerometer unit or mass wrong? accelerometer in g needs unit \"g\")"
            ));
        }
        if self.max_rate > 35.0 {
            out.push(format!(
                "max |body rate| = {:.1} rad/s (> 2000 deg/s): body rates logged in deg/s?",
                self.max_rate
            ));
        }
        let mean_omega = self.sum_omega / n;
        if mean_omega < 30.0 {
            out.push(format!(
                "mean rotor speed = {mean_omega:.2} rad/s is implausibly low for flight \
                 (rotor speeds logged in rev/s or kRPM?)"
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hampel_flags_an_isolated_spike_not_a_ramp() {
        let mut spike = [1.0, 1.1, 1.2, 9.0, 1.4, 1.5, 1.6];
        assert!(is_spike(&mut spike, 0.5));
        let mut ramp = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
        assert!(!is_spike(&mut ramp, 0.5));
    }
}
