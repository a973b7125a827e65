//! The README's diagnosis table over many seeds: every case of the table (one hidden
//! effect of the truth simulator, or none) run at `SEEDS` seeds, printing per case how
//! often the effect was named first and what else was added.
//!
//! ```text
//! cargo run --release --example diagnosis_seeds [-- SEEDS [CASE-FILTER]]
//! cargo run --release --example diagnosis_seeds -- 10 '30 s flight, $'   # clean flight only
//! ```
//!
//! Sweeps are diagnosed with [`diagnose_chunks`] (3000 Latin-hypercube points, the last
//! 600 held out); flights (30–60 s at 100 Hz, sensor noise) through the builder, with the
//! default cross-validation on contiguous blocks and the coloured-residual correction.

use std::path::Path;

use mrsysid::Identification;
use mrsysid::SampleChunk;
use mrsysid::internals::diagnose::{DiagnoseOptions, Diagnosis, diagnose_chunks};
use mrsysid::internals::estimate::FitOptions;
use mrsysid::internals::sim::flight::{FlightConfig, fly};
use mrsysid::internals::sim::test_matrix::{Design, Ranges, sweep};
use mrsysid::internals::sim::{Effect, Effects, RotorFile, TruthModel};
use mrsysid::vehicle::Vehicle;
use mrsysid::{ModelOptions, ModelStructure};

/// What a case runs on.
#[derive(Clone, Copy)]
enum Data {
    Sweep,
    /// Flight of this many seconds; `true` for an IMU-only log.
    Flight(f64, bool),
    /// Flight of this many seconds, the first ones low (rotor plane 1–4 diameters up).
    NearGround(f64, f64),
}

/// One row of the table: the effects simulated and the name the diagnosis must give (or
/// any of several, separated by " | ").
struct Case {
    data: Data,
    effects: &'static [&'static str],
    expected: Option<&'static str>,
}

const CASES: &[Case] = &[
    Case {
        data: Data::Sweep,
        effects: &["weak_rotor=3,0.9"],
        expected: Some("weak rotor 3"),
    },
    Case {
        data: Data::Sweep,
        effects: &["cg_offset=0.01,-0.008,0"],
        expected: Some("CG offset | CG offset, joint lever force"),
    },
    Case {
        data: Data::Sweep,
        effects: &["quadratic_drag=0.02,0.02,0.04"],
        expected: Some("quadratic airframe drag"),
    },
    Case {
        data: Data::Sweep,
        effects: &["ground_effect=1"],
        expected: Some("ground effect"),
    },
    Case {
        data: Data::Sweep,
        effects: &["wake_interaction=0.3"],
        expected: Some("rotor-wake interaction"),
    },
    Case {
        data: Data::Sweep,
        effects: &["wake_advance=1"],
        expected: Some("rotor-wake interaction, advance ratio"),
    },
    Case {
        data: Data::Sweep,
        effects: &["dynamic_inflow=2e-5"],
        expected: Some("thrust from rotor acceleration"),
    },
    Case {
        data: Data::Sweep,
        effects: &["flapping=1e-6"],
        expected: Some("rotor flapping moment"),
    },
    Case {
        data: Data::Sweep,
        effects: &[],
        expected: None,
    },
    Case {
        data: Data::Flight(30.0, false),
        effects: &["quadratic_drag=0.012,0.012,0.03"],
        expected: Some("quadratic airframe drag"),
    },
    Case {
        data: Data::Flight(60.0, true),
        effects: &["cg_offset=0.01,-0.008,0"],
        expected: Some("CG offset | CG offset, joint lever force"),
    },
    Case {
        data: Data::Flight(30.0, false),
        effects: &["delay=0.02"],
        expected: Some("rotor-speed delay"),
    },
    Case {
        data: Data::Flight(30.0, false),
        effects: &["wind=3,-2,0"],
        expected: Some("steady wind"),
    },
    Case {
        data: Data::Flight(60.0, false),
        effects: &["ground_effect=1"],
        expected: Some("ground effect, per-rotor height | ground effect, multirotor"),
    },
    Case {
        data: Data::NearGround(60.0, 30.0),
        effects: &["ground_effect=1"],
        expected: Some("ground effect, per-rotor height | ground effect, multirotor"),
    },
    Case {
        data: Data::Flight(30.0, false),
        effects: &[],
        expected: None,
    },
];

fn vehicle() -> Vehicle {
    Vehicle::from_toml_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("data/vehicles/quad_x.toml"),
    )
    .expect("shipped vehicle")
}

fn truth(v: &Vehicle, effects: &[&str]) -> TruthModel {
    let list: Vec<Effect> = effects.iter().map(|e| e.parse().expect("effect")).collect();
    TruthModel::new(
        v,
        &RotorFile::default(),
        Effects::new(list, v).expect("effects"),
    )
    .expect("truth model")
}

fn run_sweep(v: &Vehicle, effects: &[&str], seed: u64) -> Diagnosis {
    let truth = truth(v, effects);
    let all = sweep(
        &truth,
        &Ranges::scaled_to(&truth),
        Design::LatinHypercube,
        3000,
        seed,
    );
    let split = |r: std::ops::Range<usize>| {
        let mut c = SampleChunk::default();
        c.extend_from(&all, r);
        vec![c]
    };
    let base = ModelStructure::eq22(v, ModelOptions::default());
    diagnose_chunks(
        v,
        &base,
        &split(0..2400),
        &split(2400..3000),
        &FitOptions::default(),
        &DiagnoseOptions::default(),
    )
    .expect("diagnosis")
}

fn run_flight(
    v: &Vehicle,
    effects: &[&str],
    seed: u64,
    duration: f64,
    imu: bool,
    near_ground: f64,
) -> Diagnosis {
    let truth = truth(v, effects);
    let cfg = FlightConfig {
        duration,
        imu_only: imu,
        near_ground,
        ..Default::default()
    };
    let log = fly(&truth, &cfg, seed).expect("flight");
    // Through the CSV reader, as `mrsysid fit` reads it (an IMU-only log gets its
    // wrench derived there).
    let path = std::env::temp_dir().join(format!("diagnosis_seeds_{}.csv", std::process::id()));
    std::fs::write(&path, log.table.to_csv_bytes()).expect("temp file");
    let results = Identification::new(v.clone())
        .log(path.as_path())
        .diagnose(true)
        .run()
        .expect("fit");
    let _ = std::fs::remove_file(&path);
    results.outcome().diagnosis.clone().expect("diagnosis ran")
}

fn main() {
    let mut args = std::env::args().skip(1);
    let seeds: u64 = args.next().map_or(10, |s| s.parse().expect("seed count"));
    let filter = args.next().unwrap_or_default();
    let v = vehicle();
    for (k, case) in CASES.iter().enumerate() {
        let label = match case.data {
            Data::Sweep => "sweep".to_string(),
            Data::Flight(d, imu) => format!("{d} s {}flight", if imu { "IMU-only " } else { "" }),
            Data::NearGround(d, low) => format!("{d} s flight, first {low} s low"),
        };
        let label = format!("{label}, {}", case.effects.join(" "));
        // A filter ending in '$' must end the label.
        let wanted = match filter.strip_suffix('$') {
            Some(end) => label.ends_with(end),
            None => label.contains(&filter),
        };
        if !wanted {
            continue;
        }
        let (mut found_count, mut alike_count, mut most_extra) = (0, 0, 0);
        println!("## {label}");
        for s in 0..seeds {
            let seed = 1000 * (k as u64 + 1) + s;
            let d = match case.data {
                Data::Sweep => run_sweep(&v, case.effects, seed),
                Data::Flight(duration, imu) => {
                    run_flight(&v, case.effects, seed, duration, imu, 0.0)
                }
                Data::NearGround(duration, low) => {
                    run_flight(&v, case.effects, seed, duration, false, low)
                }
            };
            let named: Vec<&str> = d
                .effects_added
                .iter()
                .filter(|e| !e.role.is_model_completion())
                .map(|e| e.name.as_str())
                .collect();
            // The expected name, or any of several separated by " | " (forms with each
            // rotor at its own height, which the data may choose between).
            let expected: Vec<&str> = case
                .expected
                .map(|e| e.split(" | ").collect())
                .unwrap_or_default();
            let found = named.iter().any(|n| expected.contains(n));
            found_count += usize::from(found);
            // Named as a look-alike of what was added instead.
            let alike = !found
                && case.expected.is_some_and(|_| {
                    d.findings
                        .iter()
                        .any(|f| expected.iter().any(|e| f.contains(e)))
                });
            alike_count += usize::from(alike);
            let extra = named.len() - usize::from(found);
            most_extra = most_extra.max(extra);
            println!(
                "seed {seed}: {}, {extra} beyond completions and the effect: {:?}{}",
                match (found, alike) {
                    (true, _) => "found",
                    (false, true) => "look-alike",
                    _ => "NOT FOUND",
                },
                d.findings,
                if d.stopped_at_limit {
                    " (stopped at the limit)"
                } else {
                    ""
                }
            );
            println!(
                "    added: {:?}",
                d.effects_added.iter().map(|e| &e.name).collect::<Vec<_>>()
            );
            if !d.below_bar.is_empty() {
                println!("    below the bar: {:?}", d.below_bar);
            }
            if std::env::var_os("VERBOSE").is_some() {
                print_details(&d);
            }
        }
        match case.expected {
            Some(_) => println!(
                "=> found at {found_count} of {seeds} seeds (and as a look-alike at {alike_count}); at most {most_extra} other terms\n"
            ),
            None => println!("=> at most {most_extra} terms beyond completions\n"),
        }
    }
}

/// Per step: the added effect's gains, the candidates of its kind, withdrawals; the
/// candidates named in `FOCUS` at every step; the last step's best rejected candidates.
fn print_details(d: &Diagnosis) {
    let round = |g: [f64; 6]| g.map(|x| (1000.0 * x).round() / 10.0);
    for step in &d.steps {
        if let Some(added) = step.added.map(|i| &step.ranking[i]) {
            println!(
                "    + {:<32} P {:.1e} LR {:.0} gains {:?}",
                added.name,
                added.p,
                added.held_out_lr,
                round(added.validation_gain)
            );
            for r in step
                .ranking
                .iter()
                .filter(|r| r.kind == added.kind)
                .skip(1)
                .take(2)
            {
                println!(
                    "      same kind: {} LR {:.0} {:?}",
                    r.name,
                    r.held_out_lr,
                    r.rejected.as_ref().map(|r| r.to_string())
                );
            }
        }
        for w in &step.withdrawn {
            println!("    withdrawn: {w}");
        }
    }
    if let Ok(focus) = std::env::var("FOCUS") {
        for (k, step) in d.steps.iter().enumerate() {
            for r in step.ranking.iter().filter(|r| r.name.contains(&focus)) {
                println!(
                    "    step {k}: {} LR {:.1} share {:.2} local {:?} gains {:?} {:?}",
                    r.name,
                    r.held_out_lr,
                    r.active_share,
                    r.local_gain.map(round),
                    round(r.validation_gain),
                    r.rejected.as_ref().map(|r| r.to_string())
                );
            }
        }
    }
    if let Some(last) = d.steps.last() {
        for r in last.ranking.iter().take(4) {
            println!(
                "    next: {} {:?}",
                r.name,
                r.rejected.as_ref().map(|r| r.to_string())
            );
        }
    }
}
