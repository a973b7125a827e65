//! Statistics as data from Python: each log's first pass as bytes (`accumulate`), parts
//! merged (`merge_stats`), and the fit from them (`fit_from_stats`), so that any engine
//! (Dask, in `mrsysid.dask`) can read logs on many workers and fit once.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use mrsysid::{StatsError, StatsPart};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::errors::to_py;
use crate::fit::{Options, memory_log, run_interruptibly};
use crate::results::Results;
use crate::tables::Needs;
use crate::vehicle::Vehicle;

/// The first passes of `logs` and `tables` as the bytes of one statistics part (see
/// `mrsysid.accumulate`).
#[pyfunction]
#[pyo3(signature = (
    vehicle, *, logs, tables, mapping, threads, inflow, linear_vh, rotor_inertia,
    drop_invalid, loads_low_pass, keep_ground, diagnose
))]
#[allow(clippy::too_many_arguments)]
pub fn accumulate<'py>(
    py: Python<'py>,
    vehicle: PyRef<'py, Vehicle>,
    logs: Vec<PathBuf>,
    tables: Vec<(String, Bound<'py, PyDict>)>,
    mapping: Option<PathBuf>,
    threads: Option<usize>,
    inflow: &str,
    linear_vh: bool,
    rotor_inertia: &str,
    drop_invalid: bool,
    loads_low_pass: Option<f64>,
    keep_ground: bool,
    diagnose: bool,
) -> PyResult<Bound<'py, PyBytes>> {
    let options = Options {
        mapping,
        threads,
        inflow,
        linear_vh,
        rotor_inertia,
        drop_invalid,
        loads_low_pass,
        keep_ground,
    };
    let needs = Needs {
        rotors: vehicle.inner.rotor_count(),
        wrench: true,
        time: true,
    };
    let mut job = options.builder(py, &vehicle)?.logs(logs).diagnose(diagnose);
    for (name, columns) in tables {
        job = job.log(memory_log(py, name, &columns, needs)?);
    }
    let cancel = Arc::new(AtomicBool::new(false));
    let job = job.cancel(cancel.clone());
    let part = run_interruptibly(py, &cancel, move || job.accumulate())?;
    let part = part.map_err(|e| to_py(py, &e))?;
    Ok(PyBytes::new(py, &part.to_bytes()))
}

/// A statistics error as the Python exception it maps to.
pub fn stats_err(py: Python<'_>, e: StatsError) -> PyErr {
    to_py(py, &e.into())
}

/// Reads the part in `bytes` (named `name` in errors).
pub fn part(py: Python<'_>, bytes: &[u8], name: &str) -> PyResult<StatsPart> {
    StatsPart::from_bytes(bytes, name).map_err(|e| stats_err(py, e))
}

/// The parts in `parts` (named `name[k]` in errors) merged in order; `None` for none.
pub fn merged(py: Python<'_>, parts: &[Vec<u8>], name: &str) -> PyResult<Option<StatsPart>> {
    let mut all: Option<StatsPart> = None;
    for (k, bytes) in parts.iter().enumerate() {
        let p = part(py, bytes, &format!("{name}[{k}]"))?;
        match all.as_mut() {
            Some(a) => a.merge(&p).map_err(|e| stats_err(py, e))?,
            None => all = Some(p),
        }
    }
    Ok(all)
}

/// The parts in `parts` merged in order, as bytes.
#[pyfunction]
pub fn merge_stats<'py>(py: Python<'py>, parts: Vec<Vec<u8>>) -> PyResult<Bound<'py, PyBytes>> {
    let merged = merged(py, &parts, "parts")?
        .ok_or_else(|| pyo3::exceptions::PyValueError::new_err("merge_stats: no part to merge"))?;
    Ok(PyBytes::new(py, &merged.to_bytes()))
}

/// The fit from statistics parts (see `mrsysid.fit_from_stats`).
#[pyfunction]
#[pyo3(signature = (
    vehicle, *, parts, validate_parts, mapping, threads, inflow, linear_vh, rotor_inertia,
    drop_invalid, loads_low_pass, keep_ground, groups
))]
#[allow(clippy::too_many_arguments)]
pub fn fit_from_stats<'py>(
    py: Python<'py>,
    vehicle: PyRef<'py, Vehicle>,
    parts: Vec<u8>,
    validate_parts: Option<Vec<u8>>,
    mapping: Option<PathBuf>,
    threads: Option<usize>,
    inflow: &str,
    linear_vh: bool,
    rotor_inertia: &str,
    drop_invalid: bool,
    loads_low_pass: Option<f64>,
    keep_ground: bool,
    groups: Vec<String>,
) -> PyResult<Results> {
    let options = Options {
        mapping,
        threads,
        inflow,
        linear_vh,
        rotor_inertia,
        drop_invalid,
        loads_low_pass,
        keep_ground,
    };
    let job = options.builder(py, &vehicle)?.groups(groups);
    let fit = part(py, &parts, "parts")?;
    let validate = validate_parts
        .map(|b| part(py, &b, "validate_parts"))
        .transpose()?;
    let results = py.detach(|| job.run_from_stats(&fit, validate.as_ref()));
    results.map(Results::new).map_err(|e| to_py(py, &e))
}
