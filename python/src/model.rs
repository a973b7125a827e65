//! `Model`: an identified model — save, load, predict force and moment, and the
//! standard deviation of the prediction from the parameter covariance.

use std::path::PathBuf;

use mrsysid::Workspace;
use mrsysid::io::Mapping;
use mrsysid::{IdentifiedModel, Sample, SampleChunk};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::to_py;
use crate::tables::{Needs, Table};

/// Output columns of a prediction, in the library's axis order (N, N m).
const OUTPUTS: [&str; 6] = ["fx", "fy", "fz", "mx", "my", "mz"];

/// An identified model: vehicle, model structure, estimated parameters and covariance.
#[pyclass(frozen, module = "mrsysid._mrsysid")]
pub struct Model {
    inner: IdentifiedModel,
}

impl Model {
    /// Wraps the library's model.
    pub fn new(inner: IdentifiedModel) -> Self {
        Self { inner }
    }

    fn needs(&self, time: bool) -> Needs {
        Needs {
            rotors: self.inner.vehicle.rotor_count(),
            wrench: false,
            time,
        }
    }
}

/// `columns` (one per output axis) as a dict of numpy arrays named `fx … mz`, after
/// `t` when given.
fn outputs<'py>(
    py: Python<'py>,
    t: Option<Vec<f64>>,
    columns: [Vec<f64>; 6],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    if let Some(t) = t {
        out.set_item("t", t.into_pyarray(py))?;
    }
    for (name, col) in OUTPUTS.iter().zip(columns) {
        out.set_item(*name, col.into_pyarray(py))?;
    }
    Ok(out)
}

/// Appends the samples of `chunk`'s per-axis values `y` to `columns`.
fn extend(columns: &mut [Vec<f64>; 6], y: &[Vec<f64>; 6]) {
    for (c, v) in columns.iter_mut().zip(y) {
        c.extend_from_slice(v);
    }
}

/// Sample `k` of `chunk` (its state; the measured force and moment are not needed).
fn sample(chunk: &SampleChunk, k: usize) -> Sample {
    let at = |v: &Vec<f64>| v[k];
    Sample {
        t: chunk.t[k],
        velocity: chunk.velocity.each_ref().map(at),
        rates: chunk.rates.each_ref().map(at),
        omega: chunk.omega.iter().map(at).collect(),
        omega_dot: chunk.omega_dot.iter().flatten().map(at).collect(),
        wrench: [0.0; 6],
        height: chunk.height.as_ref().map(at),
        attitude: chunk.attitude.as_ref().map(|q| q.each_ref().map(at)),
    }
}

#[pymethods]
impl Model {
    /// Reads a model file written by `save` (or `mrsysid fit --model-out`).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        IdentifiedModel::load(&path)
            .map(Self::new)
            .map_err(|e| to_py(py, &e.into()))
    }

    /// Writes the model file (whole or not at all).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        self.inner.save(&path).map_err(|e| to_py(py, &e.into()))
    }

    /// Parameters as columns: name, unit, estimate, std.
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.inner.parameters;
        let out = PyDict::new(py);
        out.set_item("name", p.iter().map(|r| r.name.clone()).collect::<Vec<_>>())?;
        out.set_item("estimate", p.iter().map(|r| r.estimate).collect::<Vec<_>>())?;
        out.set_item("std", p.iter().map(|r| r.std).collect::<Vec<_>>())?;
        out.set_item("unit", p.iter().map(|r| r.unit.clone()).collect::<Vec<_>>())?;
        Ok(out)
    }

    /// The vehicle's rotor count.
    #[getter]
    fn rotor_count(&self) -> usize {
        self.inner.vehicle.rotor_count()
    }

    /// True when the model has a parameter covariance (prediction_std is then known).
    #[getter]
    fn has_covariance(&self) -> bool {
        self.inner.covariance.is_some()
    }

    /// Force and moment per row of a table of states (dict of float64 columns of the
    /// data contract; `t` optional, the measured force and moment not needed).
    fn predict<'py>(
        &self,
        py: Python<'py>,
        name: String,
        columns: &Bound<'py, PyDict>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let table = Table::new(py, name, columns)?;
        let chunks = table.chunks(py, self.needs(false))?;
        let rows = table.rows();
        let y = py.detach(|| {
            let mut ws = Workspace::default();
            let mut out: [Vec<f64>; 6] = std::array::from_fn(|_| Vec::with_capacity(rows));
            for c in &chunks {
                extend(&mut out, &self.inner.predict_chunk(c, &mut ws)?);
            }
            Ok::<_, mrsysid::Error>(out)
        });
        outputs(py, None, y.map_err(|e| to_py(py, &e))?)
    }

    /// Standard deviation of the predicted mean force and moment per row (N, N m),
    /// √(xᵀ C x) from the parameter covariance C; `None` without a covariance.
    fn prediction_std<'py>(
        &self,
        py: Python<'py>,
        name: String,
        columns: &Bound<'py, PyDict>,
    ) -> PyResult<Option<Bound<'py, PyDict>>> {
        if self.inner.covariance.is_none() {
            return Ok(None);
        }
        let table = Table::new(py, name, columns)?;
        let chunks = table.chunks(py, self.needs(false))?;
        let rows = table.rows();
        let y = py.detach(|| {
            let mut out: [Vec<f64>; 6] = std::array::from_fn(|_| Vec::with_capacity(rows));
            for c in &chunks {
                for k in 0..c.len() {
                    if let Some(s) = self.inner.prediction_std(&sample(c, k))? {
                        for (col, v) in out.iter_mut().zip(s) {
                            col.push(v);
                        }
                    }
                }
            }
            Ok::<_, mrsysid::Error>(out)
        });
        outputs(py, None, y.map_err(|e| to_py(py, &e))?).map(Some)
    }

    /// Force and moment per sample of a log file, read and derived exactly as
    /// `mrsysid predict` reads it (mapping file optional): `t, fx … mz`.
    #[pyo3(signature = (path, mapping=None))]
    fn predict_log<'py>(
        &self,
        py: Python<'py>,
        path: PathBuf,
        mapping: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mapping = mapping
            .map(|p| Mapping::from_toml_file(&p))
            .transpose()
            .map_err(|e| to_py(py, &e.into()))?;
        let y = py.detach(|| {
            let mut t = Vec::new();
            let mut out: [Vec<f64>; 6] = Default::default();
            self.inner
                .predict_log(&path, mapping.as_ref(), |c, y| {
                    t.extend_from_slice(&c.t);
                    extend(&mut out, y);
                })
                .map(|()| (t, out))
        });
        let (t, out) = y.map_err(|e| to_py(py, &e))?;
        outputs(py, Some(t), out)
    }

    fn __repr__(&self) -> String {
        format!(
            "Model(vehicle={:?}, parameters={})",
            self.inner.vehicle.name,
            self.inner.parameters.len()
        )
    }
}
