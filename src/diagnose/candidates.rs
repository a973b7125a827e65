//! The candidate-effect library: named physical hypotheses that the Eq. 22 model lacks,
//! each with the extra regressor columns it adds, its parameters and units, and a
//! sentence of physics.
//!
//! Columns that scale a rotor's thrust or torque use the per-rotor thrust T̂_i and
//! torque Q̂_i of the fitted base model (the Eq. 22 terms of one rotor with the base
//! estimates θ̂), so a parameter reads directly as a fraction ("rotor 3 thrust −7.9 %")
//! or a physical quantity (m, m², s).

use crate::model::{Column, ModelStructure, Signal, Term, term};
use crate::sample::Axis;
use crate::vehicle::{Rotor, Vehicle};

use super::local::Activity;

/// One load of a thrust change: (axis, rotor i's signed lever arm in m (1 for the force),
/// label prefix of the sum).
type ThrustLoad = (Axis, fn(&Rotor) -> f64, &'static str);

/// The loads of a change ΔT_i of rotor i's thrust (along −z_B, Eq. 13–15):
/// F_z = −Σ ΔT_i, M_x = −Σ y_i ΔT_i, M_y = Σ x_i ΔT_i.
const THRUST_LOADS: [ThrustLoad; 3] = [
    (Axis::Fz, |_| -1.0, "-Sum "),
    (Axis::Mx, |r| -r.y, "-Sum y_i*"),
    (Axis::My, |r| r.x, "Sum x_i*"),
];

/// Which physical effect a candidate stands for (look-alikes are compared by kind).
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
    /// Constant accelerometer bias in forces derived as m a.
    AccelerometerBias,
    /// Residual structure with no physical name (the generic pool).
    Generic,
}

impl EffectKind {
    /// True for completions of the Eq. 22 structure itself (terms its assumptions drop),
    /// as opposed to effects the vehicle or the log adds; reported as such.
    pub fn is_model_completion(self) -> bool {
        matches!(
            self,
            Self::YawRateDrag
                | Self::RollPitchRateDrag
                | Self::LinearVh
                | Self::CgHeight
                | Self::RotorRateDamping
                | Self::SecondOrderInflow
        )
    }

    /// True for hypotheses that name no mechanism: generic-pool terms, and moment
    /// coefficients freed from the forces (a catch-all that would mask any moment
    /// physics that follows an Eq. 22 term). A named mechanism is preferred over them
    /// when it explains about as much.
    pub fn is_unspecific(self) -> bool {
        matches!(self, Self::Generic | Self::DecoupledMoments)
    }

    /// The effect this kind is a form of (itself for most kinds). Thrust from rotor
    /// acceleration (ΔT_i ∝ Ω̇_i) and the rotor-speed delay (ΔF = τ dF/dΩ Ω̇, yaw torque
    /// included) are two forms of loads leading the logged rotor speeds: each physics
    /// text names the other's mechanism, and they agree to first order where Ω varies
    /// little.
    pub fn family(self) -> Self {
        match self {
            Self::RotorAccelerationThrust => Self::RotorSpeedDelay,
            kind => kind,
        }
    }

    /// True for an effect offered in several forms of which one enters a model.
    pub fn is_family_of_forms(self) -> bool {
        matches!(
            self.family(),
            Self::GroundEffect | Self::WakeInteraction | Self::RotorSpeedDelay
        )
    }
}

/// One parameter of a candidate with the columns it multiplies.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateParameter {
    /// Name, e.g. `thrust_scale_3`.
    pub name: String,
    /// Unit of the estimate ("-" for fractions and coefficients).
    pub unit: String,
    /// Columns (their `param` field is set when the candidate is added to a model).
    pub columns: Vec<Column>,
}

/// A named physical hypothesis.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Effect kind.
    pub kind: EffectKind,
    /// Display name, e.g. `weak rotor 3`.
    pub name: String,
    /// One sentence of physics.
    pub physics: &'static str,
    /// Parameters and their columns.
    pub parameters: Vec<CandidateParameter>,
    /// Where it acts, for an effect confined to part of the envelope (judged on the
    /// held-out samples there); `None` for an effect that acts everywhere.
    pub activity: Option<Activity>,
}

impl Candidate {
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
}

/// What the library needs to know to build candidates.
pub struct CandidateContext<'a> {
    /// The vehicle.
    pub vehicle: &'a Vehicle,
    /// The base (Eq. 22) structure.
    pub structure: &'a ModelStructure,
    /// Base estimates, one per `structure.params`.
    pub theta: &'a [f64],
    /// The data log CG height (ground-effect candidate).
    pub has_height: bool,
    /// The data has rotor accelerations (delay candidate).
    pub has_omega_dot: bool,
    /// The data has rates of the rotor accelerations (the delay's reaction-torque term).
    pub has_omega_ddot: bool,
    /// The data has the attitude (steady-wind candidate).
    pub has_attitude: bool,
}

impl CandidateContext<'_> {
    /// The base estimate of parameter `name`; 0 when the structure lacks it (a variant
    /// without that term, e.g. no linear V_h terms: its contribution is then zero).
    fn theta(&self, name: &str) -> f64 {
        self.structure
            .param_index(name)
            .map_or(0.0, |i| self.theta[i])
    }

    /// ρπR², kg/m.
    fn k(&self) -> f64 {
        let p = &self.vehicle.props;
        p.air_density * std::f64::consts::PI * p.rotor_radius.powi(2)
    }

    /// Terms of rotor `i`'s thrust T̂_i (N) from the base estimates, each multiplied by
    /// `extra` signals and `scale`. With `rate`, the terms of dT̂_i/dΩ_i · Ω̇_i (N/s).
    fn rotor_thrust(&self, i: usize, extra: &[Signal], scale: f64, rate: bool) -> Vec<Term> {
        use Signal::*;
        let r = self.vehicle.props.rotor_radius;
        let nu0 = self.vehicle.hover_induced_velocity();
        let rotor = self.vehicle.rotors()[i];
        let (w, w2, wd) = rotor_signals(i);
        let k = self.k() * scale;
        let mut t = if rate {
            // d/dt of the Ω-dependent terms: 2Ω Ω̇ and Ω̇.
            vec![
                term(2.0 * k * self.theta("C_T0") * r * r, &[w, wd]),
                term(-k * self.theta("C_T_mu0") * r * nu0, &[wd]),
                term(-k * self.theta("C_T_mu") * r, &[Vh, wd]),
                term(k * self.theta("C_T_muw") * r, &[W, wd]),
                term(k * self.theta("C_T_muw") * r * rotor.y, &[P, wd]),
                term(-k * self.theta("C_T_muw") * r * rotor.x, &[Q, wd]),
            ]
        } else {
            vec![
                term(k * self.theta("C_T0") * r * r, &[w2]),
                term(k * self.theta("C_T_mu2"), &[Vh, Vh]),
                term(-k * self.theta("C_T_mu0") * r * nu0, &[w]),
                term(-k * self.theta("C_T_mu") * r, &[Vh, w]),
                term(k * self.theta("C_T_muw") * r, &[W, w]),
                term(k * self.theta("C_T_muw") * r * rotor.y, &[P, w]),
                term(-k * self.theta("C_T_muw") * r * rotor.x, &[Q, w]),
            ]
        };
        t.retain(|t| t.coef != 0.0);
        for x in &mut t {
            x.factors.extend_from_slice(extra);
        }
        t
    }

    /// Terms of rotor `i`'s in-plane force along body x (`along_x`) or y, N, from the
    /// base estimates, times `scale`: rotor i's share of Eq. 22a–b at its hub's in-plane
    /// velocity (u − r y_i, v + r x_i) (Eq. 17, the yaw rate's share that Assumption 4
    /// drops included), ρπR² u_i (−C_H_mub R Ω_i − C_H_mub_mu0 ν0 − C_H_mub_mu V_h +
    /// C_H_mub_muw w_i), w_i = w + p y_i − q x_i its hub's axial velocity (Eq. 18).
    fn rotor_in_plane_force(&self, i: usize, along_x: bool, scale: f64) -> Vec<Term> {
        use Signal::*;
        let r = self.vehicle.props.rotor_radius;
        let nu0 = self.vehicle.hover_induced_velocity();
        let rotor = self.vehicle.rotors()[i];
        let (w, _, _) = rotor_signals(i);
        let muw = self.theta("C_H_mub_muw");
        // u_i = u − r y_i or v_i = v + r x_i.
        let hub = if along_x {
            [(U, 1.0), (R, -rotor.y)]
        } else {
            [(V, 1.0), (R, rotor.x)]
        };
        let mut t = Vec::new();
        for (velocity, arm) in hub {
            let k = self.k() * scale * arm;
            t.extend([
                term(-k * self.theta("C_H_mub") * r, &[velocity, w]),
                term(-k * self.theta("C_H_mub_mu0") * nu0, &[velocity]),
                term(-k * self.theta("C_H_mub_mu"), &[velocity, Vh]),
                term(k * muw, &[velocity, W]),
                term(k * muw * rotor.y, &[velocity, P]),
                term(-k * muw * rotor.x, &[velocity, Q]),
            ]);
        }
        t.retain(|t| t.coef != 0.0);
        t
    }

    /// Terms of rotor `i`'s aerodynamic torque Q̂_i (N m) from the base estimates, times
    /// `scale`; with `rate`, of dQ̂_i/dΩ_i · Ω̇_i (N m/s).
    fn rotor_torque(&self, i: usize, scale: f64, rate: bool) -> Vec<Term> {
        use Signal::*;
        let r = self.vehicle.props.rotor_radius;
        let nu0 = self.vehicle.hover_induced_velocity();
        let rotor = self.vehicle.rotors()[i];
        let (w, w2, wd) = rotor_signals(i);
        let k = self.k() * scale;
        let muw = self.theta("C_Q_muw") * r * r;
        let mut t = if rate {
            vec![
                term(2.0 * k * self.theta("C_Q0") * r.powi(3), &[w, wd]),
                term(k * self.theta("C_Q_mu0") * r * r * nu0, &[wd]),
                term(k * self.theta("C_Q_mu") * r * r, &[Vh, wd]),
                term(-k * muw, &[W, wd]),
                term(-k * muw * rotor.y, &[P, wd]),
                term(k * muw * rotor.x, &[Q, wd]),
            ]
        } else {
            vec![
                term(k * self.theta("C_Q0") * r.powi(3), &[w2]),
                term(k * self.theta("C_Q_mu0") * r * r * nu0, &[w]),
                term(k * self.theta("C_Q_mu") * r * r, &[Vh, w]),
                term(-k * muw, &[W, w]),
                term(-k * muw * rotor.y, &[P, w]),
                term(k * muw * rotor.x, &[Q, w]),
            ]
        };
        t.retain(|t| t.coef != 0.0);
        t
    }

    /// Columns of a change of rotor thrusts ΔT_i = θ f_i T̂_i, with f_i the product of
    /// `factor(i)` signals: F_z −ΣΔT_i, M_x −Σ y_i ΔT_i, M_y Σ x_i ΔT_i (Eq. 13–15).
    fn thrust_change(
        &self,
        label: &str,
        rotors: &[usize],
        factor: impl Fn(usize) -> Vec<Signal>,
        sign: f64,
    ) -> Vec<Column> {
        THRUST_LOADS
            .iter()
            .map(|&(axis, lever, _)| {
                let terms = rotors
                    .iter()
                    .flat_map(|&i| {
                        let arm = lever(&self.vehicle.rotors()[i]);
                        self.rotor_thrust(i, &factor(i), sign * arm, false)
                    })
                    .filter(|t| t.coef != 0.0)
                    .collect();
                column(axis, label, terms)
            })
            .filter(|c| !c.terms.is_empty())
            .collect()
    }

    /// ∂(model load of `axis`)/∂(body velocity component `k`: u, v, w) from the base
    /// estimates, as terms (u, v, w and V_h factors differentiated; ∂V_h/∂u = u/V_h).
    fn model_velocity_gradient(&self, axis: Axis, k: usize) -> Vec<Term> {
        use Signal::*;
        let velocity = [U, V, W][k];
        let vh_slope = [Some(UOverVh), Some(VOverVh), None][k];
        self.model_force(axis, 1.0)
            .iter()
            .flat_map(|t| {
                (0..t.factors.len()).filter_map(move |i| {
                    let slope = match t.factors[i] {
                        f if f == velocity => None,
                        Vh => Some(vh_slope?),
                        _ => return None,
                    };
                    let mut factors = t.factors.clone();
                    match slope {
                        Some(s) => factors[i] = s,
                        None => {
                            factors.remove(i);
                        }
                    }
                    Some(Term {
                        coef: t.coef,
                        factors,
                    })
                })
            })
            .collect()
    }

    /// Model force of axis `axis` from the base estimates, as terms times `scale`.
    fn model_force(&self, axis: Axis, scale: f64) -> Vec<Term> {
        self.structure
            .axis_columns(axis)
            .flat_map(|j| {
                let c = &self.structure.columns[j];
                let th = self.theta[c.param];
                c.terms.iter().map(move |t| Term {
                    coef: t.coef * th * scale,
                    factors: t.factors.clone(),
                })
            })
            .filter(|t| t.coef != 0.0)
            .collect()
    }
}

/// (Ω_i, Ω_i², Ω̇_i) signals of rotor `i`.
fn rotor_signals(i: usize) -> (Signal, Signal, Signal) {
    let i = u8::try_from(i).expect("rotor index below 256");
    (
        Signal::RotorSpeed(i),
        Signal::RotorSpeedSquared(i),
        Signal::RotorAcceleration(i),
    )
}

fn column(axis: Axis, label: &str, terms: Vec<Term>) -> Column {
    Column {
        axis,
        param: 0,
        label: label.to_string(),
        terms,
    }
}

fn parameter(name: &str, unit: &str, columns: Vec<Column>) -> CandidateParameter {
    CandidateParameter {
        name: name.to_string(),
        unit: unit.to_string(),
        columns,
    }
}

/// Every candidate that applies to this vehicle, model and data.
pub fn library(ctx: &CandidateContext) -> Vec<Candidate> {
    let mut out = Vec::new();
    let n = ctx.vehicle.rotor_count();
    let all: Vec<usize> = (0..n).collect();
    if ctx.has_height {
        out.extend(ground_effect(ctx));
    }
    for i in 0..n {
        out.push(weak_rotor(ctx, i));
    }
    out.push(cg_offset(ctx));
    out.push(cg_height(ctx));
    out.extend(wake_interaction(ctx));
    out.push(quadratic_drag(ctx));
    out.push(Candidate {
        kind: EffectKind::VortexRing,
        // A tenth of the full onset or more, summed over rotors.
        activity: Some(Activity {
            terms: (0..n).map(|i| term(1.0, &[Signal::VortexRing(i as u8)])).collect(),
            threshold: 0.1,
        }),
        name: "vortex-ring state".into(),
        physics: "Descending near the hover inflow speed, a rotor re-ingests its own wake and loses thrust unsteadily; forward speed clears it.",
        parameters: vec![parameter(
            "vortex_ring_thrust_loss",
            "-",
            ctx.thrust_change("-vrs_i*T_i", &all, |i| vec![Signal::VortexRing(i as u8)], -1.0),
        )],
    });
    if !ctx.structure.options.linear_vh_terms {
        out.push(linear_vh(ctx));
    }
    if ctx.has_omega_dot {
        out.push(delay(ctx));
    }
    if ctx.has_attitude {
        out.push(steady_wind(ctx));
    }
    out.push(yaw_rate_drag(ctx));
    if ctx.vehicle.props.hub_height != 0.0 {
        out.push(roll_pitch_rate_drag(ctx));
    }
    out.extend(decoupled_moments(ctx));
    out.push(rotor_flapping(ctx));
    out.push(rotor_rate_damping());
    out.push(second_order_inflow(ctx));
    if ctx.has_omega_dot {
        out.push(rotor_acceleration_thrust(ctx));
    }
    out.push(accelerometer_bias(ctx));
    out
}

/// The ground-effect family (Cheeseman–Bennett, T_IGE = T/(1 − k (R/4z)²)) in two
/// forms: every rotor at the CG's rotor-plane height (level flight, or no attitude
/// logged), and each rotor at its own height from the attitude (a tilted vehicle's low
/// rotors feel more of the ground, which also loads roll and pitch). The data choose the
/// form; one of them enters a model.
fn ground_effect(ctx: &CandidateContext) -> Vec<Candidate> {
    let n = ctx.vehicle.rotor_count();
    let all: Vec<usize> = (0..n).collect();
    let physics = "Near the ground the wake is blocked and thrust rises as 1/(1 - k (R/4z)^2) (Cheeseman-Bennett), z the rotor height.";
    // Thrust 1 % or more above its value out of ground effect (rotors within ~1.2
    // diameters of the ground), on average over the rotors.
    let uniform = |_: usize| vec![Signal::GroundEffect];
    let per_rotor = |i: usize| vec![Signal::RotorGroundEffect(i as u8)];
    let form =
        |name: &str, param: &str, label: &str, signal: &dyn Fn(usize) -> Vec<Signal>| Candidate {
            kind: EffectKind::GroundEffect,
            activity: Some(Activity {
                terms: (0..n).map(|i| term(1.0 / n as f64, &signal(i))).collect(),
                threshold: 0.01,
            }),
            name: name.into(),
            physics,
            parameters: vec![parameter(
                param,
                "-",
                ctx.thrust_change(label, &all, signal, 1.0),
            )],
        };
    let mut out = vec![form(
        "ground effect",
        "ground_effect_scale",
        "g_IGE*T_i",
        &uniform,
    )];
    if ctx.has_attitude {
        out.push(form(
            "ground effect, per-rotor height",
            "ground_effect_scale_per_rotor",
            "g_IGE,i*T_i",
            &per_rotor,
        ));
    }
    out
}

/// The rotor-wake family: rotors downstream in the wakes of rotors upstream lose the
/// fraction θ f_i of their thrust, f_i their wake overlap (capped at 1) times the
/// overlap-area form's wake strength V_h²/(V_h² + ν0²) (saturating with speed), or the
/// advance-ratio form's μ_i = V_h/(Ω_i R) (growing with speed). The data choose the
/// form; one of them enters a model.
fn wake_interaction(ctx: &CandidateContext) -> Vec<Candidate> {
    let n = ctx.vehicle.rotor_count();
    let all: Vec<usize> = (0..n).collect();
    let form = |name: &str, param: &str, label: &str, signal: fn(u8) -> Signal| Candidate {
        kind: EffectKind::WakeInteraction,
        // A tenth of a rotor's thrust or more at θ = 1, summed over rotors.
        activity: Some(Activity {
            terms: (0..n).map(|i| term(1.0, &[signal(i as u8)])).collect(),
            threshold: 0.1,
        }),
        name: name.into(),
        physics: "In forward flight rotors downstream fly in the wakes of rotors upstream and lose thrust, more so as the wake is swept back.",
        parameters: vec![parameter(
            param,
            "-",
            ctx.thrust_change(label, &all, |i| vec![signal(i as u8)], -1.0),
        )],
    };
    vec![
        form(
            "rotor-wake interaction",
            "wake_thrust_loss",
            "-wake_i*T_i",
            Signal::WakeImmersion,
        ),
        form(
            "rotor-wake interaction, advance ratio",
            "wake_thrust_loss_advance",
            "-overlap_i*mu_i*T_i",
            Signal::WakeAdvance,
        ),
    ]
}

/// Forces derived as F = m a from an accelerometer with a constant bias b carry m b.
/// Only the in-plane components: a constant on F_z cannot be told from the thrust
/// terms (δt² and ν0 δt are nearly constant near hover), while Eq. 22's in-plane forces
/// have no constant term.
fn accelerometer_bias(ctx: &CandidateContext) -> Candidate {
    let m = ctx.vehicle.props.mass;
    let axis = |axis: Axis, name: &str| {
        parameter(name, "m/s^2", vec![column(axis, "m", vec![term(m, &[])])])
    };
    Candidate {
        kind: EffectKind::AccelerometerBias,
        activity: None,
        name: "accelerometer bias".into(),
        physics: "Forces derived as m a from an accelerometer with a constant bias b (or logged with a constant offset) carry m b on every sample.",
        parameters: vec![
            axis(Axis::Fx, "accel_bias_x"),
            axis(Axis::Fy, "accel_bias_y"),
        ],
    }
}

fn weak_rotor(ctx: &CandidateContext, i: usize) -> Candidate {
    let rotor = ctx.vehicle.rotors()[i];
    let torque = ctx.rotor_torque(i, -rotor.spin, false);
    // Thrust, in-plane force and torque, each by its own fraction (a damaged blade
    // changes its lift and its drag differently); the in-plane force F_i acts with the
    // moments r_i × F_i of its hub at r_i = (x_i, y_i, −h).
    let h = ctx.vehicle.props.hub_height;
    let thrust = ctx.thrust_change(&format!("T_{}", i + 1), &[i], |_| Vec::new(), 1.0);
    let in_plane = |scale_x: f64, scale_y: f64| {
        let mut t = ctx.rotor_in_plane_force(i, true, scale_x);
        t.extend(ctx.rotor_in_plane_force(i, false, scale_y));
        t
    };
    let label = format!("H_{}", i + 1);
    let in_plane: Vec<Column> = [
        (Axis::Fx, in_plane(1.0, 0.0)),
        (Axis::Fy, in_plane(0.0, 1.0)),
        (Axis::Mx, in_plane(0.0, h)),
        (Axis::My, in_plane(-h, 0.0)),
        (Axis::Mz, in_plane(-rotor.y, rotor.x)),
    ]
    .into_iter()
    .filter(|(_, terms)| !terms.is_empty())
    .map(|(axis, terms)| column(axis, &label, terms))
    .collect();
    let mut parameters = vec![parameter(&format!("thrust_scale_{}", i + 1), "-", thrust)];
    if !in_plane.is_empty() {
        parameters.push(parameter(
            &format!("in_plane_scale_{}", i + 1),
            "-",
            in_plane,
        ));
    }
    if !torque.is_empty() {
        parameters.push(parameter(
            &format!("torque_scale_{}", i + 1),
            "-",
            vec![column(Axis::Mz, &format!("-s{0}*Q_{0}", i + 1), torque)],
        ));
    }
    Candidate {
        kind: EffectKind::RotorAsymmetry,
        activity: None,
        name: format!("weak rotor {}", i + 1),
        physics: "A damaged propeller or tired motor makes one rotor's thrust, in-plane force and torque fractions off the others' at the same logged speed.",
        parameters,
    }
}

/// ΔM = F̂ × d for a CG at d from the reference point (moments about the true CG).
fn cg_offset(ctx: &CandidateContext) -> Candidate {
    let dx = vec![
        column(Axis::My, "Fz_model", ctx.model_force(Axis::Fz, 1.0)),
        column(Axis::Mz, "-Fy_model", ctx.model_force(Axis::Fy, -1.0)),
    ];
    let dy = vec![
        column(Axis::Mx, "-Fz_model", ctx.model_force(Axis::Fz, -1.0)),
        column(Axis::Mz, "Fx_model", ctx.model_force(Axis::Fx, 1.0)),
    ];
    Candidate {
        kind: EffectKind::CgOffset,
        activity: None,
        name: "CG offset".into(),
        physics: "With the CG at (dx, dy) from the reference point, the thrust acts on a lever arm: M gains F x d.",
        parameters: vec![
            parameter(
                "cg_dx",
                "m",
                dx.into_iter().filter(|c| !c.terms.is_empty()).collect(),
            ),
            parameter(
                "cg_dy",
                "m",
                dy.into_iter().filter(|c| !c.terms.is_empty()).collect(),
            ),
        ],
    }
}

fn cg_height(ctx: &CandidateContext) -> Candidate {
    let dz = vec![
        column(Axis::Mx, "Fy_model", ctx.model_force(Axis::Fy, 1.0)),
        column(Axis::My, "-Fx_model", ctx.model_force(Axis::Fx, -1.0)),
    ];
    Candidate {
        kind: EffectKind::CgHeight,
        activity: None,
        name: "in-plane force lever arm".into(),
        physics: "In-plane forces act dz below the height Eq. 22 assumes (the hubs): the CG is not where assumed, or airframe drag, which Assumption 3 lumps into the rotors, acts nearer the CG.",
        parameters: vec![parameter(
            "cg_dz",
            "m",
            dz.into_iter().filter(|c| !c.terms.is_empty()).collect(),
        )],
    }
}

fn quadratic_drag(ctx: &CandidateContext) -> Candidate {
    use Signal::*;
    let half_rho = 0.5 * ctx.vehicle.props.air_density;
    let axis = |axis, s, a, label: &str| {
        parameter(
            label,
            "m^2",
            vec![column(
                axis,
                &format!("-rho/2*{0}|{0}|", s_name(s)),
                vec![term(-half_rho, &[s, a])],
            )],
        )
    };
    Candidate {
        kind: EffectKind::QuadraticDrag,
        activity: None,
        name: "quadratic airframe drag".into(),
        physics: "The airframe's pressure drag grows with the square of airspeed, -rho/2 CdA v|v| per axis, beyond the linear drag Eq. 22 lumps into the rotors.",
        parameters: vec![
            axis(Axis::Fx, U, AbsU, "drag_area_x"),
            axis(Axis::Fy, V, AbsV, "drag_area_y"),
            axis(Axis::Fz, W, AbsW, "drag_area_z"),
        ],
    }
}

/// Unmeasured steady wind W (NED): the model sees the logged velocity v where the rotors
/// feel v − C W (C the NED→body rotation), so to first order the loads change by
/// −(∂F/∂v) C W. ∂F/∂v is the base model's velocity gradient with the base estimates
/// (terms in u, v, w, V_h; ∂V_h/∂u = u/V_h).
fn steady_wind(ctx: &CandidateContext) -> Candidate {
    let parameters = ["wind_north", "wind_east", "wind_down"]
        .iter()
        .enumerate()
        .map(|(j, name)| {
            let columns = Axis::ALL
                .iter()
                .map(|&axis| {
                    let terms = (0..3)
                        .flat_map(|k| {
                            let c = Signal::NedToBody((3 * k + j) as u8);
                            ctx.model_velocity_gradient(axis, k)
                                .into_iter()
                                .map(move |mut t| {
                                    t.coef = -t.coef;
                                    t.factors.push(c);
                                    t
                                })
                        })
                        .collect();
                    column(axis, &format!("-dF/dv*C[:,{j}]"), terms)
                })
                .filter(|c| !c.terms.is_empty())
                .collect();
            parameter(name, "m/s", columns)
        })
        .collect();
    Candidate {
        kind: EffectKind::SteadyWind,
        activity: None,
        name: "steady wind".into(),
        physics: "A steady wind makes the airspeed differ from the logged (ground-relative) velocity by the wind rotated into body axes, which changes the rotor loads through their velocity dependence.",
        parameters,
    }
}

fn s_name(s: Signal) -> &'static str {
    match s {
        Signal::U => "u",
        Signal::V => "v",
        _ => "w",
    }
}

/// The Eq. 22 terms linear in V_h, taken from the full structure.
fn linear_vh(ctx: &CandidateContext) -> Candidate {
    let full = ModelStructure::eq22(
        ctx.vehicle,
        crate::model::ModelOptions {
            linear_vh_terms: true,
            ..ctx.structure.options
        },
    );
    let parameters = ["C_H_mub_mu", "C_T_mu", "C_Q_mu"]
        .iter()
        .filter_map(|name| {
            let p = full.param_index(name)?;
            let cols = full
                .columns
                .iter()
                .filter(|c| c.param == p)
                .cloned()
                .collect();
            Some(parameter(name, "-", cols))
        })
        .collect();
    Candidate {
        kind: EffectKind::LinearVh,
        activity: None,
        name: "terms linear in Vh".into(),
        physics: "The inflow varies with in-plane airspeed (Eq. 6, C_nu_mu); a constant-inflow model leaves out the terms linear in Vh.",
        parameters,
    }
}

/// Loads follow Ω(t + τ) while the log holds Ω(t): ΔF ≈ τ dF/dΩ Ω̇.
fn delay(ctx: &CandidateContext) -> Candidate {
    let n = ctx.vehicle.rotor_count();
    let rotors = ctx.vehicle.rotors();
    let thrust = |scale: &dyn Fn(usize) -> f64| -> Vec<Term> {
        (0..n)
            .flat_map(|i| ctx.rotor_thrust(i, &[], scale(i), true))
            .collect()
    };
    let torque: Vec<Term> = (0..n)
        .flat_map(|i| ctx.rotor_torque(i, -rotors[i].spin, true))
        .collect();
    // The gyroscopic moments J_z (q δr, −p δr) follow the true speeds too.
    let jz = match ctx.structure.options.rotor_inertia {
        crate::model::RotorInertiaTerms::Known => ctx.vehicle.props.rotor_inertia,
        _ => 0.0,
    };
    let mut roll = thrust(&|i| -rotors[i].y);
    let mut pitch = thrust(&|i| rotors[i].x);
    let mut yaw = torque;
    if jz != 0.0 {
        roll.push(term(jz, &[Signal::Q, Signal::DrDot]));
        pitch.push(term(-jz, &[Signal::P, Signal::DrDot]));
        // The reaction torque J_z δ̇r leads the log too; with a motor time constant of
        // tens of ms its rate J_z δ̈r is most of the delay's yaw moment.
        if ctx.has_omega_ddot {
            yaw.push(term(jz, &[Signal::DrDDot]));
        }
    }
    let yaw_label = if ctx.has_omega_ddot && jz != 0.0 {
        "-Sum s_i dQ_i/dt + Jz dr_ddot"
    } else {
        "-Sum s_i dQ_i/dt"
    };
    let columns = vec![
        column(Axis::Fz, "-Sum dT_i/dt", thrust(&|_| -1.0)),
        column(Axis::Mx, "-Sum y_i dT_i/dt + Jz q dr_dot", roll),
        column(Axis::My, "Sum x_i dT_i/dt - Jz p dr_dot", pitch),
        column(Axis::Mz, yaw_label, yaw),
    ];
    Candidate {
        kind: EffectKind::RotorSpeedDelay,
        activity: None,
        name: "rotor-speed delay".into(),
        physics: "When logged rotor speeds lag the true ones by tau (a pure delay, or a first-order filter of time constant tau: the two agree to first order in tau), the loads lead the log: dF = tau dF/dOmega dOmega/dt.",
        parameters: vec![parameter(
            "rotor_speed_delay",
            "s",
            columns
                .into_iter()
                .filter(|c| !c.terms.is_empty())
                .collect(),
        )],
    }
}

/// Hub in-plane velocity from the yaw rate, r × r_i (Assumption 4 drops it): rotor
/// drag gains −r y_i, r x_i components (Eq. 17).
fn yaw_rate_drag(ctx: &CandidateContext) -> Candidate {
    use Signal::*;
    let k = ctx.k();
    let r = ctx.vehicle.props.rotor_radius;
    let n = ctx.vehicle.rotor_count() as f64;
    let l2 = ctx.vehicle.arm_length().powi(2);
    let nu0 = ctx.vehicle.hover_induced_velocity();
    Candidate {
        kind: EffectKind::YawRateDrag,
        activity: None,
        name: "yaw-rate rotor drag".into(),
        physics: "Yawing moves each hub sideways (r x r_i); the rotors' H-force on that velocity damps yaw and couples yaw rate into Fx and Fy.",
        parameters: vec![
            parameter(
                "C_H_mub_r",
                "-",
                vec![
                    column(Axis::Fx, "-r*da", vec![term(-k * r, &[R, Da])]),
                    column(Axis::Fy, "-r*de", vec![term(-k * r, &[R, De])]),
                    column(
                        Axis::Mz,
                        "-l^2*N*r*dt",
                        vec![term(-k * r * l2 * n, &[R, Dt])],
                    ),
                ],
            ),
            parameter(
                "C_H_mub_mu0_r",
                "-",
                vec![column(
                    Axis::Mz,
                    "-nu0*l^2*N*r",
                    vec![term(-k * nu0 * l2 * n, &[R])],
                )],
            ),
        ],
    }
}

/// Hub in-plane velocity from the roll and pitch rates at hub height h (Eq. 18 with the
/// hubs at z = −h: u_i = u − q h, v_i = v + p h): the Eq. 22a–b H-force terms gain
/// q h, −p h and, through the hub-force lever arm h, roll and pitch damping −h² p, −h² q.
fn roll_pitch_rate_drag(ctx: &CandidateContext) -> Candidate {
    use Signal::*;
    let kn = ctx.k() * ctx.vehicle.rotor_count() as f64;
    let r = ctx.vehicle.props.rotor_radius;
    let h = ctx.vehicle.props.hub_height;
    let nu0 = ctx.vehicle.hover_induced_velocity();
    // Coefficient of (Fx, Fy, Mx, My) per unit of the lumped parameter and its signal.
    let columns = |scale: f64, with: &[Signal], label: &str| {
        let with_q: Vec<Signal> = [&[Q][..], with].concat();
        let with_p: Vec<Signal> = [&[P][..], with].concat();
        vec![
            column(
                Axis::Fx,
                &format!("h*q*{label}"),
                vec![term(kn * scale * h, &with_q)],
            ),
            column(
                Axis::Fy,
                &format!("-h*p*{label}"),
                vec![term(-kn * scale * h, &with_p)],
            ),
            column(
                Axis::Mx,
                &format!("-h^2*p*{label}"),
                vec![term(-kn * scale * h * h, &with_p)],
            ),
            column(
                Axis::My,
                &format!("-h^2*q*{label}"),
                vec![term(-kn * scale * h * h, &with_q)],
            ),
        ]
    };
    Candidate {
        kind: EffectKind::RollPitchRateDrag,
        activity: None,
        name: "roll/pitch-rate rotor drag".into(),
        physics: "Rolling and pitching move the hubs, which sit h above the CG, sideways at p h and q h; the rotors' H-force on that velocity couples the rates into Fx and Fy and damps roll and pitch through the same lever arm.",
        parameters: vec![
            parameter("C_H_mub_pq", "-", columns(r, &[Dt], "dt")),
            parameter("C_H_mub_mu0_pq", "-", columns(nu0, &[], "nu0")),
        ],
    }
}

/// Eq. 22 shares each lumped coefficient between the forces and the moments, the
/// moments' columns carrying the vehicle file's rotor positions and hub height. Wrong
/// lever arms, effective thrust and drag centres away from the hubs, or moment physics
/// the model lacks that correlates with a term (hub moments, flapping) break that tie.
/// One candidate per coefficient that acts on both and per moment axis: it gives that
/// axis a second value of the coefficient (the estimate is the moment value minus the
/// force value, so its t-statistic tests the tie).
fn decoupled_moments(ctx: &CandidateContext) -> Vec<Candidate> {
    let s = ctx.structure;
    let is_moment = |a: Axis| (a as usize) >= 3;
    let mut out = Vec::new();
    for p in 0..s.params.len() {
        let columns: Vec<&Column> = s.columns.iter().filter(|c| c.param == p).collect();
        if !columns.iter().any(|c| !is_moment(c.axis)) {
            continue;
        }
        let name = &s.params[p].name;
        for axis in [Axis::Mx, Axis::My, Axis::Mz] {
            let cols: Vec<Column> = columns
                .iter()
                .filter(|c| c.axis == axis)
                .map(|&c| c.clone())
                .collect();
            if cols.is_empty() {
                continue;
            }
            out.push(Candidate {
                kind: EffectKind::DecoupledMoments,
                activity: None,
                name: format!("decoupled {name} on {axis}"),
                physics: "Eq. 22 ties this coefficient's moment terms to its force terms through the vehicle file's lever arms; wrong arms, thrust and drag centres away from the hubs, or moment physics the model lacks that follows the same term give the moment a value of its own.",
                parameters: vec![parameter(
                    &format!("{name}@{}", axis.name()),
                    &s.params[p].unit,
                    cols,
                )],
            });
        }
    }
    out
}

/// In-plane velocity (u_i, v_i) of hub `i` at (x_i, y_i, −h) from body velocity and
/// rates (Eq. 18 with the hub height): u_i = u − q h − r y_i, v_i = v + p h + r x_i; as
/// (coefficient, factors) pairs of each component.
fn hub_in_plane_velocity(ctx: &CandidateContext, i: usize) -> [Vec<(f64, Signal)>; 2] {
    use Signal::*;
    let rotor = ctx.vehicle.rotors()[i];
    let h = ctx.vehicle.props.hub_height;
    [
        vec![(1.0, U), (-h, Q), (-rotor.y, R)],
        vec![(1.0, V), (h, P), (rotor.x, R)],
    ]
}

/// Blade flapping: each rotor's disc tilts away from the in-plane airflow at its hub by
/// an angle ∝ μ_i = V_i/(Ω_i R), so its thrust (∝ Ω_i²) gains an in-plane component, and
/// a hingeless hub a moment, ∝ Ω_i V_i. Acting above the CG both give M_x = −a Σ Ω_i v_i
/// and M_y = a Σ Ω_i u_i, the same sign for either spin direction. (The spin-weighted
/// lateral part, Σ σ_i Ω_i u_i on M_x, is Eq. 22's moment-only C_R_mub term.)
fn rotor_flapping(ctx: &CandidateContext) -> Candidate {
    let n = ctx.vehicle.rotor_count();
    let axis_terms = |component: usize, sign: f64| -> Vec<Term> {
        (0..n)
            .flat_map(|i| {
                let (w, _, _) = rotor_signals(i);
                hub_in_plane_velocity(ctx, i)[component]
                    .clone()
                    .into_iter()
                    .filter(|(c, _)| *c != 0.0)
                    .map(move |(c, s)| term(sign * c, &[s, w]))
            })
            .collect()
    };
    Candidate {
        kind: EffectKind::RotorFlapping,
        activity: None,
        name: "rotor flapping moment".into(),
        physics: "Each rotor's disc flaps back from the in-plane airflow at its hub (angle proportional to the advance ratio), tilting its thrust and loading a stiff hub: a rolling moment against the hub's sideways speed and a pitching moment against its forward speed, proportional to rotor speed times hub speed.",
        parameters: vec![parameter(
            "flapping_moment",
            "N s^2/rad",
            vec![
                column(Axis::Mx, "-Sum Omega_i v_i", axis_terms(1, -1.0)),
                column(Axis::My, "Sum Omega_i u_i", axis_terms(0, 1.0)),
            ],
        )],
    }
}

/// Roll and pitch damping with a coefficient of its own: rotor i's thrust changes by
/// c Ω_i w_i with its hub's vertical velocity w_i = p y_i − q x_i (Eq. 18), so
/// M_x = −c (p Σ y_i² Ω_i − q Σ x_i y_i Ω_i), M_y = −c (q Σ x_i² Ω_i − p Σ x_i y_i Ω_i).
/// Eq. 22 has these terms only inside the C_T_muw column, tied to w δa and to F_z.
fn rotor_rate_damping() -> Candidate {
    use Signal::*;
    Candidate {
        kind: EffectKind::RotorRateDamping,
        activity: None,
        name: "rotor rate damping".into(),
        physics: "Rolling and pitching move each hub up or down (w_i = p y_i - q x_i), changing its rotor's angle of attack and thrust in proportion to rotor speed: a damping moment, here with its own coefficient instead of the one Eq. 22 shares with the vertical force.",
        parameters: vec![parameter(
            "rate_damping",
            "N s^2/(rad m)",
            vec![
                column(
                    Axis::Mx,
                    "-(p*SumY2Omega - q*SumXYOmega)",
                    vec![term(-1.0, &[P, SumY2Omega]), term(1.0, &[Q, SumXYOmega])],
                ),
                column(
                    Axis::My,
                    "-(q*SumX2Omega - p*SumXYOmega)",
                    vec![term(-1.0, &[Q, SumX2Omega]), term(1.0, &[P, SumXYOmega])],
                ),
            ],
        )],
    }
}

/// Second-order inflow: ΔT_i = ρπR² (C_T_muvw V_h w_i + C_T_w2 w_i²), w_i = w + p y_i −
/// q x_i the hub's axial velocity (Eq. 18), so F_z = −Σ ΔT_i, M_x = −Σ y_i ΔT_i,
/// M_y = Σ x_i ΔT_i. Eq. 6's inflow plane ν = ν0 + C_νμ V_h + C_νw w is first order; in
/// momentum theory ν = ν0 F(V_h/ν0, w/ν0) with ν0 ∝ Ω, so the inflow's second-order terms
/// enter the thrust −ρπR² R Ω ν as Ω-free V_h w, w² and V_h² terms. Eq. 22 keeps V_h²
/// (C_T_mu2); these are the other two. V_h w is the growth of the heave damping with
/// forward speed (the induced flow follows the climb speed less in forward flight).
fn second_order_inflow(ctx: &CandidateContext) -> Candidate {
    use Signal::*;
    let k = ctx.k();
    let rotors = ctx.vehicle.rotors();
    let (xs, ys): (Vec<f64>, Vec<f64>) = rotors.iter().map(|r| (r.x, r.y)).unzip();
    // Σ_i lever_i g_i as terms, g_i a polynomial in the hub velocity given as
    // (factors, per-rotor coefficient) pairs.
    let axis_terms = |monomials: &[(Vec<Signal>, Vec<f64>)]| {
        THRUST_LOADS
            .iter()
            .map(|&(axis, lever, label)| {
                let arms: Vec<f64> = rotors.iter().map(lever).collect();
                let scale: f64 = arms.iter().map(|l| l.abs()).sum();
                let terms: Vec<Term> = monomials
                    .iter()
                    .filter_map(|(factors, c)| {
                        let sum: f64 = arms.iter().zip(c).map(|(l, c)| l * c).sum();
                        (sum.abs() > 1e-12 * scale).then(|| term(k * sum, factors))
                    })
                    .collect();
                (axis, label, terms)
            })
            .filter(|(_, _, t)| !t.is_empty())
            .collect::<Vec<_>>()
    };
    let one = vec![1.0; rotors.len()];
    let neg_x: Vec<f64> = xs.iter().map(|x| -x).collect();
    // w_i V_h = (w + p y_i − q x_i) V_h.
    let cross = axis_terms(&[
        (vec![W, Vh], one.clone()),
        (vec![P, Vh], ys.clone()),
        (vec![Q, Vh], neg_x.clone()),
    ]);
    // w_i² = w² + 2 w p y_i − 2 w q x_i + p² y_i² − 2 p q x_i y_i + q² x_i².
    let prod = |a: &[f64], b: &[f64], f: f64| a.iter().zip(b).map(|(a, b)| f * a * b).collect();
    let square = axis_terms(&[
        (vec![W, W], one.clone()),
        (vec![W, P], prod(&one, &ys, 2.0)),
        (vec![W, Q], prod(&one, &neg_x, 2.0)),
        (vec![P, P], prod(&ys, &ys, 1.0)),
        (vec![P, Q], prod(&ys, &neg_x, 2.0)),
        (vec![Q, Q], prod(&xs, &xs, 1.0)),
    ]);
    let columns = |list: Vec<(Axis, &str, Vec<Term>)>, what: &str| {
        list.into_iter()
            .map(|(axis, label, terms)| column(axis, &format!("{label}{what}"), terms))
            .collect()
    };
    Candidate {
        kind: EffectKind::SecondOrderInflow,
        activity: None,
        name: "second-order inflow".into(),
        physics: "In forward flight a rotor's induced flow follows the climb speed less than in hover, so its thrust changes more with axial speed as in-plane speed grows, and in hover the inflow bends with the axial speed: the V_h w and w^2 terms of momentum-theory inflow that the first-order inflow plane of Eq. 6 drops.",
        parameters: vec![
            parameter("C_T_muvw", "-", columns(cross, "Vh*w_i")),
            parameter("C_T_w2", "-", columns(square, "w_i^2")),
        ],
    }
}

/// Thrust responding to rotor acceleration: ΔT_i = c Ω̇_i (the induced flow lags a
/// change of rotor speed, or the logged speed lags the true one through a first-order
/// filter), so F_z = −c Σ Ω̇_i, M_x = −c Σ y_i Ω̇_i, M_y = c Σ x_i Ω̇_i.
fn rotor_acceleration_thrust(ctx: &CandidateContext) -> Candidate {
    let n = ctx.vehicle.rotor_count();
    let rotors = ctx.vehicle.rotors();
    let axis_terms = |weight: &dyn Fn(usize) -> f64| -> Vec<Term> {
        (0..n)
            .filter(|&i| weight(i) != 0.0)
            .map(|i| term(weight(i), &[rotor_signals(i).2]))
            .collect()
    };
    Candidate {
        kind: EffectKind::RotorAccelerationThrust,
        activity: None,
        name: "thrust from rotor acceleration".into(),
        physics: "When a rotor speeds up, its thrust changes in proportion to the rotor acceleration as well as the speed: the induced flow takes time to build (dynamic inflow), or the logged speed lags the true one through a filter.",
        parameters: vec![parameter(
            "thrust_per_rotor_acceleration",
            "N s^2/rad",
            THRUST_LOADS
                .iter()
                .map(|&(axis, lever, label)| {
                    column(
                        axis,
                        &format!("{label}dOmega_i"),
                        axis_terms(&|i| lever(&rotors[i])),
                    )
                })
                .collect(),
        )],
    }
}
