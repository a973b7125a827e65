//! The flight data kind: the independent airframe flown closed loop by a controller of
//! its own (velocity and altitude loops with an integrator on the climb rate, a
//! geometric attitude error fed to limited rate set points, a rate PI loop, mixed with
//! the nominal rotor model), with multisine excitation on the commanded moments and
//! thrust, logged with IMU-like noise.
//!
//! The flight starts low (altitude set points put the hubs 0.8–2 rotor diameters above
//! the ground for the first [`FlightConfig::low_seconds`], flown gently), then climbs
//! to 2–8 m and flies random velocity steps up to 12 m/s in every direction with random
//! yaw rates. Set points, excitation and sensor noise depend on the seed only. There is
//! no ground contact model: a flight whose CG comes within 2 cm of the ground panics.

use mrsysid::Sample;
use nalgebra::{DMatrix, Matrix3, UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::physics::{Airframe, GRAVITY, LoadState};
use super::surface::gauss;

/// Integration step, s (controller and motors run at this rate too).
const STEP: f64 = 0.001;

/// What to fly and log.
#[derive(Debug, Clone, Copy)]
pub struct FlightConfig {
    /// Flight length, s.
    pub duration: f64,
    /// Log rate, Hz (a divisor of 1000).
    pub rate_hz: u32,
    /// Seconds flown near the ground at the start, s.
    pub low_seconds: f64,
    /// Every sensor's noise (and the gyro bias) times this (-).
    pub noise_scale: f64,
}

impl Default for FlightConfig {
    /// 60 s at 200 Hz, the first 20 s low, the stated sensor noise.
    fn default() -> Self {
        Self {
            duration: 60.0,
            rate_hz: 200,
            low_seconds: 20.0,
            noise_scale: 1.0,
        }
    }
}

impl FlightConfig {
    /// A shorter flight: 30 s at 100 Hz, the first 10 s low.
    pub fn short() -> Self {
        Self {
            duration: 30.0,
            rate_hz: 100,
            low_seconds: 10.0,
            ..Self::default()
        }
    }
}

/// Sensor noise (standard deviations, SI units).
struct Noise {
    velocity: f64,
    gyro: f64,
    gyro_bias: f64,
    omega: f64,
    omega_dot: f64,
    force: f64,
    moment: f64,
    height: f64,
}

/// An estimator's velocity (0.04 m/s), a MEMS gyro (0.004 rad/s, bias 0.002 rad/s), ESC
/// telemetry (3 rad/s), a differentiated rotor speed (150 rad/s²), loads as a 6-axis
/// estimate from m a and I ω̇ (0.08 N, 0.004 N m), a range finder (0.01 m).
const NOISE: Noise = Noise {
    velocity: 0.04,
    gyro: 0.004,
    gyro_bias: 0.002,
    omega: 3.0,
    omega_dot: 150.0,
    force: 0.08,
    moment: 0.004,
    height: 0.01,
};

/// One set-point segment.
#[derive(Debug, Clone, Copy)]
struct SetPoint {
    start: f64,
    velocity_ne: [f64; 2],
    altitude: f64,
    yaw_rate: f64,
    /// Largest horizontal acceleration commanded, m/s² (the tilt limit).
    max_accel: f64,
}

/// Set points drawn for the whole flight (the low altitudes in proportion to the rotor
/// radius, `length`: the reference's rotor radii).
fn schedule(cfg: &FlightConfig, length: f64, rng: &mut StdRng) -> Vec<SetPoint> {
    let mut out = Vec::new();
    let mut t = 0.0;
    while t < cfg.duration {
        let low = t < cfg.low_seconds;
        // Near the ground: gentle (2 m/s, tilt under 12°: a hub dips at most 2.7 cm
        // below the CG); higher up: up to 12 m/s and 27°.
        let (speed, hold, max_accel) = if low {
            (2.0, 2.0, 2.0)
        } else {
            (12.0, 3.0, 5.0)
        };
        let heading = rng.random_range(0.0..std::f64::consts::TAU);
        let v = speed * rng.random::<f64>().sqrt();
        out.push(SetPoint {
            start: t,
            velocity_ne: [v * heading.cos(), v * heading.sin()],
            altitude: if low {
                rng.random_range(0.08 * length..0.25 * length)
            } else {
                rng.random_range(2.0..8.0)
            },
            yaw_rate: rng.random_range(-1.5..1.5),
            max_accel,
        });
        t += hold * rng.random_range(0.6..1.4);
    }
    out
}

/// A sum of sines with random frequencies in 0.3–10 Hz and phases, RMS `rms`.
struct Multisine {
    parts: Vec<(f64, f64, f64)>,
}

impl Multisine {
    fn new(rms: f64, rng: &mut StdRng) -> Self {
        let n = 8;
        let amplitude = rms * (2.0 / n as f64).sqrt();
        let parts = (0..n)
            .map(|_| {
                let f: f64 = rng.random_range(0.3..10.0);
                let phase = rng.random_range(0.0..std::f64::consts::TAU);
                (amplitude, std::f64::consts::TAU * f, phase)
            })
            .collect();
        Self { parts }
    }

    fn at(&self, t: f64) -> f64 {
        self.parts
            .iter()
            .map(|(a, w, p)| a * (w * t + p).sin())
            .sum()
    }
}

/// The rigid body and rotor state.
struct State {
    position: Vector3<f64>,
    velocity: Vector3<f64>,
    attitude: UnitQuaternion<f64>,
    rates: Vector3<f64>,
    omega: Vec<f64>,
}

/// The controller's memory: smoothed set points, heading set point, rate integrator.
struct Controller {
    velocity_sp: Vector3<f64>,
    altitude_sp: f64,
    heading: f64,
    yaw_rate_sp: f64,
    climb_integral: f64,
    integral: Vector3<f64>,
    mixer: DMatrix<f64>,
}

impl Controller {
    fn new(air: &Airframe, altitude: f64) -> Self {
        let c = air.rotor.k_q / air.rotor.k_t;
        let n = air.nominal_hubs.len();
        let a = DMatrix::from_fn(4, n, |row, i| match row {
            0 => 1.0,
            1 => -air.nominal_hubs[i].y,
            2 => air.nominal_hubs[i].x,
            _ => -air.spins[i] * c,
        });
        let mixer = a.pseudo_inverse(1e-12).expect("mixer of full rank");
        Self {
            velocity_sp: Vector3::zeros(),
            altitude_sp: altitude,
            heading: 0.0,
            yaw_rate_sp: 0.0,
            climb_integral: 0.0,
            integral: Vector3::zeros(),
            mixer,
        }
    }

    /// Rotor speed commands, rad/s.
    fn command(
        &mut self,
        air: &Airframe,
        s: &State,
        sp: &SetPoint,
        excitation: [f64; 4],
    ) -> Vec<f64> {
        let smooth = STEP / 0.4;
        let target = Vector3::new(sp.velocity_ne[0], sp.velocity_ne[1], 0.0);
        self.velocity_sp += smooth * (target - self.velocity_sp);
        self.altitude_sp += smooth * (sp.altitude - self.altitude_sp);
        self.yaw_rate_sp += smooth * (sp.yaw_rate - self.yaw_rate_sp);
        self.heading += self.yaw_rate_sp * STEP;
        let altitude = -s.position.z;
        // Descents under a quarter of the hover induced velocity (2.5 m/s on the
        // reference quadrotor): far from the vortex ring, which the model lacks.
        let climb_sp = (1.5 * (self.altitude_sp - altitude)).clamp(-2.5 * air.scale.induced, 3.5);
        let climb_error = climb_sp + s.velocity.z;
        self.climb_integral = (self.climb_integral + climb_error * STEP).clamp(-2.0, 2.0);
        let climb_accel = 4.0 * climb_error + 3.0 * self.climb_integral;
        let mut horizontal =
            1.5 * (self.velocity_sp - Vector3::new(s.velocity.x, s.velocity.y, 0.0));
        let h = horizontal.norm();
        if h > sp.max_accel {
            horizontal *= sp.max_accel / h;
        }
        let accel = Vector3::new(horizontal.x, horizontal.y, -climb_accel);
        let force = air.mass * (accel - Vector3::new(0.0, 0.0, GRAVITY));
        let rot = s.attitude.to_rotation_matrix().into_inner();
        let thrust = force.dot(&(-rot.column(2))) + excitation[0];
        let z_b = -force.normalize();
        let x_c = Vector3::new(self.heading.cos(), self.heading.sin(), 0.0);
        let y_b = z_b.cross(&x_c).normalize();
        let x_b = y_b.cross(&z_b);
        let desired = Matrix3::from_columns(&[x_b, y_b, z_b]);
        let e = 0.5 * (desired.transpose() * rot - rot.transpose() * desired);
        let e_r = Vector3::new(e[(2, 1)], e[(0, 2)], e[(1, 0)]);
        // Attitude P to a limited rate set point, then a rate PI loop (gains per axis:
        // roll and pitch ~14 rad/s, yaw ~3 rad/s of rate bandwidth).
        let limit = Vector3::new(4.0, 4.0, 1.5);
        let rate_sp = (-Vector3::new(6.0, 6.0, 2.5).component_mul(&e_r))
            .zip_map(&limit, |x, l| x.clamp(-l, l))
            + Vector3::new(0.0, 0.0, self.yaw_rate_sp);
        let e_w = s.rates - rate_sp;
        self.integral = (self.integral + e_w * STEP).map(|x| x.clamp(-1.0, 1.0));
        let i = &air.inertia;
        let inertia = Vector3::from(air.scale.inertia);
        let k_p = Vector3::new(0.15, 0.16, 0.06).component_mul(&inertia);
        let k_i = Vector3::new(0.3, 0.3, 0.05).component_mul(&inertia);
        let moment = -k_p.component_mul(&e_w) - k_i.component_mul(&self.integral)
            + s.rates.cross(&(i * s.rates))
            + Vector3::new(excitation[1], excitation[2], excitation[3]);
        let wanted = nalgebra::DVector::from_vec(vec![thrust, moment.x, moment.y, moment.z]);
        let per_rotor = &self.mixer * wanted;
        let hover = air.hover_omega();
        per_rotor
            .iter()
            .map(|&t| {
                (t.max(0.0) / air.rotor.k_t)
                    .sqrt()
                    .clamp(0.3 * hover, 1.8 * hover)
            })
            .collect()
    }
}

/// Flies `air` for `cfg` with seed `seed` and returns the logged samples (velocity,
/// rates, rotor speeds and accelerations, wrench, height, attitude).
pub fn fly(air: &Airframe, cfg: &FlightConfig, seed: u64) -> Vec<Sample> {
    let mut plan = StdRng::seed_from_u64(seed);
    let mut noise = StdRng::seed_from_u64(seed ^ 0xf119_470b);
    let scale = air.scale;
    let set_points = schedule(cfg, scale.length, &mut plan);
    // Thrust excitation in proportion to the mass, moments to the inertias.
    let excitation = [
        1.0 * scale.mass,
        0.06 * scale.inertia[0],
        0.06 * scale.inertia[1],
        0.015 * scale.inertia[2],
    ]
    .map(|rms| Multisine::new(rms, &mut plan));
    let sensors = Sensors {
        gyro_bias: Vector3::from_fn(|_, _| cfg.noise_scale * NOISE.gyro_bias * gauss(&mut noise)),
        force: NOISE.force * scale.mass,
        moment: NOISE.moment * scale.inertia_sum,
    };
    // A draw of sensor noise of standard deviation `sd` (scaled by the configuration).
    let mut draw = |sd: f64| cfg.noise_scale * sd * gauss(&mut noise);
    let hover = air.hover_omega();
    let start_altitude = 0.25 * scale.length;
    let mut s = State {
        position: Vector3::new(0.0, 0.0, -start_altitude),
        velocity: Vector3::zeros(),
        attitude: UnitQuaternion::identity(),
        rates: Vector3::zeros(),
        omega: vec![hover; air.hubs.len()],
    };
    let mut ctrl = Controller::new(air, start_altitude);
    let inertia_inv = air.inertia.try_inverse().expect("inertia invertible");
    let steps = (cfg.duration / STEP).round() as usize;
    let every = (1000 / cfg.rate_hz) as usize;
    let decay = (-STEP / air.rotor.motor_tau).exp();
    let mut segment = 0;
    let mut out = Vec::with_capacity(steps / every + 1);
    for k in 0..steps {
        let t = k as f64 * STEP;
        while segment + 1 < set_points.len() && set_points[segment + 1].start <= t {
            segment += 1;
        }
        let exc = [0, 1, 2, 3].map(|j| excitation[j].at(t));
        let cmd = ctrl.command(air, &s, &set_points[segment], exc);
        let omega_dot: Vec<f64> = cmd
            .iter()
            .zip(&s.omega)
            .map(|(c, w)| (c - w) / air.rotor.motor_tau)
            .collect();
        let body_velocity = s.attitude.inverse() * s.velocity;
        let height = -s.position.z;
        assert!(
            height > 0.02 * scale.length,
            "seed {seed}: the flight touched the ground at {t} s"
        );
        let wrench = air.wrench(&LoadState {
            velocity: body_velocity,
            rates: s.rates,
            omega: &s.omega,
            omega_dot: &omega_dot,
            height,
            attitude: s.attitude,
        });
        if k % every == 0 {
            out.push(log_sample(
                t,
                &s,
                body_velocity,
                &omega_dot,
                wrench,
                &sensors,
                &mut draw,
            ));
        }
        let force = Vector3::new(wrench[0], wrench[1], wrench[2]);
        let moment = Vector3::new(wrench[3], wrench[4], wrench[5]);
        let accel = s.attitude * force / air.mass + Vector3::new(0.0, 0.0, GRAVITY);
        s.velocity += accel * STEP;
        s.position += s.velocity * STEP;
        let spin = inertia_inv * (moment - s.rates.cross(&(air.inertia * s.rates)));
        s.rates += spin * STEP;
        s.attitude *= UnitQuaternion::from_scaled_axis(s.rates * STEP);
        for (w, c) in s.omega.iter_mut().zip(&cmd) {
            *w = c + (*w - c) * decay;
        }
    }
    out
}

/// What a flight's sensors add beyond [`NOISE`]: the gyro's bias, and the load
/// estimates' noise, which the accelerometer's and the differentiated gyro's noise
/// carry times the mass and the inertia (standard deviations before the flight's
/// `noise_scale`).
struct Sensors {
    gyro_bias: Vector3<f64>,
    force: f64,
    moment: f64,
}

/// One logged sample of the true state with sensor noise.
fn log_sample(
    t: f64,
    s: &State,
    body_velocity: Vector3<f64>,
    omega_dot: &[f64],
    wrench: [f64; 6],
    sensors: &Sensors,
    n: &mut impl FnMut(f64) -> f64,
) -> Sample {
    let velocity = body_velocity.map(|x| x + n(NOISE.velocity));
    let rates = (s.rates + sensors.gyro_bias).map(|x| x + n(NOISE.gyro));
    let omega = s.omega.iter().map(|w| w + n(NOISE.omega)).collect();
    let omega_dot = omega_dot.iter().map(|w| w + n(NOISE.omega_dot)).collect();
    let mut measured = wrench;
    for (j, f) in measured.iter_mut().enumerate() {
        *f += n(if j < 3 { sensors.force } else { sensors.moment });
    }
    let q = s.attitude.quaternion();
    Sample {
        t,
        velocity: velocity.into(),
        rates: rates.into(),
        omega,
        omega_dot,
        wrench: measured,
        height: Some(-s.position.z + n(NOISE.height)),
        attitude: Some([q.w, q.i, q.j, q.k]),
    }
}
