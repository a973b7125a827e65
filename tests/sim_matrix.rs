//! Test matrices: Latin-hypercube stratification, ranges scaled from Table 1, and the
//! ground-effect height column.

use std::path::Path;

use mrsysid::internals::sim::test_matrix::{Design, Ranges, latin_hypercube, sweep};
use mrsysid::internals::sim::{Effect, Effects, RotorFile, TruthModel};
use mrsysid::vehicle::Vehicle;
use rand::SeedableRng;
use rand::rngs::StdRng;

fn model(name: &str, effects: &[&str]) -> TruthModel {
    let v = Vehicle::from_toml_file(Path::new(&format!("data/vehicles/{name}.toml"))).unwrap();
    let e = effects
        .iter()
        .map(|s| s.parse::<Effect>().unwrap())
        .collect();
    TruthModel::new(&v, &RotorFile::default(), Effects::new(e, &v).unwrap()).unwrap()
}

#[test]
fn latin_hypercube_puts_one_point_in_every_stratum_of_every_variable() {
    let (n, d) = (50, 7);
    let x = latin_hypercube(&mut StdRng::seed_from_u64(3), n, d);
    for j in 0..d {
        let mut seen = vec![false; n];
        for k in 0..n {
            let s = (x[k * d + j] * n as f64).floor() as usize;
            assert!(!seen[s], "variable {j}: stratum {s} twice");
            seen[s] = true;
        }
    }
}

/// quad_x has ℓ = 0.2249 m ≈ ℓ_ref: Table 1 in SI units (× the scale 0.9997), |u|, |v| ≤ 18 m/s, w ∈ [−9, 1.5]
/// (0.45 ν0 = 4.4 m/s is not binding), |p|, |q| ≤ 12, |r| ≤ 6, Ω ∈ hover × [0.6, 1.4].
/// The hexarotor (ℓ = 0.35 m) gets speeds × √(0.35/0.225) = 1.247.
#[test]
fn ranges_follow_table_1_scaled_and_samples_stay_inside() {
    let m = model("quad_x", &[]);
    let r = Ranges::scaled_to(&m);
    let s = (m.vehicle.arm_length() / 0.225).sqrt();
    assert!((s - 0.9997).abs() < 1e-4);
    assert!((r.velocity[0].1 - 18.0 * s).abs() < 1e-12);
    assert!((r.velocity[2].0 + 9.0 * s).abs() < 1e-12 && (r.velocity[2].1 - 1.5 * s).abs() < 1e-12);
    assert!((r.rates[0].1 - 12.0 / s).abs() < 1e-12 && (r.rates[2].1 - 6.0 / s).abs() < 1e-12);
    assert!((r.omega.1 / m.hover_omega - 1.4).abs() < 1e-12);
    let hexa = Ranges::scaled_to(&model("hexa_x", &[]));
    assert!((hexa.velocity[0].1 - 18.0 * (0.35f64 / 0.225).sqrt()).abs() < 1e-9);
    for design in [Design::Uniform, Design::LatinHypercube] {
        let c = sweep(&m, &r, design, 300, 8);
        assert_eq!(c.len(), 300);
        for k in 0..3 {
            assert!(
                c.velocity[k]
                    .iter()
                    .all(|v| (r.velocity[k].0..=r.velocity[k].1).contains(v))
            );
            assert!(
                c.rates[k]
                    .iter()
                    .all(|v| (r.rates[k].0..=r.rates[k].1).contains(v))
            );
        }
        assert!(
            c.omega
                .iter()
                .flatten()
                .all(|w| (r.omega.0..=r.omega.1).contains(w))
        );
        assert!(c.wrench.iter().flatten().all(|f| f.is_finite()));
        assert_eq!(c.height, None);
    }
}

/// With ground effect on, the sweep writes `height` with hub heights in [R/2, 4R].
#[test]
fn ground_effect_sweep_samples_heights() {
    let m = model("quad_x", &["ground_effect"]);
    let r = Ranges::scaled_to(&m);
    let c = sweep(&m, &r, Design::LatinHypercube, 100, 1);
    let (rad, h) = (m.vehicle.props.rotor_radius, m.vehicle.props.hub_height);
    let height = c.height.expect("ground effect samples heights");
    assert_eq!(height.len(), 100);
    assert!(
        height
            .iter()
            .all(|z| (0.5 * rad - h..=4.0 * rad - h).contains(z))
    );
}
