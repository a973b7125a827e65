//! Shared helpers of the io tests: a test vehicle and analytic sample streams.
#![allow(dead_code)]

use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};
use mrsysid::{Sample, SampleChunk};

/// A quad-x test vehicle with J_z = 0 (no rotor-acceleration derivation).
pub fn quad(rotor_inertia: f64) -> Vehicle {
    Vehicle::preset(
        "test-quad",
        Preset::QuadX,
        0.16,
        1.0,
        MassAndRotorProperties {
            mass: 1.2,
            inertia: [[0.011, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.021]],
            air_density: 1.225,
            rotor_radius: 0.0635,
            hub_height: 0.02,
            rotor_inertia,
        },
    )
    .expect("valid test vehicle")
}

/// `n` samples at `rate_hz` of smooth analytic flight signals, in one chunk, with
/// attitude and height.
pub fn analytic_chunk(n: usize, rate_hz: f64) -> SampleChunk {
    let mut c = SampleChunk::with_capacity(4, n, true);
    for k in 0..n {
        let t = 1.0 + k as f64 / rate_hz;
        let half = 0.2 * (0.3 * t).sin();
        c.push(&Sample {
            t,
            velocity: std::array::from_fn(|a| 2.0 * (0.5 * t + a as f64).sin()),
            rates: std::array::from_fn(|a| 0.3 * (1.3 * t + a as f64).cos()),
            omega: (0..4)
                .map(|i| 900.0 + 50.0 * (2.0 * t + i as f64).sin())
                .collect(),
            omega_dot: (0..4).map(|i| 100.0 * (2.0 * t + i as f64).cos()).collect(),
            wrench: std::array::from_fn(|a| {
                let base = if a == 2 { -11.8 } else { 0.0 };
                base + 0.1 * (0.7 * t + a as f64).sin()
            }),
            height: Some(1.5 + 0.1 * t),
            attitude: Some([half.cos(), 0.0, 0.0, half.sin()]),
        });
    }
    c
}

/// Concatenates chunks into one.
pub fn concat(chunks: &[SampleChunk]) -> SampleChunk {
    let mut out = chunks[0].clone();
    out.clear();
    for c in chunks {
        for k in 0..c.len() {
            out.push(&c.sample(k));
        }
    }
    out
}

/// Asserts two chunks hold bit-identical values, naming the first difference.
pub fn assert_same(a: &SampleChunk, b: &SampleChunk) {
    assert_eq!(a.len(), b.len(), "sample counts");
    for k in 0..a.len() {
        let (x, y) = (a.sample(k), b.sample(k));
        assert!(x == y, "sample {k} differs:\n{x:?}\n{y:?}");
    }
}

/// Options of [`px4_like_log`].
#[derive(Debug, Clone, Copy)]
pub struct Px4Log {
    /// Length of the log, µs (it starts at 1 s).
    pub duration_us: u64,
    /// Time of a logger dropout ('O' message, 20 ms), µs, if any.
    pub dropout_at: Option<u64>,
}

/// Gyro of the PX4-like log at `t` s, rad/s.
pub fn px4_gyro(t: f64) -> [f32; 3] {
    [(0.1 * t.sin()) as f32, (0.2 * t.cos()) as f32, 0.05]
}

/// World velocity of the PX4-like log at `t` s (linear in t, so interpolation is exact).
pub fn px4_velocity(t: f64) -> [f64; 3] {
    [1.0 + 0.5 * t, -0.2 * t, 0.1]
}

/// PWM output `i` (0-based) of actuator_outputs instance 1 at `t_us` µs (linear in time).
pub fn px4_pwm(i: usize, t_us: f64) -> f64 {
    1100.0 + 100.0 * i as f64 + t_us / 10_000.0
}

/// ESC rpm of rotor `i` (0-based) of the PX4-like log at `t_us` µs (linear in time).
pub fn px4_rpm(i: usize, t_us: u64) -> f64 {
    6000.0 + 100.0 * i as f64 + t_us as f64 / 1000.0
}

/// A ULog file shaped like a PX4 log: sensor_combined at 250 Hz, vehicle_attitude at
/// 50 Hz (identity), vehicle_local_position at 10 Hz, esc_status at 10 Hz (4 ESCs),
/// actuator_outputs instances 0 (constant 900) and 1 (1100 + 100 i + t_us/10⁴) at
/// 10 Hz, an unmapped cpuload topic, info, CA_ROTOR parameters (quad x, 0.2 m), a log
/// string; trailing padding is left out of the data, as PX4 does.
pub fn px4_like_log(opts: Px4Log) -> Vec<u8> {
    use mrsysid::io::fixtures::ulog::UlogWriter;
    let mut w = UlogWriter::new(123);
    w.flag_bits([0; 8], [0; 8], [0; 3]);
    w.info("sys_name", "PX4");
    w.info("ver_hw", "TEST_BOARD");
    w.param_i32("CA_ROTOR_COUNT", 4);
    let a = 0.2 / 2f32.sqrt();
    for (i, (x, y, km)) in [(a, a, 0.05), (-a, -a, 0.05), (a, -a, -0.05), (-a, a, -0.05)]
        .into_iter()
        .enumerate()
    {
        w.param_f32(&format!("CA_ROTOR{i}_PX"), x);
        w.param_f32(&format!("CA_ROTOR{i}_PY"), y);
        w.param_f32(&format!("CA_ROTOR{i}_PZ"), -0.02);
        w.param_f32(&format!("CA_ROTOR{i}_KM"), km);
    }
    w.format(
        "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;\
         int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;\
         uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;uint8_t[3] _padding0;",
    );
    w.format(
        "vehicle_attitude:uint64_t timestamp;uint64_t timestamp_sample;float[4] q;\
         float[4] delta_q_reset;uint8_t quat_reset_counter;uint8_t[7] _padding0;",
    );
    w.format("vehicle_local_position:uint64_t timestamp;float vx;float vy;float vz;");
    w.format("esc_report:uint64_t timestamp;int32_t esc_rpm;float esc_voltage;");
    w.format(
        "esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[8] esc;",
    );
    w.format("actuator_outputs:uint64_t timestamp;uint32_t noutputs;float[16] output;");
    w.format("cpuload:uint64_t timestamp;float load;");
    w.add(0, 0, "sensor_combined");
    w.add(0, 1, "vehicle_attitude");
    w.add(0, 2, "vehicle_local_position");
    w.add(0, 3, "esc_status");
    w.add(0, 4, "actuator_outputs");
    w.add(1, 5, "actuator_outputs");
    w.add(0, 6, "cpuload");
    w.message(b'L', b"\x36\x40\x42\x0f\x00\x00\x00\x00\x00armed");
    let start = 1_000_000u64;
    let mut t = start;
    while t < start + opts.duration_us {
        if opts.dropout_at.is_some_and(|d| d >= t && d < t + 1000) {
            w.dropout(20);
        }
        let ts = t.to_le_bytes();
        let ft = t as f64 * 1e-6;
        if t.is_multiple_of(4000) {
            let mut d = ts.to_vec();
            for g in px4_gyro(ft) {
                d.extend_from_slice(&g.to_le_bytes());
            }
            d.extend_from_slice(&4000u32.to_le_bytes());
            d.extend_from_slice(&0i32.to_le_bytes());
            for acc in [0.1f32, -0.2, -9.81] {
                d.extend_from_slice(&acc.to_le_bytes());
            }
            d.extend_from_slice(&4000u32.to_le_bytes());
            d.push(0);
            w.data(0, &d);
        }
        if t % 20000 == 1000 {
            let mut d = ts.to_vec();
            d.extend_from_slice(&ts);
            for q in [1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0] {
                d.extend_from_slice(&q.to_le_bytes());
            }
            d.push(0);
            w.data(1, &d);
        }
        if t % 100_000 == 3000 {
            let mut d = ts.to_vec();
            for v in px4_velocity(ft) {
                d.extend_from_slice(&(v as f32).to_le_bytes());
            }
            w.data(2, &d);
        }
        if t % 100_000 == 7000 {
            let mut d = ts.to_vec();
            d.push(4);
            d.extend_from_slice(&[0; 7]);
            for i in 0..8 {
                d.extend_from_slice(&ts);
                d.extend_from_slice(&(px4_rpm(i, t) as i32).to_le_bytes());
                d.extend_from_slice(&15.2f32.to_le_bytes());
            }
            w.data(3, &d);
        }
        if t % 100_000 == 9000 {
            for (msg_id, real) in [(4u16, false), (5, true)] {
                let mut d = ts.to_vec();
                d.extend_from_slice(&8u32.to_le_bytes());
                for i in 0..16 {
                    let v = if real { px4_pwm(i, t as f64) } else { 900.0 };
                    d.extend_from_slice(&(v as f32).to_le_bytes());
                }
                w.data(msg_id, &d);
            }
        }
        if t.is_multiple_of(500_000) {
            let mut d = ts.to_vec();
            d.extend_from_slice(&0.3f32.to_le_bytes());
            w.data(6, &d);
        }
        t += 1000;
    }
    w.bytes().to_vec()
}
