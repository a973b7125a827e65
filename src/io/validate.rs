//! Physical-range checks of logged values, spike flagging (Hampel filter) and unit
//! plausibility heuristics: the blade-tip Mach number and hover thrust coefficient of the
//! rotor speeds (RPM logged as rad/s), the sample interval and span of the time (ms or
//! µs logged as s), the mean specific force, the body rates.

use super::error::{ErrorKind, IoError, Location};
use super::mapping::Signal;
use super::reader::{DIFFERENTIATED, LEAVE_GROUND};
use super::{ReadOptions, Summary};
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

/// Speed of sound of the blade-tip check, m/s (ISA sea level, 15 °C; colder air has a
/// lower one, so a tip above Mach 1 by this figure is above it in any flight air).
pub const SPEED_OF_SOUND: f64 = 340.294;

/// Largest plausible Mach number of a blade tip at the typical (median) rotor speed of a
/// log: propellers of multirotors run at about 0.2–0.7.
pub const MAX_TIP_MACH: f64 = 1.0;

/// Smallest plausible hover thrust coefficient C_T = m g / (n ρ π R⁴ Ω²) at the median
/// rotor speed (propellers have about 0.005–0.03; RPM read as rad/s gives 91 times less).
pub const MIN_HOVER_THRUST_COEFFICIENT: f64 = 1e-3;

/// One revolution per minute, rad/s.
const RPM: f64 = std::f64::consts::PI / 30.0;

/// Bins per octave of [`Median`] (2.2 % wide).
const MEDIAN_BINS_PER_OCTAVE: u32 = 32;
/// Smallest binary exponent of [`Median`]: values below 2⁻⁴⁰ (9e-13) share its first bin.
const MEDIAN_MIN_EXPONENT: i64 = -40;
/// Octaves of [`Median`]: values above 2⁴⁰ (1.1e12) share its last bin.
const MEDIAN_OCTAVES: usize = 80;

/// The median of positive values in bounded memory (40 kB however many): counts in bins
/// 1/32 octave wide, each keeping the first value that fell in it; the median is the
/// value kept in the bin of the middle value — exact when the values repeat (sample
/// intervals, hover speeds), else within 2.2 %. A bin is found from the value's bits
/// (exponent and top mantissa bits), with no logarithm.
#[derive(Debug, Clone, Default)]
pub struct Median {
    counts: Vec<u64>,
    values: Vec<f64>,
    total: u64,
}

impl Median {
    /// Adds `x`; values that are not finite and positive are ignored.
    pub fn push(&mut self, x: f64) {
        if !(x > 0.0 && x.is_finite()) {
            return;
        }
        let bins = MEDIAN_OCTAVES * MEDIAN_BINS_PER_OCTAVE as usize;
        if self.counts.is_empty() {
            self.counts = vec![0; bins];
            self.values = vec![0.0; bins];
        }
        let shift = 52 - MEDIAN_BINS_PER_OCTAVE.trailing_zeros();
        let first =
            ((1023 + MEDIAN_MIN_EXPONENT) as u64) << MEDIAN_BINS_PER_OCTAVE.trailing_zeros();
        let bin = ((x.to_bits() >> shift).saturating_sub(first) as usize).min(bins - 1);
        if self.counts[bin] == 0 {
            self.values[bin] = x;
        }
        self.counts[bin] += 1;
        self.total += 1;
    }

    /// Values added.
    pub fn count(&self) -> u64 {
        self.total
    }

    /// The value kept in the bin of the ⌈n/2⌉-th smallest value; `None` when empty.
    pub fn median(&self) -> Option<f64> {
        let half = self.total.div_ceil(2);
        let mut seen = 0;
        for (count, value) in self.counts.iter().zip(&self.values) {
            seen += count;
            if *count > 0 && seen >= half {
                return Some(*value);
            }
        }
        None
    }
}

/// `x` with at most three decimals (trailing zeros dropped), or in exponent form when it
/// is below 0.001 or above 10⁷.
fn short(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e7).contains(&x.abs()) {
        return format!("{x:.3e}");
    }
    let text = format!("{x:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// `x` to about four significant figures: whole for 1000 and more, else three decimals
/// at most ([`short`]).
fn about(x: f64) -> String {
    if x.abs() >= 1000.0 {
        format!("{x:.0}")
    } else {
        short((x * 1000.0).round() / 1000.0)
    }
}

/// Why the time of a log looks logged in ms, µs or ns rather than seconds — its samples
/// `median_step` s apart (median), more than 1 s (under 1 Hz, no flight log), or its
/// `samples` samples spanning more than a day — with the unit to declare: the
/// diagnosis, `consequence` (e.g. ", so …"), and the remedy. `None` when it looks like
/// seconds (a test-point sweep numbering its points 0, 1, 2 … is not flagged).
pub fn time_unit_suspect(
    median_step: Option<f64>,
    span: f64,
    samples: u64,
    consequence: &str,
) -> Option<String> {
    let step = median_step?;
    if !(step > 1.0 || span > 86_400.0) {
        return None;
    }
    let (word, unit) = [
        ("milliseconds", "ms", 1e-3),
        ("microseconds", "us", 1e-6),
        ("nanoseconds", "ns", 1e-9),
    ]
    .into_iter()
    .find(|u| step * u.2 <= 0.1)
    .map_or(("nanoseconds", "ns"), |u| (u.0, u.1));
    Some(format!(
        "time looks like {word}, not seconds: the median time step is {} s ({} Hz) and the \
         {samples} samples span {} s ({} h){consequence}; declare the unit in a mapping file \
         ([time] unit = \"{unit}\", docs/mapping.md)",
        short(step),
        short(1.0 / step),
        short(span),
        short(span / 3600.0),
    ))
}

/// The error of a log that gave no sample (`summary` complete, read with `opts`):
/// empty, every row on the ground (airborne detection), or every row dropped. A log whose rows were all dropped because their
/// segments are too short to differentiate cannot support a fit
/// ([`ErrorKind::TooShort`]), unless its time looks logged in ms or µs (the label of its
/// time field is `time_label`), which made every step a gap.
pub fn no_samples_error(
    summary: &Summary,
    opts: &ReadOptions,
    time_label: Option<String>,
) -> IoError {
    let s = summary;
    let file = s.file.as_str();
    let too_short = "segment too short to differentiate";
    if let Some(air) = s.airborne {
        // A take-off starts at φ = LEAVE_GROUND: φ grows with the square of the speed.
        let take_off = air.lift_speed * LEAVE_GROUND.sqrt();
        let (peak, lift) = (air.peak_speed, air.lift_speed);
        let why = if peak < take_off {
            format!("below the {take_off:.0} rad/s a take-off needs")
        } else {
            format!("but above the {take_off:.0} rad/s a take-off needs for less than a second")
        };
        return IoError::new(
            file,
            Location::File,
            None,
            ErrorKind::TooShort(format!(
                "no sample left: {} of the {} rows read are on the ground: the rotors reach \
                 {peak:.0} rad/s at most (RMS over the rotors), {why} (1.25^0.5 times the \
                 {lift:.0} rad/s at which they would carry the vehicle's weight at a thrust \
                 coefficient of 0.03; docs/data-contract.md, \"Airborne segments\"); check \
                 the vehicle file's mass and rotor_radius and the rotor-speed unit, or keep \
                 every row with --keep-ground",
                air.ground_samples, s.rows_read
            )),
        );
    }
    if s.rows_read == 0 || s.dropped.keys().any(|k| k != too_short) {
        return IoError::new(file, Location::File, None, ErrorKind::Empty);
    }
    let rows = match s.rows_read {
        1 => "the 1 row read was dropped".to_string(),
        n => format!("all {n} rows read were dropped"),
    };
    let consequence = format!(
        ", so every step is a gap that leaves each sample a segment of its own, too short to \
         differentiate ({rows})"
    );
    let suspect = time_unit_suspect(s.median_time_step, s.span, s.rows_read, &consequence);
    if let Some(text) = suspect.filter(|_| !s.time_unit_trusted) {
        return IoError::new(file, Location::File, time_label, ErrorKind::Mapping(text));
    }
    let order = opts.derive.sg_order;
    // Points farther apart than max_gap throughout (a test-point sweep): nothing can be
    // differentiated, what is derived must be logged.
    let differentiated: Vec<&str> = DIFFERENTIATED
        .iter()
        .filter(|(what, source)| {
            let entry = format!("{what} from {source} ");
            s.derived.iter().any(|d| d.starts_with(&entry))
        })
        .map(|&(what, _)| what)
        .collect();
    let points = s
        .median_time_step
        .filter(|&step| step > opts.max_gap && !differentiated.is_empty())
        .map_or(String::new(), |step| {
            format!(
                "; its rows are {} s apart (median), as a test-point sweep's points are: such a \
                 log must carry what would be differentiated ({})",
                short(step),
                differentiated.join(", ")
            )
        });
    IoError::new(
        file,
        Location::File,
        None,
        ErrorKind::TooShort(format!(
            "no sample left: {rows}, every segment being too short to differentiate (with \
             sg_order {order} a segment needs at least {} samples, and a time step longer than \
             max_gap = {} s starts a new segment){points}",
            order + 1,
            opts.max_gap
        )),
    )
}

/// Rotor speeds whose median puts the blade tips above [`MAX_TIP_MACH`] read as rad/s:
/// logged in RPM, or in eRPM when even read as RPM they would be supersonic.
#[derive(Debug, Clone, PartialEq)]
pub struct SupersonicTips {
    /// The speeds look like eRPM (supersonic also as RPM), not RPM.
    pub erpm: bool,
    /// Median rotor speed read as rad/s.
    pub speed: f64,
    /// Rotor radius R, m.
    pub radius: f64,
    /// Tip Mach number at `speed`.
    pub mach: f64,
    /// Hover thrust coefficient C_T = m g/(n ρ π R⁴ Ω²) at `speed`.
    pub thrust_coefficient: f64,
    /// Tip Mach number with `speed` read as RPM.
    pub rpm_mach: f64,
    /// Hover thrust coefficient with `speed` read as RPM.
    pub rpm_thrust_coefficient: f64,
}

impl std::fmt::Display for SupersonicTips {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (what, unit) = if self.erpm {
            (
                "electrical RPM (eRPM)",
                "unit = \"erpm\" with pole_pairs = the motor's pole pairs",
            )
        } else {
            ("RPM", "unit = \"rpm\"")
        };
        write!(
            f,
            "rotor speeds look like {what}, not rad/s: the median rotor speed {} rad/s \
             puts the blade tips (R = {} m) at {} m/s, Mach {:.2}, and hovering at it \
             would need a thrust coefficient C_T = m g/(n rho pi R^4 Omega^2) of {:.2e} \
             (propellers have about 0.005 to 0.03); read as RPM it is {} rad/s, Mach \
             {:.2}, C_T {:.2e}; declare the unit in a mapping file \
             ([signals.rotor_speeds] {unit}, docs/mapping.md)",
            about(self.speed),
            self.radius,
            about(self.speed * self.radius),
            self.mach,
            self.thrust_coefficient,
            about(self.speed * RPM),
            self.rpm_mach,
            self.rpm_thrust_coefficient,
        )
    }
}

impl std::error::Error for SupersonicTips {}

/// Sample rate below which a log gets a note (Hz): 25 Hz, ArduPilot's default IMU rate,
/// resolves angular accelerations only to a few Hz, where the attitude loops act.
pub const MIN_SAMPLE_RATE: f64 = 50.0;

/// Statistics gathered while reading, to flag implausible units.
#[derive(Debug, Clone, Default)]
pub struct UnitStats {
    samples: u64,
    sum_specific_force: f64,
    max_rate: f64,
    max_omega: f64,
    sum_omega: f64,
    /// Mean rotor speed of each sample with turning rotors, rad/s.
    rotor_speed: Median,
    /// Steps between the times of consecutive rows read, s.
    time_steps: Median,
    /// Times of the first and the last row read, s.
    times: Option<(f64, f64)>,
    /// The log's time unit was declared (a mapping's `[time] unit`).
    time_unit_declared: bool,
    /// Some row read had a t other than its row number 0, 1, 2, … (so t is no test-point
    /// sweep's numbering); `false` before the first row.
    not_numbered: bool,
}

impl UnitStats {
    /// The statistics of a log whose time unit a mapping declared (`declared`) or not.
    pub fn new(time_unit_declared: bool) -> Self {
        Self {
            time_unit_declared,
            ..Self::default()
        }
    }

    /// Adds one sample: force (N), mass (kg), rates (rad/s), rotor speeds (rad/s).
    pub fn push(&mut self, force: [f64; 3], mass: f64, rates: [f64; 3], omega: &[f64]) {
        self.samples += 1;
        let norm = (force[0] * force[0] + force[1] * force[1] + force[2] * force[2]).sqrt();
        self.sum_specific_force += norm / mass;
        for r in rates {
            self.max_rate = self.max_rate.max(r.abs());
        }
        let mut sum = 0.0;
        for &w in omega {
            self.max_omega = self.max_omega.max(w);
            self.sum_omega += w / omega.len() as f64;
            sum += w;
        }
        self.rotor_speed.push(sum / omega.len() as f64);
    }

    /// Adds the time of a row read, s (rows in reading order).
    pub fn time(&mut self, t: f64) {
        match &mut self.times {
            None => {
                self.times = Some((t, t));
                self.not_numbered = t != 0.0;
            }
            Some((_, last)) => {
                self.not_numbered |= t != *last + 1.0;
                if t > *last {
                    self.time_steps.push(t - *last);
                }
                *last = t;
            }
        }
    }

    /// Median step between the times of consecutive rows read, s; `None` with fewer
    /// than two.
    pub fn median_time_step(&self) -> Option<f64> {
        self.time_steps.median()
    }

    /// Time from the first row read to the last, s (0 with fewer than two).
    pub fn span(&self) -> f64 {
        self.times.map_or(0.0, |(first, last)| last - first)
    }

    /// Whether the time's unit is above the ms/µs suspicion of [`time_unit_suspect`]: a
    /// mapping declared it, or t numbers the rows read 0, 1, 2, … (a test-point sweep).
    pub fn time_unit_trusted(&self) -> bool {
        self.time_unit_declared || !self.not_numbered
    }

    /// The blade-tip check of the rotor speeds, for `rotors` rotors of radius `radius`
    /// (m) on a vehicle of `mass` (kg) in air of `density` (kg/m³): an error when the
    /// median rotor speed puts the tips above [`MAX_TIP_MACH`] (rotor speeds in RPM or
    /// eRPM read as rad/s), saying the unit to declare; `Ok(Some(note))` when the tips are
    /// subsonic but hovering at that speed would need a thrust coefficient below
    /// [`MIN_HOVER_THRUST_COEFFICIENT`]; else `Ok(None)`.
    pub fn rotor_speed_check(
        &self,
        rotors: usize,
        radius: f64,
        mass: f64,
        density: f64,
    ) -> Result<Option<String>, SupersonicTips> {
        let Some(omega) = self.rotor_speed.median() else {
            return Ok(None);
        };
        let mach = |w: f64| w * radius / SPEED_OF_SOUND;
        // Hover: m g = n C_T ρ π R² (Ω R)².
        let hover_ct = |w: f64| {
            mass * STANDARD_GRAVITY
                / (rotors as f64 * density * std::f64::consts::PI * radius.powi(4) * w * w)
        };
        if mach(omega) > MAX_TIP_MACH {
            return Err(SupersonicTips {
                erpm: mach(omega * RPM) > MAX_TIP_MACH,
                speed: omega,
                radius,
                mach: mach(omega),
                thrust_coefficient: hover_ct(omega),
                rpm_mach: mach(omega * RPM),
                rpm_thrust_coefficient: hover_ct(omega * RPM),
            });
        }
        let ct = hover_ct(omega);
        Ok((ct < MIN_HOVER_THRUST_COEFFICIENT).then(|| {
            format!(
                "median rotor speed {} rad/s is high for the vehicle's weight: hovering at it \
                 would need a thrust coefficient C_T = m g/(n rho pi R^4 Omega^2) of {ct:.2e} \
                 (propellers have about 0.005 to 0.03): rotor speeds logged in RPM? (a mapping \
                 with [signals.rotor_speeds] unit = \"rpm\")",
                about(omega)
            )
        }))
    }

    /// A note when the samples come slower than [`MIN_SAMPLE_RATE`] (not for a test-point
    /// sweep numbered 0, 1, 2, …, whose t is no clock): what it costs and what to log
    /// next time.
    fn slow_sampling(&self) -> Option<String> {
        let step = self.median_time_step()?;
        // The tolerance keeps a clock at exactly the limit (steps of 0.02 s written in
        // decimal, whose differences round a few ulps either way) below it.
        if !self.not_numbered || step * MIN_SAMPLE_RATE <= 1.0 + 1e-6 {
            return None;
        }
        Some(format!(
            "the samples come at {} Hz (median step {} s): angular accelerations derived \
             from the gyro, and rotor-speed dynamics, are resolved only well below {} Hz; log \
             the time base faster next time (PX4: SDLOG_PROFILE bit 3, system identification, \
             or bit 4, high rate; ArduPilot: LOG_BITMASK bit 18, IMU_FAST, for IMU at the \
             loop rate instead of 25 Hz)",
            short(1.0 / step),
            short(step),
            short(0.5 / step)
        ))
    }

    /// Human-readable warnings about units that look wrong, and about sampling too slow
    /// for the dynamics.
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
        let steps = self.time_steps.count() + 1;
        let suspect = time_unit_suspect(self.median_time_step(), self.span(), steps, "")
            .filter(|_| !self.time_unit_trusted());
        // A clock that looks like ms is no slow clock.
        out.extend(suspect.or_else(|| self.slow_sampling()));
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

    /// Repeated values give their exact median; spread ones a value within one bin
    /// (2.2 %) of the true median; values that are not positive and finite are ignored.
    #[test]
    fn median_of_binned_values() {
        let mut m = Median::default();
        assert_eq!(m.median(), None);
        for x in [0.01, 0.01, 5.0, 0.01, 0.0, -1.0, f64::NAN, 1e-30, 1e30] {
            m.push(x);
        }
        assert_eq!(m.count(), 6);
        assert_eq!(m.median(), Some(0.01));
        let mut spread = Median::default();
        for k in 1..=1001 {
            spread.push(k as f64);
        }
        let median = spread.median().unwrap();
        assert!((median / 501.0 - 1.0).abs() < 0.022, "{median}");
    }

    /// 100 Hz in ms and 250 Hz in µs are named; seconds at 100 Hz and a test-point sweep
    /// numbered 0, 1, 2 … are not; 1 kHz in ms is named by its span of days.
    #[test]
    fn time_units_named_from_step_and_span() {
        let ms = time_unit_suspect(Some(10.0), 19_990.0, 2000, ", so X").unwrap();
        assert!(ms.starts_with("time looks like milliseconds, not seconds: the median time step is 10 s (0.1 Hz) and the 2000 samples span 19990 s (5.553 h), so X; "), "{ms}");
        assert!(
            ms.ends_with("([time] unit = \"ms\", docs/mapping.md)"),
            "{ms}"
        );
        let us = time_unit_suspect(Some(4000.0), 4e7, 10_000, "").unwrap();
        assert!(
            us.contains("microseconds") && us.contains("unit = \"us\""),
            "{us}"
        );
        assert_eq!(time_unit_suspect(Some(0.01), 600.0, 60_000, ""), None);
        assert_eq!(time_unit_suspect(Some(1.0), 1999.0, 2000, ""), None);
        assert_eq!(time_unit_suspect(None, 0.0, 1, ""), None);
        let khz = time_unit_suspect(Some(1.0), 600_000.0, 600_001, "").unwrap();
        assert!(khz.contains("milliseconds"), "{khz}");
    }

    /// A log all on the ground says whether its rotors never reached the take-off speed
    /// (√1.25 × the lift speed) or reached it only briefly, never "below" a speed they
    /// passed (a PX4 SITL log reaching 347 rad/s was told it stayed below 344).
    #[test]
    fn a_log_on_the_ground_says_why_against_the_take_off_speed() {
        let text = |peak: f64| {
            let summary = Summary {
                file: "g.ulg".into(),
                rows_read: 10,
                airborne: Some(crate::io::AirborneSpan {
                    ground_samples: 10,
                    peak_speed: peak,
                    lift_speed: 344.0,
                    ..Default::default()
                }),
                ..Default::default()
            };
            no_samples_error(&summary, &ReadOptions::default(), None).to_string()
        };
        let below = text(347.0);
        assert!(below.contains("reach 347 rad/s at most (RMS over the rotors), below the 385 rad/s a take-off needs (1.25^0.5 times the 344 rad/s"), "{below}");
        let brief = text(400.0);
        assert!(brief.contains("reach 400 rad/s at most (RMS over the rotors), but above the 385 rad/s a take-off needs for less than a second"), "{brief}");
    }

    /// t numbering the rows 0, 1, 2, … (a test-point sweep) is trusted however many rows;
    /// the same steps from another start, one step other than 1, or a first t other than
    /// 0 are not (a 1 kHz clock in whole ms looks like that); a declared unit always is.
    #[test]
    fn numbered_rows_and_declared_units_are_trusted() {
        let clock = |declared: bool, times: &mut dyn Iterator<Item = f64>| {
            let mut s = UnitStats::new(declared);
            for t in times {
                s.time(t);
                s.push([0.0, 0.0, -11.77], 1.2, [0.0; 3], &[2000.0; 4]);
            }
            s
        };
        let numbered = clock(false, &mut (0..100_000).map(f64::from));
        assert!(numbered.time_unit_trusted());
        assert!(numbered.warnings().is_empty(), "{:?}", numbered.warnings());
        for times in [
            &mut (7..100_007).map(f64::from) as &mut dyn Iterator<Item = f64>,
            &mut (0..100_000).map(|k| f64::from(k + i32::from(k > 50_000))),
        ] {
            let ms = clock(false, times);
            assert!(!ms.time_unit_trusted());
            assert!(
                ms.warnings()[0].contains("milliseconds"),
                "{:?}",
                ms.warnings()
            );
        }
        assert!(clock(true, &mut (7..100_007).map(f64::from)).time_unit_trusted());
        // 25 Hz from t = 3 s (ArduPilot's default IMU rate) gets the slow-sampling note
        // naming what to log; 50 Hz does not.
        let slow = clock(false, &mut (0..500).map(|k| 3.0 + f64::from(k) * 0.04));
        let note = &slow.warnings()[0];
        assert!(
            note.starts_with("the samples come at 25 Hz") && note.contains("LOG_BITMASK bit 18"),
            "{note}"
        );
        assert!(
            clock(false, &mut (0..500).map(|k| 3.0 + f64::from(k) * 0.02))
                .warnings()
                .is_empty()
        );
    }

    /// The shipped quad's hover (2168 rad/s, R = 0.0635 m: Mach 0.40, C_T 0.010) passes;
    /// the same in RPM on 4.5-inch rotors is refused (Mach 3.4), in eRPM of 7 pole pairs
    /// too, naming eRPM; RPM too slow for Mach 1 on a light vehicle gets a note from the
    /// thrust coefficient alone; spikes above Mach 1 in a few samples do not move the
    /// median.
    #[test]
    fn rotor_speed_check_by_tip_mach_and_hover_thrust() {
        let stats = |speeds: &[f64]| {
            let mut s = UnitStats::default();
            for &w in speeds {
                s.push([0.0, 0.0, -11.77], 1.2, [0.0; 3], &[w; 4]);
            }
            s
        };
        let mut hover = vec![2167.7; 100];
        hover.extend([9000.0; 10]);
        assert_eq!(
            stats(&hover).rotor_speed_check(4, 0.0635, 1.2, 1.225),
            Ok(None)
        );
        let rpm = 2167.7 / RPM;
        let e = stats(&[rpm; 10])
            .rotor_speed_check(4, 0.0565, 1.2, 1.225)
            .unwrap_err();
        assert!(!e.erpm);
        let e = e.to_string();
        assert!(
            e.starts_with("rotor speeds look like RPM, not rad/s: the median rotor speed 20700"),
            "{e}"
        );
        assert!(
            e.contains("Mach 3.44") && e.contains("unit = \"rpm\""),
            "{e}"
        );
        let e = stats(&[7.0 * rpm; 10])
            .rotor_speed_check(4, 0.0635, 1.2, 1.225)
            .unwrap_err();
        assert!(e.erpm);
        let e = e.to_string();
        assert!(e.contains("eRPM") && e.contains("unit = \"erpm\""), "{e}");
        // 3000 RPM on a 0.25 kg vehicle with 8-inch rotors: Mach 0.88, C_T 1.8e-4.
        let note = stats(&[3000.0; 10])
            .rotor_speed_check(4, 0.1, 0.25, 1.225)
            .unwrap()
            .unwrap();
        assert!(note.contains("rotor speeds logged in RPM?"), "{note}");
    }
}
