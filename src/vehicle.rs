//! Vehicle geometry and mass properties (seed §2 and §4.2).
//!
//! A [`Vehicle`] is read from the TOML format of `docs/vehicle-file.md` (an explicit
//! rotor table or a preset) or built from a [`Preset`]. Construction checks physical validity (positive mass,
//! symmetric positive-definite inertia, …) and the layout.
//!
//! Layouts: the model (`crate::model`) is built from per-rotor sums, so it holds for any
//! *planar* layout with an even rotor count N ≥ 4, balanced spins (N/2 rotors each way),
//! coplanar uncanted rotors at one height, and a mixing matrix of full rank (thrust, roll,
//! pitch and yaw can be commanded independently); a layout that breaks one of these is
//! refused with the failing condition named. The rest of the seed's Assumption 2 (equal
//! arms, equal interior angles, alternating spin between neighbours, symmetry about both
//! body axes) is not needed: a layout that breaks it is accepted as a *general planar*
//! layout and each breach is reported as a note ([`Vehicle::assumption2_breaches`],
//! [`Vehicle::notes`]), not an error. Layouts that satisfy Assumption 2 are classified per
//! Definition 1.
//!
//! Axes are body FRD: x forward, y right, z down. Rotor positions are hub positions
//! relative to the centre of gravity, in metres. A rotor's spin `sigma = +1` means its
//! angular velocity points along +z (down), i.e. clockwise seen from above.

use std::f64::consts::PI;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::Deserialize;

/// Standard gravity, m/s², used for the hover induced velocity ν0.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Largest rotor count a vehicle may have (rotor indices are stored in one byte).
pub const MAX_ROTORS: usize = 64;

/// Default tolerance of the Assumption 2 checks, relative to the arm length ℓ (lengths)
/// or in radians (angles).
pub const DEFAULT_GEOMETRY_TOLERANCE: f64 = 1e-3;

/// One rotor: hub position in body FRD axes and spin direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rotor {
    /// Hub position along body x (forward), m.
    pub x: f64,
    /// Hub position along body y (right), m.
    pub y: f64,
    /// Spin direction σ ∈ {−1, +1}: +1 when the rotor's angular velocity points along
    /// body +z (down), by the right-hand rule (seed Eq. 10).
    pub spin: f64,
}

/// Configuration class of Definition 1 (seed §4.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ConfigurationClass {
    /// N = 4 with a rotor on a body axis, e.g. at (0, ℓ).
    QuadPlus,
    /// N = 4 with a rotor at (ℓ√2/2, ℓ√2/2).
    QuadX,
    /// N ≥ 6.
    Multirotor6Plus,
    /// A supported layout that breaks Assumption 2 (Definition 1 does not apply): the
    /// model uses the general per-rotor sums of `crate::model`.
    GeneralPlanar,
}

impl fmt::Display for ConfigurationClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::QuadPlus => "quadrotor+",
            Self::QuadX => "quadrotorx",
            Self::Multirotor6Plus => "multirotor>=6",
            Self::GeneralPlanar => "general planar",
        })
    }
}

/// Built-in layouts. Rotor 1 sits at azimuth φ0 (0 for `+` layouts, π/N for `x` layouts),
/// azimuth measured from body +x towards body +y; rotors are numbered by increasing
/// azimuth and alternate in spin starting with `first_spin`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// Quadrotor × (Definition 1): rotor 1 front-right.
    QuadX,
    /// Quadrotor + (Definition 1): rotor 1 straight ahead.
    QuadPlus,
    /// Hexarotor with rotor 1 straight ahead.
    HexaPlus,
    /// Hexarotor with rotor 1 at 30° (front-right).
    HexaX,
    /// Octorotor with rotor 1 straight ahead.
    OctoPlus,
    /// Octorotor with rotor 1 at 22.5° (front-right).
    OctoX,
}

impl Preset {
    /// Rotor count and azimuth of rotor 1 (rad).
    fn layout(self) -> (usize, f64) {
        match self {
            Self::QuadX => (4, PI / 4.0),
            Self::QuadPlus => (4, 0.0),
            Self::HexaPlus => (6, 0.0),
            Self::HexaX => (6, PI / 6.0),
            Self::OctoPlus => (8, 0.0),
            Self::OctoX => (8, PI / 8.0),
        }
    }

    /// Parses the snake_case name used in TOML and on the command line.
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "quad_x" => Self::QuadX,
            "quad_plus" => Self::QuadPlus,
            "hexa_plus" => Self::HexaPlus,
            "hexa_x" => Self::HexaX,
            "octo_plus" => Self::OctoPlus,
            "octo_x" => Self::OctoX,
            _ => return None,
        })
    }

    /// All preset names, for help texts.
    pub const NAMES: [&'static str; 6] = [
        "quad_x",
        "quad_plus",
        "hexa_plus",
        "hexa_x",
        "octo_plus",
        "octo_x",
    ];

    /// Rotor table of this layout at arm length `arm_length` (m), rotor 1 spinning
    /// `first_spin` (±1).
    pub fn rotors(self, arm_length: f64, first_spin: f64) -> Vec<Rotor> {
        let (n, phi0) = self.layout();
        (0..n)
            .map(|k| {
                let phi = phi0 + 2.0 * PI * k as f64 / n as f64;
                let spin = if k % 2 == 0 { first_spin } else { -first_spin };
                Rotor {
                    x: clean_trig(arm_length * phi.cos(), arm_length),
                    y: clean_trig(arm_length * phi.sin(), arm_length),
                    spin,
                }
            })
            .collect()
    }
}

/// Rounds a coordinate that is zero up to floating-point noise to exactly zero, so presets
/// are exactly symmetric.
fn clean_trig(value: f64, scale: f64) -> f64 {
    if value.abs() < 1e-14 * scale {
        0.0
    } else {
        value
    }
}

/// Where a vehicle definition came from, for error messages.
#[derive(Debug, Clone, PartialEq)]
pub enum VehicleSource {
    /// A TOML file.
    File(PathBuf),
    /// Built in code (preset or explicit table).
    Code,
}

impl fmt::Display for VehicleSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::File(p) => write!(f, "{}", p.display()),
            Self::Code => f.write_str("vehicle"),
        }
    }
}

/// Why a vehicle definition was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VehicleErrorKind {
    /// The file could not be read.
    #[error("cannot read file: {0}")]
    Io(String),
    /// TOML syntax error or a field of the wrong type / missing field.
    #[error("{0}")]
    Parse(String),
    /// A scalar field outside its physical range.
    #[error("field `{field}` = {value}: {requirement}")]
    OutOfRange {
        /// Field name as in the TOML file.
        field: &'static str,
        /// Offending value.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
    /// The inertia matrix is not symmetric positive definite.
    #[error("field `inertia`: {0}")]
    Inertia(String),
    /// Neither a rotor table nor a preset, or both.
    #[error("{0}")]
    Layout(String),
    /// A rotor entry is invalid on its own.
    #[error("rotor {rotor} (entry {rotor} of [[rotors]]): {problem}")]
    Rotor {
        /// 1-based rotor number.
        rotor: usize,
        /// What is wrong.
        problem: String,
    },
    /// A condition of the seed's Assumption 2 that the general planar model needs too
    /// (even rotor count, balanced spins, coplanar uncanted rotors, a mixing matrix of
    /// full rank) does not hold.
    #[error("Assumption 2 fails ({condition}): {detail}")]
    Assumption2 {
        /// The failing condition, e.g. "balanced spins".
        condition: &'static str,
        /// Which rotors and by how much.
        detail: String,
    },
}

/// A vehicle definition that was refused, with where it came from.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{source_name}: {kind}")]
pub struct VehicleError {
    /// File or code origin.
    pub source_name: VehicleSource,
    /// What is wrong.
    pub kind: VehicleErrorKind,
}

/// One condition of the seed's Assumption 2 that an accepted (general planar) layout
/// breaks. Reported as a note, not an error: the model stays exact (see `crate::model`).
#[derive(Debug, Clone, PartialEq)]
pub struct Assumption2Breach {
    /// The condition, e.g. "equal arms".
    pub condition: &'static str,
    /// Which rotors and by how much.
    pub detail: String,
}

impl fmt::Display for Assumption2Breach {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Assumption 2 does not hold ({}): {}",
            self.condition, self.detail
        )
    }
}

/// What the layout checks of [`Vehicle`] decide about a rotor table alone, before mass
/// properties are known (the PX4 skeleton reports it for a table read from a log).
#[derive(Debug, Clone, PartialEq)]
pub struct RotorLayout {
    /// Arm length ℓ (mean hub distance from the CG in the rotor plane), m.
    pub arm_length: f64,
    /// Configuration class of Definition 1, or [`ConfigurationClass::GeneralPlanar`] when
    /// the layout breaks Assumption 2.
    pub class: ConfigurationClass,
    /// The conditions of Assumption 2 the layout breaks (notes, not errors); empty when
    /// Assumption 2 holds.
    pub breaches: Vec<Assumption2Breach>,
}

impl RotorLayout {
    /// Checks `rotors` as the vehicle loader does, with the default tolerance
    /// [`DEFAULT_GEOMETRY_TOLERANCE`]: the error is the loader's refusal.
    pub fn check(rotors: &[Rotor]) -> Result<Self, VehicleErrorKind> {
        Self::with_tolerance(rotors, DEFAULT_GEOMETRY_TOLERANCE)
    }

    fn with_tolerance(rotors: &[Rotor], tol: f64) -> Result<Self, VehicleErrorKind> {
        let arm_length = check_layout(rotors, tol)?;
        let breaches = assumption2_breaches(rotors, arm_length, tol);
        let class = if breaches.is_empty() {
            classify(rotors, arm_length, tol)
        } else {
            ConfigurationClass::GeneralPlanar
        };
        Ok(Self {
            arm_length,
            class,
            breaches,
        })
    }
}

/// Mass, inertia, air and rotor properties shared by every layout.
#[derive(Debug, Clone, PartialEq)]
pub struct MassAndRotorProperties {
    /// Vehicle mass m, kg.
    pub mass: f64,
    /// Inertia matrix I about the CG in body axes, kg m².
    pub inertia: [[f64; 3]; 3],
    /// Air density ρ, kg/m³.
    pub air_density: f64,
    /// Rotor radius R, m.
    pub rotor_radius: f64,
    /// Height h of the rotor plane above the CG, m (rotor hubs at z = −h).
    pub hub_height: f64,
    /// Polar moment of inertia J_z of one motor + rotor, kg m².
    pub rotor_inertia: f64,
}

/// A multirotor with a supported planar layout: one that satisfies Assumption 2 (then
/// classified per Definition 1) or a general planar layout (see the module docs).
///
/// ```
/// use mrsysid::vehicle::{ConfigurationClass, Vehicle, VehicleSource};
/// let toml = r#"
///     name = "5-inch quad"
///     mass = 1.2                  # kg
///     inertia = [[0.011, 0, 0], [0, 0.012, 0], [0, 0, 0.021]]   # kg m^2
///     air_density = 1.225         # kg/m^3
///     rotor_radius = 0.0635       # m
///     hub_height = 0.02           # m
///     rotor_inertia = 3.0e-5      # kg m^2
///     preset = "quad_x"
///     arm_length = 0.225          # m
/// "#;
/// let v = Vehicle::from_toml_str(toml, VehicleSource::Code).expect("a valid vehicle");
/// assert_eq!(v.rotor_count(), 4);
/// assert_eq!(v.class(), ConfigurationClass::QuadX);
/// assert!((v.arm_length() - 0.225).abs() < 1e-12);
/// assert!(v.notes().is_empty(), "Assumption 2 holds");
/// // A malformed file is an error naming the problem, never a panic.
/// assert!(Vehicle::from_toml_str("mass = -1", VehicleSource::Code).is_err());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Vehicle {
    /// Human-readable name.
    pub name: String,
    /// Mass, inertia, air and rotor properties.
    pub props: MassAndRotorProperties,
    rotors: Vec<Rotor>,
    arm_length: f64,
    class: ConfigurationClass,
    tolerance: f64,
    breaches: Vec<Assumption2Breach>,
}

/// The vehicle TOML layout (`docs/vehicle-file.md`), unchecked. Embedded as is in
/// identified-model files; [`Vehicle::from_definition`] checks it.
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleDefinition {
    /// Vehicle name.
    pub name: String,
    /// Mass, kg.
    pub mass: f64,
    /// Inertia about the CG, body axes, kg m².
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

impl Vehicle {
    /// Reads and checks a vehicle TOML file.
    pub fn from_toml_file(path: &Path) -> Result<Self, VehicleError> {
        let source = VehicleSource::File(path.to_path_buf());
        let text = std::fs::read_to_string(path).map_err(|e| VehicleError {
            source_name: source.clone(),
            kind: VehicleErrorKind::Io(e.to_string()),
        })?;
        Self::from_toml_str(&text, source)
    }

    /// Parses and checks vehicle TOML text; `source` names it in errors.
    pub fn from_toml_str(text: &str, source: VehicleSource) -> Result<Self, VehicleError> {
        let err = |kind| VehicleError {
            source_name: source.clone(),
            kind,
        };
        let file: VehicleDefinition =
            toml::from_str(text).map_err(|e| err(VehicleErrorKind::Parse(one_line(&e, text))))?;
        Self::from_definition(file, source)
    }

    /// Checks a parsed vehicle definition; `source` names it in errors.
    pub fn from_definition(
        file: VehicleDefinition,
        source: VehicleSource,
    ) -> Result<Self, VehicleError> {
        let err = |kind| VehicleError {
            source_name: source.clone(),
            kind,
        };
        let rotors = file_rotors(&file).map_err(err)?;
        let props = MassAndRotorProperties {
            mass: file.mass,
            inertia: file.inertia,
            air_density: file.air_density,
            rotor_radius: file.rotor_radius,
            hub_height: file.hub_height,
            rotor_inertia: file.rotor_inertia,
        };
        let tol = file
            .geometry_tolerance
            .unwrap_or(DEFAULT_GEOMETRY_TOLERANCE);
        Self::build(file.name, props, rotors, tol).map_err(err)
    }

    /// Builds a preset layout with arm length `arm_length` (m); rotor 1 spins `first_spin`.
    pub fn preset(
        name: &str,
        preset: Preset,
        arm_length: f64,
        first_spin: f64,
        props: MassAndRotorProperties,
    ) -> Result<Self, VehicleError> {
        check_positive("arm_length", arm_length).map_err(|kind| VehicleError {
            source_name: VehicleSource::Code,
            kind,
        })?;
        Self::from_rotors(name, props, preset.rotors(arm_length, first_spin))
    }

    /// Builds a vehicle from an explicit rotor table, with the default tolerance.
    pub fn from_rotors(
        name: &str,
        props: MassAndRotorProperties,
        rotors: Vec<Rotor>,
    ) -> Result<Self, VehicleError> {
        Self::build(name.to_string(), props, rotors, DEFAULT_GEOMETRY_TOLERANCE).map_err(|kind| {
            VehicleError {
                source_name: VehicleSource::Code,
                kind,
            }
        })
    }

    fn build(
        name: String,
        props: MassAndRotorProperties,
        rotors: Vec<Rotor>,
        tol: f64,
    ) -> Result<Self, VehicleErrorKind> {
        check_properties(&props)?;
        check_positive("geometry_tolerance", tol)?;
        let RotorLayout {
            arm_length,
            class,
            breaches,
        } = RotorLayout::with_tolerance(&rotors, tol)?;
        Ok(Self {
            name,
            props,
            rotors,
            arm_length,
            class,
            tolerance: tol,
            breaches,
        })
    }

    /// The rotors, numbered 1..=N in this order.
    pub fn rotors(&self) -> &[Rotor] {
        &self.rotors
    }

    /// Rotor count N_r.
    pub fn rotor_count(&self) -> usize {
        self.rotors.len()
    }

    /// Arm length ℓ (mean hub distance from the CG in the rotor plane), m.
    pub fn arm_length(&self) -> f64 {
        self.arm_length
    }

    /// Configuration class of Definition 1, or [`ConfigurationClass::GeneralPlanar`] when
    /// the layout breaks Assumption 2.
    pub fn class(&self) -> ConfigurationClass {
        self.class
    }

    /// Tolerance of the layout checks (relative to ℓ for lengths, rad for angles).
    pub fn geometry_tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The conditions of Assumption 2 this (accepted) layout breaks, at most one entry per
    /// condition; empty when Assumption 2 holds.
    pub fn assumption2_breaches(&self) -> &[Assumption2Breach] {
        &self.breaches
    }

    /// True when the layout satisfies the seed's Assumption 2 (within the tolerance).
    pub fn satisfies_assumption2(&self) -> bool {
        self.breaches.is_empty()
    }

    /// Notes for the user, one line each (the CLI prints them on stderr as `note: …`):
    /// each Assumption 2 breach, then what the model does about it. Empty when
    /// Assumption 2 holds.
    pub fn notes(&self) -> Vec<String> {
        if self.breaches.is_empty() {
            return Vec::new();
        }
        let mut notes: Vec<String> = self
            .breaches
            .iter()
            .map(|b| format!("vehicle `{}`: {b}", self.name))
            .collect();
        notes.push(format!(
            "vehicle `{}` is identified as a general planar layout: Eq. 22 is built from per-rotor sums over its rotor positions and spins (exact, with the extra centroid and spin-offset terms; Definition 1 and the printed case table do not apply)",
            self.name
        ));
        notes
    }

    /// Area of one rotor disk πR², m².
    pub fn disk_area(&self) -> f64 {
        PI * self.props.rotor_radius.powi(2)
    }

    /// Total rotor disk area A_r = N πR², m² (seed §3).
    pub fn total_disk_area(&self) -> f64 {
        self.rotor_count() as f64 * self.disk_area()
    }

    /// Hover induced velocity ν0 = √(m g / (2 ρ A_r)), m/s (seed §3).
    pub fn hover_induced_velocity(&self) -> f64 {
        (self.props.mass * STANDARD_GRAVITY
            / (2.0 * self.props.air_density * self.total_disk_area()))
        .sqrt()
    }

    /// Hub position r_i = (x_i, y_i, −h) of rotor `i` (0-based) in body axes, m.
    pub fn hub_position(&self, i: usize) -> [f64; 3] {
        let r = self.rotors[i];
        [r.x, r.y, -self.props.hub_height]
    }

    /// The vehicle as an explicit-table definition (round-trips through
    /// [`Vehicle::from_definition`]).
    pub fn definition(&self) -> VehicleDefinition {
        let p = &self.props;
        VehicleDefinition {
            name: self.name.clone(),
            mass: p.mass,
            inertia: p.inertia,
            air_density: p.air_density,
            rotor_radius: p.rotor_radius,
            hub_height: p.hub_height,
            rotor_inertia: p.rotor_inertia,
            rotors: self
                .rotors
                .iter()
                .map(|r| RotorEntry {
                    x: r.x,
                    y: r.y,
                    z: None,
                    spin: r.spin as i64,
                    cant_deg: None,
                })
                .collect(),
            preset: None,
            arm_length: None,
            first_spin: None,
            geometry_tolerance: (self.tolerance != DEFAULT_GEOMETRY_TOLERANCE)
                .then_some(self.tolerance),
        }
    }

    /// The mirror-image spin assignment: same geometry, every spin reversed.
    pub fn with_spins_reversed(&self) -> Self {
        let mut v = self.clone();
        for r in &mut v.rotors {
            r.spin = -r.spin;
        }
        // The breach details name spins: describe the reversed ones.
        v.breaches = assumption2_breaches(&v.rotors, v.arm_length, v.tolerance);
        v
    }
}

/// TOML error text on one line, with the line number and the offending line (the toml
/// crate prints a multi-line snippet).
fn one_line(e: &toml::de::Error, text: &str) -> String {
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

fn file_rotors(file: &VehicleDefinition) -> Result<Vec<Rotor>, VehicleErrorKind> {
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

fn check_positive(field: &'static str, value: f64) -> Result<(), VehicleErrorKind> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(VehicleErrorKind::OutOfRange {
            field,
            value,
            requirement: "must be a finite number > 0",
        })
    }
}

fn check_properties(p: &MassAndRotorProperties) -> Result<(), VehicleErrorKind> {
    check_positive("mass", p.mass)?;
    check_positive("air_density", p.air_density)?;
    check_positive("rotor_radius", p.rotor_radius)?;
    if !p.hub_height.is_finite() {
        return Err(VehicleErrorKind::OutOfRange {
            field: "hub_height",
            value: p.hub_height,
            requirement: "must be finite",
        });
    }
    if !(p.rotor_inertia.is_finite() && p.rotor_inertia >= 0.0) {
        return Err(VehicleErrorKind::OutOfRange {
            field: "rotor_inertia",
            value: p.rotor_inertia,
            requirement: "must be a finite number >= 0",
        });
    }
    check_inertia(&p.inertia)
}

/// Symmetric positive definite, by Sylvester's criterion on the leading minors.
fn check_inertia(i: &[[f64; 3]; 3]) -> Result<(), VehicleErrorKind> {
    if i.iter().flatten().any(|v| !v.is_finite()) {
        return Err(VehicleErrorKind::Inertia("entries must be finite".into()));
    }
    let scale = i[0][0].abs().max(i[1][1].abs()).max(i[2][2].abs());
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        if (i[a][b] - i[b][a]).abs() > 1e-9 * scale.max(f64::MIN_POSITIVE) {
            return Err(VehicleErrorKind::Inertia(format!(
                "not symmetric: I[{a}][{b}] = {} but I[{b}][{a}] = {}",
                i[a][b], i[b][a]
            )));
        }
    }
    let m1 = i[0][0];
    let m2 = i[0][0] * i[1][1] - i[0][1] * i[1][0];
    let m3 = nalgebra::Matrix3::from_fn(|r, c| i[r][c]).determinant();
    if !(m1 > 0.0 && m2 > 0.0 && m3 > 0.0) {
        return Err(VehicleErrorKind::Inertia(format!(
            "not positive definite (leading minors {m1:.3e}, {m2:.3e}, {m3:.3e} kg m^2 powers must all be > 0)"
        )));
    }
    Ok(())
}

/// Checks the conditions the (general planar) model needs and returns the arm length ℓ
/// (mean hub radius), m: at most [`MAX_ROTORS`] rotors, an even count N ≥ 4, no two rotors
/// at one position, balanced spins and a mixing matrix of rank 4. Cant and height are
/// checked per rotor when the file is read.
fn check_layout(rotors: &[Rotor], tol: f64) -> Result<f64, VehicleErrorKind> {
    let n = rotors.len();
    let fail = |condition, detail| Err(VehicleErrorKind::Assumption2 { condition, detail });
    if n > MAX_ROTORS {
        return Err(VehicleErrorKind::Layout(format!(
            "{n} rotors: at most {MAX_ROTORS} are supported"
        )));
    }
    if n < 4 || !n.is_multiple_of(2) {
        return fail(
            "even rotor count N >= 4",
            format!("the vehicle has {n} rotors"),
        );
    }
    let arm = rotors.iter().map(|r| r.x.hypot(r.y)).sum::<f64>() / n as f64;
    if arm <= 0.0 {
        return fail("rotors off the CG", "every rotor sits on the CG".into());
    }
    for i in 0..n {
        for j in i + 1..n {
            let d = (rotors[i].x - rotors[j].x).hypot(rotors[i].y - rotors[j].y);
            if d <= tol * arm {
                return Err(VehicleErrorKind::Rotor {
                    rotor: j + 1,
                    problem: format!("same position as rotor {} (duplicate rotor)", i + 1),
                });
            }
        }
    }
    let cw = rotors.iter().filter(|r| r.spin > 0.0).count();
    if 2 * cw != n {
        return fail(
            "balanced spins",
            format!(
                "{cw} rotors spin +1 and {} spin -1: the rotor torques do not cancel in hover (the model needs N/2 rotors each way)",
                n - cw
            ),
        );
    }
    check_mixing_rank(rotors, arm, tol)
        .map(|()| arm)
        .or_else(|detail| fail("independent thrust, roll, pitch and yaw", detail))
}

/// The rows 1, y_i, x_i, σ_i of the mixing matrix (Eq. 20, lengths over ℓ) must be linearly
/// independent: otherwise two of thrust, roll, pitch and yaw cannot be commanded apart
/// (e.g. spins following the sign of y_i couple yaw to roll). Smallest singular value
/// relative to the largest at most `tol` counts as dependent; the error names the
/// dependency.
fn check_mixing_rank(rotors: &[Rotor], arm: f64, tol: f64) -> Result<(), String> {
    let n = rotors.len();
    let m = nalgebra::DMatrix::from_fn(n, 4, |i, c| match c {
        0 => 1.0,
        1 => rotors[i].x / arm,
        2 => rotors[i].y / arm,
        _ => rotors[i].spin,
    });
    let svd = m.svd(false, true);
    let sv = &svd.singular_values;
    let (lo, hi) = (sv.min(), sv.max());
    if lo > tol * hi {
        return Ok(());
    }
    let v_t = svd.v_t.expect("requested");
    let k = sv.imin();
    let c: Vec<f64> = (0..4).map(|j| v_t[(k, j)]).collect();
    let big = c.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let names = ["1", "x_i/l", "y_i/l", "spin_i"];
    let combo: Vec<String> = c
        .iter()
        .zip(names)
        .filter(|(x, _)| x.abs() > 1e-6 * big)
        .map(|(x, name)| format!("{:+.3}*{name}", x / big))
        .collect();
    Err(format!(
        "the mixing matrix (Eq. 20) has rank 3: {} = 0 for every rotor (l = {arm:.4} m), so the rotors cannot produce thrust, roll, pitch and yaw moment independently",
        combo.join(" ")
    ))
}

/// The conditions of Assumption 2 beyond those [`check_layout`] enforces: equal arms,
/// equal interior angles 2π/N, opposite spins of azimuthal neighbours, symmetry about
/// both body axes. The first offence of each condition is reported.
fn assumption2_breaches(rotors: &[Rotor], arm: f64, tol: f64) -> Vec<Assumption2Breach> {
    let n = rotors.len();
    let mut out = Vec::new();
    let mut breach = |condition, detail| {
        if !out
            .iter()
            .any(|b: &Assumption2Breach| b.condition == condition)
        {
            out.push(Assumption2Breach { condition, detail });
        }
    };
    let radii: Vec<f64> = rotors.iter().map(|r| r.x.hypot(r.y)).collect();
    // Arms are compared with the median, so the odd one out is the one reported.
    let mut sorted = radii.clone();
    sorted.sort_by(f64::total_cmp);
    let median = (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0;
    for (i, r) in radii.iter().enumerate() {
        if (r - median).abs() > tol * median {
            breach(
                "equal arms",
                format!(
                    "rotor {} has arm {r:.6} m, the median arm is {median:.6} m (tolerance {:.2e} m)",
                    i + 1,
                    tol * median
                ),
            );
        }
    }
    let mut order: Vec<(f64, usize)> = rotors
        .iter()
        .enumerate()
        .map(|(i, r)| (r.y.atan2(r.x).rem_euclid(2.0 * PI), i))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0));
    let gap = 2.0 * PI / n as f64;
    for k in 0..n {
        let (a0, i0) = order[k];
        let (a1, i1) = order[(k + 1) % n];
        let d = (a1 - a0).rem_euclid(2.0 * PI);
        if (d - gap).abs() > tol {
            breach(
                "equal interior angles",
                format!(
                    "rotors {} and {} are {:.4} deg apart, expected {:.4} deg",
                    i0 + 1,
                    i1 + 1,
                    d.to_degrees(),
                    gap.to_degrees()
                ),
            );
        }
        if rotors[i0].spin == rotors[i1].spin {
            breach(
                "neighbouring rotors spin in opposite directions",
                format!(
                    "neighbouring rotors {} and {} both have spin {:+}",
                    i0 + 1,
                    i1 + 1,
                    rotors[i0].spin
                ),
            );
        }
    }
    let has = |x: f64, y: f64| rotors.iter().any(|r| (r.x - x).hypot(r.y - y) <= tol * arm);
    for (i, r) in rotors.iter().enumerate() {
        if !has(r.x, -r.y) {
            breach(
                "symmetric about the body x axis",
                format!(
                    "rotor {} at ({}, {}) m has no mirror image at y = {}",
                    i + 1,
                    r.x,
                    r.y,
                    -r.y
                ),
            );
        }
        if !has(-r.x, r.y) {
            breach(
                "symmetric about the body y axis",
                format!(
                    "rotor {} at ({}, {}) m has no mirror image at x = {}",
                    i + 1,
                    r.x,
                    r.y,
                    -r.x
                ),
            );
        }
    }
    out
}

/// Definition 1 (seed §4.2).
fn classify(rotors: &[Rotor], arm: f64, tol: f64) -> ConfigurationClass {
    if rotors.len() >= 6 {
        return ConfigurationClass::Multirotor6Plus;
    }
    let on_axis = rotors
        .iter()
        .any(|r| r.x.abs() <= tol * arm || r.y.abs() <= tol * arm);
    if on_axis {
        ConfigurationClass::QuadPlus
    } else {
        ConfigurationClass::QuadX
    }
}

/// The mass and rotor properties of the crate's unit-test vehicles: 1 kg, I =
/// diag(0.01, 0.01, 0.02) kg m², ρ = 1.225 kg/m³, R = 0.1 m, rotors in the CG plane,
/// J_z = 0. A test that needs another value overrides it with `..test_props()`.
#[cfg(test)]
pub(crate) fn test_props() -> MassAndRotorProperties {
    MassAndRotorProperties {
        mass: 1.0,
        inertia: [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.02]],
        air_density: 1.225,
        rotor_radius: 0.1,
        hub_height: 0.0,
        rotor_inertia: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn props() -> MassAndRotorProperties {
        MassAndRotorProperties {
            hub_height: 0.02,
            rotor_inertia: 3e-5,
            ..test_props()
        }
    }

    #[test]
    fn presets_classify_per_definition_1() {
        let cases = [
            (Preset::QuadX, ConfigurationClass::QuadX),
            (Preset::QuadPlus, ConfigurationClass::QuadPlus),
            (Preset::HexaX, ConfigurationClass::Multirotor6Plus),
            (Preset::OctoPlus, ConfigurationClass::Multirotor6Plus),
        ];
        for (p, class) in cases {
            let v = Vehicle::preset("t", p, 0.25, 1.0, props()).unwrap();
            assert_eq!(v.class(), class);
            assert!((v.arm_length() - 0.25).abs() < 1e-15);
        }
    }

    #[test]
    fn definition_round_trips_through_toml() {
        let v = Vehicle::preset("t", Preset::HexaX, 0.3, -1.0, props()).unwrap();
        let text = toml::to_string(&v.definition()).unwrap();
        let back = Vehicle::from_toml_str(&text, VehicleSource::Code).unwrap();
        assert_eq!(back, v);
    }

    #[test]
    fn reversed_spins_describe_the_reversed_vehicle() {
        // A hexa with neighbours 1–2 spinning alike: a general planar layout.
        let mut rotors = Preset::HexaX.rotors(0.3, 1.0);
        rotors[1].spin = 1.0;
        rotors[2].spin = -1.0;
        let v = Vehicle::from_rotors("t", props(), rotors).unwrap();
        let detail = |v: &Vehicle| v.assumption2_breaches()[0].detail.clone();
        assert_eq!(v.class(), ConfigurationClass::GeneralPlanar);
        assert!(detail(&v).ends_with("both have spin +1"), "{}", detail(&v));
        let r = v.with_spins_reversed();
        assert!(detail(&r).ends_with("both have spin -1"), "{}", detail(&r));
    }

    #[test]
    fn hover_induced_velocity_matches_momentum_theory() {
        // ν0 = sqrt(m g / (2 ρ N π R²)) for m = 1 kg, N = 4, R = 0.1 m: 5.6438 m/s.
        let v = Vehicle::preset("t", Preset::QuadX, 0.25, 1.0, props()).unwrap();
        let expected = (9.80665_f64 / (2.0 * 1.225 * 4.0 * PI * 0.01)).sqrt();
        assert!((v.hover_induced_velocity() - expected).abs() < 1e-12);
        assert!((expected - 5.64381).abs() < 1e-5);
    }
}
