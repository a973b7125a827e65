//! Time-domain flights: the rigid-body equations of seed Eq. 1 integrated by fixed-step
//! RK4 with first-order motor dynamics Ω̇ = (Ω_cmd − Ω)/τ_m, flown by the cascaded
//! [`Controller`] along an aggressive reference, logged through [`Sensors`].
//!
//! State: NED position, body velocity relative to the ground v, attitude quaternion
//! (body → NED), body rates ω, rotor speeds Ω, and with `inflow_lag` each rotor's induced
//! velocity ν (ν̇ = (ν_qs − ν)/τ, in the same RK4 step). Eq. 1: ṗ = R v, Ṙ = R[ω×],
//! v̇ = v × ω + g Rᵀe₃ + F/m, ω̇ = I⁻¹(Iω × ω + M), with F, M the truth wrench at the
//! air-relative velocity v − Rᵀ w_wind, plus the `trim_moment` moment at the stage's time.
//!
//! Log effects: `rotor_speed_lag` runs the logged rotor speed through its first-order lag
//! once per step ([`super::sensors::lag_step`]), `delay` then reads that history τ late,
//! and `smoothed_loads` filters the finished log's loads ([`super::filter`]).
//!
//! Reference (Froude-scaled by s = √(ℓ/ℓ_ref), lengths × s², times × s): a figure-of-eight
//! with 30 s² m along north at 0.5/s rad/s (15 s m/s peak) and 7 s² m east at twice the
//! frequency, altitude swings of 12 s² m (climb and descent to ~4 s m/s), heading
//! oscillation ±1.2 rad at 1.7/s rad/s, and a multisine roll/pitch excitation (0.07 rad
//! per tone at 0.6, 1.3 and 2.2 Hz ÷ s, random phases) added to the attitude command.
//! Over the first 8 s the tones start from rest: their time argument is ∫env dt with a
//! smoothstep envelope, so frequencies (and the excitation amplitude) ramp in. With ground effect on, the altitude swings start
//! from a hub height of 2R so the flight makes passes near the ground.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::controller::{Controller, Gains, Reference};
use super::disturbance::TrimMoment;
use super::filter::{Butterworth, FilterError};
use super::inflow::InflowState;
use super::output::LogTable;
use super::sensors::{SensorConfig, Sensors, lag_step};
use super::test_matrix::REFERENCE_ARM;
use super::truth::{TruthInput, TruthModel};
use crate::sample::{Sample, SampleChunk};
use crate::vehicle::STANDARD_GRAVITY;

/// Length of the ramp-in of the reference, s (× the Froude time scale).
pub const RAMP_SECONDS: f64 = 8.0;
/// Amplitude of each roll/pitch excitation tone, rad.
pub const EXCITATION_PER_TONE: f64 = 0.07;

/// Settings of one flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightConfig {
    /// Flight duration, s.
    pub duration: f64,
    /// RK4 integration step, s.
    pub step: f64,
    /// Log rate, Hz; the step must divide the log period.
    pub log_rate: f64,
    /// Sensor models.
    pub sensors: SensorConfig,
    /// Omit the true force/moment columns (an "IMU only" log).
    pub imu_only: bool,
    /// Seconds flown low at the start, s: the rotor plane swings between 1 and 4 rotor
    /// diameters above the ground, then the vehicle climbs to the usual altitude
    /// profile (0: the usual profile throughout).
    pub near_ground: f64,
}

impl Default for FlightConfig {
    /// 60 s at a 500 Hz RK4 step, logged at 100 Hz, default sensors, with true wrench.
    fn default() -> Self {
        Self {
            duration: 60.0,
            step: 0.002,
            log_rate: 100.0,
            sensors: SensorConfig::default(),
            imu_only: false,
            near_ground: 0.0,
        }
    }
}

/// Extremes of a flight, for stability checks.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FlightSummary {
    /// Largest tilt of the body z axis from vertical, rad.
    pub max_tilt: f64,
    /// Largest distance from the reference position, m.
    pub max_position_error: f64,
    /// Largest ground speed, m/s.
    pub max_speed: f64,
    /// Largest |ω|, rad/s.
    pub max_rate: f64,
    /// Lowest CG height above ground, m.
    pub min_height: f64,
}

impl FlightSummary {
    fn record(&mut self, tilt: f64, position_error: f64, speed: f64, rate: f64, height: f64) {
        self.max_tilt = self.max_tilt.max(tilt);
        self.max_position_error = self.max_position_error.max(position_error);
        self.max_speed = self.max_speed.max(speed);
        self.max_rate = self.max_rate.max(rate);
        self.min_height = self.min_height.min(height);
    }
}

/// A flown and logged flight.
#[derive(Debug, Clone)]
pub struct FlightLog {
    /// The logged samples (sensor values; wrench true).
    pub samples: SampleChunk,
    /// Logged accelerometer specific force ax, ay, az, m/s².
    pub specific_force: [Vec<f64>; 3],
    /// The log as a table in the CSV data contract.
    pub table: LogTable,
    /// Extremes over the flight.
    pub summary: FlightSummary,
}

/// The aggressive reference of the module documentation.
#[derive(Debug, Clone)]
pub struct Manoeuvre {
    scale: f64,
    base_height: f64,
    phases: [f64; 6],
    /// Low start: its duration (s) and the rotor diameter and hub height (m).
    low: Option<(f64, f64, f64)>,
}

impl Manoeuvre {
    /// The reference for `model`'s vehicle, phases drawn from `rng`.
    pub fn new(model: &TruthModel, rng: &mut StdRng) -> Self {
        let scale = (model.vehicle.arm_length() / REFERENCE_ARM).sqrt();
        let base_height = if model.effects.ground_effect().is_some() {
            2.0 * model.vehicle.props.rotor_radius - model.vehicle.props.hub_height
        } else {
            3.0 * scale * scale
        };
        let phases = [0; 6].map(|_| rng.random_range(0.0..std::f64::consts::TAU));
        Self {
            scale,
            base_height,
            phases,
            low: None,
        }
    }

    /// The same reference flown low for its first `seconds` (see
    /// [`FlightConfig::near_ground`]), then at the altitude of a flight without ground
    /// effect.
    pub fn with_low_start(mut self, model: &TruthModel, seconds: f64) -> Self {
        if seconds > 0.0 {
            let p = &model.vehicle.props;
            self.low = Some((seconds, 2.0 * p.rotor_radius, p.hub_height));
            self.base_height = 3.0 * self.scale * self.scale;
        }
        self
    }

    /// CG height of the reference at time `t` (s) and scaled time `ts`: the usual swing
    /// above `base_height`, or while low the rotor plane between 1 and 4 diameters,
    /// blended into the usual swing over 4 s (smoothstep).
    fn height(&self, t: f64, ts: f64) -> f64 {
        let l = self.scale * self.scale;
        let usual = self.base_height + 6.0 * l * (1.0 - (0.7 * ts).cos());
        let Some((until, diameter, hub)) = self.low else {
            return usual;
        };
        let low = diameter * (2.5 - 1.5 * (0.9 * ts).cos()) - hub;
        let x = ((t - until) / 4.0).clamp(0.0, 1.0);
        let blend = x * x * (3.0 - 2.0 * x);
        (1.0 - blend) * low + blend * usual
    }

    fn position(&self, t: f64) -> (Vector3<f64>, f64, [f64; 2]) {
        let s = self.scale;
        let l = s * s;
        // Amplitude envelope (smoothstep over the ramp) and warped time ∫env dt, so every
        // tone starts from rest and reaches its full frequency at the end of the ramp.
        let ramp = RAMP_SECONDS * s;
        let x = (t / ramp).clamp(0.0, 1.0);
        let env = x * x * (3.0 - 2.0 * x);
        let warped = if t < ramp {
            ramp * (x.powi(3) - 0.5 * x.powi(4))
        } else {
            0.5 * ramp + (t - ramp)
        };
        let ts = warped / s;
        let pos = Vector3::new(
            30.0 * l * (0.5 * ts).sin(),
            7.0 * l * (1.0 * ts).sin(),
            -self.height(t, ts),
        );
        let yaw = 1.2 * (1.7 * ts).sin();
        let tau = std::f64::consts::TAU;
        let tone =
            |k: usize, f: f64| EXCITATION_PER_TONE * (tau * f * t / s + self.phases[k]).sin();
        let exc = [
            env * (tone(0, 0.6) + tone(1, 1.3) + tone(2, 2.2)),
            env * (tone(3, 0.6) + tone(4, 1.3) + tone(5, 2.2)),
        ];
        (pos, yaw, exc)
    }

    /// Reference at time `t` (s); derivatives by central differences (h = 1 ms).
    pub fn reference(&self, t: f64) -> Reference {
        let h = 1e-3;
        let (p0, yaw, excitation) = self.position(t);
        let (pm, yaw_m, _) = self.position(t - h);
        let (pp, yaw_p, _) = self.position(t + h);
        Reference {
            position: p0,
            velocity: (pp - pm) / (2.0 * h),
            acceleration: (pp - 2.0 * p0 + pm) / (h * h),
            yaw,
            yaw_rate: (yaw_p - yaw_m) / (2.0 * h),
            excitation,
        }
    }
}

/// Rigid-body state; `x` = [position(3), body velocity(3), quaternion w,x,y,z(4),
/// rates(3), rotor speeds(N)], followed with `inflow_lag` by the induced velocities (N).
struct Dynamics<'a> {
    model: &'a TruthModel,
    inertia: Matrix3<f64>,
    inertia_inv: Matrix3<f64>,
    wind: Vector3<f64>,
    /// The `trim_moment` effect's moment, if on.
    trim: Option<TrimMoment>,
    /// The `inflow_lag` time constant (s), if on.
    inflow_lag: Option<f64>,
    /// RK4 step h, s.
    step: f64,
}

impl Dynamics<'_> {
    /// Writes ẋ at time `t` (s) into `dx` and returns the wrench (and Ω̇ into
    /// `omega_dot`, one per rotor).
    fn derivative(
        &self,
        x: &[f64],
        t: f64,
        cmd: &[f64],
        inflow: &mut [InflowState],
        dx: &mut [f64],
        omega_dot: &mut [f64],
    ) -> [f64; 6] {
        let n = omega_dot.len();
        let tau = self.model.motor_time_constant;
        let q = UnitQuaternion::from_quaternion(Quaternion::new(x[6], x[7], x[8], x[9]));
        let rot = q.to_rotation_matrix();
        let r = rot.matrix();
        let v = Vector3::new(x[3], x[4], x[5]);
        let w = Vector3::new(x[10], x[11], x[12]);
        let omega = &x[13..13 + n];
        for ((d, c), o) in omega_dot.iter_mut().zip(cmd).zip(omega) {
            *d = (c - o) / tau;
        }
        let v_air = v - r.transpose() * self.wind;
        let input = TruthInput {
            velocity: [v_air.x, v_air.y, v_air.z],
            rates: [w.x, w.y, w.z],
            omega,
            omega_dot,
            height: Some(-x[2]),
            down_row: Some([r[(2, 0)], r[(2, 1)], r[(2, 2)]]),
        };
        let mut wrench = match self.inflow_lag {
            None => self.model.wrench(&input, inflow),
            Some(lag) => {
                // ν̇ = (ν_qs − ν)/τ, the quasi-steady values written into dx first.
                let (nu, nu_dot) = (&x[13 + n..], &mut dx[13 + n..]);
                let wrench = self.model.wrench_lagged_inflow(&input, inflow, nu, nu_dot);
                for (d, v) in nu_dot.iter_mut().zip(nu) {
                    *d = (*d - v) / lag;
                }
                wrench
            }
        };
        if let Some(trim) = &self.trim {
            let m = trim.at(t);
            for k in 0..3 {
                wrench[3 + k] += m[k];
            }
        }
        let f = Vector3::new(wrench[0], wrench[1], wrench[2]);
        let m = Vector3::new(wrench[3], wrench[4], wrench[5]);
        let pdot = r * v;
        let qdot =
            Quaternion::new(x[6], x[7], x[8], x[9]) * Quaternion::new(0.0, w.x, w.y, w.z) * 0.5;
        let vdot = v.cross(&w)
            + STANDARD_GRAVITY * r.transpose() * Vector3::z()
            + f / self.model.vehicle.props.mass;
        let wdot = self.inertia_inv * ((self.inertia * w).cross(&w) + m);
        dx[0..3].copy_from_slice(pdot.as_slice());
        dx[3..6].copy_from_slice(vdot.as_slice());
        dx[6..10].copy_from_slice(&[qdot.w, qdot.i, qdot.j, qdot.k]);
        dx[10..13].copy_from_slice(wdot.as_slice());
        dx[13..13 + n].copy_from_slice(omega_dot);
        wrench
    }
}

/// Work vectors of one RK4 step.
struct Rk4Scratch {
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    tmp: Vec<f64>,
    omega_dot: Vec<f64>,
}

impl Rk4Scratch {
    /// Work vectors for a state of `len` values and `rotors` rotors.
    fn new(len: usize, rotors: usize) -> Self {
        Self {
            k2: vec![0.0; len],
            k3: vec![0.0; len],
            k4: vec![0.0; len],
            tmp: vec![0.0; len],
            omega_dot: vec![0.0; rotors],
        }
    }
}

impl Dynamics<'_> {
    /// One classical RK4 step of length h (s) from `x` at time `t` (s) with slope `k1`
    /// at `x`, the rotor command held; renormalises the quaternion.
    // The stage arrays are indexed together; an index loop reads as the textbook formula.
    #[allow(clippy::needless_range_loop)]
    fn rk4_step(
        &self,
        x: &mut [f64],
        t: f64,
        cmd: &[f64],
        k1: &[f64],
        inflow: &mut [InflowState],
        s: &mut Rk4Scratch,
    ) {
        let h = self.step;
        for i in 0..x.len() {
            s.tmp[i] = x[i] + 0.5 * h * k1[i];
        }
        self.derivative(
            &s.tmp,
            t + 0.5 * h,
            cmd,
            inflow,
            &mut s.k2,
            &mut s.omega_dot,
        );
        for i in 0..x.len() {
            s.tmp[i] = x[i] + 0.5 * h * s.k2[i];
        }
        self.derivative(
            &s.tmp,
            t + 0.5 * h,
            cmd,
            inflow,
            &mut s.k3,
            &mut s.omega_dot,
        );
        for i in 0..x.len() {
            s.tmp[i] = x[i] + h * s.k3[i];
        }
        self.derivative(&s.tmp, t + h, cmd, inflow, &mut s.k4, &mut s.omega_dot);
        for i in 0..x.len() {
            x[i] += h / 6.0 * (k1[i] + 2.0 * s.k2[i] + 2.0 * s.k3[i] + s.k4[i]);
        }
        let norm = x[6..10].iter().map(|c| c * c).sum::<f64>().sqrt();
        x[6..10].iter_mut().for_each(|c| *c /= norm);
    }
}

/// Why a flight cannot be flown, or diverged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlightError {
    /// A duration, step or log rate that is not positive.
    #[error("flight: duration, step and log rate must be > 0")]
    NotPositive,
    /// A log period that is not a whole number of integration steps.
    #[error(
        "flight: the log period 1/{log_rate} s must be a whole number of integration steps of {step} s"
    )]
    LogPeriod {
        /// Log rate, Hz.
        log_rate: f64,
        /// Integration step, s.
        step: f64,
    },
    /// The `smoothed_loads` filter cannot be designed at the log rate.
    #[error("effect `smoothed_loads` at the log rate {log_rate} Hz: {source}")]
    Smoothing {
        /// Log rate, Hz.
        log_rate: f64,
        /// Why the filter cannot be designed.
        source: FilterError,
    },
    /// An `inflow_lag` time constant shorter than the integration step.
    #[error(
        "effect `inflow_lag`: tau = {lag} s is shorter than the integration step {step} s; use a step (`--step`) of at most {lag} s"
    )]
    InflowLag {
        /// The time constant, s.
        lag: f64,
        /// Integration step, s.
        step: f64,
    },
    /// The vehicle's inertia matrix has no inverse.
    #[error("flight: singular inertia")]
    SingularInertia,
    /// The vehicle tipped over, hit the ground, left the reference or went non-finite.
    #[error(
        "flight diverged at t = {t:.3} s: tilt {tilt:.1} deg, {distance:.2} m from the reference, height {height:.2} m"
    )]
    Diverged {
        /// Time, s.
        t: f64,
        /// Tilt of the body z axis from the vertical, deg.
        tilt: f64,
        /// Distance from the reference position, m.
        distance: f64,
        /// Height, m.
        height: f64,
    },
}

/// Integration steps per log period; refuses periods that are not a whole number of steps.
fn steps_per_log(config: &FlightConfig) -> Result<usize, FlightError> {
    if !(config.step > 0.0 && config.duration > 0.0 && config.log_rate > 0.0) {
        return Err(FlightError::NotPositive);
    }
    let ratio = (1.0 / (config.step * config.log_rate)).round();
    if ratio < 1.0 || (ratio * config.step * config.log_rate - 1.0).abs() > 1e-9 {
        return Err(FlightError::LogPeriod {
            log_rate: config.log_rate,
            step: config.step,
        });
    }
    Ok(ratio as usize)
}

/// Aerodynamic torque of one rotor in still-air hover, N m (for the allocation k_Q).
fn hover_torque(model: &TruthModel) -> f64 {
    let kin = super::blade_element::RotorKinematics {
        omega: model.hover_omega,
        spin: 1.0,
        hub_velocity: [0.0; 3],
        body_rates: [0.0; 3],
    };
    -model
        .rotor
        .loads(&kin, &model.inflow, &mut InflowState::default())
        .moment[2]
}

/// Flies `model` for `config` with seed `seed`; an error says when and how the flight
/// diverged (tilt beyond 90°, ground contact, or 50 s² m from the reference).
pub fn fly(model: &TruthModel, config: &FlightConfig, seed: u64) -> Result<FlightLog, FlightError> {
    let ratio = steps_per_log(config)?;
    let smoothing = load_smoothing(model, config)?;
    let inflow_lag = model.effects.inflow_lag();
    if let Some(lag) = inflow_lag
        && lag < config.step
    {
        return Err(FlightError::InflowLag {
            lag,
            step: config.step,
        });
    }
    let vehicle = &model.vehicle;
    let n = vehicle.rotor_count();
    let mut rng = StdRng::seed_from_u64(seed);
    let manoeuvre = Manoeuvre::new(model, &mut rng).with_low_start(model, config.near_ground);
    let sensors = Sensors::new(config.sensors, &mut rng);
    let inertia = Matrix3::from_fn(|r, c| vehicle.props.inertia[r][c]);
    let wind = model.effects.wind();
    let dynamics = Dynamics {
        model,
        inertia,
        inertia_inv: inertia.try_inverse().ok_or(FlightError::SingularInertia)?,
        wind: Vector3::new(wind[0], wind[1], wind[2]),
        trim: model
            .effects
            .trim_moment()
            .map(|(rms, f)| TrimMoment::new(rms, f, seed)),
        inflow_lag,
        step: config.step,
    };
    let mut inflow = model.inflow_states();
    let controller = Controller::new(
        vehicle,
        model.hover_omega,
        hover_torque(model),
        Gains::for_time_scale(manoeuvre.scale),
    );
    let r0 = manoeuvre.reference(0.0);
    let len = 13 + n + if inflow_lag.is_some() { n } else { 0 };
    let mut x = vec![0.0; len];
    x[0..3].copy_from_slice(r0.position.as_slice());
    x[6] = 1.0;
    x[13..13 + n].fill(model.hover_omega);
    if inflow_lag.is_some() {
        // The lagged inflow starts at its quasi-steady value (written into the state's ν;
        // the wrench at ν = 0 is not used): a steady hover start.
        let (state, nu) = x.split_at_mut(13 + n);
        let zeros = vec![0.0; n];
        let input = TruthInput {
            velocity: [0.0; 3],
            rates: [0.0; 3],
            omega: &state[13..],
            omega_dot: &zeros,
            height: Some(-state[2]),
            down_row: Some([0.0, 0.0, 1.0]),
        };
        model.wrench_lagged_inflow(&input, &mut inflow, &zeros, nu);
    }
    let steps = (config.duration / config.step).round() as usize;
    let n_log = steps / ratio + 1;
    let mut samples = SampleChunk::with_capacity(n, n_log, true);
    let mut specific_force: [Vec<f64>; 3] = Default::default();
    let mut summary = FlightSummary {
        min_height: f64::INFINITY,
        ..Default::default()
    };
    let delay_steps = model.effects.delay() / config.step;
    let speed_lag = model.effects.rotor_speed_lag();
    // The logged (lagged) rotor speeds y, starting at the true hover speeds.
    let mut lagged = x[13..13 + n].to_vec();
    let mut previous = lagged.clone();
    let mut history: Vec<f64> = Vec::with_capacity((steps + 1) * 2 * n);
    let mut cmd = vec![0.0; n];
    let mut omega_dot = vec![0.0; n];
    let mut k1 = vec![0.0; len];
    let mut scratch = Rk4Scratch::new(len, n);
    let mut sample = Sample {
        omega: vec![0.0; n],
        omega_dot: vec![0.0; n],
        ..Default::default()
    };
    for step in 0..=steps {
        let t = step as f64 * config.step;
        let reference = manoeuvre.reference(t);
        let q = UnitQuaternion::from_quaternion(Quaternion::new(x[6], x[7], x[8], x[9]));
        let rot: Rotation3<f64> = q.to_rotation_matrix();
        let pos = Vector3::new(x[0], x[1], x[2]);
        let v_ned = rot * Vector3::new(x[3], x[4], x[5]);
        let rates = Vector3::new(x[10], x[11], x[12]);
        controller.command(&reference, &pos, &v_ned, &rot, &rates, &mut cmd);
        let wrench = dynamics.derivative(&x, t, &cmd, &mut inflow, &mut k1, &mut omega_dot);
        match speed_lag {
            None => {
                history.extend_from_slice(&x[13..13 + n]);
                history.extend_from_slice(&omega_dot);
            }
            Some(lag) => {
                // y' = (Ω − y)/τ over the step just taken, Ω linear in between; the
                // logged Ω̇ is y', the derivative of the logged speed.
                for i in 0..n {
                    lagged[i] = lag_step(lagged[i], previous[i], x[13 + i], config.step, lag);
                }
                previous.copy_from_slice(&x[13..13 + n]);
                history.extend_from_slice(&lagged);
                history.extend((0..n).map(|i| (x[13 + i] - lagged[i]) / lag));
            }
        }
        // Extremes and divergence checks.
        let tilt = rot.matrix()[(2, 2)].clamp(-1.0, 1.0).acos();
        let err = (reference.position - pos).norm();
        summary.record(tilt, err, v_ned.norm(), rates.norm(), -x[2]);
        let l = manoeuvre.scale * manoeuvre.scale;
        if !(tilt < std::f64::consts::FRAC_PI_2
            && err < 50.0 * l
            && -x[2] > 0.0
            && x.iter().all(|v| v.is_finite()))
        {
            return Err(FlightError::Diverged {
                t,
                tilt: tilt.to_degrees(),
                distance: err,
                height: -x[2],
            });
        }
        if step % ratio == 0 {
            log_sample(
                &mut sample,
                t,
                &x,
                &wrench,
                &history,
                step as f64 - delay_steps,
                &sensors,
                &mut rng,
                &q,
            );
            samples.push(&sample);
            let a =
                sensors.accelerometer([0, 1, 2].map(|k| wrench[k] / vehicle.props.mass), &mut rng);
            for k in 0..3 {
                specific_force[k].push(a[k]);
            }
        }
        if step == steps {
            break;
        }
        dynamics.rk4_step(&mut x, t, &cmd, &k1, &mut inflow, &mut scratch);
    }
    if let Some(filter) = smoothing {
        for column in samples.wrench.iter_mut().chain(specific_force.iter_mut()) {
            *column = filter.filtfilt(column);
        }
    }
    let mut table = LogTable::from_chunk(&samples, !config.imu_only);
    for (k, name) in ["ax", "ay", "az"].iter().enumerate() {
        table.insert_before("height", name, specific_force[k].clone());
    }
    Ok(FlightLog {
        samples,
        specific_force,
        table,
        summary,
    })
}

/// The `smoothed_loads` filter at the log rate, if the effect is on; refuses a cut-off at
/// or above half the log rate.
fn load_smoothing(
    model: &TruthModel,
    config: &FlightConfig,
) -> Result<Option<Butterworth>, FlightError> {
    model
        .effects
        .smoothed_loads()
        .map(|(cutoff, order)| {
            Butterworth::low_pass(order, cutoff, config.log_rate).map_err(|source| {
                FlightError::Smoothing {
                    log_rate: config.log_rate,
                    source,
                }
            })
        })
        .transpose()
}

/// Fills `s` with the logged values at time `t`: gyro, velocity estimate (ground-relative
/// body velocity), eRPM rotor speeds and true Ω̇ at the (possibly delayed) step
/// `delayed_step`, true wrench, height and attitude.
#[allow(clippy::too_many_arguments)]
fn log_sample(
    s: &mut Sample,
    t: f64,
    x: &[f64],
    wrench: &[f64; 6],
    history: &[f64],
    delayed_step: f64,
    sensors: &Sensors,
    rng: &mut StdRng,
    q: &UnitQuaternion<f64>,
) {
    let n = s.omega.len();
    s.t = t;
    s.velocity = sensors.velocity([x[3], x[4], x[5]], rng);
    s.rates = sensors.gyro([x[10], x[11], x[12]], rng);
    // Linear interpolation in the per-step history of (Ω, Ω̇).
    let last = history.len() / (2 * n) - 1;
    let pos = delayed_step.clamp(0.0, last as f64);
    let i0 = pos.floor() as usize;
    let i1 = (i0 + 1).min(last);
    let frac = pos - i0 as f64;
    for i in 0..n {
        let at = |row: usize, col: usize| history[row * 2 * n + col];
        let w = at(i0, i) * (1.0 - frac) + at(i1, i) * frac;
        s.omega[i] = sensors.rotor_speed(w);
        s.omega_dot[i] = at(i0, n + i) * (1.0 - frac) + at(i1, n + i) * frac;
    }
    s.wrench = *wrench;
    s.height = Some(-x[2]);
    s.attitude = Some([q.w, q.i, q.j, q.k]);
}
