//! Derived signals against analytic ones, with the error bounds claimed.

mod io_support;
mod scratch;

use std::f64::consts::PI;
use std::io::Write;
use std::path::{Path, PathBuf};

use io_support::quad;
use mrsysid::SampleChunk;
use mrsysid::io::{Mapping, ReadOptions, open_log};

fn tmp(name: &str) -> PathBuf {
    scratch::dir("derive").join(name)
}

const RATE_HZ: f64 = 400.0;
const AMP: f64 = 1.5; // rad/s
const FREQ: f64 = 2.0 * PI * 1.5; // rad/s: a 1.5 Hz body-rate oscillation

/// Contract CSV without moments and with accelerometer instead of force; rates
/// p = A sin ωt, q = A cos ωt, r = A/2 sin ωt.
fn write_rates_log(path: &Path, n: usize) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    writeln!(f, "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,ax,ay,az").unwrap();
    for k in 0..n {
        let t = k as f64 / RATE_HZ;
        let (s, c) = (FREQ * t).sin_cos();
        writeln!(
            f,
            "{t:?},3,0,0.5,{:?},{:?},{:?},900,910,920,930,0.25,-0.5,-9.5",
            AMP * s,
            AMP * c,
            0.5 * AMP * s
        )
        .unwrap();
    }
}

fn read_all(path: &Path, mapping: Option<&Mapping>, opts: &ReadOptions) -> SampleChunk {
    let v = quad(0.0);
    let chunks: Vec<SampleChunk> = open_log(path, &v, mapping, opts)
        .unwrap()
        .map(Result::unwrap)
        .collect();
    io_support::concat(&chunks)
}

#[test]
fn moment_from_sg_derivative_within_the_truncation_bound() {
    let path = tmp("rates.csv");
    write_rates_log(&path, 4000);
    let opts = ReadOptions::default(); // SG window 11, order 2
    let c = read_all(&path, None, &opts);
    let i = [0.011, 0.012, 0.021];
    // Interior samples: the order-2 symmetric SG derivative is the least-squares slope,
    // whose error for x = A sin ωt is bounded by A ω³ h² Σj⁴ / (6 Σj²) (third-order
    // Taylor term), h = 1/400 s, j = -5..5; the moment error is I_kk times that plus the
    // gyroscopic term, which uses exact rates.
    let (s2, s4): (f64, f64) = (-5..=5)
        .map(|j: i32| ((j * j) as f64, (j.pow(4)) as f64))
        .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let h = 1.0 / RATE_HZ;
    let bound = AMP * FREQ.powi(3) * h * h * s4 / (6.0 * s2);
    let mut worst: f64 = 0.0;
    for k in 5..c.len() - 5 {
        let t = c.t[k];
        let (s, co) = (FREQ * t).sin_cos();
        let w = [AMP * s, AMP * co, 0.5 * AMP * s];
        let wd = [AMP * FREQ * co, -AMP * FREQ * s, 0.5 * AMP * FREQ * co];
        let iw = [i[0] * w[0], i[1] * w[1], i[2] * w[2]];
        let gyro = [
            w[1] * iw[2] - w[2] * iw[1],
            w[2] * iw[0] - w[0] * iw[2],
            w[0] * iw[1] - w[1] * iw[0],
        ];
        for a in 0..3 {
            let exact = i[a] * wd[a] + gyro[a];
            let err = (c.wrench[3 + a][k] - exact).abs();
            assert!(
                err <= i[a] * bound * 1.01 + 1e-12,
                "k={k} axis {a}: {err} > {}",
                i[a] * bound
            );
            worst = worst.max(err / (i[a] * bound));
        }
    }
    // The bound is attained to within a few per cent (it is the leading error term).
    assert!(worst > 0.9, "bound is tight: worst ratio {worst}");
}

#[test]
fn force_is_mass_times_specific_force_exactly() {
    let path = tmp("accel.csv");
    write_rates_log(&path, 200);
    let c = read_all(&path, None, &ReadOptions::default());
    // F = m a with m = 1.2 kg: one multiplication, compared with ==.
    assert!(c.wrench[0].iter().all(|&f| f == 1.2 * 0.25));
    assert!(c.wrench[2].iter().all(|&f| f == 1.2 * -9.5));
}

#[test]
fn lever_arm_correction_removes_centripetal_and_tangential_terms() {
    // An IMU at r = (0.1, 0, 0) m on a body spinning at constant r = 2 rad/s reads the
    // centripetal -ω² r_x = -0.4 m/s² along x on top of the CG specific force.
    let path = tmp("lever.csv");
    let mut f = std::fs::File::create(&path).unwrap();
    writeln!(f, "t,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,ax,ay,az").unwrap();
    for k in 0..100 {
        writeln!(
            f,
            "{},0,0,0,0,0,2,900,900,900,900,-0.4,0,-9.8",
            k as f64 * 0.01
        )
        .unwrap();
    }
    let mut opts = ReadOptions::default();
    opts.derive.imu_lever_arm = Some([0.1, 0.0, 0.0]);
    let c = read_all(&path, None, &opts);
    for k in 0..c.len() {
        // ω̇ = 0 from the derivative of a constant (exact), so only rounding remains: 1e-12.
        assert!(c.wrench[0][k].abs() < 1e-12, "{}", c.wrench[0][k]);
        assert!((c.wrench[2][k] + 1.2 * 9.8).abs() < 1e-12);
    }
}

#[test]
fn units_frames_and_world_velocity_are_converted_exactly() {
    // FLU body, ENU world, deg/s rates, RPM rotors, ft/s world velocity, accelerometer in
    // g. Attitude: yaw of 90° about up (ENU) = body x points north... see below.
    let path = tmp("mapped.csv");
    let mut f = std::fs::File::create(&path).unwrap();
    writeln!(
        f,
        "time_ms,gx,gy,gz,m1,m2,m3,m4,ve,vn,vu,qw,qx,qy,qz,accx,accy,accz"
    )
    .unwrap();
    // Body→ENU quaternion: identity, i.e. body FLU x = east, y = north, z = up.
    for k in 0..50 {
        writeln!(
            f,
            "{},90,-45,180,6000,6000,6000,6000,10,20,-5,1,0,0,0,0.1,0.2,1",
            10 * k
        )
        .unwrap();
    }
    let m = Mapping::from_toml_str(
        r#"
        [frames]
        body = "flu"
        world = "enu"
        [time]
        columns = ["time_ms"]
        unit = "ms"
        [signals.rates]
        columns = ["gx", "gy", "gz"]
        unit = "deg/s"
        [signals.rotor_speeds]
        columns = ["m1", "m2", "m3", "m4"]
        unit = "rpm"
        [signals.velocity_world]
        columns = ["ve", "vn", "vu"]
        unit = "ft/s"
        [signals.attitude]
        columns = ["qw", "qx", "qy", "qz"]
        [signals.specific_force]
        columns = ["accx", "accy", "accz"]
        unit = "g"
        "#,
        "map.toml",
    )
    .unwrap();
    let c = read_all(&path, Some(&m), &ReadOptions::default());
    assert_eq!(c.t[3], 0.03);
    // Rates: FLU (90, -45, 180) deg/s → FRD (90, 45, -180) deg/s, exact factor π/180.
    assert_eq!(c.rates[0][0], 90.0 * (PI / 180.0));
    assert_eq!(c.rates[1][0], 45.0 * (PI / 180.0));
    assert_eq!(c.rates[2][0], -180.0 * (PI / 180.0));
    assert_eq!(c.omega[2][0], 6000.0 * (PI / 30.0));
    assert_eq!(c.wrench[2][0], 1.2 * -9.80665);
    // Body FLU x = east, y = north, z = up, so body FRD x = east, y = south, z = down.
    // World velocity (E, N, U) = (10, 20, -5) ft/s → body FRD (10, -20, 5) ft/s.
    // Rotation through quaternions: 1e-12 m/s tolerance for rounding.
    let ft = 0.3048;
    for (a, want) in [10.0 * ft, -20.0 * ft, 5.0 * ft].into_iter().enumerate() {
        assert!(
            (c.velocity[a][0] - want).abs() < 1e-12,
            "axis {a}: {}",
            c.velocity[a][0]
        );
    }
    // Attitude body FRD → NED: body x = east, i.e. yaw +90°: q = (cos 45°, 0, 0, sin 45°).
    let h = (0.5f64).sqrt();
    let attitude = c.attitude.as_ref().expect("attitude derived");
    let q: Vec<f64> = attitude.iter().map(|a| a[0]).collect();
    for (a, want) in [h, 0.0, 0.0, h].into_iter().enumerate() {
        assert!((q[a] - want).abs() < 1e-15, "{q:?}");
    }
}
