//! `Results`: what a fit produced, as plain Python values (the package's pandas layer
//! makes DataFrames of them).

use mrsysid::AxisMetrics;
use numpy::PyArray2;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::model::Model;

/// The results of `fit`: the final model (Eq. 22 after the diagnosis when it ran) with
/// its statistics, and everything the pipeline computed on the way.
#[pyclass(frozen, module = "mrsysid._mrsysid")]
pub struct Results {
    inner: mrsysid::Results,
}

/// One row of the metrics table: data set, stage, and the axis' figures.
type MetricsRow = (&'static str, &'static str, String, f64, f64, f64, f64);

impl Results {
    /// Wraps the library's results.
    pub fn new(inner: mrsysid::Results) -> Self {
        Self { inner }
    }
}

fn rows(data: &'static str, stage: &'static str, m: &[AxisMetrics; 6]) -> Vec<MetricsRow> {
    m.iter()
        .map(|a| {
            (
                data,
                stage,
                a.axis.to_string(),
                a.r2,
                a.rmse,
                a.nrmse,
                a.tic,
            )
        })
        .collect()
}

#[pymethods]
impl Results {
    /// The final model's parameters as columns: name, unit, estimate, std (with the
    /// coloured-residual correction), std_white, t, p, ci_low, ci_high (95 %).
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = self.inner.parameters();
        let out = PyDict::new(py);
        let column =
            |f: fn(&mrsysid::ParameterResult) -> f64| -> Vec<f64> { p.iter().map(f).collect() };
        out.set_item("name", p.iter().map(|r| r.name.clone()).collect::<Vec<_>>())?;
        out.set_item("estimate", column(|r| r.estimate))?;
        out.set_item("std", column(|r| r.std))?;
        out.set_item("std_white", column(|r| r.std_white))?;
        out.set_item("t", column(|r| r.t))?;
        out.set_item("p", column(|r| r.p_value))?;
        out.set_item("ci_low", column(|r| r.ci95[0]))?;
        out.set_item("ci_high", column(|r| r.ci95[1]))?;
        out.set_item("unit", p.iter().map(|r| r.unit.clone()).collect::<Vec<_>>())?;
        Ok(out)
    }

    /// Goodness of fit per axis as rows `(data, stage, axis, r2, rmse, nrmse, tic)`:
    /// data `fit` (all fit data), `cross-validated` (every fold's held-out predictions
    /// pooled) and, with validation logs, `validation`; stage `before` (the Eq. 22
    /// model) and, when the diagnosis ran, `after` (the adopted model: the final model,
    /// with the Eq. 22 model on the axes it predicts better, `eq22_axes` of the report).
    fn metrics(&self) -> Vec<MetricsRow> {
        let o = self.inner.outcome();
        let mut out = rows("fit", "before", &o.fit.metrics);
        if o.diagnosis.is_some() {
            out.extend(rows("fit", "after", &self.inner.fit_metrics()));
        }
        out.extend(rows(
            "cross-validated",
            "before",
            &o.cross_validation.1.pooled_metrics(),
        ));
        if let Some(d) = &o.diagnosis {
            out.extend(rows("cross-validated", "after", &d.after));
        }
        if o.validation_stats.count() > 0 {
            out.extend(rows("validation", "before", &o.validation));
            if let Some([_, after]) = o.diagnosis.as_ref().and_then(|d| d.validation) {
                out.extend(rows("validation", "after", &after));
            }
        }
        out
    }

    /// The JSON report of `mrsysid fit --json` (schema in docs/report-schema.md), as text.
    fn report_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.inner.report())
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// The printed tables of `mrsysid fit`, then the final model's parameters.
    fn summary(&self) -> String {
        self.inner.summary()
    }

    /// The final model as equations, one line per axis.
    fn equations(&self) -> String {
        self.inner.equations()
    }

    /// Coloured-residual variance inflation κ ≥ 1 applied to σ² (1 without the
    /// residual pass).
    #[getter]
    fn variance_inflation(&self) -> f64 {
        self.inner.variance_inflation()
    }

    /// Parameter names of the final model's structure, in the order of `covariance`.
    fn structure_parameters(&self) -> Vec<String> {
        let s = self.inner.structure();
        s.params.iter().map(|p| p.name.clone()).collect()
    }

    /// θ̂ over the final structure's parameters (0 for dropped ones).
    fn theta(&self) -> Vec<f64> {
        self.inner.theta().to_vec()
    }

    /// Parameter covariance with the coloured-residual correction, n × n over the final
    /// structure's parameters (products of their units).
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = self.inner.covariance();
        let rows: Vec<Vec<f64>> = (0..c.nrows())
            .map(|i| c.row(i).iter().copied().collect())
            .collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// The final model, ready to predict and save.
    fn model(&self) -> Model {
        Model::new(self.inner.to_identified_model())
    }
}
