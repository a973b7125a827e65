//! Undeclared effects: physics the Eq. 22 model does not contain, each named,
//! parameterised with units, and off unless asked for.
//!
//! Command-line syntax `NAME[=p1,p2,…]` ([`Effect::from_str`]):
//!
//! | name | parameters (units) | physics |
//! |---|---|---|
//! | `ground_effect[=k]` | k (–, default 1) | Cheeseman–Bennett: each rotor's thrust × 1/(1 − k (R/4z)²), z = hub height above ground, capped at z ≥ R/2 (ratio ≤ 1/(1 − k/4)); needs height |
//! | `weak_rotor=i,s[,s_q]` | rotor i (1-based), thrust scale s, torque scale s_q (default s) | a damaged propeller: rotor i's force and hub roll/pitch moment × s, its drag torque × s_q |
//! | `cg_offset=dx,dy,dz` | m, body axes | the true CG sits at d from the reference point of the vehicle file: hubs at r_i − d, moments about the true CG |
//! | `wake_interaction=k` | k (–) | rotor i loses the fraction k min(1, Σ_j o_ij) V_h²/(V_h² + ν0²) of its thrust, o_ij = max(0, 1 − e_ij/2R) the overlap of rotor j's wake (swept downstream along −V_h) with rotor i at lateral miss distance e_ij, for rotors i downstream of j |
//! | `wake_advance=k` | k (–) | the same downstream rotors lose the fraction k min(1, Σ_j o_ij) μ_i of their thrust instead, μ_i = V_h/(Ω_i R) the rotor's advance ratio: a loss that keeps growing with speed |
//! | `quadratic_drag=cx,cy,cz` | drag areas C_d A per body axis, m² | F_k = −½ ρ (C_d A)_k v_k |v_k| at the CG (air-relative velocity) |
//! | `vortex_ring=k` | k (–, peak fractional thrust loss) | each rotor's thrust × (1 − k exp(−((w_i/ν0 − 1)/0.5)²) exp(−(V_h/ν0)²)), w_i its descent speed (down +) |
//! | `delay=τ` | s | the logged rotor speed is the true one τ seconds earlier (flight only) |
//! | `wind=wn,we,wd` | m/s, NED | steady wind; the log holds ground-relative velocity instead of the air-relative velocity of the data contract (flight only) |
//! | `flapping=a` | N s²/rad | blade flapping at a stiff hub: rotor i adds the hub moment a Ω_i (−v_i, u_i, 0), (u_i, v_i) its hub's in-plane air-relative velocity |
//! | `dynamic_inflow=k` | N s²/rad | thrust responding to rotor acceleration: rotor i's thrust changes by k Ω̇_i (acting at its hub) |
//! | `trim_moment=mx,my,mz[,f]` | RMS moment per body axis, N m; top frequency f, Hz (default 0.5) | a slowly varying airframe moment (fuselage or payload aerodynamics, a shifting battery) that the controller trims with differential thrust: per axis a sum of 8 sinusoids, frequencies drawn in [0.05, f] Hz, random phases, long-run RMS m ([`super::disturbance`]); part of the logged moment (flight only) |
//! | `smoothed_loads=f[,n]` | cut-off f, Hz; Butterworth order n (default 2) | the log's loads were smoothed when it was made: `fx..mz` and `ax..az` pass through a zero-phase (forward-backward) Butterworth low-pass of order n at f, f below half the log rate ([`super::filter`]); NeuroBEM's angular acceleration is order 2 at ~29 Hz (flight only) |
//! | `rotor_speed_lag=τ` | s | the logged rotor speed is the true one through a first-order lag y' = (Ω − y)/τ (an ESC telemetry filter), and the logged Ω̇ is y' (flight only) |
//! | `inflow_lag=τ` | s, at least the integration step | dynamic inflow: each rotor's induced velocity follows its quasi-steady momentum value through a first-order lag ν' = (ν_qs − ν)/τ, integrated with the rigid body; thrust and torque then depend on the history of Ω (flight only) |

use std::fmt;
use std::str::FromStr;

use super::disturbance::LOWEST_FREQUENCY;
use crate::vehicle::Vehicle;

/// One undeclared effect and its physical parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Effect {
    /// Ground effect, scale k on the Cheeseman–Bennett term (k = 1 is the textbook form).
    GroundEffect {
        /// Scale on (R/4z)², dimensionless, in (0, 3].
        k: f64,
    },
    /// A weak or damaged rotor.
    WeakRotor {
        /// Rotor number, 1-based as in the vehicle file.
        rotor: usize,
        /// Scale on its force and hub roll/pitch moment, dimensionless.
        thrust_scale: f64,
        /// Scale on its drag torque, dimensionless.
        torque_scale: f64,
    },
    /// Offset d of the true CG from the vehicle file's reference point, m, body axes.
    CgOffset {
        /// Offset, m.
        d: [f64; 3],
    },
    /// Thrust loss of rotors immersed in the wake of rotors upstream.
    WakeInteraction {
        /// Fractional thrust loss of a fully immersed rotor at high speed, dimensionless.
        k: f64,
    },
    /// Rear rotors losing thrust in proportion to their advance ratio.
    WakeAdvance {
        /// Fractional thrust loss of a fully immersed rotor per unit advance ratio.
        k: f64,
    },
    /// Quadratic airframe drag.
    QuadraticDrag {
        /// Drag areas C_d A along body x, y, z, m².
        areas: [f64; 3],
    },
    /// Vortex-ring-state thrust loss in descent.
    VortexRing {
        /// Peak fractional thrust loss, dimensionless, in [0, 1).
        k: f64,
    },
    /// Delay between true and logged rotor speed.
    Delay {
        /// Delay τ, s.
        seconds: f64,
    },
    /// Unmeasured steady wind; the log holds ground-relative velocity.
    Wind {
        /// Wind velocity, NED, m/s.
        ned: [f64; 3],
    },
    /// Hub moment of flapping rotors, a Ω_i (−v_i, u_i, 0).
    Flapping {
        /// Moment per unit rotor speed and hub in-plane speed, N s²/rad.
        a: f64,
    },
    /// Thrust change with rotor acceleration, k Ω̇_i per rotor.
    DynamicInflow {
        /// Thrust per unit rotor acceleration, N s²/rad.
        k: f64,
    },
    /// Slowly varying airframe moment, a sum of sinusoids per body axis.
    TrimMoment {
        /// Long-run RMS per body axis, N m.
        rms: [f64; 3],
        /// Highest tone frequency, Hz.
        max_frequency: f64,
    },
    /// Zero-phase Butterworth smoothing of the logged loads.
    SmoothedLoads {
        /// Cut-off (−3 dB of one pass, −6 dB of the two), Hz.
        cutoff: f64,
        /// Butterworth order.
        order: usize,
    },
    /// First-order lag between true and logged rotor speed.
    RotorSpeedLag {
        /// Time constant τ, s.
        seconds: f64,
    },
    /// First-order lag of each rotor's induced velocity behind its quasi-steady value.
    InflowLag {
        /// Time constant τ, s.
        seconds: f64,
    },
}

/// All effect names, for help texts.
pub const EFFECT_NAMES: [&str; 15] = [
    "ground_effect",
    "weak_rotor",
    "cg_offset",
    "wake_interaction",
    "wake_advance",
    "quadratic_drag",
    "vortex_ring",
    "delay",
    "wind",
    "flapping",
    "dynamic_inflow",
    "trim_moment",
    "smoothed_loads",
    "rotor_speed_lag",
    "inflow_lag",
];

impl Effect {
    /// The effect's command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::GroundEffect { .. } => "ground_effect",
            Self::WeakRotor { .. } => "weak_rotor",
            Self::CgOffset { .. } => "cg_offset",
            Self::WakeInteraction { .. } => "wake_interaction",
            Self::WakeAdvance { .. } => "wake_advance",
            Self::QuadraticDrag { .. } => "quadratic_drag",
            Self::VortexRing { .. } => "vortex_ring",
            Self::Delay { .. } => "delay",
            Self::Wind { .. } => "wind",
            Self::Flapping { .. } => "flapping",
            Self::DynamicInflow { .. } => "dynamic_inflow",
            Self::TrimMoment { .. } => "trim_moment",
            Self::SmoothedLoads { .. } => "smoothed_loads",
            Self::RotorSpeedLag { .. } => "rotor_speed_lag",
            Self::InflowLag { .. } => "inflow_lag",
        }
    }

    /// True for effects that act on the log rather than on the wrench (flight only).
    pub fn is_logging_effect(&self) -> bool {
        matches!(
            self,
            Self::Delay { .. }
                | Self::Wind { .. }
                | Self::SmoothedLoads { .. }
                | Self::RotorSpeedLag { .. }
        )
    }

    /// True for effects that need a flight: logging effects, and effects with a time
    /// history of their own (a moment varying in time, a lagged inflow state).
    pub fn needs_flight(&self) -> bool {
        self.is_logging_effect() || matches!(self, Self::TrimMoment { .. } | Self::InflowLag { .. })
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(",")
        };
        match self {
            Self::GroundEffect { k } => write!(f, "ground_effect={k}"),
            Self::WeakRotor {
                rotor,
                thrust_scale,
                torque_scale,
            } => write!(f, "weak_rotor={rotor},{thrust_scale},{torque_scale}"),
            Self::CgOffset { d } => write!(f, "cg_offset={}", list(d)),
            Self::WakeInteraction { k } => write!(f, "wake_interaction={k}"),
            Self::WakeAdvance { k } => write!(f, "wake_advance={k}"),
            Self::Flapping { a } => write!(f, "flapping={a}"),
            Self::DynamicInflow { k } => write!(f, "dynamic_inflow={k}"),
            Self::QuadraticDrag { areas } => write!(f, "quadratic_drag={}", list(areas)),
            Self::VortexRing { k } => write!(f, "vortex_ring={k}"),
            Self::Delay { seconds } => write!(f, "delay={seconds}"),
            Self::Wind { ned } => write!(f, "wind={}", list(ned)),
            Self::TrimMoment { rms, max_frequency } => {
                write!(f, "trim_moment={},{max_frequency}", list(rms))
            }
            Self::SmoothedLoads { cutoff, order } => write!(f, "smoothed_loads={cutoff},{order}"),
            Self::RotorSpeedLag { seconds } => write!(f, "rotor_speed_lag={seconds}"),
            Self::InflowLag { seconds } => write!(f, "inflow_lag={seconds}"),
        }
    }
}

/// An effect that cannot be parsed, or a set of effects the vehicle cannot take.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EffectError {
    /// A parameter that is not a finite number.
    #[error("effect `{effect}`: parameter {index} = {text:?} is not a finite number")]
    NotANumber {
        /// The effect's name as given.
        effect: String,
        /// The parameter's 1-based position.
        index: usize,
        /// The parameter as given.
        text: String,
    },
    /// Too few or too many parameters.
    #[error("effect `{effect}` takes {usage}, got {given} value(s)")]
    Arity {
        /// The effect's name.
        effect: String,
        /// Its usage, e.g. `` `wake_advance=k` ``.
        usage: String,
        /// Parameters given.
        given: usize,
    },
    /// A parameter outside its range.
    #[error("effect `{effect}`: {parameter} = {value} {requirement}")]
    OutOfRange {
        /// The effect's name.
        effect: String,
        /// The parameter's name.
        parameter: &'static str,
        /// Its value.
        value: f64,
        /// What it must satisfy, e.g. `must be in [0, 2]`.
        requirement: &'static str,
    },
    /// A name that is none of [`EFFECT_NAMES`].
    #[error("unknown effect `{name}`; known effects: {}", EFFECT_NAMES.join(", "))]
    Unknown {
        /// The name as given.
        name: String,
    },
    /// An effect given twice.
    #[error("effect `{effect}` given more than once")]
    Repeated {
        /// The effect's name.
        effect: &'static str,
    },
    /// `weak_rotor` on a rotor the vehicle does not have.
    #[error("effect `weak_rotor`: rotor {rotor} does not exist (the vehicle has {rotors} rotors)")]
    NoSuchRotor {
        /// The rotor number given (1-based).
        rotor: usize,
        /// The vehicle's rotor count.
        rotors: usize,
    },
}

impl FromStr for Effect {
    type Err = EffectError;

    /// Parses `NAME[=p1,p2,…]`; the error names the effect and the offending parameter.
    fn from_str(s: &str) -> Result<Self, EffectError> {
        let (name, args) = match s.split_once('=') {
            Some((n, a)) => (n.trim(), Some(a)),
            None => (s.trim(), None),
        };
        let values: Vec<f64> = match args {
            None => Vec::new(),
            Some(a) => a
                .split(',')
                .enumerate()
                .map(|(i, x)| {
                    x.trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| EffectError::NotANumber {
                            effect: name.to_string(),
                            index: i + 1,
                            text: x.trim().to_string(),
                        })
                })
                .collect::<Result<_, _>>()?,
        };
        let want = |n: std::ops::RangeInclusive<usize>, usage: &str| {
            if n.contains(&values.len()) {
                Ok(())
            } else {
                Err(EffectError::Arity {
                    effect: name.to_string(),
                    usage: usage.to_string(),
                    given: values.len(),
                })
            }
        };
        let in_range =
            |parameter: &'static str, value: f64, ok: bool, requirement: &'static str| {
                if ok {
                    Ok(value)
                } else {
                    Err(EffectError::OutOfRange {
                        effect: name.to_string(),
                        parameter,
                        value,
                        requirement,
                    })
                }
            };
        let effect = match name {
            "ground_effect" => {
                want(0..=1, "`ground_effect[=k]`")?;
                let k = values.first().copied().unwrap_or(1.0);
                Self::GroundEffect {
                    k: in_range("k", k, k > 0.0 && k <= 3.0, "must be in (0, 3]")?,
                }
            }
            "weak_rotor" => {
                want(2..=3, "`weak_rotor=rotor,thrust_scale[,torque_scale]`")?;
                let r = values[0];
                let rotor = in_range(
                    "rotor",
                    r,
                    r >= 1.0 && r.fract() == 0.0,
                    "must be a rotor number 1, 2, …",
                )?;
                let s = in_range(
                    "thrust_scale",
                    values[1],
                    values[1] >= 0.0 && values[1] <= 2.0,
                    "must be in [0, 2]",
                )?;
                let sq = values.get(2).copied().unwrap_or(s);
                Self::WeakRotor {
                    rotor: rotor as usize,
                    thrust_scale: s,
                    torque_scale: in_range(
                        "torque_scale",
                        sq,
                        (0.0..=2.0).contains(&sq),
                        "must be in [0, 2]",
                    )?,
                }
            }
            "cg_offset" => {
                want(3..=3, "`cg_offset=dx,dy,dz` (m)")?;
                Self::CgOffset {
                    d: [values[0], values[1], values[2]],
                }
            }
            "wake_interaction" => {
                want(1..=1, "`wake_interaction=k`")?;
                let k = values[0];
                Self::WakeInteraction {
                    k: in_range("k", k, (0.0..1.0).contains(&k), "must be in [0, 1)")?,
                }
            }
            "wake_advance" => {
                want(1..=1, "`wake_advance=k`")?;
                let k = values[0];
                Self::WakeAdvance {
                    k: in_range("k", k, (0.0..=3.0).contains(&k), "must be in [0, 3]")?,
                }
            }
            "quadratic_drag" => {
                want(3..=3, "`quadratic_drag=cx,cy,cz` (drag areas, m^2)")?;
                for (i, v) in values.iter().enumerate() {
                    in_range(["cx", "cy", "cz"][i], *v, *v >= 0.0, "must be >= 0")?;
                }
                Self::QuadraticDrag {
                    areas: [values[0], values[1], values[2]],
                }
            }
            "vortex_ring" => {
                want(1..=1, "`vortex_ring=k`")?;
                let k = values[0];
                Self::VortexRing {
                    k: in_range("k", k, (0.0..1.0).contains(&k), "must be in [0, 1)")?,
                }
            }
            "delay" => {
                want(1..=1, "`delay=seconds`")?;
                let t = values[0];
                Self::Delay {
                    seconds: in_range(
                        "seconds",
                        t,
                        (0.0..=1.0).contains(&t),
                        "must be in [0, 1] s",
                    )?,
                }
            }
            "wind" => {
                want(3..=3, "`wind=wn,we,wd` (m/s, NED)")?;
                Self::Wind {
                    ned: [values[0], values[1], values[2]],
                }
            }
            "flapping" => {
                want(1..=1, "`flapping=a` (N s^2/rad)")?;
                Self::Flapping { a: values[0] }
            }
            "dynamic_inflow" => {
                want(1..=1, "`dynamic_inflow=k` (N s^2/rad)")?;
                Self::DynamicInflow { k: values[0] }
            }
            "trim_moment" => {
                want(
                    3..=4,
                    "`trim_moment=mx,my,mz[,f]` (N m RMS per body axis, Hz)",
                )?;
                for (i, v) in values[..3].iter().enumerate() {
                    in_range(["mx", "my", "mz"][i], *v, *v >= 0.0, "must be >= 0 N m")?;
                }
                let f = values.get(3).copied().unwrap_or(0.5);
                Self::TrimMoment {
                    rms: [values[0], values[1], values[2]],
                    max_frequency: in_range(
                        "f",
                        f,
                        f > LOWEST_FREQUENCY && f <= 10.0,
                        "must be in (0.05, 10] Hz",
                    )?,
                }
            }
            "smoothed_loads" => {
                want(1..=2, "`smoothed_loads=f[,order]` (Hz, Butterworth order)")?;
                let f = in_range("f", values[0], values[0] > 0.0, "must be > 0 Hz")?;
                let n = values.get(1).copied().unwrap_or(2.0);
                let order = in_range(
                    "order",
                    n,
                    (1.0..=8.0).contains(&n) && n.fract() == 0.0,
                    "must be a whole number 1 to 8",
                )?;
                Self::SmoothedLoads {
                    cutoff: f,
                    order: order as usize,
                }
            }
            "rotor_speed_lag" | "inflow_lag" => {
                want(1..=1, &format!("`{name}=seconds`"))?;
                let t = values[0];
                let seconds = in_range("seconds", t, t > 0.0 && t <= 1.0, "must be in (0, 1] s")?;
                if name == "inflow_lag" {
                    Self::InflowLag { seconds }
                } else {
                    Self::RotorSpeedLag { seconds }
                }
            }
            other => {
                return Err(EffectError::Unknown {
                    name: other.to_string(),
                });
            }
        };
        Ok(effect)
    }
}

/// A set of effects, at most one of each kind, kept in [`EFFECT_NAMES`] order so output
/// never depends on the order of the command line.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Effects(Vec<Effect>);

impl Effects {
    /// No effect: the truth model without undeclared physics.
    pub fn none() -> Self {
        Self(Vec::new())
    }

    /// Builds the set; refuses a kind given twice and rotor numbers beyond the vehicle.
    pub fn new(effects: Vec<Effect>, vehicle: &Vehicle) -> Result<Self, EffectError> {
        let mut v = effects;
        v.sort_by_key(|e| EFFECT_NAMES.iter().position(|n| *n == e.name()));
        for pair in v.windows(2) {
            if pair[0].name() == pair[1].name() {
                return Err(EffectError::Repeated {
                    effect: pair[0].name(),
                });
            }
        }
        for e in &v {
            if let Effect::WeakRotor { rotor, .. } = e
                && *rotor > vehicle.rotor_count()
            {
                return Err(EffectError::NoSuchRotor {
                    rotor: *rotor,
                    rotors: vehicle.rotor_count(),
                });
            }
        }
        Ok(Self(v))
    }

    /// The effects in canonical order.
    pub fn iter(&self) -> impl Iterator<Item = &Effect> {
        self.0.iter()
    }

    /// True when no effect is on.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    fn find<T>(&self, f: impl Fn(&Effect) -> Option<T>) -> Option<T> {
        self.0.iter().find_map(f)
    }

    /// Ground-effect scale k, if on.
    pub fn ground_effect(&self) -> Option<f64> {
        self.find(|e| match e {
            Effect::GroundEffect { k } => Some(*k),
            _ => None,
        })
    }

    /// Weak rotor (0-based index, thrust scale, torque scale), if on.
    pub fn weak_rotor(&self) -> Option<(usize, f64, f64)> {
        self.find(|e| match e {
            Effect::WeakRotor {
                rotor,
                thrust_scale,
                torque_scale,
            } => Some((rotor - 1, *thrust_scale, *torque_scale)),
            _ => None,
        })
    }

    /// CG offset (m, body axes); zero when off.
    pub fn cg_offset(&self) -> [f64; 3] {
        self.find(|e| match e {
            Effect::CgOffset { d } => Some(*d),
            _ => None,
        })
        .unwrap_or([0.0; 3])
    }

    /// Wake-interaction k, if on.
    pub fn wake_interaction(&self) -> Option<f64> {
        self.find(|e| match e {
            Effect::WakeInteraction { k } => Some(*k),
            _ => None,
        })
    }

    /// Advance-ratio wake loss k, if on.
    pub fn wake_advance(&self) -> Option<f64> {
        self.find(|e| match e {
            Effect::WakeAdvance { k } => Some(*k),
            _ => None,
        })
    }

    /// Flapping hub-moment coefficient a (N s²/rad); zero when off.
    pub fn flapping(&self) -> f64 {
        self.find(|e| match e {
            Effect::Flapping { a } => Some(*a),
            _ => None,
        })
        .unwrap_or(0.0)
    }

    /// Thrust per unit rotor acceleration k (N s²/rad); zero when off.
    pub fn dynamic_inflow(&self) -> f64 {
        self.find(|e| match e {
            Effect::DynamicInflow { k } => Some(*k),
            _ => None,
        })
        .unwrap_or(0.0)
    }

    /// Quadratic drag areas (m²), if on.
    pub fn quadratic_drag(&self) -> Option<[f64; 3]> {
        self.find(|e| match e {
            Effect::QuadraticDrag { areas } => Some(*areas),
            _ => None,
        })
    }

    /// Vortex-ring k, if on.
    pub fn vortex_ring(&self) -> Option<f64> {
        self.find(|e| match e {
            Effect::VortexRing { k } => Some(*k),
            _ => None,
        })
    }

    /// Logged rotor-speed delay (s); zero when off.
    pub fn delay(&self) -> f64 {
        self.find(|e| match e {
            Effect::Delay { seconds } => Some(*seconds),
            _ => None,
        })
        .unwrap_or(0.0)
    }

    /// Trim moment (RMS per body axis N m, top frequency Hz), if on.
    pub fn trim_moment(&self) -> Option<([f64; 3], f64)> {
        self.find(|e| match e {
            Effect::TrimMoment { rms, max_frequency } => Some((*rms, *max_frequency)),
            _ => None,
        })
    }

    /// Load smoothing (cut-off Hz, Butterworth order), if on.
    pub fn smoothed_loads(&self) -> Option<(f64, usize)> {
        self.find(|e| match e {
            Effect::SmoothedLoads { cutoff, order } => Some((*cutoff, *order)),
            _ => None,
        })
    }

    /// Time constant of the logged rotor-speed lag (s), if on.
    pub fn rotor_speed_lag(&self) -> Option<f64> {
        self.find(|e| match e {
            Effect::RotorSpeedLag { seconds } => Some(*seconds),
            _ => None,
        })
    }

    /// Time constant of the induced-velocity lag (s), if on.
    pub fn inflow_lag(&self) -> Option<f64> {
        self.find(|e| match e {
            Effect::InflowLag { seconds } => Some(*seconds),
            _ => None,
        })
    }

    /// Steady wind (m/s, NED); zero when off.
    pub fn wind(&self) -> [f64; 3] {
        self.find(|e| match e {
            Effect::Wind { ned } => Some(*ned),
            _ => None,
        })
        .unwrap_or([0.0; 3])
    }
}

/// Cheeseman–Bennett thrust ratio T/T∞ = 1/(1 − k (R/4z)²) at hub height `z` (m) above
/// ground for radius `radius` (m); z is capped below at R/2.
pub fn ground_effect_ratio(k: f64, radius: f64, z: f64) -> f64 {
    let z = z.max(0.5 * radius);
    let x = radius / (4.0 * z);
    1.0 / (1.0 - k * x * x)
}

/// Vortex-ring thrust factor 1 − k exp(−((w/ν0 − 1)/0.5)²) exp(−(V_h/ν0)²) for descent
/// speed `w` (m/s, down +), in-plane airspeed `vh` (m/s) and hover inflow `nu0` (m/s).
pub fn vortex_ring_factor(k: f64, w: f64, vh: f64, nu0: f64) -> f64 {
    let x = (w / nu0 - 1.0) / 0.5;
    let y = vh / nu0;
    1.0 - k * (-x * x).exp() * (-y * y).exp()
}

/// Wake-interaction thrust factor of every rotor (see the module table), for in-plane
/// airspeed (u, v) in body axes (m/s), hub positions `hubs` (m), radius (m) and hover
/// inflow `nu0` (m/s). Writes one factor per rotor into `out`.
pub fn wake_factors(
    k: f64,
    uv: [f64; 2],
    hubs: &[[f64; 3]],
    radius: f64,
    nu0: f64,
    out: &mut [f64],
) {
    let vh2 = uv[0] * uv[0] + uv[1] * uv[1];
    let strength = vh2 / (vh2 + nu0 * nu0);
    wake_immersions(uv, hubs, radius, out);
    out.iter_mut().for_each(|f| *f = 1.0 - k * *f * strength);
}

/// Advance-ratio wake thrust factor of every rotor, 1 − k min(1, Σ_j o_ij) V_h/(Ω_i R)
/// (see the module table), for in-plane airspeed (u, v) (m/s), rotor speeds `omega`
/// (rad/s), hub positions `hubs` (m) and radius (m). Writes one factor per rotor into
/// `out`.
pub fn wake_advance_factors(
    k: f64,
    uv: [f64; 2],
    omega: &[f64],
    hubs: &[[f64; 3]],
    radius: f64,
    out: &mut [f64],
) {
    let vh = uv[0].hypot(uv[1]);
    wake_immersions(uv, hubs, radius, out);
    for (f, w) in out.iter_mut().zip(omega) {
        let mu = if *w > 0.0 { vh / (w * radius) } else { 0.0 };
        *f = 1.0 - k * *f * mu;
    }
}

/// Each rotor's immersion min(1, Σ_j o_ij) in the wakes of the rotors upstream of it
/// (module table) at in-plane airspeed (u, v) (m/s); 0 in hover.
fn wake_immersions(uv: [f64; 2], hubs: &[[f64; 3]], radius: f64, out: &mut [f64]) {
    let vh = uv[0].hypot(uv[1]);
    out.fill(0.0);
    if vh == 0.0 {
        return;
    }
    // Downstream direction: where the air goes relative to the vehicle.
    let e = [-uv[0] / vh, -uv[1] / vh];
    for (i, hi) in hubs.iter().enumerate() {
        let mut immersion = 0.0;
        for (j, hj) in hubs.iter().enumerate() {
            if i == j {
                continue;
            }
            let d = [hi[0] - hj[0], hi[1] - hj[1]];
            let along = d[0] * e[0] + d[1] * e[1];
            if along <= 0.0 {
                continue;
            }
            let miss = (d[0] * e[1] - d[1] * e[0]).abs();
            immersion += (1.0 - miss / (2.0 * radius)).max(0.0);
        }
        out[i] = immersion.min(1.0);
    }
}
