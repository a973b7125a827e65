//! `mrsysid._mrsysid`: the Python extension of mrsysid, a thin PyO3 layer over the
//! library's front (the fit builder, its results, the identified model, the vehicle).
//! Nothing is computed here that the library does not compute for `mrsysid fit`: this
//! layer only moves data across (numpy columns in, numpy arrays and plain Python values
//! out), releases the GIL while the library works, and turns the library's errors into
//! the exceptions of `mrsysid.errors`. The Python package `mrsysid` (beside this crate)
//! wraps these classes with pandas.

mod errors;
mod fit;
mod model;
mod passes;
mod results;
mod stats;
mod tables;
mod vehicle;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _mrsysid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("CHUNK_SAMPLES", mrsysid::CHUNK_SAMPLES)?;
    m.add_class::<vehicle::Vehicle>()?;
    m.add_class::<results::Results>()?;
    m.add_class::<model::Model>()?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(stats::accumulate, m)?)?;
    m.add_function(wrap_pyfunction!(stats::merge_stats, m)?)?;
    m.add_function(wrap_pyfunction!(stats::fit_from_stats, m)?)?;
    m.add_class::<passes::PlannedFit>()?;
    m.add_class::<passes::PreparedPass>()?;
    m.add_class::<passes::PendingFit>()?;
    Ok(())
}
