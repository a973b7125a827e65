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

mod checks;
mod error;
mod file;
mod presets;

use std::f64::consts::PI;
use std::fmt;
use std::path::Path;

use checks::{
    assumption2_breaches, check_layout, check_length_units, check_positive, check_properties,
    classify,
};
use file::{file_rotors, one_line};

pub use error::{Assumption2Breach, VehicleError, VehicleErrorKind, VehicleSource};
pub use file::{RotorEntry, VehicleDefinition};
pub use presets::Preset;

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
        let vehicle = Self::build(file.name, props, rotors, tol).map_err(err)?;
        check_length_units(vehicle.arm_length, vehicle.props.rotor_radius).map_err(err)?;
        Ok(vehicle)
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
