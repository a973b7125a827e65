//! `Vehicle`: a checked vehicle definition (geometry, mass properties, Assumption 2).

use std::path::PathBuf;

use mrsysid::vehicle::VehicleSource;
use pyo3::prelude::*;

use crate::errors::to_py;

/// A multirotor vehicle: rotor layout, mass, inertia, rotor size (the vehicle TOML file).
#[pyclass(frozen, module = "mrsysid._mrsysid")]
pub struct Vehicle {
    pub inner: mrsysid::Vehicle,
}

#[pymethods]
impl Vehicle {
    /// Reads and checks a vehicle TOML file.
    #[staticmethod]
    fn from_toml(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        mrsysid::Vehicle::from_toml_file(&path)
            .map(|inner| Self { inner })
            .map_err(|e| to_py(py, &e.into()))
    }

    /// Parses and checks vehicle TOML text.
    #[staticmethod]
    fn from_toml_str(py: Python<'_>, text: &str) -> PyResult<Self> {
        mrsysid::Vehicle::from_toml_str(text, VehicleSource::Code)
            .map(|inner| Self { inner })
            .map_err(|e| to_py(py, &e.into()))
    }

    /// The vehicle's name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// Number of rotors.
    #[getter]
    fn rotor_count(&self) -> usize {
        self.inner.rotor_count()
    }

    /// Mass, kg.
    #[getter]
    fn mass(&self) -> f64 {
        self.inner.props.mass
    }

    /// Configuration class of the seed's Definition 1 (`quadrotor+`, `quadrotorx`,
    /// `multirotor>=6`, or `general planar`).
    #[getter]
    fn configuration(&self) -> String {
        self.inner.class().to_string()
    }

    /// Notes on Assumption 2 breaches and what the model does about them (empty when
    /// the assumption holds).
    fn notes(&self) -> Vec<String> {
        self.inner.notes()
    }

    fn __repr__(&self) -> String {
        format!(
            "Vehicle(name={:?}, rotors={}, configuration={:?})",
            self.inner.name,
            self.inner.rotor_count(),
            self.inner.class().to_string()
        )
    }
}
