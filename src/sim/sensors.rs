//! Flight-log sensors: accelerometer specific force and gyro with white noise and a
//! constant bias drawn per flight, velocity from a state estimator with white noise, and
//! rotor speed from ESC telemetry quantised in electrical RPM (optionally through the
//! first-order lag of [`lag_step`]).

use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};

/// Noise, bias and quantisation settings (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorConfig {
    /// Accelerometer white-noise standard deviation, m/s².
    pub accel_noise: f64,
    /// Standard deviation of the per-flight accelerometer bias, m/s².
    pub accel_bias: f64,
    /// Gyro white-noise standard deviation, rad/s.
    pub gyro_noise: f64,
    /// Standard deviation of the per-flight gyro bias, rad/s.
    pub gyro_bias: f64,
    /// Velocity white-noise standard deviation, m/s.
    pub velocity_noise: f64,
    /// Motor pole pairs (eRPM = RPM × pole pairs).
    pub pole_pairs: f64,
    /// eRPM resolution of the telemetry (DShot telemetry reports eRPM/100).
    pub erpm_resolution: f64,
}

impl Default for SensorConfig {
    /// A consumer MEMS IMU and bidirectional-DShot telemetry: 0.05 m/s² and 0.003 rad/s
    /// noise at the log rate, biases 0.03 m/s² and 0.002 rad/s, velocity noise 0.03 m/s,
    /// 7 pole pairs, 100 eRPM steps (1.5 rad/s).
    fn default() -> Self {
        Self {
            accel_noise: 0.05,
            accel_bias: 0.03,
            gyro_noise: 0.003,
            gyro_bias: 0.002,
            velocity_noise: 0.03,
            pole_pairs: 7.0,
            erpm_resolution: 100.0,
        }
    }
}

/// Sensors of one flight, with their drawn biases.
#[derive(Debug, Clone)]
pub struct Sensors {
    config: SensorConfig,
    accel_bias: [f64; 3],
    gyro_bias: [f64; 3],
}

impl Sensors {
    /// Draws the per-flight biases from `rng`.
    pub fn new(config: SensorConfig, rng: &mut StdRng) -> Self {
        let mut draw = |s: f64| [0; 3].map(|_| s * gauss(rng));
        let accel_bias = draw(config.accel_bias);
        let gyro_bias = draw(config.gyro_bias);
        Self {
            config,
            accel_bias,
            gyro_bias,
        }
    }

    /// Accelerometer reading of specific force `f` (m/s², F/m, gravity excluded).
    pub fn accelerometer(&self, f: [f64; 3], rng: &mut StdRng) -> [f64; 3] {
        [0, 1, 2].map(|k| f[k] + self.accel_bias[k] + self.config.accel_noise * gauss(rng))
    }

    /// Gyro reading of body rates `w` (rad/s).
    pub fn gyro(&self, w: [f64; 3], rng: &mut StdRng) -> [f64; 3] {
        [0, 1, 2].map(|k| w[k] + self.gyro_bias[k] + self.config.gyro_noise * gauss(rng))
    }

    /// Estimated body velocity from `v` (m/s).
    pub fn velocity(&self, v: [f64; 3], rng: &mut StdRng) -> [f64; 3] {
        v.map(|x| x + self.config.velocity_noise * gauss(rng))
    }

    /// Rotor speed (rad/s) as reported through eRPM telemetry: rounded down to the
    /// telemetry resolution, converted back to rad/s.
    pub fn rotor_speed(&self, omega: f64) -> f64 {
        let per_erpm = 2.0 * std::f64::consts::PI / 60.0 / self.config.pole_pairs;
        let erpm = omega / per_erpm;
        let q = (erpm / self.config.erpm_resolution).floor() * self.config.erpm_resolution;
        q * per_erpm
    }
}

/// One step of the first-order lag y' = (x − y)/τ (an ESC telemetry filter, the
/// `rotor_speed_lag` effect): from y = `y0` with the input moving linearly from `x0` to
/// `x1` over `h` s, the exact solution y(h) = x1 + (y0 − x0) a − (x1 − x0)(τ/h)(1 − a),
/// a = e^(−h/τ) (τ = `tau`, s).
pub fn lag_step(y0: f64, x0: f64, x1: f64, h: f64, tau: f64) -> f64 {
    let a = (-h / tau).exp();
    x1 + (y0 - x0) * a - (x1 - x0) * (tau / h) * (1.0 - a)
}

fn gauss(rng: &mut StdRng) -> f64 {
    let x: f64 = StandardNormal.sample(rng);
    x
}
