//! The library's front door: [`Identification`] builds a fit request from a vehicle and
//! its logs (files, or samples in memory), runs the whole pipeline of `mrsysid fit`
//! (cross-validation, coloured-residual correction, the closing-the-loop diagnosis) and
//! returns [`Results`] for the final model.
//!
//! The same data fitted from a file and from samples parsed by the caller's own code
//! give the same bits: both pass through the same chunking, statistics and decisions.
//!
//! ```
//! use mrsysid::{Identification, Sample, Vehicle};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
//! let vehicle = Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml"))?;
//! let csv = root.join("data/quad_x_flight_quadratic_drag.csv");
//!
//! // The caller's own parser: a contract CSV by column name.
//! let text = std::fs::read_to_string(&csv)?;
//! let mut lines = text.lines();
//! let header: Vec<&str> = lines.next().unwrap().split(',').collect();
//! let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
//! let mut samples = Vec::new();
//! for line in lines {
//!     let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
//!     let get = |name: &str| f[col(name)];
//!     let rotors = |prefix: &str| (1..=4).map(|i| get(&format!("{prefix}_{i}"))).collect();
//!     samples.push(Sample {
//!         t: get("t"),
//!         velocity: [get("u"), get("v"), get("w")],
//!         rates: [get("p"), get("q"), get("r")],
//!         omega: rotors("omega"),
//!         omega_dot: rotors("omega_dot"),
//!         wrench: ["fx", "fy", "fz", "mx", "my", "mz"].map(get),
//!         height: Some(get("height")),
//!         attitude: Some(["qw", "qx", "qy", "qz"].map(get)),
//!     });
//! }
//!
//! let request = Identification::new(vehicle).threads(1);
//! let from_file = request.clone().log(csv).run()?;
//! let from_memory = request.samples("flight in memory", samples).run()?;
//! assert_eq!(from_file.theta(), from_memory.theta());
//! assert_eq!(from_file.covariance(), from_memory.covariance());
//! assert_eq!(from_file.outcome().diagnosis, from_memory.outcome().diagnosis);
//! let c_t0 = from_memory.parameter("C_T0").expect("an Eq. 22 parameter");
//! assert!(c_t0.estimate > 0.0 && c_t0.p_value < 1e-6);
//! println!("{}", from_memory.equations());
//! # Ok(())
//! # }
//! ```

use std::borrow::Cow;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use nalgebra::DMatrix;

use crate::diagnose::DiagnoseOptions;
use crate::error::Error;
use crate::estimate::{self, AxisMetrics, FitOptions};
use crate::identified::IdentifiedModel;
use crate::io::{IoError, Mapping, ReadOptions};
use crate::loads_scan::LowPassScan;
use crate::model::{ModelOptions, ModelStructure, ParamId, ParamOrigin, Workspace};
use crate::pipeline::{
    self, FitOutcome, FitRequest, Holdout, PassPlan, PendingFit, PlannedFit, PreparedPass,
    RemainderPart, StatsPart,
};
use crate::progress::Progress;
use crate::report::summary::Report;
use crate::report::tables;
use crate::sample::{Axis, Sample, SampleChunk};
use crate::source::{LogSource, MemoryLog};
use crate::vehicle::Vehicle;

/// A fit request, built step by step; [`Identification::run`] carries it out.
///
/// Defaults: the Eq. 22 structure of the vehicle with [`ModelOptions::default`], the
/// diagnosis on, the residual pass on, every available core, contract CSV logs (no
/// mapping), the contiguous cross-validation blocks of [`Holdout::DEFAULT`] when only one
/// log is fitted.
/// With two or more fit logs every decision is cross-validated by leaving one log out;
/// logs given to [`Identification::validate`] are only reported on.
#[derive(Debug, Clone)]
pub struct Identification {
    request: FitRequest,
    /// The first malformed in-memory sample given, reported by `run`.
    bad_samples: Option<IoError>,
    /// Whether `run` estimates the loads' low-pass cut-off ([`crate::loads_scan`]).
    estimate_low_pass: bool,
}

impl Identification {
    /// A request for `vehicle` with the defaults above and no log yet.
    pub fn new(vehicle: Vehicle) -> Self {
        let structure = ModelStructure::eq22(&vehicle, ModelOptions::default());
        Self {
            request: FitRequest {
                logs: Vec::new(),
                vehicle,
                mapping: None,
                read: ReadOptions::default(),
                structure,
                fit: FitOptions::default(),
                holdout: Holdout::default(),
                validate: Vec::new(),
                groups: Vec::new(),
                threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
                second_pass: true,
                diagnose: Some(DiagnoseOptions::default()),
                progress: None,
                cancel: None,
                loads_low_pass_hz: None,
            },
            bad_samples: None,
            estimate_low_pass: false,
        }
    }

    /// Cross-validation groups, one name per fit log in the order the logs are added:
    /// the logs of a group are left out together (e.g. one group per flight day).
    /// Without it each log is its own fold. Checked when the fit runs
    /// ([`crate::RequestError::InvalidGroups`]).
    pub fn groups<S: Into<String>>(mut self, groups: impl IntoIterator<Item = S>) -> Self {
        self.request.groups = groups.into_iter().map(Into::into).collect();
        self
    }

    /// The Eq. 22 variant to fit (inflow correction, linear V_h terms, J_z terms).
    pub fn model_options(mut self, options: ModelOptions) -> Self {
        self.request.structure = ModelStructure::eq22(&self.request.vehicle, options);
        self
    }

    /// A structure of your own (e.g. Eq. 22 with added parameters); it must be built
    /// from this vehicle, which `run` checks.
    pub fn structure(mut self, structure: ModelStructure) -> Self {
        self.request.structure = structure;
        self
    }

    /// Adds a log to fit: a file path, or a [`MemoryLog`].
    pub fn log(mut self, log: impl Into<LogSource>) -> Self {
        self.request.logs.push(log.into());
        self
    }

    /// Adds logs to fit.
    pub fn logs<L: Into<LogSource>>(mut self, logs: impl IntoIterator<Item = L>) -> Self {
        self.request.logs.extend(logs.into_iter().map(Into::into));
        self
    }

    /// Adds a log to fit from samples in memory, named `name` in reports and errors.
    /// The samples are checked here; the first malformed one is reported by `run`.
    pub fn samples(self, name: &str, samples: impl IntoIterator<Item = Sample>) -> Self {
        match MemoryLog::from_samples(name, samples) {
            Ok(log) => self.log(log),
            Err(e) => self.refuse(e),
        }
    }

    /// Adds a reporting-only validation log (no decision sees it): a path or a
    /// [`MemoryLog`].
    pub fn validate(mut self, log: impl Into<LogSource>) -> Self {
        self.request.validate.push(log.into());
        self
    }

    /// Adds a reporting-only validation log from samples in memory.
    pub fn validate_samples(self, name: &str, samples: impl IntoIterator<Item = Sample>) -> Self {
        match MemoryLog::from_samples(name, samples) {
            Ok(log) => self.validate(log),
            Err(e) => self.refuse(e),
        }
    }

    fn refuse(mut self, e: IoError) -> Self {
        self.bad_samples.get_or_insert(e);
        self
    }

    /// Mapping for log files that do not follow the CSV contract (and for MCAP, ULog).
    pub fn mapping(mut self, mapping: Mapping) -> Self {
        self.request.mapping = Some(mapping);
        self
    }

    /// Reader options (invalid-sample policy, gap length, derivations).
    pub fn read_options(mut self, read: ReadOptions) -> Self {
        self.request.read = read;
        self
    }

    /// Estimation options (rank tolerance, unidentifiable-parameter policy, F_in).
    pub fn fit_options(mut self, fit: FitOptions) -> Self {
        self.request.fit = fit;
        self
    }

    /// The logs' loads were low-passed at `hz` (−3 dB, Hz, > 0) when they were made: the
    /// regressor signals pass through the same kind of zero-phase filter (consistent
    /// filtering; overrides a mapping file's `[loads] low_pass_hz`). The final model
    /// remembers it, so `predict`/`validate` on logs made the same way filter alike.
    pub fn loads_low_pass(mut self, hz: f64) -> Self {
        self.request.loads_low_pass_hz = Some(hz);
        self
    }

    /// The logs' loads were low-passed when they were made, at a cut-off the user does
    /// not know: `run` fits the logs unfiltered and with the regressor signals low-passed
    /// at each cut-off of a grid (64 Hz down to 2 Hz in steps of √2, up to a quarter of
    /// the sample rate), keeps the one whose final model predicts held-out loads best
    /// (mean ln RMSE over the axes, at least 0.5 % better than unfiltered, else none) and
    /// reports the scan ([`Results::loads_low_pass_scan`]). Costs up to twelve fits; a
    /// [`Identification::progress`] counter counts the samples of all of them.
    /// Overrides [`Identification::loads_low_pass`] and a mapping's `[loads]`.
    pub fn estimate_loads_low_pass(mut self) -> Self {
        self.estimate_low_pass = true;
        self
    }

    /// Hold-out segments of a single fit log.
    pub fn holdout(mut self, holdout: Holdout) -> Self {
        self.request.holdout = holdout;
        self
    }

    /// Threads for reading and accumulating, and for the diagnosis's screening and trial
    /// fits (at least 1). Results do not depend on it.
    pub fn threads(mut self, threads: usize) -> Self {
        self.request.threads = threads.max(1);
        self
    }

    /// Runs the closing-the-loop diagnosis (default) or not.
    pub fn diagnose(mut self, on: bool) -> Self {
        self.request.diagnose = on.then(DiagnoseOptions::default);
        self
    }

    /// Runs the diagnosis with these options.
    pub fn diagnose_options(mut self, options: DiagnoseOptions) -> Self {
        self.request.diagnose = Some(options);
        self
    }

    /// Runs the second pass (residual diagnostics, coloured-residual correction, plot
    /// series; default) or not. The diagnosis runs it regardless.
    pub fn residual_pass(mut self, on: bool) -> Self {
        self.request.second_pass = on;
        self
    }

    /// Where `run` says what it has done so far, for a progress display on another
    /// thread: the phase under way, bytes of the first pass and samples of the later
    /// passes done of their total.
    pub fn progress(mut self, progress: Arc<Progress>) -> Self {
        self.request.progress = Some(progress);
        self
    }

    /// A cancellation flag: once set (from any thread), `run` stops before the next
    /// chunk of data it would read or pass and returns
    /// [`crate::error::RequestError::Cancelled`]. Chunks are [`crate::CHUNK_SAMPLES`]
    /// samples, so a fit stops within milliseconds while it streams data; estimation
    /// steps between passes (solves on the merged statistics) run to their end.
    pub fn cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.request.cancel = Some(flag);
        self
    }

    /// Reads the fit logs (not the validation logs) and returns each one's first pass as
    /// statistics: a part that can be saved, sent, merged with the parts of other logs
    /// made with the same settings, and fitted by [`Identification::run_from_stats`]
    /// (statistics as data: one task per log, a merge, one fit). With the diagnosis on
    /// (the default) each log's part also keeps its thinned samples (up to 20 000), which
    /// a diagnosis from statistics needs ([`Identification::plan_from_stats`]);
    /// `diagnose(false)` makes parts of about 25 kB a log for the Eq. 22 fit alone. Logs
    /// are checked as [`Identification::run`] checks them.
    pub fn accumulate(&self) -> Result<StatsPart, Error> {
        if let Some(e) = &self.bad_samples {
            return Err(e.clone().into());
        }
        pipeline::accumulate(&self.request)
    }

    /// Fits the logs of `fit` (at least two; leave-one-log-out cross-validation) and
    /// reports on those of `validate`, from their statistics alone: the result equals
    /// [`Identification::run`] on the same logs with [`Identification::residual_pass`]
    /// off and without the diagnosis, which need the samples again. The builder's logs
    /// are ignored; its vehicle, mapping and options must be those the parts were made
    /// with ([`crate::StatsError::OtherSettings`] otherwise), and an estimated cut-off
    /// is not available (declare it).
    pub fn run_from_stats(
        &self,
        fit: &StatsPart,
        validate: Option<&StatsPart>,
    ) -> Result<Results, Error> {
        let outcome = pipeline::run_from_parts(&self.request, fit, validate)?;
        Ok(self.results_from_stats(outcome))
    }

    /// The results of a fit from statistics.
    fn results_from_stats(&self, outcome: FitOutcome) -> Results {
        Results {
            vehicle: self.request.vehicle.clone(),
            base: self.request.structure.clone(),
            outcome,
            loads_low_pass_hz: self.request.effective_loads_low_pass(),
            loads_low_pass_scan: None,
        }
    }

    /// The Eq. 22 fit of the logs of `fit` (at least two) and `validate` from their
    /// parts, made with the diagnosis on (the default), and the plan of their second
    /// pass: the driver's first step of the diagnosis from statistics. Each worker
    /// prepares the plan ([`Identification::prepare_pass`]) and passes its logs
    /// ([`PreparedPass::pass_part`]); [`PlannedFit::diagnose`] reduces those parts into
    /// a [`PendingFit`] that waits for the remainder pass
    /// ([`PendingFit::remainder_plan`], [`PreparedPass::remainder_part`]) before
    /// [`Identification::finish_from_stats`]. The results equal
    /// [`Identification::run`] of the same logs in the same order, less the plot series.
    pub fn plan_from_stats(
        &self,
        fit: &StatsPart,
        validate: Option<&StatsPart>,
    ) -> Result<PlannedFit, Error> {
        pipeline::plan_fit(&self.request, fit, validate)
    }

    /// `plan` prepared for passing its logs ([`PreparedPass::pass_part`]) and, after
    /// the diagnosis, their remainder ([`PreparedPass::remainder_part`]): once per
    /// process, as it fits Eq. 22 and builds the candidate effects.
    pub fn prepare_pass(&self, plan: PassPlan) -> Result<PreparedPass, Error> {
        PreparedPass::new(&self.request, plan)
    }

    /// The results of `pending` with the remainder parts `parts` (one per fit log of
    /// [`PendingFit::remainder_plan`]; none when it is `None`).
    pub fn finish_from_stats(
        &self,
        pending: PendingFit,
        parts: &[RemainderPart],
    ) -> Result<Results, Error> {
        pending.finish(parts).map(|o| self.results_from_stats(o))
    }

    /// The request as built.
    pub fn request(&self) -> &FitRequest {
        &self.request
    }

    /// Reads the logs, fits, cross-validates and diagnoses. Before reading, a log given
    /// twice among the fit logs (the same file, a copy, the same samples in memory) and a
    /// validation log that is also a fit log are refused
    /// ([`crate::error::RequestError::DuplicateLog`],
    /// [`crate::error::RequestError::ValidationIsFitLog`]): their cross-validated or
    /// validation figures would be in-sample.
    pub fn run(&self) -> Result<Results, Error> {
        if let Some(e) = &self.bad_samples {
            return Err(e.clone().into());
        }
        let mut request = self.request.clone();
        let (scan, outcome) = if self.estimate_low_pass {
            let (scan, kept_fit) = crate::loads_scan::scan(&request)?;
            request.loads_low_pass_hz = scan.chosen_hz;
            if let Some(m) = request.mapping.as_mut() {
                m.loads = None;
            }
            // The trial at the cut-off kept is this fit, unless validation logs (which
            // no trial reads) are to be reported on.
            let outcome = if request.validate.is_empty() {
                kept_fit
            } else {
                if let Some(p) = &request.progress {
                    p.start_scan_fit(scan.chosen_hz);
                }
                pipeline::run(&request)?
            };
            (Some(scan), outcome)
        } else {
            (None, pipeline::run(&request)?)
        };
        Ok(Results {
            vehicle: request.vehicle.clone(),
            base: request.structure.clone(),
            outcome,
            loads_low_pass_hz: request.effective_loads_low_pass(),
            loads_low_pass_scan: scan,
        })
    }
}

/// One parameter of the final model, in the spirit of a regression results table.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterResult {
    /// Name (e.g. `C_T0`).
    pub name: String,
    /// Unit of the estimate and σ ("-" for dimensionless coefficients).
    pub unit: String,
    /// θ̂.
    pub estimate: f64,
    /// σ(θ̂) for white residuals, from (Hᵀ(R⁻¹⊗I)H)⁻¹ (seed Eq. 24).
    pub std_white: f64,
    /// σ(θ̂) with the coloured-residual correction √κ · `std_white` (see
    /// [`Results::variance_inflation`]): the one to use on flight data.
    pub std: f64,
    /// t₀ = θ̂/`std`.
    pub t: f64,
    /// Two-sided P-value of H₀: θ = 0 from `t` (Student's t, N − n_θ degrees of freedom).
    pub p_value: f64,
    /// 95 % confidence interval θ̂ ± t(0.975)·`std`.
    pub ci95: [f64; 2],
}

/// Akaike and Bayesian information criteria of one axis' fit, Gaussian residuals:
/// AIC = N ln(SSE/N) + 2k, BIC = N ln(SSE/N) + k ln N, with k the parameters that have a
/// column on the axis. Residuals of flight data are coloured, so compare models on the
/// same data only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InformationCriteria {
    /// Output axis.
    pub axis: Axis,
    /// Parameters with a column on the axis.
    pub parameters: usize,
    /// AIC (dimensionless).
    pub aic: f64,
    /// BIC (dimensionless).
    pub bic: f64,
}

/// What [`Identification::run`] produced: the final model (Eq. 22 after the diagnosis
/// when it ran) with its statistics, and everything the pipeline computed on the way.
#[derive(Debug, Clone)]
pub struct Results {
    vehicle: Vehicle,
    base: ModelStructure,
    outcome: FitOutcome,
    /// The cut-off the regressor signals were low-passed at, Hz.
    loads_low_pass_hz: Option<f64>,
    /// The cut-offs tried when the cut-off was estimated.
    loads_low_pass_scan: Option<LowPassScan>,
}

impl Results {
    /// Everything the pipeline computed: the Eq. 22 fit (FSOA tables, MMR), its
    /// cross-validation, residual diagnostics, the diagnosis, plot series, reader
    /// summaries.
    pub fn outcome(&self) -> &FitOutcome {
        &self.outcome
    }

    /// The cut-off (Hz) the regressor signals were low-passed at (consistent
    /// filtering: declared, or estimated), `None` when they were not filtered.
    pub fn loads_low_pass_hz(&self) -> Option<f64> {
        self.loads_low_pass_hz
    }

    /// The cut-offs tried and their held-out scores, when the cut-off was estimated
    /// ([`Identification::estimate_loads_low_pass`]).
    pub fn loads_low_pass_scan(&self) -> Option<&LowPassScan> {
        self.loads_low_pass_scan.as_ref()
    }

    /// The vehicle.
    pub fn vehicle(&self) -> &Vehicle {
        &self.vehicle
    }

    /// The final model's structure: the diagnosed one (effects added, unsupported terms
    /// left out) when the diagnosis ran, else Eq. 22. The adopted model, which predicts
    /// with Eq. 22 any axis whose held-out data the final model predicted worse
    /// ([`crate::internals::diagnose::Eq22Axes`]), is [`Results::to_identified_model`]'s.
    pub fn structure(&self) -> &ModelStructure {
        match &self.outcome.diagnosis {
            Some(d) => &d.structure,
            None => &self.base,
        }
    }

    /// The final model's estimation on all fit data (FSOA tables, MMR estimates and
    /// white-residual covariance, fit metrics).
    pub fn estimation(&self) -> &estimate::Fit {
        match &self.outcome.diagnosis {
            Some(d) => &d.fit,
            None => &self.outcome.fit,
        }
    }

    /// Coloured-residual variance inflation κ ≥ 1 applied to σ² (1 without the residual
    /// pass).
    pub fn variance_inflation(&self) -> f64 {
        self.outcome.variance_inflation
    }

    /// Why σ, t and P carry no information for these data, when they do not.
    pub fn inference_withheld(&self) -> Option<&str> {
        self.estimation().mmr.inference_withheld.as_deref()
    }

    /// The estimated parameters of the final model, in structure order (parameters
    /// dropped as unidentifiable are listed in `estimation().identifiability`).
    pub fn parameters(&self) -> Vec<ParameterResult> {
        let mmr = &self.estimation().mmr;
        let scale = self.variance_inflation().max(1.0).sqrt();
        mmr.parameters
            .iter()
            .map(|p| {
                let std = p.std_error * scale;
                let t = p.estimate / std;
                let (p_value, t975) = estimate::inference::t_test(t, mmr.dof);
                ParameterResult {
                    name: p.name.clone(),
                    unit: p.unit.clone(),
                    estimate: p.estimate,
                    std_white: p.std_error,
                    std,
                    t,
                    p_value,
                    ci95: [p.estimate - t975 * std, p.estimate + t975 * std],
                }
            })
            .collect()
    }

    /// The estimated parameter named `name`, if the final model has it.
    pub fn parameter(&self, name: &str) -> Option<ParameterResult> {
        self.parameters().into_iter().find(|p| p.name == name)
    }

    /// θ̂ over all parameters of [`Results::structure`] (0 for dropped ones).
    pub fn theta(&self) -> &[f64] {
        &self.estimation().mmr.theta
    }

    /// Parameter covariance with the coloured-residual correction (κ times the white
    /// one), over all parameters of [`Results::structure`] in order; rows and columns
    /// of dropped parameters are zero. Units: products of the parameters' units.
    pub fn covariance(&self) -> DMatrix<f64> {
        corrected_covariance(
            self.estimation(),
            self.structure().params.len(),
            self.variance_inflation(),
        )
    }

    /// Goodness of fit of the adopted model on all fit data, per axis: the final model's,
    /// and the Eq. 22 model's on the axes it predicts
    /// ([`crate::internals::diagnose::Eq22Axes`]).
    pub fn fit_metrics(&self) -> [AxisMetrics; 6] {
        let mut metrics = self.estimation().metrics;
        if let Some(e) = self
            .outcome
            .diagnosis
            .as_ref()
            .and_then(|d| d.eq22.as_ref())
        {
            for &axis in &e.axes {
                metrics[axis as usize] = e.fit.metrics[axis as usize];
            }
        }
        metrics
    }

    /// Goodness of fit of the final model on data it was not fitted to: the
    /// reporting-only validation logs when given, else cross-validated (every fold's
    /// held-out predictions pooled).
    pub fn validation_metrics(&self) -> [AxisMetrics; 6] {
        match &self.outcome.diagnosis {
            Some(d) => d.validation.map_or(d.after, |v| v[1]),
            None => self.outcome.validation,
        }
    }

    /// AIC and BIC per axis of the final model on the fit data.
    pub fn information_criteria(&self) -> [InformationCriteria; 6] {
        let fit = self.estimation();
        let structure = self.structure();
        let n = fit.samples as f64;
        fit.metrics.map(|m| {
            let mut params: Vec<ParamId> = structure
                .axis_columns(m.axis)
                .map(|j| structure.columns[j].param)
                .filter(|p| fit.mmr.param_index.contains(p))
                .collect();
            params.sort_unstable();
            params.dedup();
            let k = params.len() as f64;
            let log_likelihood_term = n * (m.rmse * m.rmse).ln();
            InformationCriteria {
                axis: m.axis,
                parameters: params.len(),
                aic: log_likelihood_term + 2.0 * k,
                bic: log_likelihood_term + k * n.ln(),
            }
        })
    }

    /// The adopted model's output for every sample of `chunk` per axis (N, N m): the
    /// final model's, and the Eq. 22 model's on the axes it predicts better
    /// ([`crate::internals::diagnose::Eq22Axes`]).
    pub fn fitted(&self, chunk: &SampleChunk) -> Result<[Vec<f64>; 6], Error> {
        let (structure, theta) = self.adopted();
        let mut ws = Workspace::default();
        Ok(structure.predict_chunk(&theta, chunk, &mut ws)?)
    }

    /// The adopted model's structure and θ̂: the final model's, with the axes of
    /// [`crate::internals::diagnose::Eq22Axes`] predicted by the Eq. 22 model.
    fn adopted(&self) -> (Cow<'_, ModelStructure>, Cow<'_, [f64]>) {
        match &self.outcome.diagnosis {
            Some(d) if d.eq22.is_some() => {
                let (structure, theta) = d.adopted_theta();
                (Cow::Owned(structure), Cow::Owned(theta))
            }
            _ => (Cow::Borrowed(self.structure()), Cow::Borrowed(self.theta())),
        }
    }

    /// Measured minus fitted output for every sample of `chunk` per axis (N, N m).
    pub fn residuals(&self, chunk: &SampleChunk) -> Result<[Vec<f64>; 6], Error> {
        let mut y = self.fitted(chunk)?;
        for (a, col) in y.iter_mut().enumerate() {
            for (r, z) in col.iter_mut().zip(&chunk.wrench[a]) {
                *r = z - *r;
            }
        }
        Ok(y)
    }

    /// The report of `mrsysid fit` (serialisable to the JSON schema of
    /// `docs/report-schema.md`).
    pub fn report(&self) -> Report {
        let o = &self.outcome;
        let mut report = Report::new(
            &self.vehicle,
            &self.base,
            &o.fit,
            &o.validation,
            o.validation_samples,
            &o.validation_source,
            (&o.cross_validation.0, &o.cross_validation.1),
            o.diagnostics.as_ref(),
            o.diagnosis.as_ref(),
        );
        report.loads_low_pass_hz = self.loads_low_pass_hz;
        report.loads_low_pass_scan = self.loads_low_pass_scan.clone();
        report.airborne = o
            .summaries
            .iter()
            .filter_map(crate::report::summary::AirborneRow::of)
            .collect();
        report
    }

    /// The paper-style tables of `mrsysid fit` (FSOA, MMR estimates, fit metrics,
    /// diagnosis), followed by the final model's parameters.
    pub fn summary(&self) -> String {
        let mut out = tables::render(&self.report());
        out.push_str(&self.parameter_table());
        out
    }

    /// The final model's parameters: estimate, σ (coloured-corrected), t, P, 95 % CI.
    fn parameter_table(&self) -> String {
        use std::fmt::Write;
        let mut out = format!(
            "\nFinal model: {} parameters; σ with the coloured-residual correction (κ = {:.3})\n",
            self.estimation().mmr.parameters.len(),
            self.variance_inflation()
        );
        let _ = writeln!(
            out,
            "  {:<24} {:>13} {:>11} {:>9} {:>10}  {:<27} unit",
            "parameter", "estimate", "σ", "t", "P", "95 % CI"
        );
        for p in self.parameters() {
            let _ = writeln!(
                out,
                "  {:<24} {:>13.5e} {:>11.3e} {:>9.2} {:>10.2e}  [{:>11.4e}, {:>11.4e}] {}",
                p.name, p.estimate, p.std, p.t, p.p_value, p.ci95[0], p.ci95[1], p.unit
            );
        }
        out
    }

    /// The final model as equations, one per axis: `Fx [N] = θ·regressor + …`, with
    /// the estimates in place of θ (known terms, moved to the output side, noted).
    pub fn equations(&self) -> String {
        let (structure, theta) = self.adopted();
        let mut out = String::new();
        for axis in Axis::ALL {
            let mut line = format!("{axis} [{}] =", axis.unit());
            let mut first = true;
            for j in structure.axis_columns(axis) {
                let c = &structure.columns[j];
                let th = theta[c.param.index()];
                let sign = if th < 0.0 {
                    "-"
                } else if first {
                    ""
                } else {
                    "+"
                };
                let label = if c.label.contains([' ', '+', '-']) {
                    format!("({})", c.label)
                } else {
                    c.label.clone()
                };
                line.push_str(&format!(
                    " {sign} {:.5e}*{label} [{}]",
                    th.abs(),
                    structure.param(c.param).name
                ));
                first = false;
            }
            if first {
                line.push_str(" 0");
            }
            let known = structure.known[axis as usize].len();
            if known > 0 {
                line.push_str(&format!(" + {known} known term(s)"));
            }
            out.push_str(&line);
            out.push('\n');
        }
        out
    }

    /// The adopted model, ready to save, load and predict with: estimates, the
    /// coloured-corrected σ, and the coloured-corrected covariance. On the axes the
    /// Eq. 22 model predicts better ([`crate::internals::diagnose::Eq22Axes`]) its parameters are
    /// the Eq. 22 model's, copied to those axes (named `<parameter>@<axis> (Eq. 22)`);
    /// the covariance between them and the final model's parameters is left at zero, which
    /// no axis's prediction uses (each axis uses one of the two sets).
    pub fn to_identified_model(&self) -> IdentifiedModel {
        let diagnosis = self.outcome.diagnosis.as_ref();
        let (structure, theta, cov) = match diagnosis.and_then(|d| Some((d, d.eq22.as_ref()?))) {
            Some((d, e)) => {
                let (structure, origins) = d.adopted();
                let theta = d.adopted_values(&origins);
                let own = self.covariance();
                let inflation = self.variance_inflation();
                let eq22 = corrected_covariance(&e.fit, e.structure.params.len(), inflation);
                let cov = DMatrix::from_fn(origins.len(), origins.len(), |i, j| {
                    match (origins[i], origins[j]) {
                        (ParamOrigin::Own(a), ParamOrigin::Own(b)) => own[(a.index(), b.index())],
                        (ParamOrigin::Other(a), ParamOrigin::Other(b)) => {
                            eq22[(a.index(), b.index())]
                        }
                        _ => 0.0,
                    }
                });
                (structure, theta, cov)
            }
            None => (
                self.structure().clone(),
                self.theta().to_vec(),
                self.covariance(),
            ),
        };
        let std: Vec<f64> = (0..theta.len()).map(|i| cov[(i, i)].sqrt()).collect();
        let mut model = IdentifiedModel::new(self.vehicle.clone(), structure, &theta, &std)
            .with_covariance(cov);
        model.loads_low_pass_hz = self.loads_low_pass_hz;
        model
    }
}

/// The parameter covariance of `fit` with the coloured-residual correction (κ =
/// `variance_inflation`, at least 1, times the white one) over the `n` parameters of its
/// structure; rows and columns of dropped parameters are zero.
fn corrected_covariance(fit: &estimate::Fit, n: usize, variance_inflation: f64) -> DMatrix<f64> {
    let mmr = &fit.mmr;
    let k = mmr.param_index.len();
    let kappa = variance_inflation.max(1.0);
    let mut c = DMatrix::zeros(n, n);
    for (a, &i) in mmr.param_index.iter().enumerate() {
        for (b, &j) in mmr.param_index.iter().enumerate() {
            c[(i.index(), j.index())] = kappa * mmr.covariance[a * k + b];
        }
    }
    c
}
