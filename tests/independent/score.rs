//! The harness: the cases (five hidden effects × two data kinds, plus the two clean
//! sets), the product's diagnosis run on each through the public library
//! (`Identification` with in-memory samples, `.diagnose(true)`, default options), and
//! the score of a diagnosis against the hidden effect and against the clean set of the
//! same seed.

use std::path::Path;

use mrsysid::internals::diagnose::{CandidateScore, Diagnosis, EffectKind};
use mrsysid::{Identification, Sample, Vehicle};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::effects::Hidden;
use super::flight::{FlightConfig, fly};
use super::physics::{Airframe, LoadState};
use super::surface::response_surface;

/// Points of a response-surface set.
pub const SURFACE_POINTS: usize = 3000;

/// The two data kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DataKind {
    /// Random steady states and rotor speeds over the envelope, loads with balance noise.
    Surface,
    /// A noisy closed-loop flight.
    Flight,
}

impl DataKind {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            DataKind::Surface => "surface",
            DataKind::Flight => "flight",
        }
    }
}

/// One case: a data kind with one hidden effect, or none (the clean set).
#[derive(Debug, Clone, Copy)]
pub struct Case {
    /// Data kind.
    pub data: DataKind,
    /// The hidden effect, `None` for the clean set.
    pub hidden: Option<Hidden>,
}

impl Case {
    /// "surface, CG offset", "flight, clean", …
    pub fn label(&self) -> String {
        let effect = self.hidden.map_or("clean".into(), |h| h.label());
        format!("{}, {effect}", self.data.label())
    }
}

/// The ten effect cases of `effects` (each effect in both kinds, e.g. of
/// [`Hidden::all`]), then the two clean sets.
pub fn cases(effects: [Hidden; 5]) -> Vec<Case> {
    let mut out = Vec::new();
    for hidden in effects {
        for data in [DataKind::Surface, DataKind::Flight] {
            out.push(Case {
                data,
                hidden: Some(hidden),
            });
        }
    }
    for data in [DataKind::Surface, DataKind::Flight] {
        out.push(Case { data, hidden: None });
    }
    out
}

/// The shipped quadrotor × (`data/vehicles/quad_x.toml`), the harness's reference.
pub fn vehicle() -> Vehicle {
    shipped_vehicle("quad_x")
}

/// A second airframe of another size and layout: the shipped Gazebo iris
/// (`data/vehicles/gazebo_iris.toml`: 1.5 kg, R = 128 mm, arms 0.13 m fore and aft and
/// 0.20–0.22 m to the side), its rotors, controller, envelope and noise scaled from the
/// reference ([`super::physics::Scale`]).
pub fn iris() -> Vehicle {
    shipped_vehicle("gazebo_iris")
}

/// `data/vehicles/<name>.toml`.
fn shipped_vehicle(name: &str) -> Vehicle {
    Vehicle::from_toml_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("data/vehicles/{name}.toml")),
    )
    .expect("shipped vehicle")
}

/// The data of `case` at `seed` (the clean set of the same kind and seed shares its
/// points or set points, excitation and noise).
pub fn data(vehicle: &Vehicle, case: &Case, seed: u64) -> Vec<Sample> {
    data_flown(vehicle, case, seed, &FlightConfig::default())
}

/// As [`data`], a flight flown as `flight` says.
pub fn data_flown(vehicle: &Vehicle, case: &Case, seed: u64, flight: &FlightConfig) -> Vec<Sample> {
    let air = Airframe::new(vehicle, case.hidden);
    match case.data {
        DataKind::Surface => response_surface(&air, SURFACE_POINTS, seed),
        DataKind::Flight => fly(&air, flight, seed),
    }
}

/// RMS over `samples` of what the hidden effect of `case` adds to the wrench, per axis
/// (N, N m): the loads with and without it at each logged state (rotor speeds,
/// velocity, rates, height, attitude as logged). A size to hold against the noise and
/// against what Eq. 22 can absorb.
pub fn effect_size(vehicle: &Vehicle, case: &Case, samples: &[Sample]) -> [f64; 6] {
    let with = Airframe::new(vehicle, case.hidden);
    let without = Airframe::new(vehicle, None);
    let mut sum = [0.0; 6];
    for s in samples {
        let state = LoadState {
            velocity: Vector3::from(s.velocity),
            rates: Vector3::from(s.rates),
            omega: &s.omega,
            omega_dot: &s.omega_dot,
            height: s.height.unwrap_or(f64::INFINITY),
            attitude: s
                .attitude
                .map_or(UnitQuaternion::identity(), |[w, x, y, z]| {
                    UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z))
                }),
        };
        let (a, b) = (with.wrench(&state), without.wrench(&state));
        for j in 0..6 {
            sum[j] += (a[j] - b[j]).powi(2);
        }
    }
    sum.map(|x| (x / samples.len().max(1) as f64).sqrt())
}

/// The product's diagnosis of `samples` through the public library with default options.
pub fn diagnose(vehicle: &Vehicle, name: &str, samples: Vec<Sample>) -> Diagnosis {
    let results = Identification::new(vehicle.clone())
        .samples(name, samples)
        .diagnose(true)
        .run()
        .unwrap_or_else(|e| panic!("{name}: fit failed: {e}"));
    results
        .outcome()
        .diagnosis
        .clone()
        .expect("the diagnosis ran")
}

/// The diagnosis's kind for a hidden effect.
pub fn expected_kind(hidden: &Hidden) -> EffectKind {
    match hidden {
        Hidden::RearWake { .. } => EffectKind::WakeInteraction,
        Hidden::QuadraticDrag { .. } => EffectKind::QuadraticDrag,
        Hidden::WeakRotor { .. } => EffectKind::RotorAsymmetry,
        Hidden::CgOffset { .. } => EffectKind::CgOffset,
        Hidden::GroundEffect { .. } => EffectKind::GroundEffect,
    }
}

/// How a diagnosis names the hidden effect.
#[derive(Debug, Clone, PartialEq)]
pub enum Naming {
    /// An effect of the right kind was added (its name).
    Added(String),
    /// A candidate of the right kind is named in a finding as explaining about as much
    /// as an added effect (its name).
    LookAlike(String),
    /// Not added, but reported as present below the importance bar (its name).
    BelowBar(String),
    /// Not named.
    Missed,
}

/// A diagnosis scored against its hidden effect and the clean set of the same seed.
#[derive(Debug, Clone)]
pub struct Score {
    /// Whether and how the effect is named.
    pub naming: Naming,
    /// Effects added (completions, named effects, generic terms), in order.
    pub added: Vec<String>,
    /// Added effects not of the hidden effect's kind.
    pub beyond_effect: Vec<String>,
    /// Of those, the ones the clean set of the same seed does not get.
    pub beyond_clean: Vec<String>,
}

/// Scores `d` for hidden-effect kind `target` (`None` for a clean set) against `clean`,
/// the diagnosis of the clean set of the same kind and seed.
pub fn score(d: &Diagnosis, clean: &Diagnosis, target: Option<EffectKind>) -> Score {
    let is_target = |s: &CandidateScore| target.is_some_and(|k| s.kind == k || s.family() == k);
    let added: Vec<String> = d.effects_added.iter().map(|e| e.name.clone()).collect();
    let clean_added: Vec<&str> = clean
        .effects_added
        .iter()
        .map(|e| e.name.as_str())
        .collect();
    let beyond_effect: Vec<String> = d
        .effects_added
        .iter()
        .filter(|e| !is_target(e))
        .map(|e| e.name.clone())
        .collect();
    let beyond_clean = beyond_effect
        .iter()
        .filter(|n| !clean_added.contains(&n.as_str()))
        .cloned()
        .collect();
    let naming = if let Some(e) = d.effects_added.iter().find(|e| is_target(e)) {
        Naming::Added(e.name.clone())
    } else {
        look_alike(d, &is_target)
            .map(Naming::LookAlike)
            .or_else(|| below_bar(d, &is_target).map(Naming::BelowBar))
            .unwrap_or(Naming::Missed)
    };
    Score {
        naming,
        added,
        beyond_effect,
        beyond_clean,
    }
}

/// The first candidate satisfying `is_target` (its kind read from the last step's
/// ranking) that the diagnosis reports as present below the importance bar.
fn below_bar(d: &Diagnosis, is_target: &dyn Fn(&CandidateScore) -> bool) -> Option<String> {
    let last = d.steps.last()?;
    d.below_bar.iter().find_map(|said| {
        last.ranking
            .iter()
            .find(|s| said.starts_with(&format!("{}:", s.name)))
            .filter(|s| is_target(s))
            .map(|s| s.name.clone())
    })
}

/// The first candidate satisfying `is_target` named as a look-alike of an effect in the
/// final model (the step that added it lists it; its kind is read from that step's
/// ranking).
fn look_alike(d: &Diagnosis, is_target: &dyn Fn(&CandidateScore) -> bool) -> Option<String> {
    let kept = |name: &str| d.effects_added.iter().any(|e| e.name == name);
    d.steps
        .iter()
        .filter(|step| step.added.is_some_and(|i| kept(&step.ranking[i].name)))
        .flat_map(|step| {
            step.look_alikes.iter().filter_map(|name| {
                step.ranking
                    .iter()
                    .find(|s| &s.name == name)
                    .filter(|s| is_target(s))
                    .map(|s| s.name.clone())
            })
        })
        .next()
}
