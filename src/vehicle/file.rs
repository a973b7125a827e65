//! The vehicle TOML file (`docs/vehicle-file.md`): its unchecked layout
//! ([`VehicleDefinition`], [`RotorEntry`]) and the rotor table read off it.

use serde::Deserialize;

use super::checks::check_positive;
use super::{Preset, Rotor, VehicleErrorKind};

/// The vehicle TOML layout (`docs/vehicle-file.md`), unchecked. Embedded as is in
/// identified-model files; [`Vehicle::from_definition`](super::Vehicle::from_definition) checks it.
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleDefinition {
    /// Vehicle name.
    pub name: String,
    /// Mass, kg.
    pub mass: f64,
    /// Inertia about the CG, body axes, kg m² (a file may give its diagonal
    /// `[Ixx, Iyy, Izz]` alone, for principal body axes).
    #[serde(deserialize_with = "matrix_or_diagonal")]
    pub inertia: [[f64; 3]; 3],
    /// Air density, kg/m³ (default 1.225).
    #[serde(default = "default_air_density")]
    pub air_density: f64,
    /// Rotor radius R, m.
    pub rotor_radius: f64,
    /// Rotor plane height above the CG, m.
    pub hub_height: f64,
    /// J_z of one motor + rotor, kg m² (default 0).
    #[serde(default)]
    pub rotor_inertia: f64,
    /// Explicit rotor table (or use `preset`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rotors: Vec<RotorEntry>,
    /// Preset layout name (or use `rotors`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<Preset>,
    /// Arm length for a preset, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_length: Option<f64>,
    /// Spin of rotor 1 for a preset (+1 or −1, default +1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_spin: Option<i64>,
    /// Tolerance of the Assumption 2 checks (relative to ℓ, or rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub geometry_tolerance: Option<f64>,
}

/// An inertia written as a 3×3 matrix or as its diagonal `[Ixx, Iyy, Izz]` (kg m²).
fn matrix_or_diagonal<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[[f64; 3]; 3], D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Inertia {
        Matrix([[f64; 3]; 3]),
        Diagonal([f64; 3]),
    }
    match Inertia::deserialize(d) {
        Ok(Inertia::Matrix(m)) => Ok(m),
        Ok(Inertia::Diagonal([xx, yy, zz])) => Ok([[xx, 0.0, 0.0], [0.0, yy, 0.0], [0.0, 0.0, zz]]),
        Err(_) => Err(serde::de::Error::custom(
            "expected a 3x3 matrix [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] or its \
             diagonal [Ixx, Iyy, Izz], kg m^2",
        )),
    }
}

/// One `[[rotors]]` entry of a vehicle file.
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RotorEntry {
    /// Hub x (forward), m.
    pub x: f64,
    /// Hub y (right), m.
    pub y: f64,
    /// Optional hub z (m, FRD); must equal −hub_height (coplanar rotors).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z: Option<f64>,
    /// Spin direction, +1 (clockwise seen from above) or −1.
    pub spin: i64,
    /// Optional cant angle (deg); Assumption 2 requires 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cant_deg: Option<f64>,
}

fn default_air_density() -> f64 {
    1.225
}

/// TOML error text on one line, with the line number and the offending line (the toml
/// crate prints a multi-line snippet).
pub(super) fn one_line(e: &toml::de::Error, text: &str) -> String {
    let msg = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let start = span.start.min(text.len());
            let line_no = text[..start].matches('\n').count() + 1;
            let line = text.lines().nth(line_no - 1).unwrap_or("").trim();
            format!("TOML error at line {line_no} (`{line}`): {msg}")
        }
        None => format!("TOML error: {msg}"),
    }
}

pub(super) fn file_rotors(file: &VehicleDefinition) -> Result<Vec<Rotor>, VehicleErrorKind> {
    match (&file.preset, file.rotors.is_empty()) {
        (Some(_), false) => Err(VehicleErrorKind::Layout(
            "give either `preset` or a [[rotors]] table, not both".into(),
        )),
        (None, true) => Err(VehicleErrorKind::Layout(
            "no rotors: give a [[rotors]] table or a `preset` with `arm_length`".into(),
        )),
        (Some(preset), true) => {
            let arm = file.arm_length.ok_or_else(|| {
                VehicleErrorKind::Layout("`preset` needs `arm_length` (m)".into())
            })?;
            check_positive("arm_length", arm)?;
            let spin =
                spin_value(file.first_spin.unwrap_or(1)).ok_or(VehicleErrorKind::OutOfRange {
                    field: "first_spin",
                    value: file.first_spin.unwrap_or(0) as f64,
                    requirement: "must be +1 or -1",
                })?;
            Ok(preset.rotors(arm, spin))
        }
        (None, false) => file
            .rotors
            .iter()
            .enumerate()
            .map(|(i, r)| rotor_from_entry(i + 1, r, file.hub_height))
            .collect(),
    }
}

fn spin_value(s: i64) -> Option<f64> {
    match s {
        1 => Some(1.0),
        -1 => Some(-1.0),
        _ => None,
    }
}

fn rotor_from_entry(n: usize, r: &RotorEntry, hub_height: f64) -> Result<Rotor, VehicleErrorKind> {
    let bad = |problem: String| VehicleErrorKind::Rotor { rotor: n, problem };
    if !r.x.is_finite() || !r.y.is_finite() {
        return Err(bad("position is not finite".into()));
    }
    let spin =
        spin_value(r.spin).ok_or_else(|| bad(format!("spin = {} must be +1 or -1", r.spin)))?;
    if let Some(z) = r.z
        && (z + hub_height).abs() > 1e-9_f64.max(1e-6 * hub_height.abs())
    {
        return Err(VehicleErrorKind::Assumption2 {
            condition: "coplanar rotors at one height",
            detail: format!(
                "rotor {n} has z = {z} m but hub_height = {hub_height} m requires z = {}",
                -hub_height
            ),
        });
    }
    if let Some(cant) = r.cant_deg
        && cant != 0.0
    {
        return Err(VehicleErrorKind::Assumption2 {
            condition: "uncanted rotors",
            detail: format!("rotor {n} is canted by {cant} deg"),
        });
    }
    Ok(Rotor {
        x: r.x,
        y: r.y,
        spin,
    })
}
