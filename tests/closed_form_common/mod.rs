//! Shared fixtures of the closed-form-world tests: a 1.2 kg 5-inch vehicle and blade
//! constants that lift it at about 2000 rad/s.

use mrsysid::internals::rotor::BladeConstants;
use mrsysid::vehicle::{MassAndRotorProperties, Preset, Vehicle};

/// Blade and inflow constants of the test rotor.
pub const BLADE: BladeConstants = BladeConstants {
    blades: 2.0,
    chord: 0.012,
    lift_slope: 5.7,
    mean_drag: 0.012,
    theta0: 0.35,
    theta_tw: -0.12,
    c_nu_mu: -0.1,
    c_nu_w: 0.3,
};

/// The test vehicle in layout `preset` (arm 0.225 m, rotor 1 spinning +1).
pub fn vehicle(preset: Preset) -> Vehicle {
    let props = MassAndRotorProperties {
        mass: 1.2,
        inertia: [[0.011, 0.0, 0.0], [0.0, 0.012, 0.0], [0.0, 0.0, 0.021]],
        air_density: 1.225,
        rotor_radius: 0.0635,
        hub_height: 0.02,
        rotor_inertia: 3e-5,
    };
    Vehicle::preset("q", preset, 0.225, 1.0, props).unwrap()
}
