//! What a candidate effect is: a named physical hypothesis the Eq. 22 model lacks, with
//! the regressor columns it adds, its parameters (unit, plausible range, how the estimate
//! reads), its sentence of physics, how the search treats it and how a finding states it.
//!
//! Each effect of the library builds its candidates in a file of its own
//! ([`super::effects`]); the procedure reads everything it needs from these fields and
//! never from a candidate's or parameter's name.

use std::ops::RangeInclusive;

use crate::model::{Column, ModelStructure, ParamId, Parameter, Term};
use crate::sample::Axis;

/// Which physical effect a candidate stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EffectKind {
    /// Thrust gain near the ground.
    GroundEffect,
    /// One rotor producing more or less thrust and torque than the others.
    RotorAsymmetry,
    /// Centre of gravity away from the reference point, in the rotor plane.
    CgOffset,
    /// Centre of gravity above or below the assumed height.
    CgHeight,
    /// Rear rotors losing thrust in the front rotors' wake.
    WakeInteraction,
    /// Airframe drag growing with the square of airspeed.
    QuadraticDrag,
    /// Thrust loss in descent near the hover inflow speed.
    VortexRing,
    /// The Eq. 22 terms linear in V_h, when the model left them out.
    LinearVh,
    /// Loads lagging or leading the logged rotor speeds.
    RotorSpeedDelay,
    /// In-plane rotor velocity from the yaw rate (dropped by Assumption 4).
    YawRateDrag,
    /// Eq. 22c's edgewise thrust taken at each yawing hub's own in-plane airspeed
    /// (dropped by Assumption 4).
    YawRateHubAirspeed,
    /// In-plane hub velocity from the roll and pitch rates at hub height.
    RollPitchRateDrag,
    /// Unmeasured steady wind: the logged velocity is not the airspeed.
    SteadyWind,
    /// Moment axes with their own value of a lumped coefficient Eq. 22 shares with the
    /// forces.
    DecoupledMoments,
    /// Rotor hub moment from blade flapping in the hub's in-plane airflow.
    RotorFlapping,
    /// Roll and pitch damping from each rotor's thrust change with its hub's vertical
    /// velocity, with its own coefficient (a completion: Eq. 22 holds these terms only
    /// inside the C_T_muw column it shares with the vertical force).
    RotorRateDamping,
    /// Thrust responding to rotor acceleration (dynamic inflow, or a rotor speed logged
    /// through a lag).
    RotorAccelerationThrust,
    /// Rotor thrust terms of second order in the hub's in-plane and axial velocities
    /// (V_h w_i, w_i²) that the first-order inflow plane of Eq. 6 drops (a completion).
    SecondOrderInflow,
    /// Linear vertical airframe drag, independent of rotor speed (a completion of
    /// Assumption 3: Eq. 22 lumps such a drag into the in-plane forces only).
    VerticalLinearDrag,
    /// Constant accelerometer bias in forces derived as m a.
    AccelerometerBias,
    /// A slow moment the model lacks, balanced by the attitude loop: the slow part of
    /// the control moment produces no angular acceleration.
    TrimMoment,
    /// Residual structure with no physical name (the generic pool).
    Generic,
}

/// What kind of hypothesis a candidate is, which decides how the search treats it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Role {
    /// A named mechanism the vehicle or the log adds (a weak rotor, a CG offset, wind).
    Mechanism,
    /// A completion of the Eq. 22 structure itself: terms its own assumptions drop.
    /// Added before undeclared effects, and reported as such.
    Completion,
    /// Names no mechanism but an Eq. 22 term's shape (a moment coefficient freed from the
    /// forces, a catch-all that would mask any moment physics that follows the term). A
    /// named mechanism is preferred over it when it explains about as much.
    Unspecific,
    /// A term of the generic pool ([`super::generic`]): unspecific, with its own
    /// Bonferroni divisor (the whole pool) and a limit on how many enter a model.
    Generic,
}

impl Role {
    /// True for completions of the Eq. 22 structure (terms its assumptions drop), as
    /// opposed to effects the vehicle or the log adds.
    pub fn is_model_completion(self) -> bool {
        self == Self::Completion
    }

    /// True for hypotheses that name no mechanism: generic-pool terms and freed moment
    /// coefficients.
    pub fn is_unspecific(self) -> bool {
        matches!(self, Self::Unspecific | Self::Generic)
    }
}

/// How a parameter's estimate reads (for reports).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum Reading {
    /// A value in the parameter's unit.
    #[default]
    Value,
    /// A relative change (of a rotor's thrust, of the thrust near the ground, …),
    /// dimensionless: shown in %.
    Fraction,
    /// A moment coefficient freed from the forces, estimated as its moment value minus
    /// its force value: its t-statistic tests Eq. 22's tie between the two.
    MomentMinusForce,
}

/// How a finding states an added candidate.
#[derive(Debug, Clone, PartialEq)]
pub enum Statement {
    /// By the candidate's name.
    Name,
    /// As a signed relative change, the estimate of parameter `parameter` (a fraction):
    /// "`less` by 9.8 %" for a negative estimate, "`more` by …" otherwise.
    Change {
        /// Index of the parameter (into [`Candidate::parameters`]).
        parameter: usize,
        /// The change when the estimate is negative, e.g. `rotor 3 weaker`.
        less: String,
        /// The change otherwise, e.g. `rotor 3 stronger`.
        more: String,
    },
    /// As the name with the centre of pressure of a drag acting off the CG: the distance
    /// z_cp (m, body z, below the CG positive) that best relates the moment areas
    /// m = z_cp A to the areas A in least squares, z_cp = Σ m A / Σ A², shown in mm; "not
    /// resolved" when it lies farther than `max` from the CG (areas too small to place
    /// it).
    CentreOfPressure {
        /// Indices of the areas A (m²).
        areas: [usize; 2],
        /// Indices of the moment areas z_cp A (m³), in the order of `areas`.
        moments: [usize; 2],
        /// Largest plausible |z_cp|, m.
        max: f64,
    },
}

/// One parameter of a candidate with the columns it multiplies.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateParameter {
    /// Name, e.g. `thrust_scale_3`.
    pub name: String,
    /// Unit of the estimate ("-" for fractions and coefficients).
    pub unit: String,
    /// Physical range of the estimate, in `unit`: an estimate outside it is implausible.
    /// `None`: any finite estimate is plausible.
    pub range: Option<RangeInclusive<f64>>,
    /// How the estimate reads.
    pub reading: Reading,
    /// Columns (their `param` field is set when the candidate is added to a model).
    pub columns: Vec<Column>,
}

impl CandidateParameter {
    /// A parameter in `unit` multiplying `columns`, any finite estimate plausible, read
    /// as a value.
    pub fn new(name: impl Into<String>, unit: &str, columns: Vec<Column>) -> Self {
        Self {
            name: name.into(),
            unit: unit.to_string(),
            range: None,
            reading: Reading::Value,
            columns,
        }
    }

    /// The same, plausible only from `lo` to `hi` (in its unit, both included).
    pub fn within(self, lo: f64, hi: f64) -> Self {
        Self {
            range: Some(lo..=hi),
            ..self
        }
    }

    /// The same, read as a relative change (shown in %).
    pub fn fraction(self) -> Self {
        self.read_as(Reading::Fraction)
    }

    /// The same, read as `reading`.
    pub fn read_as(self, reading: Reading) -> Self {
        Self { reading, ..self }
    }

    /// True when `estimate` lies in the parameter's physical range (is finite, without
    /// one).
    pub fn plausible(&self, estimate: f64) -> bool {
        match &self.range {
            Some(range) => range.contains(&estimate),
            None => estimate.is_finite(),
        }
    }
}

/// The part of the envelope where a candidate acts: samples whose activity (a sum of
/// signal products, dimensionless) reaches `threshold` ([`super::local`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Activity {
    /// Activity signal of one sample, e.g. the Cheeseman–Bennett thrust gain.
    pub terms: Vec<Term>,
    /// Smallest activity that counts as acting.
    pub threshold: f64,
}

/// A named physical hypothesis.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Effect kind.
    pub kind: EffectKind,
    /// What kind of hypothesis it is (how the search treats it).
    pub role: Role,
    /// For one form of an effect offered in several, of which one enters a model (the
    /// data choose): that effect. `None` for a candidate that is no such form.
    pub forms_of: Option<EffectKind>,
    /// Display name, e.g. `weak rotor 3`.
    pub name: String,
    /// One sentence of physics.
    pub physics: &'static str,
    /// Parameters and their columns.
    pub parameters: Vec<CandidateParameter>,
    /// Where it acts, for an effect confined to part of the envelope (judged on the
    /// held-out samples there); `None` for an effect that acts everywhere.
    pub activity: Option<Activity>,
    /// How a finding states it once added.
    pub statement: Statement,
}

impl Candidate {
    /// A candidate of `kind` and `role` that acts everywhere, is no form of a family and
    /// is stated by its name.
    pub fn new(
        kind: EffectKind,
        role: Role,
        name: impl Into<String>,
        physics: &'static str,
        parameters: Vec<CandidateParameter>,
    ) -> Self {
        Self {
            kind,
            role,
            forms_of: None,
            name: name.into(),
            physics,
            parameters,
            activity: None,
            statement: Statement::Name,
        }
    }

    /// The same as one form of effect `family`, offered in several forms of which one
    /// enters a model.
    pub fn form_of(self, family: EffectKind) -> Self {
        Self {
            forms_of: Some(family),
            ..self
        }
    }

    /// The same, confined to where `activity` reaches its threshold.
    pub fn acting_where(self, activity: Activity) -> Self {
        Self {
            activity: Some(activity),
            ..self
        }
    }

    /// The same, stated by `statement` in a finding.
    pub fn stated_as(self, statement: Statement) -> Self {
        Self { statement, ..self }
    }

    /// The effect this candidate is a form of ([`Candidate::forms_of`]), else its kind.
    pub fn family(&self) -> EffectKind {
        self.forms_of.unwrap_or(self.kind)
    }

    /// Axes the candidate's columns act on, in [`Axis`] order.
    pub fn axes(&self) -> Vec<Axis> {
        let mut axes: Vec<Axis> = self
            .parameters
            .iter()
            .flat_map(|p| p.columns.iter().map(|c| c.axis))
            .collect();
        axes.sort();
        axes.dedup();
        axes
    }

    /// Adds the candidate's parameters and columns to `structure`; returns the new
    /// parameters.
    pub fn add_to(&self, structure: &mut ModelStructure) -> Vec<ParamId> {
        self.parameters
            .iter()
            .map(|p| {
                structure.add_parameter(
                    Parameter {
                        name: p.name.clone(),
                        unit: p.unit.clone(),
                    },
                    p.columns.clone(),
                )
            })
            .collect()
    }

    /// What a finding says of it with `estimates` (one per parameter, in order): its
    /// [`Statement`], e.g. "rotor 3 weaker by 9.8 %", or its name.
    pub fn describe(&self, estimates: &[f64]) -> String {
        match &self.statement {
            Statement::Change {
                parameter,
                less,
                more,
            } => match estimates.get(*parameter) {
                Some(&x) => {
                    let how = if x < 0.0 { less } else { more };
                    format!("{how} by {:.1} %", 100.0 * x.abs())
                }
                None => self.name.clone(),
            },
            Statement::CentreOfPressure {
                areas,
                moments,
                max,
            } => {
                let value = |k: &usize| estimates.get(*k).copied();
                let pairs: Option<Vec<(f64, f64)>> = areas
                    .iter()
                    .zip(moments)
                    .map(|(a, m)| Some((value(a)?, value(m)?)))
                    .collect();
                let Some(pairs) = pairs else {
                    return self.name.clone();
                };
                let a2: f64 = pairs.iter().map(|(a, _)| a * a).sum();
                let z = pairs.iter().map(|(a, m)| a * m).sum::<f64>() / a2;
                if !z.is_finite() {
                    return self.name.clone();
                }
                let side = if z < 0.0 { "above" } else { "below" };
                if z.abs() > *max {
                    return format!(
                        "{}, centre of pressure not resolved (least squares put it {:.1} m \
                         {side} the CG, beyond {max} m)",
                        self.name,
                        z.abs()
                    );
                }
                format!(
                    "{}, centre of pressure {:.0} mm {side} the CG",
                    self.name,
                    1000.0 * z.abs()
                )
            }
            Statement::Name => self.name.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stated(statement: Statement) -> Candidate {
        Candidate::new(
            EffectKind::RotorAsymmetry,
            Role::Mechanism,
            "weak rotor 3",
            "",
            Vec::new(),
        )
        .stated_as(statement)
    }

    #[test]
    fn a_change_is_stated_with_its_direction_and_size_in_percent() {
        let c = stated(Statement::Change {
            parameter: 1,
            less: "rotor 3 weaker".into(),
            more: "rotor 3 stronger".into(),
        });
        assert_eq!(c.describe(&[0.5, -0.098]), "rotor 3 weaker by 9.8 %");
        assert_eq!(c.describe(&[0.5, 0.102]), "rotor 3 stronger by 10.2 %");
        // Without that estimate, and for a candidate stated by name: the name.
        assert_eq!(c.describe(&[0.5]), "weak rotor 3");
        assert_eq!(stated(Statement::Name).describe(&[0.5]), "weak rotor 3");
    }

    #[test]
    fn a_drag_off_the_cg_is_stated_with_its_centre_of_pressure() {
        let c = stated(Statement::CentreOfPressure {
            areas: [0, 1],
            moments: [3, 4],
            max: 0.5,
        });
        // Moment areas z A with z = −15 mm (above the CG) on both axes, then one that
        // disagrees: the least-squares z_cp = Σ m A / Σ A².
        let (ax, ay) = (0.01, 0.012);
        let z = -0.015;
        let exact = c.describe(&[ax, ay, 0.03, z * ax, z * ay]);
        assert_eq!(exact, "weak rotor 3, centre of pressure 15 mm above the CG");
        let mixed = c.describe(&[ax, ay, 0.03, 0.0, 0.02 * ay]);
        let z = 0.02 * ay * ay / (ax * ax + ay * ay);
        assert_eq!(
            mixed,
            format!(
                "weak rotor 3, centre of pressure {:.0} mm below the CG",
                1000.0 * z
            )
        );
        // Areas too small to place it: 1.8 m below the CG, beyond the 0.5 m allowed.
        assert_eq!(
            c.describe(&[1e-4, 0.0, 0.017, 1.8e-4, 0.0]),
            "weak rotor 3, centre of pressure not resolved (least squares put it 1.8 m \
             below the CG, beyond 0.5 m)"
        );
        // Without its estimates, or with no area: the name.
        assert_eq!(c.describe(&[ax, ay, 0.03]), "weak rotor 3");
        assert_eq!(c.describe(&[0.0, 0.0, 0.03, 0.0, 0.0]), "weak rotor 3");
    }

    #[test]
    fn a_range_bounds_the_plausible_estimates_both_ends_included() {
        let p = CandidateParameter::new("cg_dx", "m", Vec::new());
        assert!(p.plausible(1e9) && !p.plausible(f64::INFINITY) && !p.plausible(f64::NAN));
        let p = p.within(-0.2, 0.2);
        assert!(p.plausible(-0.2) && p.plausible(0.2) && p.plausible(0.0));
        assert!(!p.plausible(0.2000001) && !p.plausible(f64::NAN));
    }
}
