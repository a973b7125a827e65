//! The library's [`mrsysid::Error`] as a Python exception: one class of `mrsysid.errors`
//! per variant (same names), carrying the message, the exit code `mrsysid` would give,
//! and where the error happened (file; line, message, byte or sample; field).

use mrsysid::io::{IoError, Location};
use mrsysid::vehicle::VehicleSource;
use mrsysid::{Error, StatsError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The Python exception for `e`.
pub fn to_py(py: Python<'_>, e: &Error) -> PyErr {
    build(py, e).unwrap_or_else(|failed| failed)
}

/// Raises the exception of `mrsysid.errors` named `class` with `message`, exit code
/// `exit_code` and the attributes in `fields`.
pub fn raise(
    py: Python<'_>,
    class: &str,
    message: &str,
    exit_code: u8,
    fields: &[(&str, Option<String>)],
) -> PyErr {
    let made = || -> PyResult<PyErr> {
        let kw = PyDict::new(py);
        kw.set_item("exit_code", exit_code)?;
        for (name, value) in fields {
            kw.set_item(name, value)?;
        }
        let class = py.import("mrsysid.errors")?.getattr(class)?;
        Ok(PyErr::from_value(class.call((message,), Some(&kw))?))
    };
    made().unwrap_or_else(|failed| failed)
}

fn build(py: Python<'_>, e: &Error) -> PyResult<PyErr> {
    let kw = PyDict::new(py);
    kw.set_item("exit_code", e.exit_code())?;
    let class = match e {
        Error::Vehicle(v) => {
            if let VehicleSource::File(path) = &v.source_name {
                kw.set_item("file", path.display().to_string())?;
            }
            "VehicleError"
        }
        Error::Input(io) => {
            input_fields(&kw, io)?;
            "InputError"
        }
        Error::Model(_) => "ModelError",
        Error::Accumulate { log, .. } => {
            kw.set_item("file", log)?;
            "AccumulateError"
        }
        Error::Estimate(_) => "EstimateError",
        Error::Diagnose(_) => "DiagnoseError",
        Error::ModelFile(m) => {
            kw.set_item("file", m.path.display().to_string())?;
            "ModelFileError"
        }
        Error::Request(_) => "RequestError",
        Error::Spill { path, .. } => {
            kw.set_item("file", path.display().to_string())?;
            "SpillError"
        }
        Error::Stats(s) => {
            if let StatsError::Io { file, .. } | StatsError::Format { file, .. } = s {
                kw.set_item("file", file)?;
            }
            "StatsError"
        }
    };
    let class = py.import("mrsysid.errors")?.getattr(class)?;
    Ok(PyErr::from_value(class.call((e.to_string(),), Some(&kw))?))
}

/// File, location (one of `line`, `record`, `offset`, `sample`), field and reason of an
/// input error.
fn input_fields(kw: &Bound<'_, PyDict>, io: &IoError) -> PyResult<()> {
    kw.set_item("file", &io.file)?;
    match io.location {
        Location::File => {}
        Location::Line(n) => kw.set_item("line", n)?,
        Location::Record(n) => kw.set_item("record", n)?,
        Location::Offset(n) => kw.set_item("offset", n)?,
        Location::Sample(n) => kw.set_item("sample", n)?,
    }
    kw.set_item("field", io.field.as_deref())?;
    kw.set_item("reason", io.reason())
}
