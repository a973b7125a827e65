//! The diagnosis on an independent simulator (`tests/independent/`): each of five
//! hidden effects in a response-surface set and in a noisy closed-loop flight, and the
//! two clean sets, diagnosed at `SEEDS` seeds through the public library with default
//! options. Prints per case and seed whether the effect was named and what else was
//! added, then the table: named k of SEEDS, and the terms added beyond the effect and
//! beyond what the clean set of the same seed gets.
//!
//! ```text
//! cargo run --release --example independent_truth [-- [--other-values] [--short-flight] [--noisy] [--iris] SEEDS [CASE-FILTER]]
//! cargo run --release --example independent_truth -- 10 'flight, CG'
//! ```
//!
//! `--other-values` runs the same five kinds at other values, sizes and places
//! ([`Hidden::others`]: not the values the harness was first run with);
//! `--short-flight` flies 30 s at 100 Hz (the first 10 s low) instead of 60 s at 200 Hz,
//! `--noisy` doubles every sensor's noise in the flights, and `--iris` flies the
//! second airframe ([`independent::score::iris`]: 1.5 kg, 10-inch rotors, a
//! rectangular ×) instead of the shipped 1.2 kg quadrotor ×.

#[path = "../tests/independent/mod.rs"]
mod independent;

use std::collections::HashMap;
use std::time::Instant;

use independent::effects::Hidden;
use independent::flight::FlightConfig;
use independent::score::{
    Case, DataKind, Naming, Score, cases, data_flown, diagnose, effect_size, expected_kind, iris,
    score, vehicle,
};
use mrsysid::internals::diagnose::Diagnosis;

/// First seed; seed k of a run is `FIRST_SEED + k`.
const FIRST_SEED: u64 = 42_000;

/// One case's results over the seeds.
#[derive(Default)]
struct Tally {
    added: usize,
    look_alike: usize,
    below_bar: usize,
    most_beyond_effect: usize,
    most_beyond_clean: usize,
    total_beyond_clean: usize,
    seeds: usize,
}

fn main() {
    let all_args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |name: &str| all_args.iter().any(|a| a == name);
    let other_values = flag("--other-values");
    let mut flight = if flag("--short-flight") {
        FlightConfig::short()
    } else {
        FlightConfig::default()
    };
    if flag("--noisy") {
        flight.noise_scale = 2.0;
    }
    let mut args = all_args.iter().filter(|a| !a.starts_with("--")).cloned();
    let seeds: u64 = args.next().map_or(10, |s| s.parse().expect("seed count"));
    let filter = args.next().unwrap_or_default();
    let v = if flag("--iris") { iris() } else { vehicle() };
    let all = cases(if other_values {
        Hidden::others()
    } else {
        Hidden::all()
    });
    let wanted: Vec<&Case> = all.iter().filter(|c| c.label().contains(&filter)).collect();
    let mut tallies: HashMap<String, Tally> = HashMap::new();
    for k in 0..seeds {
        let seed = FIRST_SEED + k;
        let mut clean: HashMap<&str, Diagnosis> = HashMap::new();
        for kind in [DataKind::Surface, DataKind::Flight] {
            if wanted.iter().any(|c| c.data == kind) {
                let case = Case {
                    data: kind,
                    hidden: None,
                };
                clean.insert(kind.label(), run(&v, &case, seed, &flight));
            }
        }
        for case in &wanted {
            let clean_d = &clean[case.data.label()];
            let d = if case.hidden.is_none() {
                clean_d.clone()
            } else {
                run(&v, case, seed, &flight)
            };
            let s = score(&d, clean_d, case.hidden.as_ref().map(expected_kind));
            report(case, seed, &d, &s);
            let t = tallies.entry(case.label()).or_default();
            t.seeds += 1;
            match s.naming {
                Naming::Added(_) => t.added += 1,
                Naming::LookAlike(_) => t.look_alike += 1,
                Naming::BelowBar(_) => t.below_bar += 1,
                Naming::Missed => {}
            }
            t.most_beyond_effect = t.most_beyond_effect.max(s.beyond_effect.len());
            t.most_beyond_clean = t.most_beyond_clean.max(s.beyond_clean.len());
            t.total_beyond_clean += s.beyond_clean.len();
        }
    }
    println!(
        "\n| case | named (added + look-alike + below the bar) | most terms beyond the effect | most beyond the clean set | sum beyond the clean set |"
    );
    println!("| --- | --- | --- | --- | --- |");
    for case in &wanted {
        let t = &tallies[&case.label()];
        let named = if case.hidden.is_some() {
            format!(
                "{} of {} ({} + {} + {})",
                t.added + t.look_alike + t.below_bar,
                t.seeds,
                t.added,
                t.look_alike,
                t.below_bar
            )
        } else {
            "—".into()
        };
        println!(
            "| {} | {named} | {} | {} | {} |",
            case.label(),
            t.most_beyond_effect,
            t.most_beyond_clean,
            t.total_beyond_clean
        );
    }
}

/// The data of `case` at `seed` (a flight flown as `flight` says), diagnosed, with the
/// time it took (and, for an effect, its size in the data).
fn run(v: &mrsysid::Vehicle, case: &Case, seed: u64, flight: &FlightConfig) -> Diagnosis {
    let start = Instant::now();
    let samples = data_flown(v, case, seed, flight);
    if case.hidden.is_some() {
        let size = effect_size(v, case, &samples).map(|x| format!("{x:.3}"));
        println!("{} | seed {seed}: effect RMS Fx..Mz {size:?}", case.label());
    }
    let d = diagnose(v, &case.label(), samples);
    eprintln!(
        "  {} seed {seed}: {:.1} s",
        case.label(),
        start.elapsed().as_secs_f64()
    );
    d
}

fn report(case: &Case, seed: u64, d: &Diagnosis, s: &Score) {
    let naming = match (&s.naming, case.hidden) {
        (_, None) => "clean".to_string(),
        (Naming::Added(n), _) => format!("NAMED ({n})"),
        (Naming::LookAlike(n), _) => format!("LOOK-ALIKE ({n})"),
        (Naming::BelowBar(n), _) => format!("BELOW THE BAR ({n})"),
        (Naming::Missed, _) => "MISSED".to_string(),
    };
    println!(
        "{} | seed {seed}: {naming}; {} beyond the effect, {} beyond the clean set {:?}",
        case.label(),
        s.beyond_effect.len(),
        s.beyond_clean.len(),
        s.beyond_clean
    );
    println!("    added: {:?}", s.added);
    println!("    findings: {:?}", d.findings);
    if !d.below_bar.is_empty() {
        println!("    below the bar: {:?}", d.below_bar);
    }
    let rmse = |m: &[mrsysid::AxisMetrics; 6]| m.map(|a| format!("{:.3}", a.rmse));
    println!(
        "    held-out RMSE Fx..Mz: Eq. 22 {:?}, final {:?}",
        rmse(&d.before),
        rmse(&d.after)
    );
    if !d.unsupported.is_empty() {
        let left: Vec<&str> = d.unsupported.iter().map(|u| u.name.as_str()).collect();
        println!("    left out: {left:?}");
    }
}
