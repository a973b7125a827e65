//! Blade-element rotor against the seed's closed form (Eq. 5 with the plane inflow of
//! Eq. 7, summed over the airframe by `airframe::closed_form_wrench`), and its departure
//! from it with the full momentum inflow.

use std::path::Path;

use mrsysid::internals::airframe::closed_form_wrench;
use mrsysid::internals::rotor::BladeConstants;
use mrsysid::internals::sim::blade_element::{BladeOverrides, RotorKinematics};
use mrsysid::internals::sim::inflow::{InflowModel, InflowState, fit_plane};
use mrsysid::internals::sim::test_matrix::{Design, Ranges, sweep};
use mrsysid::internals::sim::{Effects, RotorFile, TruthInput, TruthModel};
use mrsysid::vehicle::Vehicle;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

fn quad_x() -> Vehicle {
    Vehicle::from_toml_file(Path::new("data/vehicles/quad_x.toml")).unwrap()
}

/// The blade in the closed form's own terms: no root cutout, constant drag coefficient,
/// no stall, no airframe drag; a fine quadrature so integration error is negligible.
fn closed_form_like_model(v: &Vehicle) -> (TruthModel, BladeConstants) {
    let file = RotorFile {
        blade: BladeOverrides {
            root_cutout: Some(0.0),
            cd2: Some(0.0),
            stall_angle: Some(0.7),
            ..Default::default()
        },
        linear_drag: Some([0.0; 3]),
        radial_stations: Some(12),
        azimuth_stations: Some(32),
        ..Default::default()
    };
    let mut m = TruthModel::new(v, &file, Effects::none()).unwrap();
    let nu0 = v.hover_induced_velocity();
    let (c_nu_mu, c_nu_w) = fit_plane(nu0, 18.0, -9.0, 1.5);
    m.inflow = InflowModel::Plane {
        nu0,
        c_nu_mu,
        c_nu_w,
    };
    let tip = m.hover_omega * v.props.rotor_radius;
    let bc = m.rotor.blade.blade_constants(nu0 / tip, c_nu_mu, c_nu_w);
    (m, bc)
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// Per rotor, in the rotor frame of seed Fig. 1 (T = −F_z, H = −F_x, S = F_y), at advance
/// ratios μ ≤ 0.03 and plane inflow. Tolerances are the size of the small-angle
/// approximation Eq. 5 makes (φ ≈ U_P/U_T, cos φ ≈ 1) at this rotor's hover inflow ratio
/// λ ≈ 0.07: O(λ²) ≈ 0.5 % spread over the span gives ~1.2 % on T and Q; H and S carry a
/// θλμ term weighted evenly along the span, so the root region (φ → 90° for r̄ < λ)
/// moves them by ~8 %; we assert 2 % and 10 %.
///
/// Finding: the blade-element hub rolling and pitching moments have the magnitude of
/// Eq. 5d–e but the opposite sign from Eq. 11 with the σ convention of Eq. 12 (σ = +1:
/// angular velocity along +b₃). Physically, for σ = +1 and u > 0 the advancing blade is on
/// the left, its extra lift rolls the vehicle right (M_x > 0); Eq. 11 gives −σℛ < 0.
#[test]
fn per_rotor_loads_agree_with_eq5_at_small_advance_ratio() {
    let v = quad_x();
    let (m, bc) = closed_form_like_model(&v);
    let nu0 = v.hover_induced_velocity();
    let mut rng = StdRng::seed_from_u64(5);
    let (mut err, mut refv) = (vec![Vec::new(); 6], vec![Vec::new(); 6]);
    for k in 0..200 {
        let spin = if k % 2 == 0 { 1.0 } else { -1.0 };
        let omega = m.hover_omega * rng.random_range(0.8..1.2);
        let mu_max = 0.03 * omega * v.props.rotor_radius;
        let vel = [
            rng.random_range(-mu_max..mu_max),
            rng.random_range(-mu_max..mu_max),
            rng.random_range(-1.0..1.0),
        ];
        let kin = RotorKinematics {
            omega,
            spin,
            hub_velocity: vel,
            body_rates: [0.0; 3],
        };
        let b = m.rotor.loads(&kin, &m.inflow, &mut InflowState::default());
        let c = bc.loads(v.props.air_density, v.props.rotor_radius, omega, vel, nu0);
        let pairs = [
            (-b.force[2], c.thrust),
            (-b.force[0], c.hub_force),
            (b.force[1], c.side_force),
            (spin * b.moment[0], c.rolling_moment),
            (-spin * b.moment[1], c.pitching_moment),
            (-spin * b.moment[2], c.torque),
        ];
        for (j, (bem, cf)) in pairs.into_iter().enumerate() {
            err[j].push(bem - cf);
            refv[j].push(cf);
        }
    }
    let tol = [0.02, 0.10, 0.10, 0.02, 0.02, 0.02];
    let names = ["T", "H", "S", "R (sign reversed)", "P (sign reversed)", "Q"];
    for j in 0..6 {
        let rel = rms(&err[j]) / rms(&refv[j]);
        println!("{}: relative RMS difference {rel:.4}", names[j]);
        assert!(rel < tol[j], "{}: {rel} >= {}", names[j], tol[j]);
    }
}

/// Airframe sum against `closed_form_wrench` (which transmits the hub rolling/pitching
/// moments with the physical sign found above, σ(ℛ, −𝒫)), at small advance ratios
/// and body rates (|p|, |q| ≤ 0.5 rad/s, |r| ≤ 0.3 rad/s, so ω × r along the blade, which
/// Eq. 5 lacks, stays below 0.3 % of the tip speed). Tolerances (RMS difference over RMS
/// of the axis): F_z and the moments 2 % (small-angle error of T and Q, as above), F_x and
/// F_y 10 % (H, S as above).
#[test]
fn airframe_wrench_agrees_with_closed_form_sum() {
    let v = quad_x();
    let (m, bc) = closed_form_like_model(&v);
    let mut rng = StdRng::seed_from_u64(7);
    let (mut err, mut refv) = (vec![Vec::new(); 6], vec![Vec::new(); 6]);
    let mut inflow = m.inflow_states();
    for _ in 0..200 {
        let omega: Vec<f64> = (0..4)
            .map(|_| m.hover_omega * rng.random_range(0.8..1.2))
            .collect();
        let omega_dot: Vec<f64> = (0..4).map(|_| rng.random_range(-2000.0..2000.0)).collect();
        let vmax = 0.03 * m.hover_omega * 0.8 * v.props.rotor_radius;
        let vel = [
            rng.random_range(-vmax..vmax),
            rng.random_range(-vmax..vmax),
            rng.random_range(-1.0..1.0),
        ];
        let rates = [
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.3..0.3),
        ];
        let bem = m.wrench(
            &TruthInput {
                velocity: vel,
                rates,
                omega: &omega,
                omega_dot: &omega_dot,
                height: None,
                down_row: None,
            },
            &mut inflow,
        );
        let cf = closed_form_wrench(&v, &bc, vel, rates, &omega, &omega_dot);
        for j in 0..6 {
            err[j].push(bem[j] - cf[j]);
            refv[j].push(cf[j]);
        }
    }
    let tol = [0.10, 0.10, 0.02, 0.02, 0.02, 0.02];
    for j in 0..6 {
        let rel = rms(&err[j]) / rms(&refv[j]);
        println!("axis {j}: relative RMS difference {rel:.4}");
        assert!(rel < tol[j], "axis {j}: {rel} >= {}", tol[j]);
    }
}

/// With the full coupled momentum inflow, root cutout, drag polar and stall (the default
/// truth rotor), over the scaled Table 1 ranges, the wrench departs from the closed form
/// (= Eq. 22, proven exact in tests/eq22_exactness.rs) with the best plane fitted to the
/// momentum surface. "Measurably": the NRMSE (RMS difference over the axis range) of F_z
/// and of the in-plane forces exceeds 1 %, far above the 1e-6 the 6-digit CSV resolves.
/// It stays the same physics: below 30 %.
#[test]
fn full_inflow_departs_from_eq22_measurably() {
    let v = quad_x();
    let m = TruthModel::new(&v, &RotorFile::default(), Effects::none()).unwrap();
    let nu0 = v.hover_induced_velocity();
    let tip = m.hover_omega * v.props.rotor_radius;
    let ranges = Ranges::scaled_to(&m);
    let (c_nu_mu, c_nu_w) = fit_plane(
        nu0,
        ranges.velocity[0].1,
        ranges.velocity[2].0,
        ranges.velocity[2].1,
    );
    let bc = m.rotor.blade.blade_constants(nu0 / tip, c_nu_mu, c_nu_w);
    let chunk = sweep(&m, &ranges, Design::LatinHypercube, 400, 3);
    let mut nrmse = [0.0; 6];
    for (j, out) in nrmse.iter_mut().enumerate() {
        let mut diff = Vec::new();
        for k in 0..chunk.len() {
            let s = chunk.sample(k);
            let cf = closed_form_wrench(&v, &bc, s.velocity, s.rates, &s.omega, &s.omega_dot);
            diff.push(s.wrench[j] - cf[j]);
        }
        let col = &chunk.wrench[j];
        let range = col.iter().cloned().fold(f64::MIN, f64::max)
            - col.iter().cloned().fold(f64::MAX, f64::min);
        *out = rms(&diff) / range;
    }
    println!("NRMSE of Eq. 22 against the truth per axis: {nrmse:?}");
    for j in [0, 1, 2] {
        assert!(nrmse[j] > 0.01 && nrmse[j] < 0.3, "axis {j}: {}", nrmse[j]);
    }
}

/// The coupled inflow satisfies Glauert's relation ν √(V_h² + (ν − w)²) = T/(2ρA) with the
/// blade-element thrust at the solution, to 1e-8 relative (iteration tolerance 1e-10 on ν).
#[test]
fn coupled_inflow_satisfies_momentum_with_blade_thrust() {
    let v = quad_x();
    let m = TruthModel::new(&v, &RotorFile::default(), Effects::none()).unwrap();
    let mut rng = StdRng::seed_from_u64(11);
    let area = m.rotor.disk_area();
    for _ in 0..100 {
        let kin = RotorKinematics {
            omega: m.hover_omega * rng.random_range(0.6..1.4),
            spin: 1.0,
            hub_velocity: [
                rng.random_range(-18.0..18.0),
                rng.random_range(-18.0..18.0),
                rng.random_range(-9.0..1.5),
            ],
            body_rates: [0.0; 3],
        };
        let l = m
            .rotor
            .loads(&kin, &InflowModel::Momentum, &mut InflowState::default());
        let [vx, vy, w] = kin.hub_velocity;
        let nu = l.induced_velocity;
        let lhs = nu * (vx * vx + vy * vy + (nu - w) * (nu - w)).sqrt();
        let rhs = -l.force[2] / (2.0 * v.props.air_density * area);
        assert!(
            (lhs - rhs).abs() < 1e-8 * rhs.abs().max(1.0),
            "{lhs} vs {rhs}"
        );
    }
}
