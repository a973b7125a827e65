//! The mapping of a CSV file that follows the data contract, read off its header.

use std::collections::HashSet;

use super::super::error::{ErrorKind, IoError, Location, column};
use super::super::mapping::{Mapping, Signal};

/// The mapping of a contract CSV (`docs/data-contract.md`) with header `header`: SI units, FRD/NED,
/// `omega_1..omega_N` in vehicle order, optional `ax..`, `height`, `qw..`,
/// `omega_dot_1..`. Errors name the file (line 1) and the column concerned.
pub(super) fn contract_mapping(
    header: &[&str],
    rotors: usize,
    file: &str,
) -> Result<Mapping, IoError> {
    let err = |col: Option<String>, kind| IoError::new(file, Location::Line(1), col, kind);
    let mut seen = HashSet::new();
    for name in header {
        if !seen.insert(*name) {
            return Err(err(
                column(name),
                ErrorKind::Format("duplicate column name".into()),
            ));
        }
    }
    let has = |c: &str| seen.contains(c);
    let mut m = Mapping::default();
    let groups: [(Signal, Vec<String>); 8] = [
        (Signal::Time, vec!["t".into()]),
        (Signal::VelocityBody, names(&["u", "v", "w"])),
        (Signal::Rates, names(&["p", "q", "r"])),
        (Signal::Force, names(&["fx", "fy", "fz"])),
        (Signal::Moment, names(&["mx", "my", "mz"])),
        (Signal::SpecificForce, names(&["ax", "ay", "az"])),
        (Signal::Height, vec!["height".into()]),
        (Signal::Attitude, names(&["qw", "qx", "qy", "qz"])),
    ];
    for (signal, cols) in groups {
        let present = cols.iter().filter(|c| has(c)).count();
        if present == cols.len() {
            m.set_columns(signal, cols);
        } else if present > 0 {
            let missing = cols
                .iter()
                .find(|c| !has(c))
                .expect("some column is missing");
            return Err(err(
                column(missing),
                ErrorKind::MissingSignal(format!(
                    "missing column of {} (has {present} of {})",
                    signal.key(),
                    cols.join(",")
                )),
            ));
        }
    }
    for (signal, prefix) in [
        (Signal::RotorSpeeds, "omega_"),
        (Signal::RotorAccelerations, "omega_dot_"),
    ] {
        let count = header
            .iter()
            .filter(|h| {
                h.strip_prefix(prefix)
                    .is_some_and(|n| n.parse::<usize>().is_ok())
            })
            .count();
        if count == 0 {
            continue;
        }
        if count != rotors {
            return Err(err(
                None,
                ErrorKind::Mapping(format!(
                    "header has {count} {prefix}* columns but the vehicle has {rotors} rotors"
                )),
            ));
        }
        let cols: Vec<String> = (1..=rotors).map(|i| format!("{prefix}{i}")).collect();
        if let Some(missing) = cols.iter().find(|c| !has(c)) {
            return Err(err(
                column(missing),
                ErrorKind::MissingSignal(format!(
                    "missing column (rotors are numbered {prefix}1..{prefix}{rotors})"
                )),
            ));
        }
        m.set_columns(signal, cols);
    }
    Ok(m)
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}
