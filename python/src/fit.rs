//! `fit`: the library's [`Identification`] from Python arguments, run with the GIL
//! released on a worker thread while the calling thread watches for Ctrl-C.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

use mrsysid::Holdout;
use mrsysid::ModelOptions;
use mrsysid::io::{InvalidSamples, Mapping, ReadOptions};
use mrsysid::{Identification, MemoryLog};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{raise, to_py};
use crate::results::Results;
use crate::tables::{Needs, Table};
use crate::vehicle::Vehicle;

/// How often the calling thread looks for a pending Ctrl-C while a fit runs.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// The options every entry point shares: how logs are read and what model is fitted.
pub struct Options<'a> {
    pub mapping: Option<PathBuf>,
    pub threads: Option<usize>,
    pub inflow: &'a str,
    pub linear_vh: bool,
    pub rotor_inertia: &'a str,
    pub drop_invalid: bool,
    pub loads_low_pass: Option<f64>,
    pub keep_ground: bool,
}

impl Options<'_> {
    /// The library's builder for `vehicle` with these options (no log yet).
    pub fn builder(&self, py: Python<'_>, vehicle: &Vehicle) -> PyResult<Identification> {
        let options = ModelOptions {
            inflow: option(py, "inflow", self.inflow)?,
            linear_vh_terms: self.linear_vh,
            rotor_inertia: option(py, "rotor_inertia", self.rotor_inertia)?,
        };
        let mut job = Identification::new(vehicle.inner.clone())
            .model_options(options)
            .read_options(ReadOptions {
                invalid: if self.drop_invalid {
                    InvalidSamples::DropAndCount
                } else {
                    InvalidSamples::Error
                },
                airborne_only: !self.keep_ground,
                ..ReadOptions::default()
            });
        if let Some(hz) = self.loads_low_pass {
            job = job.loads_low_pass(hz);
        }
        if let Some(path) = &self.mapping {
            let mapping = Mapping::from_toml_file(path).map_err(|e| to_py(py, &e.into()))?;
            job = job.mapping(mapping);
        }
        if let Some(n) = self.threads {
            job = job.threads(n);
        }
        Ok(job)
    }
}

/// Fits `vehicle`'s model to log files and tables (see `mrsysid.fit` for the arguments).
#[pyfunction]
#[pyo3(signature = (
    vehicle, *, logs, tables, validate_logs, validate_tables, mapping, diagnose, threads,
    inflow, linear_vh, rotor_inertia, drop_invalid, holdout_blocks, holdout_guard, loads_low_pass, estimate_loads_low_pass, keep_ground,
    residual_pass, groups
))]
#[allow(clippy::too_many_arguments)]
pub fn fit<'py>(
    py: Python<'py>,
    vehicle: PyRef<'py, Vehicle>,
    logs: Vec<PathBuf>,
    tables: Vec<(String, Bound<'py, PyDict>)>,
    validate_logs: Vec<PathBuf>,
    validate_tables: Vec<(String, Bound<'py, PyDict>)>,
    mapping: Option<PathBuf>,
    diagnose: bool,
    threads: Option<usize>,
    inflow: &str,
    linear_vh: bool,
    rotor_inertia: &str,
    drop_invalid: bool,
    holdout_blocks: usize,
    holdout_guard: f64,
    loads_low_pass: Option<f64>,
    estimate_loads_low_pass: bool,
    keep_ground: bool,
    residual_pass: bool,
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
    let rotors = vehicle.inner.rotor_count();
    let mut job = options
        .builder(py, &vehicle)?
        .holdout(Holdout {
            blocks: holdout_blocks,
            guard_seconds: holdout_guard,
        })
        .diagnose(diagnose)
        .residual_pass(residual_pass)
        .groups(groups)
        .logs(logs);
    if estimate_loads_low_pass {
        job = job.estimate_loads_low_pass();
    }
    for log in validate_logs {
        job = job.validate(log);
    }
    let needs = Needs {
        rotors,
        wrench: true,
        time: true,
    };
    for (name, columns) in tables {
        job = job.log(memory_log(py, name, &columns, needs)?);
    }
    for (name, columns) in validate_tables {
        job = job.validate(memory_log(py, name, &columns, needs)?);
    }
    let cancel = Arc::new(AtomicBool::new(false));
    let job = job.cancel(cancel.clone());
    let results = run_interruptibly(py, &cancel, move || job.run())?;
    results.map(Results::new).map_err(|e| to_py(py, &e))
}

/// A model option given by its name in the model file (e.g. `inflow="paper"`).
fn option<T: serde::de::DeserializeOwned>(py: Python<'_>, what: &str, name: &str) -> PyResult<T> {
    serde_json::from_value(serde_json::Value::String(name.to_string())).map_err(|e| {
        let message = format!("{what}: {e}");
        raise(
            py,
            "RequestError",
            &message,
            2,
            &[("field", Some(what.to_string()))],
        )
    })
}

/// A table as a log in memory, its samples checked by the library.
pub fn memory_log(
    py: Python<'_>,
    name: String,
    columns: &Bound<'_, PyDict>,
    needs: Needs,
) -> PyResult<MemoryLog> {
    let table = Table::new(py, name, columns)?;
    let chunks = table.chunks(py, needs)?;
    MemoryLog::from_chunks(&table.name, chunks).map_err(|e| to_py(py, &e.into()))
}

/// Runs `job` on a worker thread with the GIL released. The calling thread checks for
/// signals every [`SIGNAL_POLL`]; on Ctrl-C (or any signal handler that raises) it sets
/// `cancel`, which the library polls between chunks, waits for the worker to stop and
/// raises the handler's exception (`KeyboardInterrupt`).
pub fn run_interruptibly<T: Send>(
    py: Python<'_>,
    cancel: &Arc<AtomicBool>,
    job: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    py.detach(|| {
        std::thread::scope(|s| {
            let (done, finished) = mpsc::channel();
            let worker = s.spawn(move || {
                let out = job();
                let _ = done.send(());
                out
            });
            let mut interrupt: Option<PyErr> = None;
            loop {
                match finished.recv_timeout(SIGNAL_POLL) {
                    Err(RecvTimeoutError::Timeout) if interrupt.is_none() => {
                        if let Err(e) = Python::attach(|py| py.check_signals()) {
                            cancel.store(true, Ordering::Relaxed);
                            interrupt = Some(e);
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                    Ok(()) | Err(RecvTimeoutError::Disconnected) => break,
                }
            }
            let out = worker.join();
            match (interrupt, out) {
                (Some(e), _) => Err(e),
                (None, Ok(out)) => Ok(out),
                (None, Err(_)) => Err(PyRuntimeError::new_err(
                    "the fit's worker thread stopped without a result (a bug: please report it)",
                )),
            }
        })
    })
}
