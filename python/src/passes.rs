//! The closing of the loop from statistics (the second and third passes as data): the
//! driver's fit and plan (`PlannedFit`), the plan prepared once per worker process
//! (`PreparedPass`: each log's second pass and remainder pass as bytes), the reduce
//! (`PlannedFit.diagnose`) and the finish (`PendingFit.finish`). `mrsysid.dask` drives
//! them; any engine can.

use std::path::PathBuf;

use mrsysid::{Identification, PassPart, PassPlan, RemainderPart, RemainderPlan};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::to_py;
use crate::fit::Options;
use crate::results::Results;
use crate::stats::{merged, stats_err};
use crate::vehicle::Vehicle;

/// The Eq. 22 fit of the logs of `parts` and `validate_parts` and the plan of their
/// second pass (see `mrsysid.dask`): the driver's side of the diagnosis from statistics.
#[pyclass(module = "mrsysid._mrsysid")]
pub struct PlannedFit {
    job: Identification,
    inner: Option<mrsysid::PlannedFit>,
    plan: Vec<u8>,
}

#[pymethods]
impl PlannedFit {
    /// Fits the logs of the first-pass parts `parts` (merged in order) and plans their
    /// second pass, with validation figures on those of `validate_parts`.
    #[new]
    #[pyo3(signature = (
        vehicle, *, parts, validate_parts, mapping, threads, inflow, linear_vh, rotor_inertia,
        drop_invalid, loads_low_pass, keep_ground, groups
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        vehicle: PyRef<'_, Vehicle>,
        parts: Vec<Vec<u8>>,
        validate_parts: Vec<Vec<u8>>,
        mapping: Option<PathBuf>,
        threads: Option<usize>,
        inflow: &str,
        linear_vh: bool,
        rotor_inertia: &str,
        drop_invalid: bool,
        loads_low_pass: Option<f64>,
        keep_ground: bool,
        groups: Vec<String>,
    ) -> PyResult<Self> {
        let job = Options {
            mapping,
            threads,
            inflow,
            linear_vh,
            rotor_inertia,
            drop_invalid,
            loads_low_pass,
            keep_ground,
        }
        .builder(py, &vehicle)?
        .groups(groups);
        let fit = merged(py, &parts, "parts")?
            .ok_or_else(|| pyo3::exceptions::PyValueError::new_err("PlannedFit: no part to fit"))?;
        let validate = merged(py, &validate_parts, "validate_parts")?;
        let planned = py.detach(|| job.plan_from_stats(&fit, validate.as_ref()));
        let planned = planned.map_err(|e| to_py(py, &e))?;
        let plan = planned.plan().to_bytes();
        Ok(Self {
            job,
            inner: Some(planned),
            plan,
        })
    }

    /// The plan's bytes, for `PreparedPass` on every worker.
    fn plan<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.plan)
    }

    /// The fit and diagnosis from the second-pass parts `passes` (bytes of
    /// `PreparedPass.pass_log`, one per log). Once only.
    fn diagnose(&mut self, py: Python<'_>, passes: Vec<Vec<u8>>) -> PyResult<PendingFit> {
        let passes: Vec<PassPart> = (passes.iter().enumerate())
            .map(|(k, b)| PassPart::from_bytes(b, &format!("passes[{k}]")))
            .collect::<Result<_, _>>()
            .map_err(|e| stats_err(py, e))?;
        let planned = self.inner.take().ok_or_else(|| {
            pyo3::exceptions::PyRuntimeError::new_err("PlannedFit.diagnose was already called")
        })?;
        let pending = py.detach(|| planned.diagnose(passes));
        let pending = pending.map_err(|e| to_py(py, &e))?;
        Ok(PendingFit {
            job: self.job.clone(),
            inner: Some(pending),
        })
    }
}

/// A second-pass plan prepared for passing its logs: made once per worker process.
#[pyclass(frozen, module = "mrsysid._mrsysid")]
pub struct PreparedPass {
    inner: mrsysid::PreparedPass,
}

#[pymethods]
impl PreparedPass {
    /// Prepares the plan in `plan` (bytes of `PlannedFit.plan`) for the vehicle and options it
    /// was made with.
    #[new]
    #[pyo3(signature = (
        vehicle, plan, *, mapping, threads, inflow, linear_vh, rotor_inertia, drop_invalid,
        loads_low_pass, keep_ground
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        vehicle: PyRef<'_, Vehicle>,
        plan: Vec<u8>,
        mapping: Option<PathBuf>,
        threads: Option<usize>,
        inflow: &str,
        linear_vh: bool,
        rotor_inertia: &str,
        drop_invalid: bool,
        loads_low_pass: Option<f64>,
        keep_ground: bool,
    ) -> PyResult<Self> {
        let job = Options {
            mapping,
            threads,
            inflow,
            linear_vh,
            rotor_inertia,
            drop_invalid,
            loads_low_pass,
            keep_ground,
        }
        .builder(py, &vehicle)?;
        let plan = PassPlan::from_bytes(&plan, "plan").map_err(|e| stats_err(py, e))?;
        let inner = py.detach(|| job.prepare_pass(plan));
        let inner = inner.map_err(|e| to_py(py, &e))?;
        Ok(Self { inner })
    }

    /// The second pass of the log at `path` (one of the plan's logs), as bytes.
    fn pass_log<'py>(&self, py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyBytes>> {
        let part = py.detach(|| self.inner.pass_part(&path.into()));
        let part = part.map_err(|e| to_py(py, &e))?;
        Ok(PyBytes::new(py, &part.to_bytes()))
    }

    /// The remainder pass of the fit log at `path` with the final model in `model`
    /// (bytes of `PendingFit.remainder_plan`), as bytes.
    fn remainder_log<'py>(
        &self,
        py: Python<'py>,
        model: Vec<u8>,
        path: PathBuf,
    ) -> PyResult<Bound<'py, PyBytes>> {
        let model =
            RemainderPlan::from_bytes(&model, "remainder plan").map_err(|e| stats_err(py, e))?;
        let part = py.detach(|| self.inner.remainder_part(&model, &path.into()));
        let part = part.map_err(|e| to_py(py, &e))?;
        Ok(PyBytes::new(py, &part.to_bytes()))
    }
}

/// The fit and diagnosis from statistics, waiting for the remainder pass.
#[pyclass(module = "mrsysid._mrsysid")]
pub struct PendingFit {
    job: Identification,
    inner: Option<mrsysid::PendingFit>,
}

#[pymethods]
impl PendingFit {
    /// `(model bytes, fit log names)` for the remainder pass over each fit log, or
    /// `None` when there is none (no diagnosis, or logs that are not time series).
    fn remainder_plan<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<(Bound<'py, PyBytes>, Vec<String>)>> {
        let pending = self.pending()?;
        Ok(pending
            .remainder_plan()
            .map(|(plan, logs)| (PyBytes::new(py, &plan.to_bytes()), logs.to_vec())))
    }

    /// The results, with the remainder parts `parts` (bytes of
    /// `PreparedPass.remainder_log`, one per fit log; none without a remainder plan).
    /// Once only.
    fn finish(&mut self, py: Python<'_>, parts: Vec<Vec<u8>>) -> PyResult<Results> {
        let parts: Vec<RemainderPart> = (parts.iter().enumerate())
            .map(|(k, b)| RemainderPart::from_bytes(b, &format!("remainder parts[{k}]")))
            .collect::<Result<_, _>>()
            .map_err(|e| stats_err(py, e))?;
        self.pending()?;
        let pending = self.inner.take().expect("checked above");
        let results = py.detach(|| self.job.finish_from_stats(pending, &parts));
        results.map(Results::new).map_err(|e| to_py(py, &e))
    }
}

impl PendingFit {
    fn pending(&self) -> PyResult<&mrsysid::PendingFit> {
        self.inner.as_ref().ok_or_else(|| {
            pyo3::exceptions::PyRuntimeError::new_err("PendingFit.finish was already called")
        })
    }
}
