//! ArduPilot helpers: the rotor layout of a `FRAME_CLASS`/`FRAME_TYPE`, in ArduPilot's
//! motor numbering; a vehicle TOML skeleton from a DataFlash log's parameters; the
//! actuator map of `RCOU` outputs from the `MOT_*` parameters; and what to change on the
//! vehicle when a log lacks rotor speeds.
//!
//! ArduPilot places motor k at angle a_k from the nose, positive towards the right,
//! and gives it a yaw factor: "CCW" motors turn counter-clockwise seen from above
//! (spin −1 here), "CW" clockwise (spin +1). The hub is at (L cos a, L sin a) in body
//! FRD for arm length L, which ArduPilot does not log.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::px4::layout_words;
use crate::vehicle::Rotor;

/// What to change on an ArduPilot vehicle when a log has no rotor-speed telemetry.
pub const MISSING_ROTOR_SPEEDS: &str = "ArduPilot logs ESC messages only with ESC telemetry: \
     bidirectional DShot (SERVO_BLH_BDMASK, MOT_PWM_TYPE = DShot) or BLHeli telemetry \
     (SERVO_BLH_AUTO = 1, SERVO_BLH_TRATE >= 50 Hz) or DroneCAN ESCs, and LOG_BITMASK with \
     IMU and RCOUT set; without telemetry, map RCOU with an `actuator` table (commanded \
     speeds, see `mrsysid vehicle --from-log`). For IMU at the loop rate instead of 25 Hz \
     set LOG_BITMASK bit 18 (IMU_FAST; the batch sampler's ISBD messages, \
     INS_LOG_BAT_MASK, are not read); the SYSID flight mode (SID_AXIS, SID_MAGNITUDE, SID_F_START_HZ, \
     SID_F_STOP_HZ) flies chirps made for identification";

/// Appended to a sample a slow message could not be aligned to: what to change on the
/// vehicle (or in the mapping) next time.
pub const SLOW_MESSAGES: &str = " (a message logged slower than that: raise `[mcap] align_gap` \
     for it, or log it faster next time: ESC telemetry with SERVO_BLH_TRATE >= 50 Hz or \
     bidirectional DShot (SERVO_BLH_BDMASK), the EKF and IMU with LOG_BITMASK and \
     LOG_FILE_RATEMAX = 0)";

/// ArduPilot's motors of frame `class`/`frame_type`: (angle from the nose, degrees,
/// positive right; crate spin), motor 1 first, and the frame's name.
fn frame(class: u32, frame_type: u32) -> Option<(&'static str, Vec<(f64, f64)>)> {
    const CW: f64 = 1.0;
    const CCW: f64 = -1.0;
    let quad_x = vec![(45.0, CCW), (-135.0, CCW), (-45.0, CW), (135.0, CW)];
    Some(match (class, frame_type) {
        (1, 0) => (
            "quad +",
            vec![(90.0, CCW), (-90.0, CCW), (0.0, CW), (180.0, CW)],
        ),
        (1, 1) => ("quad X", quad_x),
        (1, 3) => ("quad H", quad_x.into_iter().map(|(a, s)| (a, -s)).collect()),
        (2, 0) => (
            "hexa +",
            vec![
                (0.0, CW),
                (180.0, CCW),
                (-120.0, CW),
                (60.0, CCW),
                (-60.0, CCW),
                (120.0, CW),
            ],
        ),
        (2, 1) => (
            "hexa X",
            vec![
                (90.0, CW),
                (-90.0, CCW),
                (-30.0, CW),
                (150.0, CCW),
                (30.0, CCW),
                (-150.0, CW),
            ],
        ),
        (3, 0) => (
            "octa +",
            vec![
                (0.0, CW),
                (180.0, CW),
                (45.0, CCW),
                (135.0, CCW),
                (-45.0, CCW),
                (-135.0, CCW),
                (-90.0, CW),
                (90.0, CW),
            ],
        ),
        (3, 1) => (
            "octa X",
            vec![
                (22.5, CW),
                (-157.5, CW),
                (67.5, CCW),
                (157.5, CCW),
                (-22.5, CCW),
                (-112.5, CCW),
                (-67.5, CW),
                (112.5, CW),
            ],
        ),
        _ => return None,
    })
}

/// Why ArduPilot's parameters (and the arm length given with them) give no rotor table
/// or actuator map; names the parameter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArduPilotParameterError {
    /// `FRAME_CLASS` or `FRAME_TYPE` absent or not a whole number ≥ 0.
    #[error("parameter {name} is not in the log or not a whole number")]
    NotWholeNumber {
        /// The parameter.
        name: &'static str,
    },
    /// A frame whose motor order the reader does not know.
    #[error(
        "FRAME_CLASS = {class}, FRAME_TYPE = {frame_type}: not a frame this reader knows \
         (quad 1 with type 0 +, 1 X, 3 H; hexa 2 and octa 3 with type 0 + or 1 X); write \
         the vehicle file's rotor table by hand in ArduPilot's motor order"
    )]
    UnknownFrame {
        /// `FRAME_CLASS`.
        class: f64,
        /// `FRAME_TYPE`.
        frame_type: f64,
    },
    /// An arm length that is not a positive number of metres.
    #[error("arm length {arm} m must be positive")]
    ArmLength {
        /// The arm length given, m.
        arm: f64,
    },
    /// A thrust curve exponent outside the actuator map's 0..1.
    #[error("MOT_THST_EXPO = {expo}: only 0..1 maps onto the actuator map's thr_mdl_fac")]
    ThrustExpo {
        /// `MOT_THST_EXPO`.
        expo: f64,
    },
    /// PWM or spin bounds that do not increase.
    #[error(
        "MOT_PWM_MIN/MAX = {pwm_min}/{pwm_max}, MOT_SPIN_MIN/MAX = {spin_min}/{spin_max}: not an increasing range"
    )]
    MotorRange {
        /// PWM at zero output (1000 when not logged positive).
        pwm_min: f64,
        /// PWM at full output (2000 when not logged positive).
        pwm_max: f64,
        /// `MOT_SPIN_MIN`.
        spin_min: f64,
        /// `MOT_SPIN_MAX`.
        spin_max: f64,
    },
}

/// The rotor table of the log's `FRAME_CLASS`/`FRAME_TYPE` with arm length `arm` (m),
/// rotor k being ArduPilot's motor k, and the frame's name; errors name the parameter.
pub fn ardupilot_rotors(
    params: &BTreeMap<String, f64>,
    arm: f64,
) -> Result<(Vec<Rotor>, &'static str), ArduPilotParameterError> {
    let get = |name: &'static str| {
        params
            .get(name)
            .copied()
            .filter(|v| v.is_finite() && *v >= 0.0 && v.fract() == 0.0)
            .ok_or(ArduPilotParameterError::NotWholeNumber { name })
    };
    let (class, frame_type) = (get("FRAME_CLASS")?, get("FRAME_TYPE")?);
    let (name, motors) = frame(class as u32, frame_type as u32)
        .ok_or(ArduPilotParameterError::UnknownFrame { class, frame_type })?;
    if !(arm.is_finite() && arm > 0.0) {
        return Err(ArduPilotParameterError::ArmLength { arm });
    }
    let snap = |v: f64| if v.abs() < 1e-12 { 0.0 } else { v };
    let rotors = motors
        .into_iter()
        .map(|(a, spin)| {
            let a = f64::to_radians(a);
            Rotor {
                x: snap(arm * a.cos()),
                y: snap(arm * a.sin()),
                spin,
            }
        })
        .collect();
    Ok((rotors, name))
}

/// The `actuator` table that turns `RCOU` PWM outputs into commanded rotor speeds, from
/// the `MOT_*` parameters, as TOML lines (`max_speed` left to fill in).
///
/// ArduPilot outputs PWM = p₀ + (p₁ − p₀)·(s₀ + (s₁ − s₀)·a) for throttle a ∈ [0, 1]
/// with thrust fraction (1 − e)·a + e·a² (p₀, p₁ = `MOT_PWM_MIN`/`MAX`, else 1000/2000;
/// s₀, s₁ = `MOT_SPIN_MIN`/`MAX`; e = `MOT_THST_EXPO`). That is the crate's actuator map
/// with `pwm_min` = p₀ + s₀(p₁ − p₀), `pwm_max` = p₀ + s₁(p₁ − p₀) and `thr_mdl_fac`
/// = e; the rotor speed is then `max_speed` · √(thrust fraction) (thrust ∝ Ω²).
pub fn actuator_lines(params: &BTreeMap<String, f64>) -> Result<String, ArduPilotParameterError> {
    let get = |name: &str, default: f64| params.get(name).copied().unwrap_or(default);
    let (mut p0, mut p1) = (get("MOT_PWM_MIN", 0.0), get("MOT_PWM_MAX", 0.0));
    if p0 <= 0.0 || p1 <= 0.0 {
        (p0, p1) = (1000.0, 2000.0);
    }
    let (s0, s1) = (get("MOT_SPIN_MIN", 0.15), get("MOT_SPIN_MAX", 0.95));
    let e = get("MOT_THST_EXPO", 0.65);
    if !(0.0..=1.0).contains(&e) {
        return Err(ArduPilotParameterError::ThrustExpo { expo: e });
    }
    if !(p0 < p1 && 0.0 <= s0 && s0 < s1 && s1 <= 1.0) {
        return Err(ArduPilotParameterError::MotorRange {
            pwm_min: p0,
            pwm_max: p1,
            spin_min: s0,
            spin_max: s1,
        });
    }
    let lo = p0 + s0 * (p1 - p0);
    let hi = p0 + s1 * (p1 - p0);
    Ok(format!(
        "[signals.rotor_speeds.actuator]   # MOT_PWM_MIN/MAX {}/{}, MOT_SPIN_MIN/MAX {}/{}\n\
         pwm_min = {}\npwm_max = {}\nthr_mdl_fac = {}            # MOT_THST_EXPO\n\
         # max_speed = 2500.0          # rad/s at MOT_SPIN_MAX  FILL IN (ESC telemetry or a motor test)",
        p0 as f32, p1 as f32, s0 as f32, s1 as f32, lo as f32, hi as f32, e as f32
    ))
}

/// The vehicle TOML skeleton for `rotors` of frame `frame_name` (from log `log_name`,
/// vehicle `name`, arm length `arm`); mass, inertia, rotor radius, hub height and rotor
/// inertia left as commented lines for the user. The last comment checks the layout.
pub fn ardupilot_skeleton(
    rotors: &[Rotor],
    frame_name: &str,
    arm: f64,
    name: &str,
    log_name: &str,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Vehicle skeleton from ArduPilot's FRAME_CLASS/FRAME_TYPE in {log_name}\n\
         # (`mrsysid vehicle --from-log`): {frame_name}, {} motors, arm length {arm} m (given).\n\
         # Rotor k is ArduPilot's motor k (output SERVOk with MOTORk): map ESC[k-1].RPM or\n\
         # RCOU Ck in this order. Axes: body FRD (x forward, y right).\n\
         # spin = +1 is clockwise seen from above (ArduPilot CW), -1 counter-clockwise (CCW).\n\
         # FILL IN mass, inertia, rotor_radius and hub_height: ArduPilot does not log them,\n\
         # and the vehicle loader refuses this file until they are given.",
        rotors.len()
    );
    let _ = writeln!(s, "name = {name:?}");
    s += "# mass = 1.5                 # kg  FILL IN\n";
    s +=
        "# inertia = [[0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.04]]   # kg m^2 about the CG  FILL IN\n";
    s += "air_density = 1.225          # kg/m^3 (sea-level standard atmosphere)\n";
    s += "# rotor_radius = 0.12        # R, m  FILL IN\n";
    s += "# hub_height = 0.02          # m, rotor plane above the CG  FILL IN\n";
    s += "# rotor_inertia = 0.0        # J_z of one motor + rotor, kg m^2 (0: neglected)\n";
    for (i, r) in rotors.iter().enumerate() {
        let _ = writeln!(
            s,
            "\n[[rotors]]   # motor {}\nx = {}\ny = {}\nspin = {}",
            i + 1,
            r.x as f32,
            r.y as f32,
            r.spin
        );
    }
    let _ = writeln!(s, "\n# Layout check: {}", layout_words(rotors));
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::{Vehicle, VehicleSource};

    fn params(class: f64, frame_type: f64) -> BTreeMap<String, f64> {
        BTreeMap::from([
            ("FRAME_CLASS".to_string(), class),
            ("FRAME_TYPE".to_string(), frame_type),
        ])
    }

    /// Quad X: motor 1 front right CCW, 2 rear left CCW, 3 front left CW, 4 rear right
    /// CW (ArduPilot's AP_MotorsMatrix); hexa X motor 1 straight right, CW. Every frame
    /// loads once filled in and satisfies Assumption 2.
    #[test]
    fn frames_in_ardupilot_order_load_once_filled_in() {
        let a = 0.25;
        let (quad, name) = ardupilot_rotors(&params(1.0, 1.0), a).unwrap();
        assert_eq!(name, "quad X");
        let d = a / 2f64.sqrt();
        let want = [(d, d, -1.0), (-d, -d, -1.0), (d, -d, 1.0), (-d, d, 1.0)];
        for (r, (x, y, spin)) in quad.iter().zip(want) {
            assert!((r.x - x).abs() < 1e-12 && (r.y - y).abs() < 1e-12, "{r:?}");
            assert_eq!(r.spin, spin);
        }
        let (hexa, _) = ardupilot_rotors(&params(2.0, 1.0), a).unwrap();
        assert_eq!((hexa[0].x, hexa[0].y, hexa[0].spin), (0.0, a, 1.0));
        for (class, ty) in [
            (1.0, 0.0),
            (1.0, 1.0),
            (1.0, 3.0),
            (2.0, 0.0),
            (2.0, 1.0),
            (3.0, 0.0),
            (3.0, 1.0),
        ] {
            let (rotors, name) = ardupilot_rotors(&params(class, ty), a).unwrap();
            let text = ardupilot_skeleton(&rotors, name, a, "t", "t.bin");
            assert!(text.contains("satisfies Assumption 2"), "{name}: {text}");
            assert!(Vehicle::from_toml_str(&text, VehicleSource::Code).is_err());
            let filled = text
                .replace("# mass", "mass")
                .replace("# inertia", "inertia")
                .replace("# rotor_radius", "rotor_radius")
                .replace("# hub_height", "hub_height");
            let v = Vehicle::from_toml_str(&filled, VehicleSource::Code).unwrap();
            assert!((v.arm_length() - a).abs() < 1e-6, "{name}");
        }
        let e = ardupilot_rotors(&params(1.0, 2.0), a).unwrap_err();
        assert!(e.to_string().contains("FRAME_TYPE = 2"), "{e}");
        assert_eq!(
            ardupilot_rotors(&BTreeMap::new(), a),
            Err(ArduPilotParameterError::NotWholeNumber {
                name: "FRAME_CLASS"
            })
        );
    }

    /// Defaults (PWM 1000..2000, spin 0.15..0.95, expo 0.65) give PWM 1150..1950.
    #[test]
    fn actuator_from_mot_parameters() {
        let text = actuator_lines(&BTreeMap::new()).unwrap();
        assert!(
            text.contains("pwm_min = 1150\npwm_max = 1950\nthr_mdl_fac = 0.65"),
            "{text}"
        );
        let p = BTreeMap::from([
            ("MOT_PWM_MIN".to_string(), 1100.0),
            ("MOT_PWM_MAX".to_string(), 1900.0),
            ("MOT_SPIN_MIN".to_string(), 0.1),
            ("MOT_SPIN_MAX".to_string(), 1.0),
            ("MOT_THST_EXPO".to_string(), 0.5),
        ]);
        let text = actuator_lines(&p).unwrap();
        assert!(
            text.contains("pwm_min = 1180\npwm_max = 1900\nthr_mdl_fac = 0.5"),
            "{text}"
        );
        let p = BTreeMap::from([("MOT_THST_EXPO".to_string(), -0.2)]);
        assert_eq!(
            actuator_lines(&p),
            Err(ArduPilotParameterError::ThrustExpo { expo: -0.2 })
        );
    }
}
