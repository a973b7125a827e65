//! PX4 helpers: a vehicle TOML skeleton from the autopilot's control-allocation
//! parameters in a ULog file.
//!
//! PX4 gives rotor `i` (0-based, motor `i + 1`) its hub position `CA_ROTOR{i}_P{X,Y,Z}`
//! (m, body FRD: x forward, y right, z down — the crate's axes) and moment coefficient
//! `CA_ROTOR{i}_KM` (torque = KM · thrust, positive for counter-clockwise rotation seen
//! from above). The crate's spin is +1 for clockwise seen from above, so
//! spin = −sign(KM); the hub height above the CG is −mean(PZ).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::vehicle::{Rotor, RotorLayout};

/// What to change on a PX4 vehicle when a log has no rotor-speed telemetry.
pub(crate) const MISSING_ROTOR_SPEEDS: &str = "PX4 logs esc_status with rotor speeds only \
     from ESCs that report them: bidirectional DShot (DSHOT_BIDIR_EN = 1, with \
     MOT_POLE_COUNT), DShot telemetry on a serial port (DSHOT_TEL_CFG) or DroneCAN ESCs; \
     SDLOG_PROFILE with bit 3 (system identification) or bit 4 (high rate) logs rates, \
     attitude and actuator outputs fast. Without telemetry, map actuator_outputs with an \
     `actuator` table (commanded speeds, docs/mapping.md)";

/// Appended to a sample a slow topic could not be aligned to: what to change on the
/// vehicle (or in the mapping) next time.
pub(crate) const SLOW_TOPICS: &str = " (or a logger dropout between them; raise \
     `[mcap] align_gap` for a slow topic, or log it faster next time: SDLOG_PROFILE bit 4 \
     (high rate) or bit 3 (system identification), ESC telemetry by bidirectional DShot, \
     DSHOT_BIDIR_EN = 1)";

/// One rotor from PX4's control-allocation parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Px4Rotor {
    /// Hub x (forward), m.
    pub x: f64,
    /// Hub y (right), m.
    pub y: f64,
    /// Hub z (down), m.
    pub z: f64,
    /// Moment coefficient KM (torque / thrust), m; positive counter-clockwise.
    pub km: f64,
}

/// Why PX4's control-allocation parameters give no rotor table; names the parameter.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Px4ParameterError {
    /// No `CA_ROTOR_COUNT` (a log of PX4 before v1.13, whose mixer files are not logged:
    /// only the airframe's `SYS_AUTOSTART`).
    #[error(
        "parameter CA_ROTOR_COUNT is not in the log (PX4 before v1.13 has no control-allocation \
         parameters: its geometry is a mixer file the log does not hold, only the airframe, \
         SYS_AUTOSTART = {}); write the [[rotors]] table by hand from the airframe's mixer, \
         in PX4's motor order (docs/vehicle-file.md)",
        autostart.map_or("absent".to_string(), |a| a.to_string())
    )]
    NoRotorCount {
        /// The airframe's `SYS_AUTOSTART`, when logged.
        autostart: Option<f64>,
    },
    /// A rotor count that is not a whole number 1..=[`MAX_ROTORS`](super::MAX_ROTORS).
    #[error(
        "CA_ROTOR_COUNT = {count}: expected a whole number 1..={}",
        super::MAX_ROTORS
    )]
    RotorCount {
        /// The value logged.
        count: f64,
    },
    /// A rotor's parameter absent or not finite.
    #[error("parameter {name} is not in the log or not finite")]
    Missing {
        /// The parameter, e.g. `CA_ROTOR2_KM`.
        name: String,
    },
    /// A rotor whose moment coefficient is 0, so its spin is unknown.
    #[error(
        "CA_ROTOR{index}_KM = 0: the spin direction of rotor {} is unknown",
        index + 1
    )]
    ZeroMomentCoefficient {
        /// PX4's 0-based rotor index.
        index: usize,
    },
}

/// The rotors `CA_ROTOR0..CA_ROTOR{n−1}` of `CA_ROTOR_COUNT`; errors name the missing or
/// invalid parameter.
pub fn rotors_from_parameters(
    params: &BTreeMap<String, f64>,
) -> Result<Vec<Px4Rotor>, Px4ParameterError> {
    let count = *params
        .get("CA_ROTOR_COUNT")
        .ok_or_else(|| Px4ParameterError::NoRotorCount {
            autostart: params.get("SYS_AUTOSTART").copied(),
        })?;
    if !(1.0..=super::MAX_ROTORS as f64).contains(&count) || count.fract() != 0.0 {
        return Err(Px4ParameterError::RotorCount { count });
    }
    (0..count as usize)
        .map(|i| {
            let get = |suffix: &str| {
                let name = format!("CA_ROTOR{i}_{suffix}");
                params
                    .get(&name)
                    .copied()
                    .filter(|v| v.is_finite())
                    .ok_or(Px4ParameterError::Missing { name })
            };
            let km = get("KM")?;
            if km == 0.0 {
                return Err(Px4ParameterError::ZeroMomentCoefficient { index: i });
            }
            Ok(Px4Rotor {
                x: get("PX")?,
                y: get("PY")?,
                z: get("PZ")?,
                km,
            })
        })
        .collect()
}

/// The vehicle TOML skeleton for `rotors` (from log `log_name`, vehicle `name`): the
/// rotor table, spins and hub height filled in; mass, inertia, rotor radius and rotor
/// inertia left as commented lines for the user. The last comment says whether the
/// layout satisfies the seed's Assumption 2, is accepted as a general planar layout (with
/// notes), or is refused.
pub fn vehicle_skeleton(rotors: &[Px4Rotor], name: &str, log_name: &str) -> String {
    let n = rotors.len().max(1) as f64;
    // PX4 stores the parameters as f32: print them at f32 precision (+ 0.0 clears −0).
    let hub_height = (-rotors.iter().map(|r| r.z).sum::<f64>() / n) as f32 + 0.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Vehicle skeleton from PX4's control-allocation parameters in {log_name}\n\
         # (`mrsysid vehicle --from-ulog`): CA_ROTOR_COUNT = {}, CA_ROTOR{{i}}_P{{X,Y,Z}}, CA_ROTOR{{i}}_KM.\n\
         # Rotor k is PX4's CA rotor k-1 (motor k): map actuator_motors.control[k-1] or\n\
         # esc_status.esc[k-1] in this order. Axes: body FRD (x forward, y right), as PX4's.\n\
         # spin = +1 is clockwise seen from above, i.e. CA_ROTOR_KM < 0 (PX4: KM > 0 is CCW).\n\
         # FILL IN mass, inertia, rotor_radius and rotor_inertia: PX4 does not log them, and\n\
         # the vehicle loader refuses this file until they are given.",
        rotors.len()
    );
    let _ = writeln!(s, "name = {name:?}");
    s += "# mass = 1.5                 # kg  FILL IN\n";
    s +=
        "# inertia = [[0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.04]]   # kg m^2 about the CG  FILL IN\n";
    s += "air_density = 1.225          # kg/m^3 (sea-level standard atmosphere)\n";
    s += "# rotor_radius = 0.12        # R, m  FILL IN\n";
    let _ = writeln!(
        s,
        "hub_height = {hub_height}    # m, rotor plane above the CG (-mean CA_ROTOR*_PZ)"
    );
    s += "# rotor_inertia = 0.0        # J_z of one motor + rotor, kg m^2 (0: neglected)\n";
    for (i, r) in rotors.iter().enumerate() {
        let spin = if r.km < 0.0 { 1 } else { -1 };
        let _ = writeln!(
            s,
            "\n[[rotors]]   # CA rotor {i}, KM = {}\nx = {}\ny = {}\nspin = {spin}",
            r.km as f32, r.x as f32, r.y as f32
        );
    }
    let check = layout_check(rotors);
    let _ = writeln!(s, "\n# Layout check: {check}");
    s
}

/// Whether the rotor layout satisfies the seed's Assumption 2, is a general planar layout
/// the vehicle loader accepts with a note, or is refused, in words.
pub fn layout_check(rotors: &[Px4Rotor]) -> String {
    let table: Vec<Rotor> = rotors
        .iter()
        .map(|r| Rotor {
            x: r.x,
            y: r.y,
            spin: if r.km < 0.0 { 1.0 } else { -1.0 },
        })
        .collect();
    layout_words(&table)
}

/// Whether the rotor table satisfies Assumption 2, is accepted as a general planar
/// layout, or is refused, in words (PX4 and ArduPilot skeletons).
pub(crate) fn layout_words(table: &[Rotor]) -> String {
    match RotorLayout::check(table) {
        Ok(layout) if layout.breaches.is_empty() => format!(
            "satisfies Assumption 2 (arm length {:.4} m, {:?})",
            layout.arm_length, layout.class
        ),
        Ok(layout) => {
            let breaches: Vec<String> = layout.breaches.iter().map(|b| b.to_string()).collect();
            format!(
                "general planar layout (mean arm {:.4} m), accepted with a note: {}",
                layout.arm_length,
                breaches.join("; ")
            )
        }
        Err(kind) => format!("the vehicle loader will refuse this layout: {kind}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::{Vehicle, VehicleSource};

    fn params(arms: [(f64, f64, f64); 4]) -> BTreeMap<String, f64> {
        let mut p = BTreeMap::from([("CA_ROTOR_COUNT".to_string(), 4.0)]);
        for (i, (x, y, km)) in arms.into_iter().enumerate() {
            p.insert(format!("CA_ROTOR{i}_PX"), x);
            p.insert(format!("CA_ROTOR{i}_PY"), y);
            p.insert(format!("CA_ROTOR{i}_PZ"), -0.03);
            p.insert(format!("CA_ROTOR{i}_KM"), km);
        }
        p
    }

    #[test]
    fn quad_x_skeleton_loads_once_filled_in() {
        let a = 0.15;
        let rotors = quad(a, a, a, [0.05, 0.05, -0.05, -0.05]);
        let text = vehicle_skeleton(&rotors, "test", "t.ulg");
        assert!(text.contains("satisfies Assumption 2"), "{text}");
        let filled = text
            .replace("# mass = 1.5", "mass = 1.5")
            .replace("# inertia", "inertia")
            .replace("# rotor_radius", "rotor_radius");
        let v = Vehicle::from_toml_str(&filled, VehicleSource::Code).unwrap();
        assert_eq!(v.rotor_count(), 4);
        // KM > 0 (CCW) -> spin -1; hub 3 cm above the CG (PZ = -0.03, z down).
        assert_eq!(v.rotors()[0].spin, -1.0);
        assert_eq!(v.rotors()[2].spin, 1.0);
        assert!((v.props.hub_height - 0.03).abs() < 1e-12);
        assert!((v.arm_length() - a * 2f64.sqrt()).abs() < 1e-12);
        assert!(Vehicle::from_toml_str(&text, VehicleSource::Code).is_err());
    }

    /// A four-rotor table in PX4's quad-x order (front right, rear left, front left,
    /// rear right) with front hubs at (x, ±y_front), rear hubs at (−x, ±y_rear) and
    /// moment coefficients `km`.
    fn quad(x: f64, y_front: f64, y_rear: f64, km: [f64; 4]) -> Vec<Px4Rotor> {
        let p = params([
            (x, y_front, km[0]),
            (-x, -y_rear, km[1]),
            (x, -y_front, km[2]),
            (-x, y_rear, km[3]),
        ]);
        rotors_from_parameters(&p).unwrap()
    }

    #[test]
    fn missing_and_asymmetric() {
        // A log of PX4 before v1.13: the airframe named, and what to do.
        let old = BTreeMap::from([("SYS_AUTOSTART".to_string(), 4001.0)]);
        let e = rotors_from_parameters(&old).unwrap_err().to_string();
        assert!(
            e.contains("SYS_AUTOSTART = 4001") && e.contains("docs/vehicle-file.md"),
            "{e}"
        );
        let mut p = params([(0.1, 0.1, 0.05); 4]);
        p.remove("CA_ROTOR2_KM");
        assert_eq!(
            rotors_from_parameters(&p),
            Err(Px4ParameterError::Missing {
                name: "CA_ROTOR2_KM".into()
            })
        );
        let balanced = [0.05, 0.05, -0.05, -0.05];
        // (layout, words the check must say): a rectangle (H-frame: equal arms, unequal
        // angles); the SITL airframe's arms (0.288 m front, 0.241 m rear), accepted with
        // a note; three rotors spinning one way, refused.
        for (rotors, start, words) in [
            (
                quad(0.29, 0.24, 0.24, balanced),
                "general planar layout",
                "(equal interior angles)",
            ),
            (
                quad(0.1515, 0.245, 0.1875, balanced),
                "general planar layout",
                "(equal arms)",
            ),
            (
                quad(0.15, 0.15, 0.15, [0.05, 0.05, -0.05, 0.05]),
                "the vehicle loader will refuse this layout",
                "balanced spins",
            ),
        ] {
            let text = layout_check(&rotors);
            assert!(text.starts_with(start) && text.contains(words), "{text}");
        }
    }
}
