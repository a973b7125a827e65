//! Tables from Python as the library's sample chunks. The package's pandas layer hands
//! a table over as a dict of column name → one-dimensional float64 numpy array in C
//! order (a view of the caller's DataFrame or arrays where their layout allows, never a
//! per-value conversion); the columns are read in place through the numpy C API and
//! copied once, [`CHUNK_SAMPLES`] samples at a time, into the library's chunks.
//!
//! Column names are those of the CSV data contract: `t`, `u v w`, `p q r`,
//! `omega_1..omega_N`, optional `omega_dot_1..omega_dot_N`, `fx fy fz mx my mz`,
//! optional `height` and `qw qx qy qz`.

use std::collections::HashMap;

use mrsysid::{CHUNK_SAMPLES, SampleChunk};
use numpy::{PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::raise;

/// A named table of equal-length float64 columns, borrowed from Python.
pub struct Table<'py> {
    /// The name errors and reports use for it.
    pub name: String,
    columns: HashMap<String, PyReadonlyArray1<'py, f64>>,
    rows: usize,
}

/// What the chunks of a table must carry.
#[derive(Clone, Copy)]
pub struct Needs {
    /// Rotor count of the vehicle: columns `omega_1..omega_N`.
    pub rotors: usize,
    /// The measured force and moment (`fx … mz`): a fit needs them, a prediction not.
    pub wrench: bool,
    /// The time column `t`: a fit needs it; without it a prediction numbers the rows.
    pub time: bool,
}

const VELOCITY: [&str; 3] = ["u", "v", "w"];
const RATES: [&str; 3] = ["p", "q", "r"];
const WRENCH: [&str; 6] = ["fx", "fy", "fz", "mx", "my", "mz"];
const ATTITUDE: [&str; 4] = ["qw", "qx", "qy", "qz"];

impl<'py> Table<'py> {
    /// The table `columns` (name → float64 array) named `name`.
    pub fn new(py: Python<'py>, name: String, columns: &Bound<'py, PyDict>) -> PyResult<Self> {
        let mut table = Self {
            name,
            columns: HashMap::new(),
            rows: 0,
        };
        let mut first: Option<String> = None;
        for (key, value) in columns.iter() {
            let key: String = key.extract()?;
            let array: PyReadonlyArray1<'py, f64> = value.extract().map_err(|_| {
                table.error(py, &key, "not a one-dimensional array of float64", "format")
            })?;
            let n = array.len();
            match &first {
                None => {
                    table.rows = n;
                    first = Some(key.clone());
                }
                Some(f) if n != table.rows => {
                    let m = format!("{n} values where column {f:?} holds {}", table.rows);
                    return Err(table.error(py, &key, &m, "malformed record"));
                }
                Some(_) => {}
            }
            table.columns.insert(key, array);
        }
        Ok(table)
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// An `InputError` about column `column` of this table.
    fn error(&self, py: Python<'_>, column: &str, what: &str, reason: &str) -> PyErr {
        let field = format!("column {column:?}");
        raise(
            py,
            "InputError",
            &format!("{}: {field}: {what}", self.name),
            2,
            &[
                ("file", Some(self.name.clone())),
                ("field", Some(field)),
                ("reason", Some(reason.to_string())),
            ],
        )
    }

    /// The values of column `name`, or `None` when the table has no such column.
    fn column(&self, py: Python<'_>, name: &str) -> PyResult<Option<&[f64]>> {
        match self.columns.get(name) {
            None => Ok(None),
            Some(a) => a.as_slice().map(Some).map_err(|_| {
                self.error(
                    py,
                    name,
                    "not a contiguous array (pass a C-ordered copy)",
                    "format",
                )
            }),
        }
    }

    /// The values of the required column `name`.
    fn required(&self, py: Python<'_>, name: &str, what: &str) -> PyResult<&[f64]> {
        self.column(py, name)?.ok_or_else(|| {
            let m = format!("no such column: the {what} is required (see the data contract)");
            self.error(py, name, &m, "missing signal")
        })
    }

    /// All of `names`, or none of them (an optional group of signals).
    fn group(&self, py: Python<'_>, names: &[String], what: &str) -> PyResult<Vec<&[f64]>> {
        let found: Vec<Option<&[f64]>> = names
            .iter()
            .map(|n| self.column(py, n))
            .collect::<PyResult<_>>()?;
        match found.iter().position(Option::is_none) {
            None => Ok(found.into_iter().flatten().collect()),
            Some(_) if found.iter().all(Option::is_none) => Ok(Vec::new()),
            Some(k) => {
                let m =
                    format!("no such column, while others of the {what} are given (all or none)");
                Err(self.error(py, &names[k], &m, "missing signal"))
            }
        }
    }

    /// The table as consecutive chunks of [`CHUNK_SAMPLES`] samples (the last shorter).
    /// Values are not checked here: a fit checks them at the library's boundary
    /// ([`mrsysid::MemoryLog`]), a prediction returns what the model gives.
    pub fn chunks(&self, py: Python<'_>, needs: Needs) -> PyResult<Vec<SampleChunk>> {
        let index: Vec<f64>;
        let t = match (self.column(py, "t")?, needs.time) {
            (Some(t), _) => t,
            (None, true) => self.required(py, "t", "time (s)")?,
            (None, false) => {
                index = (0..self.rows).map(|k| k as f64).collect();
                &index
            }
        };
        let get = |names: &[&str], what: &str| -> PyResult<Vec<&[f64]>> {
            names.iter().map(|n| self.required(py, n, what)).collect()
        };
        let velocity = get(&VELOCITY, "air-relative body velocity (m/s)")?;
        let rates = get(&RATES, "body rate (rad/s)")?;
        let omega_names: Vec<String> = (1..=needs.rotors).map(|i| format!("omega_{i}")).collect();
        let omega: Vec<&[f64]> = omega_names
            .iter()
            .map(|n| self.required(py, n, "rotor speed (rad/s) of every rotor of the vehicle"))
            .collect::<PyResult<_>>()?;
        let omega_dot_names: Vec<String> = (1..=needs.rotors)
            .map(|i| format!("omega_dot_{i}"))
            .collect();
        let omega_dot = self.group(py, &omega_dot_names, "rotor accelerations (rad/s²)")?;
        let wrench = if needs.wrench {
            get(&WRENCH, "measured force (N) and moment (N m)")?
        } else {
            Vec::new()
        };
        let height = self.column(py, "height")?;
        let attitude_names: Vec<String> = ATTITUDE.iter().map(|s| s.to_string()).collect();
        let attitude = self.group(py, &attitude_names, "attitude quaternion")?;

        let mut chunks = Vec::with_capacity(self.rows.div_ceil(CHUNK_SAMPLES));
        let mut start = 0;
        while start < self.rows {
            let r = start..(start + CHUNK_SAMPLES).min(self.rows);
            let n = r.len();
            let take = |v: &[f64]| v[r.clone()].to_vec();
            let three = |v: &[&[f64]]| [take(v[0]), take(v[1]), take(v[2])];
            chunks.push(SampleChunk {
                t: take(t),
                velocity: three(&velocity),
                rates: three(&rates),
                omega: omega.iter().map(|v| take(v)).collect(),
                omega_dot: (!omega_dot.is_empty())
                    .then(|| omega_dot.iter().map(|v| take(v)).collect()),
                wrench: std::array::from_fn(|a| {
                    wrench.get(a).map_or_else(|| vec![0.0; n], |v| take(v))
                }),
                height: height.map(take),
                attitude: (!attitude.is_empty())
                    .then(|| std::array::from_fn(|k| take(attitude[k]))),
                ..SampleChunk::default()
            });
            start = r.end;
        }
        Ok(chunks)
    }
}
