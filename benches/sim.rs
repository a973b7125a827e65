//! Truth-simulator speed: one blade-element rotor with the coupled momentum inflow (cold
//! and warm start), the whole-vehicle wrench, a 2000-point sweep and a 2 s flight at a
//! 500 Hz RK4 step. The 100 000-point sweep and the 60 s flight of the issue scale
//! linearly from the last two (× 50 and × 30).

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use mrsysid::internals::sim::blade_element::RotorKinematics;
use mrsysid::internals::sim::flight::{FlightConfig, fly};
use mrsysid::internals::sim::inflow::{InflowModel, InflowState};
use mrsysid::internals::sim::test_matrix::{Design, Ranges, sweep};
use mrsysid::internals::sim::{Effects, RotorFile, TruthInput, TruthModel};
use mrsysid::vehicle::Vehicle;

fn model() -> TruthModel {
    let v = Vehicle::from_toml_file(Path::new("data/vehicles/quad_x.toml")).unwrap();
    TruthModel::new(&v, &RotorFile::default(), Effects::none()).unwrap()
}

fn rotor(c: &mut Criterion) {
    let m = model();
    let kin = RotorKinematics {
        omega: m.hover_omega * 1.1,
        spin: 1.0,
        hub_velocity: [10.0, -4.0, -2.0],
        body_rates: [1.0, -2.0, 0.5],
    };
    c.bench_function("rotor_loads_momentum_cold", |b| {
        b.iter(|| {
            let mut st = InflowState::default();
            black_box(
                m.rotor
                    .loads(black_box(&kin), &InflowModel::Momentum, &mut st),
            )
        })
    });
    let mut warm = InflowState::default();
    m.rotor.loads(&kin, &InflowModel::Momentum, &mut warm);
    c.bench_function("rotor_loads_momentum_warm", |b| {
        b.iter(|| {
            let mut st = warm;
            black_box(
                m.rotor
                    .loads(black_box(&kin), &InflowModel::Momentum, &mut st),
            )
        })
    });
    let omega = [
        m.hover_omega * 1.1,
        m.hover_omega * 0.9,
        m.hover_omega,
        m.hover_omega * 1.2,
    ];
    let omega_dot = [100.0, -200.0, 0.0, 50.0];
    c.bench_function("vehicle_wrench_quad", |b| {
        b.iter(|| {
            let mut st = m.inflow_states();
            black_box(m.wrench(
                &TruthInput {
                    velocity: [10.0, -4.0, -2.0],
                    rates: [1.0, -2.0, 0.5],
                    omega: &omega,
                    omega_dot: &omega_dot,
                    height: None,
                    down_row: None,
                },
                &mut st,
            ))
        })
    });
}

fn sweep_and_flight(c: &mut Criterion) {
    let m = model();
    let ranges = Ranges::scaled_to(&m);
    let mut g = c.benchmark_group("end_to_end");
    g.sample_size(10);
    g.bench_function("sweep_2000_points", |b| {
        b.iter(|| black_box(sweep(&m, &ranges, Design::LatinHypercube, 2000, 1)))
    });
    let cfg = FlightConfig {
        duration: 2.0,
        ..Default::default()
    };
    g.bench_function("flight_2s_500Hz", |b| {
        b.iter(|| black_box(fly(&m, &cfg, 1).unwrap()))
    });
    g.finish();
}

// Plots off: the crate enables plotters' bundled-font backend (`ab_glyph`), under which
// criterion's own plots find no font; the numbers are what matter.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = rotor, sweep_and_flight
}
criterion_main!(benches);
