//! What the library needs to build candidates, and the shared pieces of their columns.
//!
//! Columns that scale a rotor's thrust or torque use the per-rotor thrust T̂_i and
//! torque Q̂_i of the fitted base model (the Eq. 22 terms of one rotor with the base
//! estimates θ̂), so a parameter reads directly as a fraction ("rotor 3 thrust −7.9 %")
//! or a physical quantity (m, m², s).

use crate::model::{Column, ModelStructure, ParamId, Signal, Term, term};
use crate::sample::Axis;
use crate::vehicle::{Rotor, Vehicle};

/// One load of a thrust change: (axis, rotor i's signed lever arm in m (1 for the force),
/// label prefix of the sum).
pub(super) type ThrustLoad = (Axis, fn(&Rotor) -> f64, &'static str);

/// The loads of a change ΔT_i of rotor i's thrust (along −z_B, Eq. 13–15):
/// F_z = −Σ ΔT_i, M_x = −Σ y_i ΔT_i, M_y = Σ x_i ΔT_i.
pub(super) const THRUST_LOADS: [ThrustLoad; 3] = [
    (Axis::Fz, |_| -1.0, "-Sum "),
    (Axis::Mx, |r| -r.y, "-Sum y_i*"),
    (Axis::My, |r| r.x, "Sum x_i*"),
];

/// What the library needs to know to build candidates.
pub struct CandidateContext<'a> {
    /// The vehicle.
    pub vehicle: &'a Vehicle,
    /// The base (Eq. 22) structure.
    pub structure: &'a ModelStructure,
    /// Base estimates, one per `structure.params`.
    pub theta: &'a [f64],
    /// Each force axis's own OLS estimates (step 1 of the base fit), one per
    /// `structure.columns` (0 where that fit dropped the column; moment columns unused):
    /// the force on a lever arm (`CandidateContext::lever_force`).
    pub force_theta: &'a [f64],
    /// The data log CG height (ground-effect candidate).
    pub has_height: bool,
    /// The data has rotor accelerations (delay candidate).
    pub has_omega_dot: bool,
    /// The data has rates of the rotor accelerations (the delay's reaction-torque term).
    pub has_omega_ddot: bool,
    /// The data has the attitude (steady-wind candidate).
    pub has_attitude: bool,
    /// The data are time series with the slow rotor thrusts derived (trim-moment
    /// candidates).
    pub has_slow_thrust: bool,
    /// Thrust per Ω² of one rotor that carries the vehicle's weight on average over the
    /// fit data, N s²/rad² ([`hover_thrust_coefficient`]); `None` when unknown.
    pub hover_thrust_coefficient: Option<f64>,
}

/// m g / mean(Σ Ω_i²) over the samples of `chunks`, N s²/rad²: the thrust coefficient
/// of a rotor if the rotors carried the weight on every sample (on average over a
/// flight they do). A scale for candidates whose parameter reads as a fraction of a
/// control moment, independent of the base fit (whose Ĉ_T0 can take any sign when other
/// thrust terms share its work). `None` without samples or rotor speed.
pub fn hover_thrust_coefficient(
    vehicle: &Vehicle,
    chunks: &[&crate::sample::SampleChunk],
) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for c in chunks {
        for k in 0..c.len() {
            sum += c.omega.iter().map(|w| w[k] * w[k]).sum::<f64>();
            n += 1;
        }
    }
    let mean = sum / n as f64;
    (n > 0 && mean > 0.0).then(|| vehicle.props.mass * crate::vehicle::STANDARD_GRAVITY / mean)
}

impl CandidateContext<'_> {
    /// The base estimate of parameter `name`; 0 when the structure lacks it (a variant
    /// without that term, e.g. no linear V_h terms: its contribution is then zero).
    pub(super) fn theta(&self, name: &str) -> f64 {
        self.structure
            .param_id(name)
            .map_or(0.0, |p| self.theta[p.index()])
    }

    /// The estimate of thrust parameter `name` in F_z's own OLS ([`Self::force_theta`]);
    /// the joint one where F_z has no column of it. The thrust a rotor loses or gains
    /// (a weak rotor, a wake, the ground) is the thrust F_z identifies: a lost thrust
    /// distorts the moments, which share the thrust coefficients in the joint fit.
    pub(super) fn thrust_theta(&self, name: &str) -> f64 {
        let Some(p) = self.structure.param_id(name) else {
            return 0.0;
        };
        self.structure
            .axis_columns(Axis::Fz)
            .find(|&j| self.structure.columns[j].param == p)
            .map_or(self.theta[p.index()], |j| self.force_theta[j])
    }

    /// ρπR², kg/m.
    pub(super) fn k(&self) -> f64 {
        let p = &self.vehicle.props;
        p.air_density * std::f64::consts::PI * p.rotor_radius.powi(2)
    }

    /// Terms of rotor `i`'s thrust T̂_i (N) with F_z's own estimates
    /// ([`Self::thrust_theta`]), each multiplied by `extra` signals and `scale`. With
    /// `rate`, the terms of dT̂_i/dΩ_i · Ω̇_i (N/s), with the joint estimates.
    pub(super) fn rotor_thrust(
        &self,
        i: usize,
        extra: &[Signal],
        scale: f64,
        rate: bool,
    ) -> Vec<Term> {
        use Signal::*;
        let r = self.vehicle.props.rotor_radius;
        let nu0 = self.vehicle.hover_induced_velocity();
        let rotor = self.vehicle.rotors()[i];
        let (w, w2, wd) = rotor_signals(i);
        let k = self.k() * scale;
        let mut t = if rate {
            // d/dt of the Ω-dependent terms: 2Ω Ω̇ and Ω̇, with the joint estimates: F_z
            // alone splits the thrust among its terms in Ω² and Ω (collinear there) at
            // will, and the slope dT/dΩ depends on that split.
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
                term(k * self.thrust_theta("C_T0") * r * r, &[w2]),
                term(k * self.thrust_theta("C_T_mu2"), &[Vh, Vh]),
                term(-k * self.thrust_theta("C_T_mu0") * r * nu0, &[w]),
                term(-k * self.thrust_theta("C_T_mu") * r, &[Vh, w]),
                term(k * self.thrust_theta("C_T_muw") * r, &[W, w]),
                term(k * self.thrust_theta("C_T_muw") * r * rotor.y, &[P, w]),
                term(-k * self.thrust_theta("C_T_muw") * r * rotor.x, &[Q, w]),
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
    pub(super) fn rotor_in_plane_force(&self, i: usize, along_x: bool, scale: f64) -> Vec<Term> {
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
    pub(super) fn rotor_torque(&self, i: usize, scale: f64, rate: bool) -> Vec<Term> {
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
    pub(super) fn thrust_change(
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

    /// Columns of a thrust change ΔT_i = ρπR² Σ_m c_m,i Π factors_m per unit of its
    /// parameter, a polynomial in signals whose coefficients c_m,i differ by rotor
    /// (`monomials`: factors and one coefficient per rotor), summed over the layout with
    /// each load's lever arm ([`THRUST_LOADS`]) and labelled `<sum><what>`. A sum below
    /// 1e-12 of the lever arms' is a symmetric layout's zero, rounded, and is dropped,
    /// and so is a load left without terms.
    pub(super) fn thrust_polynomial(
        &self,
        what: &str,
        monomials: &[(Vec<Signal>, Vec<f64>)],
    ) -> Vec<Column> {
        let rotors = self.vehicle.rotors();
        THRUST_LOADS
            .iter()
            .filter_map(|&(axis, lever, label)| {
                let arms: Vec<f64> = rotors.iter().map(lever).collect();
                let scale: f64 = arms.iter().map(|l| l.abs()).sum();
                let terms: Vec<Term> = monomials
                    .iter()
                    .filter_map(|(factors, c)| {
                        let sum: f64 = arms.iter().zip(c).map(|(l, c)| l * c).sum();
                        (sum.abs() > 1e-12 * scale).then(|| term(self.k() * sum, factors))
                    })
                    .collect();
                (!terms.is_empty()).then(|| column(axis, &format!("{label}{what}"), terms))
            })
            .collect()
    }

    /// ∂(model load of `axis`)/∂(body velocity component `k`: u, v, w) from the base
    /// estimates, as terms (u, v, w and V_h factors differentiated; ∂V_h/∂u = u/V_h).
    pub(super) fn model_velocity_gradient(&self, axis: Axis, k: usize) -> Vec<Term> {
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
    pub(super) fn model_force(&self, axis: Axis, scale: f64) -> Vec<Term> {
        self.force_terms(axis, scale, |j| {
            self.theta[self.structure.columns[j].param.index()]
        })
    }

    /// Force of axis `axis` (Fx, Fy or Fz) that acts on a lever arm, as terms times
    /// `scale`: the model force with that axis's own OLS estimates, not the joint ones.
    /// An offset lever arm distorts the moments, and the joint fit shares the thrust
    /// coefficients between F_z and the moments (C_T0 on δ²t, δ²a, δ²e), so there the
    /// joint F̂ misses the force the offset multiplies (RotorPy's hummingbird with a
    /// 17 mm CG offset: joint Ĉ_T0 −0.0135 against 0.0139 without it, F_z R² 19 %
    /// against 87 %), and an offset fitted on it comes out 7.6 % short.
    pub(super) fn lever_force(&self, axis: Axis, scale: f64) -> Vec<Term> {
        self.force_terms(axis, scale, |j| self.force_theta[j])
    }

    fn force_terms(&self, axis: Axis, scale: f64, estimate: impl Fn(usize) -> f64) -> Vec<Term> {
        self.structure
            .axis_columns(axis)
            .flat_map(|j| {
                let c = &self.structure.columns[j];
                let th = estimate(j);
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
pub(super) fn rotor_signals(i: usize) -> (Signal, Signal, Signal) {
    let i = u8::try_from(i).expect("rotor index below 256");
    (
        Signal::RotorSpeed(i),
        Signal::RotorSpeedSquared(i),
        Signal::RotorAcceleration(i),
    )
}

/// A column of `terms` on `axis` (its parameter is set when the candidate is added to a
/// model).
pub(super) fn column(axis: Axis, label: &str, terms: Vec<Term>) -> Column {
    Column {
        axis,
        param: ParamId::default(),
        label: label.to_string(),
        terms,
    }
}
