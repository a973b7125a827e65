//! Built-in layouts ([`Preset`]): quadrotor, hexarotor and octorotor, `+` and `x`, as
//! rotor tables.

use std::f64::consts::PI;

use serde::Deserialize;

use super::Rotor;

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
