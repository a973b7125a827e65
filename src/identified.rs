//! An identified model: vehicle, Eq. 22 variant and estimated parameters, saved as a TOML
//! model file and evaluated by downstream tools (`predict(state, rotor speeds) -> F, M`).

use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::model::{Column, ModelError, ModelOptions, ModelStructure, Parameter, Workspace};
use crate::sample::{Axis, Sample, SampleChunk};
use crate::util::write_atomically;
use crate::vehicle::{Vehicle, VehicleDefinition, VehicleSource};

/// Version of the model-file layout written by [`IdentifiedModel::save`].
pub const MODEL_FILE_VERSION: u32 = 1;

/// One estimated parameter as stored in the model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredParameter {
    /// Parameter name (e.g. `C_T0`).
    pub name: String,
    /// Unit of the estimate ("-" for dimensionless).
    pub unit: String,
    /// Estimate θ̂.
    pub estimate: f64,
    /// Standard deviation σ(θ̂), same unit.
    pub std: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    schema_version: u32,
    vehicle: VehicleDefinition,
    model: ModelOptions,
    /// Parameters beyond Eq. 22 (effects added by the diagnosis), with their columns.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    extra: Vec<ExtraParameter>,
    /// Terms of Eq. 22 and of `extra` left out of the model (not supported by held-out
    /// data); a parameter without any term left is not in the model.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    left_out: Vec<LeftOutTerm>,
    parameters: Vec<StoredParameter>,
    /// Parameter covariance (coloured-residual corrected), rows in `parameters` order;
    /// absent in files written without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    covariance: Option<Vec<Vec<f64>>>,
    /// The cut-off (Hz) at which the fit logs' loads were low-passed and the regressor
    /// signals with them; absent when they were not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    loads_low_pass_hz: Option<f64>,
}

/// A parameter's columns on one axis, left out of the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct LeftOutTerm {
    parameter: String,
    axis: Axis,
}

/// A parameter added to the Eq. 22 structure, stored with its regressor columns.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExtraParameter {
    name: String,
    unit: String,
    columns: Vec<Column>,
}

/// A model file that could not be read or written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ModelFileError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong.
    pub message: String,
}

/// Vehicle + model structure + estimated parameters (and their covariance when known):
/// saved, loaded and evaluated by downstream tools.
///
/// ```
/// use mrsysid::{Identification, IdentifiedModel, Sample, Vehicle};
/// # fn main() -> Result<(), mrsysid::Error> {
/// let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
/// let vehicle = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml"))?;
/// let model = Identification::new(vehicle)
///     .log(root.join("data/quad_x_sweep.csv"))
///     .diagnose(false)
///     .run()?
///     .to_identified_model();
/// let path = std::env::temp_dir().join(format!("doc-model-{}.toml", std::process::id()));
/// model.save(&path)?;
/// let back = IdentifiedModel::load(&path)?;
/// // 5 m/s forward at hover rotor speeds (rad/s); Ω̇ = 0 for the J_z terms.
/// let state = Sample {
///     velocity: [5.0, 0.0, 0.0],
///     omega: vec![1200.0; 4],
///     omega_dot: vec![0.0; 4],
///     ..Sample::default()
/// };
/// assert_eq!(back.predict(&state)?, model.predict(&state)?, "TOML keeps f64 exactly");
/// let sigma = back.prediction_std(&state)?.expect("the covariance is saved");
/// assert!(sigma.iter().all(|s| s.is_finite() && *s >= 0.0));
/// # std::fs::remove_file(&path).ok();
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone)]
pub struct IdentifiedModel {
    /// The vehicle.
    pub vehicle: Vehicle,
    /// The model structure the parameters belong to.
    pub structure: ModelStructure,
    /// Estimates and standard deviations, in `structure.params` order.
    pub parameters: Vec<StoredParameter>,
    /// Parameter covariance in `structure.params` order (coloured-residual corrected
    /// when it comes from [`crate::Results::to_identified_model`]), for prediction
    /// intervals; `None` when not known.
    pub covariance: Option<DMatrix<f64>>,
    /// The cut-off (Hz) at which the fit logs' loads had been low-passed, the regressor
    /// signals with them (consistent filtering, [`crate::io::LoadsProcessing`]);
    /// `predict`/`validate` on logs filter alike unless their mapping says otherwise.
    /// `None`: not filtered.
    pub loads_low_pass_hz: Option<f64>,
}

impl IdentifiedModel {
    /// A model from a structure and its estimates `theta` with standard deviations `std`
    /// (both in `structure.params` order).
    pub fn new(vehicle: Vehicle, structure: ModelStructure, theta: &[f64], std: &[f64]) -> Self {
        let parameters = structure
            .params
            .iter()
            .zip(theta.iter().zip(std))
            .map(|(p, (&estimate, &std))| StoredParameter {
                name: p.name.clone(),
                unit: p.unit.clone(),
                estimate,
                std,
            })
            .collect();
        Self {
            vehicle,
            structure,
            parameters,
            covariance: None,
            loads_low_pass_hz: None,
        }
    }

    /// The model with parameter covariance `covariance` (n × n over
    /// `structure.params`, units products of the parameters' units).
    pub fn with_covariance(mut self, covariance: DMatrix<f64>) -> Self {
        self.covariance = Some(covariance);
        self
    }

    /// θ̂ in `structure.params` order.
    pub fn theta(&self) -> Vec<f64> {
        self.parameters.iter().map(|p| p.estimate).collect()
    }

    /// Reads a model file written by [`IdentifiedModel::save`].
    pub fn load(path: &Path) -> Result<Self, ModelFileError> {
        let err = |message: String| ModelFileError {
            path: path.to_path_buf(),
            message,
        };
        let text =
            std::fs::read_to_string(path).map_err(|e| err(format!("cannot read file: {e}")))?;
        let file: ModelFile = toml::from_str(&text)
            .map_err(|e| err(format!("not a model file: {}", e.message().trim())))?;
        if file.schema_version != MODEL_FILE_VERSION {
            return Err(err(format!(
                "schema_version {} is not supported (this build reads {MODEL_FILE_VERSION})",
                file.schema_version
            )));
        }
        let vehicle =
            Vehicle::from_definition(file.vehicle, VehicleSource::File(path.to_path_buf()))
                .map_err(|e| err(format!("[vehicle]: {}", e.kind)))?;
        let mut structure = ModelStructure::eq22(&vehicle, file.model);
        for x in file.extra {
            structure.add_parameter(
                Parameter {
                    name: x.name,
                    unit: x.unit,
                },
                x.columns,
            );
        }
        let structure = without(&structure, &file.left_out);
        let names: Vec<&str> = structure.params.iter().map(|p| p.name.as_str()).collect();
        let stored: Vec<&str> = file.parameters.iter().map(|p| p.name.as_str()).collect();
        if names != stored {
            return Err(err(format!(
                "parameters [{}] do not match the model's [{}]",
                stored.join(", "),
                names.join(", ")
            )));
        }
        if let Some(p) = file.parameters.iter().find(|p| !p.estimate.is_finite()) {
            return Err(err(format!(
                "parameter `{}`: estimate is not a finite number",
                p.name
            )));
        }
        let covariance = file
            .covariance
            .map(|rows| covariance_matrix(rows, names.len()))
            .transpose()
            .map_err(|e| err(e.to_string()))?;
        Ok(Self {
            vehicle,
            structure,
            parameters: file.parameters,
            covariance,
            loads_low_pass_hz: file.loads_low_pass_hz,
        })
    }

    /// Writes the model file (through a temporary file, so no partial file is left).
    pub fn save(&self, path: &Path) -> Result<(), ModelFileError> {
        let err = |message: String| ModelFileError {
            path: path.to_path_buf(),
            message,
        };
        let mut full = ModelStructure::eq22(&self.vehicle, self.structure.options);
        let is_eq22 = |name: &str| full.param_id(name).is_some();
        let extra: Vec<ExtraParameter> = self
            .structure
            .param_ids()
            .filter(|&p| !is_eq22(&self.structure.param(p).name))
            .map(|p| ExtraParameter {
                name: self.structure.param(p).name.clone(),
                unit: self.structure.param(p).unit.clone(),
                columns: self
                    .structure
                    .columns
                    .iter()
                    .filter(|c| c.param == p)
                    .cloned()
                    .collect(),
            })
            .collect();
        for x in &extra {
            full.add_parameter(
                Parameter {
                    name: x.name.clone(),
                    unit: x.unit.clone(),
                },
                x.columns.clone(),
            );
        }
        let term = |s: &ModelStructure, c: &Column| (s.param(c.param).name.clone(), c.axis);
        let mut kept: Vec<(String, Axis)> = self
            .structure
            .columns
            .iter()
            .map(|c| term(&self.structure, c))
            .collect();
        kept.sort();
        let mut left_out: Vec<LeftOutTerm> = full
            .columns
            .iter()
            .map(|c| term(&full, c))
            .filter(|t| kept.binary_search(t).is_err())
            .map(|(parameter, axis)| LeftOutTerm { parameter, axis })
            .collect();
        left_out.dedup();
        let file = ModelFile {
            schema_version: MODEL_FILE_VERSION,
            vehicle: self.vehicle.definition(),
            model: self.structure.options,
            extra,
            left_out,
            parameters: self.parameters.clone(),
            covariance: self.covariance.as_ref().map(|c| {
                (0..c.nrows())
                    .map(|i| c.row(i).iter().copied().collect())
                    .collect()
            }),
            loads_low_pass_hz: self.loads_low_pass_hz,
        };
        let text = toml::to_string(&file).map_err(|e| err(e.to_string()))?;
        write_atomically(path, text.as_bytes()).map_err(|e| err(format!("cannot write file: {e}")))
    }

    /// Force and moment `[F_x, F_y, F_z, M_x, M_y, M_z]` (N, N m, body axes) in the
    /// state of `sample`: air-relative body velocity (m/s), rates (rad/s), rotor speeds
    /// (rad/s), and where the model's terms need them rotor accelerations (rad/s²), CG
    /// height (m) and attitude; its measured force and moment are ignored.
    pub fn predict(&self, sample: &Sample) -> Result<[f64; 6], ModelError> {
        let state = Sample {
            wrench: [0.0; 6],
            ..sample.clone()
        };
        self.structure.predict(&self.theta(), &state)
    }

    /// Standard deviation of the predicted mean force and moment in the state of
    /// `sample` (N, N m), √(xᵀ C x) per axis from the parameter covariance C: the
    /// model's parameter uncertainty, without the residual noise. `None` without a
    /// covariance.
    pub fn prediction_std(&self, sample: &Sample) -> Result<Option<[f64; 6]>, ModelError> {
        let Some(c) = &self.covariance else {
            return Ok(None);
        };
        let mut chunk =
            SampleChunk::with_capacity(sample.omega.len(), 1, !sample.omega_dot.is_empty());
        chunk.push(sample);
        let mut ws = Workspace::default();
        self.structure.assemble(&chunk, &mut ws)?;
        let n = self.structure.params.len();
        Ok(Some(Axis::ALL.map(|axis| {
            // Sensitivity of the axis' output to each parameter.
            let mut x = vec![0.0; n];
            for j in self.structure.axis_columns(axis) {
                x[self.structure.columns[j].param.index()] += ws.column(j)[0];
            }
            let x = DVector::from_vec(x);
            (x.transpose() * c * &x)[(0, 0)].max(0.0).sqrt()
        })))
    }

    /// Model output for every sample of `chunk`, in [`Axis`] order (N, N m), using `ws`
    /// as scratch space.
    pub fn predict_chunk(
        &self,
        chunk: &SampleChunk,
        ws: &mut Workspace,
    ) -> Result<[Vec<f64>; 6], ModelError> {
        self.structure.predict_chunk(&self.theta(), chunk, ws)
    }
}

/// `structure` without the columns of the `left_out` terms, and without the parameters
/// left with no column.
fn without(structure: &ModelStructure, left_out: &[LeftOutTerm]) -> ModelStructure {
    let keep: Vec<usize> = (0..structure.columns.len())
        .filter(|&j| {
            let c = &structure.columns[j];
            !left_out
                .iter()
                .any(|t| t.axis == c.axis && t.parameter == structure.param(c.param).name)
        })
        .collect();
    structure.select_columns(&keep)
}

/// Why a model file's covariance rows are not the parameters' covariance matrix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum CovarianceError {
    /// Not n rows of n values for n parameters.
    #[error("covariance: expected {0} rows of {0} values (one per parameter)")]
    Shape(usize),
    /// A value that is NaN or infinite.
    #[error("covariance: a value is not a finite number")]
    NotFinite,
}

/// The stored covariance rows as an n × n matrix, or why they are not one.
fn covariance_matrix(rows: Vec<Vec<f64>>, n: usize) -> Result<DMatrix<f64>, CovarianceError> {
    if rows.len() != n || rows.iter().any(|r| r.len() != n) {
        return Err(CovarianceError::Shape(n));
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(CovarianceError::NotFinite);
    }
    Ok(DMatrix::from_fn(n, n, |i, j| rows[i][j]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stored rows of the wrong shape or with a non-finite value are refused, in the
    /// words the model file's error carries.
    #[test]
    fn covariance_rows_are_checked() {
        let words = |rows: Vec<Vec<f64>>| covariance_matrix(rows, 2).map_err(|e| e.to_string());
        assert_eq!(
            words(vec![vec![1.0, 0.0], vec![0.0, 2.0]]),
            Ok(DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 2.0]))
        );
        assert_eq!(
            words(vec![vec![1.0, 0.0]]),
            Err("covariance: expected 2 rows of 2 values (one per parameter)".into())
        );
        assert_eq!(
            words(vec![vec![1.0, 0.0], vec![0.0, f64::NAN]]),
            Err("covariance: a value is not a finite number".into())
        );
    }
}
