//! The truth wrench of the whole vehicle: blade-element rotors at their local velocity,
//! carried to the CG as in seed §4.1 (Eq. 11–17, with the full ω × r_i of Eq. 17 rather
//! than Eq. 18), plus airframe drag and the undeclared effects. Each rotor is at its
//! quasi-steady inflow, or with `inflow_lag` at an induced velocity the flight carries as
//! a state ([`TruthModel::wrench_lagged_inflow`]).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::blade_element::{
    BladeDescription, BladeElementRotor, BladeError, BladeOverrides, RotorKinematics,
};
use super::effects::{
    Effects, ground_effect_ratio, vortex_ring_factor, wake_advance_factors, wake_factors,
};
use super::inflow::{InflowModel, InflowState};
use crate::util::{cross, dot};
use crate::vehicle::Vehicle;

/// Radial Gauss points of the default quadrature.
pub const DEFAULT_RADIAL_STATIONS: usize = 8;
/// Azimuth stations of the default quadrature.
pub const DEFAULT_AZIMUTH_STATIONS: usize = 12;

/// The `--rotor` TOML file: blade overrides (see [`BladeOverrides`]) plus airframe and
/// motor values. Every field is optional.
#[derive(Debug, Clone, Default)]
pub struct RotorFile {
    /// Blade values.
    pub blade: BladeOverrides,
    /// Linear airframe drag per body axis, N s/m (default ½ ρ S_f ν0 with S_f = ℓ²/4 for
    /// x, y and ℓ²/2 for z: the central body in the rotor wash).
    pub linear_drag: Option<[f64; 3]>,
    /// First-order motor time constant, s (default 0.03).
    pub motor_time_constant: Option<f64>,
    /// Radial quadrature points (default 8).
    pub radial_stations: Option<usize>,
    /// Azimuth quadrature points (default 12).
    pub azimuth_stations: Option<usize>,
}

/// Why a rotor file, or the truth model's rotor built from its values, cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum RotorError {
    /// The file could not be read.
    #[error("cannot read file: {0}")]
    Read(std::io::Error),
    /// Not TOML, or a key that is unknown or of the wrong type.
    #[error("TOML error{}: {message}", line.map(|l| format!(" on line {l}")).unwrap_or_default())]
    Toml {
        /// 1-based line of the offending key, when known.
        line: Option<usize>,
        /// The TOML parser's message.
        message: String,
    },
    /// A blade value out of range, or a blade that cannot hover.
    #[error(transparent)]
    Blade(#[from] BladeError),
    /// Quadrature station counts out of range.
    #[error(
        "fields `radial_stations` = {radial}, `azimuth_stations` = {azimuthal}: need 2..=64 and 4..=256"
    )]
    Stations {
        /// Radial stations.
        radial: usize,
        /// Azimuth stations.
        azimuthal: usize,
    },
    /// A linear drag coefficient that is negative or not finite.
    #[error("field `linear_drag` = {0:?}: must be finite and >= 0")]
    LinearDrag([f64; 3]),
    /// A motor time constant that is not positive.
    #[error("field `motor_time_constant` = {0}: must be > 0 s")]
    MotorTimeConstant(f64),
}

/// A [`RotorError`] of the rotor file `path`.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct RotorFileError {
    /// The rotor file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub source: RotorError,
}

/// The file as written: one flat table (no serde flatten, so TOML errors keep the
/// position of the offending field).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RotorFileToml {
    blades: Option<u32>,
    chord: Option<f64>,
    theta0: Option<f64>,
    theta_tw: Option<f64>,
    root_cutout: Option<f64>,
    lift_slope: Option<f64>,
    cd0: Option<f64>,
    cd2: Option<f64>,
    stall_angle: Option<f64>,
    cd_flat_plate: Option<f64>,
    hover_tip_speed: Option<f64>,
    linear_drag: Option<[f64; 3]>,
    motor_time_constant: Option<f64>,
    radial_stations: Option<usize>,
    azimuth_stations: Option<usize>,
}

impl RotorFile {
    /// Reads a rotor file; errors name the file, the line and the field.
    pub fn from_toml_file(path: &Path) -> Result<Self, RotorFileError> {
        let in_file = |source| RotorFileError {
            path: path.to_path_buf(),
            source,
        };
        let text = std::fs::read_to_string(path).map_err(|e| in_file(RotorError::Read(e)))?;
        Self::from_toml_str(&text).map_err(in_file)
    }

    /// Parses rotor-file text.
    pub fn from_toml_str(text: &str) -> Result<Self, RotorError> {
        let f: RotorFileToml = toml::from_str(text).map_err(|e| RotorError::Toml {
            line: e.span().map(|s| line_of(text, s.start)),
            message: e.message().trim().to_string(),
        })?;
        Ok(Self {
            blade: BladeOverrides {
                blades: f.blades,
                chord: f.chord,
                theta0: f.theta0,
                theta_tw: f.theta_tw,
                root_cutout: f.root_cutout,
                lift_slope: f.lift_slope,
                cd0: f.cd0,
                cd2: f.cd2,
                stall_angle: f.stall_angle,
                cd_flat_plate: f.cd_flat_plate,
                hover_tip_speed: f.hover_tip_speed,
            },
            linear_drag: f.linear_drag,
            motor_time_constant: f.motor_time_constant,
            radial_stations: f.radial_stations,
            azimuth_stations: f.azimuth_stations,
        })
    }
}

/// Inputs of one wrench evaluation.
#[derive(Debug, Clone, Copy)]
pub struct TruthInput<'a> {
    /// Air-relative velocity of the CG in body axes, m/s.
    pub velocity: [f64; 3],
    /// Body rates (p, q, r), rad/s.
    pub rates: [f64; 3],
    /// Rotor speeds Ω_i, rad/s.
    pub omega: &'a [f64],
    /// Rotor accelerations Ω̇_i, rad/s².
    pub omega_dot: &'a [f64],
    /// CG height above ground, m (None: far from the ground).
    pub height: Option<f64>,
    /// Third row of R_IB (body → NED), to place hubs above the ground; None = level.
    pub down_row: Option<[f64; 3]>,
}

/// The truth model of one vehicle.
#[derive(Debug, Clone)]
pub struct TruthModel {
    /// The vehicle (reference geometry).
    pub vehicle: Vehicle,
    /// The blade-element rotor shared by all rotors.
    pub rotor: BladeElementRotor,
    /// Inflow model (momentum for truth, plane for comparisons).
    pub inflow: InflowModel,
    /// Undeclared effects.
    pub effects: Effects,
    /// Linear airframe drag per body axis, N s/m.
    pub linear_drag: [f64; 3],
    /// Hover rotor speed, rad/s.
    pub hover_omega: f64,
    /// First-order motor time constant, s.
    pub motor_time_constant: f64,
    /// Hub positions relative to the true CG (r_i − d), m.
    hubs: Vec<[f64; 3]>,
}

impl TruthModel {
    /// Builds the truth model of `vehicle` with the rotor file values `file` and `effects`.
    pub fn new(vehicle: &Vehicle, file: &RotorFile, effects: Effects) -> Result<Self, RotorError> {
        let (blade, hover_omega) = BladeDescription::sized_for(vehicle, &file.blade)?;
        let radial = file.radial_stations.unwrap_or(DEFAULT_RADIAL_STATIONS);
        let azimuthal = file.azimuth_stations.unwrap_or(DEFAULT_AZIMUTH_STATIONS);
        if !(2..=64).contains(&radial) || !(4..=256).contains(&azimuthal) {
            return Err(RotorError::Stations { radial, azimuthal });
        }
        let rotor = BladeElementRotor::new(blade, vehicle, radial, azimuthal);
        let ell = vehicle.arm_length();
        let k = 0.5 * vehicle.props.air_density * vehicle.hover_induced_velocity() * ell * ell;
        let linear_drag = file.linear_drag.unwrap_or([0.25 * k, 0.25 * k, 0.5 * k]);
        if linear_drag.iter().any(|d| !(d.is_finite() && *d >= 0.0)) {
            return Err(RotorError::LinearDrag(linear_drag));
        }
        let tau = file.motor_time_constant.unwrap_or(0.03);
        if !(tau.is_finite() && tau > 0.0) {
            return Err(RotorError::MotorTimeConstant(tau));
        }
        let d = effects.cg_offset();
        let hubs = (0..vehicle.rotor_count())
            .map(|i| {
                let r = vehicle.hub_position(i);
                [r[0] - d[0], r[1] - d[1], r[2] - d[2]]
            })
            .collect();
        Ok(Self {
            vehicle: vehicle.clone(),
            rotor,
            inflow: InflowModel::Momentum,
            effects,
            linear_drag,
            hover_omega,
            motor_time_constant: tau,
            hubs,
        })
    }

    /// Hub positions relative to the true CG, m.
    pub fn hubs(&self) -> &[[f64; 3]] {
        &self.hubs
    }

    /// Fresh inflow warm-start states, one per rotor.
    pub fn inflow_states(&self) -> Vec<InflowState> {
        vec![InflowState::default(); self.vehicle.rotor_count()]
    }

    /// Force (N) and moment about the true CG (N m) on the airframe, body axes,
    /// `[F_x, F_y, F_z, M_x, M_y, M_z]`, gravity excluded; each rotor at its quasi-steady
    /// inflow (the `inflow_lag` effect is not applied: see [`Self::wrench_lagged_inflow`]).
    pub fn wrench(&self, x: &TruthInput, inflow: &mut [InflowState]) -> [f64; 6] {
        self.wrench_inner(x, inflow, None)
    }

    /// The wrench of [`Self::wrench`] with each rotor at the induced velocity `nu[i]`
    /// (m/s) instead of its quasi-steady value; writes the quasi-steady values ν_qs,i
    /// (m/s, momentum theory coupled to the blade thrust at `x`) into `nu_qs`. The
    /// `inflow_lag` effect integrates ν̇_i = (ν_qs,i − ν_i)/τ with the rigid body.
    pub fn wrench_lagged_inflow(
        &self,
        x: &TruthInput,
        inflow: &mut [InflowState],
        nu: &[f64],
        nu_qs: &mut [f64],
    ) -> [f64; 6] {
        self.wrench_inner(x, inflow, Some((nu, nu_qs)))
    }

    fn wrench_inner(
        &self,
        x: &TruthInput,
        inflow: &mut [InflowState],
        mut lag: Option<(&[f64], &mut [f64])>,
    ) -> [f64; 6] {
        let props = &self.vehicle.props;
        let radius = props.rotor_radius;
        let nu0 = self.vehicle.hover_induced_velocity();
        let n = self.hubs.len();
        let wake = match self.effects.wake_interaction() {
            Some(k) => {
                let mut w = vec![1.0; n];
                wake_factors(
                    k,
                    [x.velocity[0], x.velocity[1]],
                    &self.hubs,
                    radius,
                    nu0,
                    &mut w,
                );
                w
            }
            None => Vec::new(),
        };
        let wake_advance = match self.effects.wake_advance() {
            Some(k) => {
                let mut w = vec![1.0; n];
                wake_advance_factors(
                    k,
                    [x.velocity[0], x.velocity[1]],
                    x.omega,
                    &self.hubs,
                    radius,
                    &mut w,
                );
                w
            }
            None => Vec::new(),
        };
        let weak = self.effects.weak_rotor();
        let mut out = [0.0; 6];
        for (i, (hub, rotor)) in self.hubs.iter().zip(self.vehicle.rotors()).enumerate() {
            let v_hub = add(x.velocity, cross(x.rates, *hub));
            let kin = RotorKinematics {
                omega: x.omega[i],
                spin: rotor.spin,
                hub_velocity: v_hub,
                body_rates: x.rates,
            };
            let loads = match &mut lag {
                None => self.rotor.loads(&kin, &self.inflow, &mut inflow[i]),
                Some((nu, nu_qs)) => {
                    nu_qs[i] = self.rotor.solve_inflow(&kin, &self.inflow, &mut inflow[i]);
                    self.rotor.loads_at_inflow(&kin, nu[i], false)
                }
            };
            let (mut f, mut m) = (loads.force, loads.moment);
            let mut thrust_factor =
                wake.get(i).copied().unwrap_or(1.0) * wake_advance.get(i).copied().unwrap_or(1.0);
            if let (Some(k), Some(h)) = (self.effects.ground_effect(), x.height) {
                let down = x.down_row.unwrap_or([0.0, 0.0, 1.0]);
                let z = h - dot(&down, hub);
                thrust_factor *= ground_effect_ratio(k, radius, z);
            }
            if let Some(k) = self.effects.vortex_ring() {
                thrust_factor *= vortex_ring_factor(k, v_hub[2], v_hub[0].hypot(v_hub[1]), nu0);
            }
            f[2] *= thrust_factor;
            f[2] -= self.effects.dynamic_inflow() * x.omega_dot[i];
            let flapping = self.effects.flapping() * x.omega[i];
            m[0] -= flapping * v_hub[1];
            m[1] += flapping * v_hub[0];
            if let Some((j, s, sq)) = weak
                && j == i
            {
                f = f.map(|v| v * s);
                m = [m[0] * s, m[1] * s, m[2] * sq];
            }
            let arm = cross(*hub, f);
            let jz = props.rotor_inertia;
            let s = rotor.spin;
            let gyro = [
                -s * jz * x.rates[1] * x.omega[i],
                s * jz * x.rates[0] * x.omega[i],
                -s * jz * x.omega_dot[i],
            ];
            for k in 0..3 {
                out[k] += f[k];
                out[3 + k] += m[k] + arm[k] + gyro[k];
            }
        }
        let rho = props.air_density;
        let areas = self.effects.quadratic_drag().unwrap_or([0.0; 3]);
        let d = self.effects.cg_offset();
        let mut drag = [0.0; 3];
        for k in 0..3 {
            let v = x.velocity[k];
            drag[k] = -self.linear_drag[k] * v - 0.5 * rho * areas[k] * v * v.abs();
        }
        // Drag acts at the reference point, which lies at −d from the true CG.
        let arm = cross([-d[0], -d[1], -d[2]], drag);
        for k in 0..3 {
            out[k] += drag[k];
            out[3 + k] += arm[k];
        }
        out
    }
}

/// 1-based line number of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
