//! The command handlers of the binary: read arguments, call the library, print and
//! write outputs (each output file written whole or not at all, and never over an
//! input; a closed stdout ends the printing quietly).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::progress_bar::with_progress;
use crate::{FitArgs, ModelArgs};
use mrsysid::io;
use mrsysid::report::plots::{
    self, AxisSeries, EffectResidual, FoldR2, NormalProbability, ResidualDensity,
};
use mrsysid::report::summary::AxisRow;
use mrsysid::report::tables;
use mrsysid::{
    Axis, FitOutcome, IdentifiedModel, Mapping, Report, ResidualDiagnostics, Results, Validation,
    Vehicle, same_file, write_atomically,
};
use statrs::distribution::{ContinuousCDF, Normal};

/// A failed command: message and process exit code (1 fit failed, 2 bad input).
pub struct Failure {
    pub code: u8,
    pub message: String,
}

impl Failure {
    pub fn input(message: String) -> Self {
        Self { code: 2, message }
    }

    pub fn fit(message: String) -> Self {
        Self { code: 1, message }
    }
}

/// Any library error: its message, and the exit code its variant maps to.
impl<E: Into<mrsysid::Error>> From<E> for Failure {
    fn from(e: E) -> Self {
        let e = e.into();
        Self {
            code: e.exit_code(),
            message: e.to_string(),
        }
    }
}

/// Set once stdout was found closed: nothing more is written to it.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Prints `text` on stdout. A closed stdout (the reading end of a pipe gone, as with
/// `| head`) is no error: printing stops quietly and the command goes on (its files are
/// still written) and exits 0. Any other write error fails the command.
pub fn print_out(text: &str) -> Result<(), Failure> {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return Ok(());
    }
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            STDOUT_CLOSED.store(true, Ordering::Relaxed);
            Ok(())
        }
        Err(e) => Err(Failure::input(format!("cannot write to stdout: {e}"))),
    }
}

/// Prints `line` and a line end on stderr; a closed stderr is ignored (nothing is left
/// to report it on).
pub fn print_err(line: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// `path` with its directory resolved (links, `..`) when that exists: two spellings of
/// one file yet to be written compare equal.
fn resolved(path: &Path) -> PathBuf {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (dir.canonicalize(), path.file_name()) {
        (Ok(d), Some(name)) => d.join(name),
        _ => path.to_path_buf(),
    }
}

/// Refuses, before any work, an output (option, path) that is the same file as an
/// input (role, path) — however spelled: links, `..` — and two outputs that are one
/// file: an input is never overwritten, an output never overwrites another.
pub fn check_outputs(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<(), Failure> {
    for (i, (option, out)) in outputs.iter().enumerate() {
        if let Some((role, input)) = inputs.iter().find(|(_, input)| same_file(out, input)) {
            return Err(Failure::input(format!(
                "{option} {} is the same file as the {role} {}: refusing to overwrite an input",
                out.display(),
                input.display()
            )));
        }
        let twin = outputs[i + 1..]
            .iter()
            .find(|(_, other)| same_file(out, other) || resolved(out) == resolved(other));
        if let Some((other, path)) = twin {
            return Err(Failure::input(format!(
                "{option} {} and {other} {} are the same file: give each output a file of its \
                 own",
                out.display(),
                path.display()
            )));
        }
    }
    Ok(())
}

/// File names (without extension) of the plots `fit --plots` writes; each is written as
/// `.svg` and `.png`.
const PLOT_STEMS: [&str; 6] = [
    "fit_time_histories",
    "validation_time_histories",
    "residual_density",
    "normal_probability",
    "cross_validation_r2",
    "added_effects",
];

pub fn load_mapping(path: Option<&Path>) -> Result<Option<Mapping>, Failure> {
    Ok(path.map(Mapping::from_toml_file).transpose()?)
}

/// The outputs of `fit` (for [`check_outputs`]): the JSON report, the model file, the
/// plot directory and the plot files in it.
pub fn fit_outputs(cmd: &FitArgs) -> Vec<(&'static str, PathBuf)> {
    let mut out = Vec::new();
    out.extend(cmd.json.iter().map(|p| ("--json", p.clone())));
    out.extend(cmd.model_out.iter().map(|p| ("--model-out", p.clone())));
    out.extend(cmd.plan_out.iter().map(|p| ("--plan-out", p.clone())));
    out.extend((cmd.remainder_plan_out.iter()).map(|p| ("--remainder-plan-out", p.clone())));
    if let Some(dir) = &cmd.plots {
        out.push(("--plots", dir.clone()));
        for stem in PLOT_STEMS {
            for ext in ["svg", "png"] {
                out.push(("--plots", dir.join(stem).with_extension(ext)));
            }
        }
    }
    out
}

/// `mrsysid fit` (and `diagnose`, which prints only the diagnosis) on logs; with
/// `--from-stats`, `stats_commands::fit_from_stats` runs instead.
pub fn fit(cmd: &FitArgs, diagnosis_only: bool) -> Result<(), Failure> {
    check_fit_outputs(cmd, ("fit log", "validation log"))?;
    let vehicle = Vehicle::from_toml_file(&cmd.model.vehicle)?;
    if !cmd.quiet {
        for note in vehicle.notes() {
            print_err(&format!("note: {}: {note}", cmd.model.vehicle.display()));
        }
    }
    if let Some(dir) = &cmd.plots {
        std::fs::create_dir_all(dir).map_err(|e| {
            Failure::input(format!(
                "{}: cannot create plot directory: {e}",
                dir.display()
            ))
        })?;
    }
    let job = cmd.identification(vehicle, load_mapping(cmd.model.mapping.as_deref())?);
    let (results, finished) = with_progress(job, cmd.quiet, |job| job.run());
    let results = results?;
    let report = results.report();
    if !cmd.quiet {
        print_reader_notes(results.outcome());
        print_out(&match (&report.diagnosis, diagnosis_only) {
            (Some(d), true) => tables::render_diagnosis(d),
            (None, true) => "diagnosis skipped (--no-diagnose)\n".to_string(),
            (_, false) => tables::render(&report),
        })?;
    }
    write_report_and_model(cmd, &results, &report)?;
    if let Some(dir) = &cmd.plots {
        write_plots(dir, results.outcome()).map_err(|e| Failure::input(e.to_string()))?;
    }
    if !cmd.quiet {
        print_err(&finished.line("fit", cmd.logs.len() + cmd.validate.len()));
    }
    Ok(())
}

/// The vehicle and mapping files of `model` and the files `more` names, as inputs no
/// output may overwrite.
pub fn model_inputs<'a>(
    model: &'a ModelArgs,
    more: impl IntoIterator<Item = (&'static str, &'a Path)>,
) -> Vec<(&'static str, &'a Path)> {
    let mut inputs = vec![("vehicle file", model.vehicle.as_path())];
    inputs.extend(model.mapping.iter().map(|p| ("mapping file", p.as_path())));
    inputs.extend(more);
    inputs
}

/// Refuses a fit whose output would overwrite one of its inputs: the vehicle and mapping
/// files, the logs and the validation logs (called `kinds` in the message).
pub fn check_fit_outputs(
    cmd: &FitArgs,
    kinds: (&'static str, &'static str),
) -> Result<(), Failure> {
    let outputs = fit_outputs(cmd);
    let outputs: Vec<(&str, &Path)> = outputs.iter().map(|(o, p)| (*o, p.as_path())).collect();
    let logs = cmd.logs.iter().map(|p| (kinds.0, p.as_path()));
    let validate = cmd.validate.iter().map(|p| (kinds.1, p.as_path()));
    let passes = (cmd.passes.iter().map(|p| ("pass file", p.as_path()))).chain(
        cmd.remainders
            .iter()
            .map(|p| ("remainder file", p.as_path())),
    );
    check_outputs(
        &outputs,
        &model_inputs(&cmd.model, logs.chain(validate).chain(passes)),
    )
}

/// Writes the JSON report (`--json`) and the identified model (`--model-out`) of a fit.
pub fn write_report_and_model(
    cmd: &FitArgs,
    results: &Results,
    report: &Report,
) -> Result<(), Failure> {
    if let Some(path) = &cmd.json {
        let text = serde_json::to_string_pretty(report).map_err(|e| Failure::fit(e.to_string()))?;
        write_atomically(path, text.as_bytes())
            .map_err(|e| Failure::input(format!("{}: cannot write: {e}", path.display())))?;
    }
    if let Some(path) = &cmd.model_out {
        results.to_identified_model().save(path)?;
    }
    Ok(())
}

fn print_reader_notes(out: &FitOutcome) {
    for s in &out.summaries {
        let dropped: u64 = s.dropped.values().sum();
        let spikes: u64 = s.spikes.values().sum();
        let mut notes = Vec::new();
        if dropped > 0 {
            notes.push(format!("{dropped} samples dropped {:?}", s.dropped));
        }
        if spikes > 0 {
            notes.push(format!("{spikes} samples look like spikes {:?}", s.spikes));
        }
        if s.segments > 1 && s.segments as u64 == s.samples {
            notes.push(format!(
                "{} samples, each a point of its own (every time step over max_gap): a \
                 test-point sweep, not a time series",
                s.samples
            ));
        } else if s.segments > 1 {
            notes.push(format!("{} segments (gaps split the log)", s.segments));
        }
        if !s.dropouts.is_empty() {
            let ms: f64 = s.dropouts.iter().map(|d| d.duration).sum::<f64>() * 1e3;
            notes.push(format!(
                "{} logger dropouts ({ms:.0} ms in all), never bridged",
                s.dropouts.len()
            ));
        }
        notes.extend(s.cut_off.clone());
        notes.extend(
            s.derived
                .iter()
                .filter(|d| d.contains("COMMANDED"))
                .cloned(),
        );
        notes.extend(s.unit_warnings.iter().cloned());
        for note in notes {
            print_err(&format!("note: {}: {note}", s.file));
        }
    }
}

fn write_plots(dir: &Path, out: &FitOutcome) -> Result<(), plots::PlotError> {
    let [
        fit_histories,
        validation_histories,
        density,
        probability,
        folds,
        added,
    ] = PLOT_STEMS;
    let diagnosed = out.diagnosis.is_some();
    let (fit_title, validation_title) = if diagnosed {
        (
            "Fit data: measured, Eq. 22 model (before diagnosis) and final model",
            "Validation data: measured, Eq. 22 model (before diagnosis) and final model",
        )
    } else {
        (
            "Fit data: measured vs Eq. 22 model",
            "Validation data: measured vs Eq. 22 model",
        )
    };
    let eq22_axes = (out.diagnosis.as_ref())
        .and_then(|d| d.eq22.as_ref())
        .map_or_else(Vec::new, |e| e.axes.clone());
    for (name, title, s) in [
        (fit_histories, fit_title, &out.fit_series),
        (
            validation_histories,
            validation_title,
            &out.validation_series,
        ),
    ] {
        if s.t.is_empty() {
            continue;
        }
        let axes: Vec<AxisSeries> = Axis::ALL
            .iter()
            .map(|&axis| {
                let a = axis as usize;
                AxisSeries {
                    axis,
                    t: &s.t,
                    measured: &s.measured[a],
                    predicted: &s.predicted[a],
                    final_model: (!s.final_predicted[a].is_empty())
                        .then_some(s.final_predicted[a].as_slice()),
                    final_is_eq22: eq22_axes.contains(&axis),
                }
            })
            .collect();
        plots::time_histories(&dir.join(name), title, &axes)?;
    }
    if let Some(d) = &out.diagnosis {
        let axes: Vec<FoldR2> = Axis::ALL
            .iter()
            .map(|&axis| {
                let a = axis as usize;
                FoldR2 {
                    axis,
                    folds: d.folds.clone(),
                    before: d.before_folds.iter().map(|m| 100.0 * m[a].r2).collect(),
                    after: d.after_folds.iter().map(|m| 100.0 * m[a].r2).collect(),
                }
            })
            .collect();
        plots::fold_r2(
            &dir.join(folds),
            "Held-out R² per fold, each predicted by the model fitted without it: \
             Eq. 22 model (red), final model (blue)",
            &axes,
        )?;
    }
    let effects: Vec<EffectResidual> = out
        .fit_series
        .effects
        .iter()
        .map(|e| EffectResidual {
            name: &e.name,
            axis: e.axis,
            load: &e.load,
            before: &e.before,
            after: &e.after,
        })
        .collect();
    if !effects.is_empty() {
        plots::effect_residuals(
            &dir.join(added),
            "Added effects (fit data): residual without (red) and with (blue) each effect \
             against its load",
            &effects,
        )?;
    }
    if let Some(d) = &out.diagnostics {
        plots::residual_densities(
            &dir.join(density),
            "Residual probability density (fit data)",
            &densities(d),
        )?;
        plots::normal_probability(
            &dir.join(probability),
            "Normal probability of residuals (fit data)",
            &normal_points(d),
        )?;
    }
    Ok(())
}

fn densities(d: &ResidualDiagnostics) -> Vec<ResidualDensity> {
    d.axes
        .iter()
        .map(|a| {
            let h = &a.histogram;
            let bins = h.counts.len().max(1);
            let width = (h.hi - h.lo) / bins as f64;
            let total = d.samples.max(1) as f64;
            ResidualDensity {
                axis: a.axis,
                edges: (0..=bins).map(|i| h.lo + width * i as f64).collect(),
                density: h
                    .counts
                    .iter()
                    .map(|&c| c as f64 / (total * width))
                    .collect(),
                mean: a.mean,
                std: a.std_dev,
            }
        })
        .collect()
}

/// Ordered residuals at 200 probability levels, read off the histogram's cumulative
/// distribution (under- and overflow spread over min..lo and hi..max), against
/// standard-normal quantiles.
fn normal_points(d: &ResidualDiagnostics) -> Vec<NormalProbability> {
    let normal = Normal::standard();
    d.axes
        .iter()
        .map(|a| {
            let cells = a.histogram.cells();
            let n = cells.iter().map(|c| c.2).sum::<u64>().max(1) as f64;
            let points = (1..=200)
                .filter_map(|i| {
                    let p = i as f64 / 201.0;
                    let mut cum = 0.0;
                    for &(lo, hi, c) in &cells {
                        let next = cum + c as f64;
                        if c > 0 && next / n >= p {
                            let frac = (p * n - cum) / c as f64;
                            return Some((normal.inverse_cdf(p), lo + (hi - lo) * frac));
                        }
                        cum = next;
                    }
                    None
                })
                .collect();
            NormalProbability {
                axis: a.axis,
                points,
                correlation: a.normal_probability_correlation,
            }
        })
        .collect()
}

/// A failure of `predict` or `validate` on `log`: bad input (exit 2), the log named
/// where the library's error does not name it already.
fn naming_the_log(log: &Path, e: mrsysid::Error) -> Failure {
    match e {
        mrsysid::Error::Model(m) => Failure::input(format!("{}: {m}", log.display())),
        mrsysid::Error::Accumulate { .. } | mrsysid::Error::Input(_) => {
            Failure::input(e.to_string())
        }
        other => Failure::from(other),
    }
}

/// `mrsysid predict`: model output per sample of a log, as CSV.
pub fn predict(
    model: &Path,
    log: &Path,
    mapping: Option<&Path>,
    out: &Path,
) -> Result<(), Failure> {
    let mut inputs = vec![("model file", model), ("log", log)];
    inputs.extend(mapping.map(|p| ("mapping file", p)));
    check_outputs(&[("--out", out)], &inputs)?;
    let m = IdentifiedModel::load(model)?;
    let mapping = load_mapping(mapping)?;
    let mut text = String::from("t,fx,fy,fz,mx,my,mz\n");
    m.predict_log(log, mapping.as_ref(), |chunk, y| {
        for k in 0..chunk.len() {
            text.push_str(&format!("{}", chunk.t[k]));
            for col in y {
                text.push_str(&format!(",{}", col[k]));
            }
            text.push('\n');
        }
    })
    .map_err(|e| naming_the_log(log, e))?;
    write_atomically(out, text.as_bytes())
        .map_err(|e| Failure::input(format!("{}: cannot write: {e}", out.display())))
}

/// `mrsysid validate`: fit metrics of a saved model on other logs.
pub fn validate(
    model: &Path,
    logs: &[PathBuf],
    mapping: Option<&Path>,
    json: Option<&Path>,
) -> Result<(), Failure> {
    let mut inputs = vec![("model file", model)];
    inputs.extend(mapping.map(|p| ("mapping file", p)));
    inputs.extend(logs.iter().map(|p| ("log", p.as_path())));
    let outputs: Vec<(&str, &Path)> = json.iter().map(|p| ("--json", *p)).collect();
    check_outputs(&outputs, &inputs)?;
    let m = IdentifiedModel::load(model)?;
    let mapping = load_mapping(mapping)?;
    let mut validation = Validation::new(&m);
    for log in logs {
        validation
            .add_log(log, mapping.as_ref())
            .map_err(|e| naming_the_log(log, e))?;
    }
    if validation.samples() == 0 {
        return Err(Failure::fit("no samples in the validation logs".into()));
    }
    let metrics = validation.metrics()?;
    let rows: Vec<AxisRow> = metrics.iter().map(AxisRow::from).collect();
    let mut text = format!(
        "{} samples; model {}\n  {:<4} {:>10} {:>8} {:>8} {:>12}\n",
        validation.samples(),
        model.display(),
        "axis",
        "NRMSE [%]",
        "TIC",
        "R2 [%]",
        "RMSE"
    );
    for r in &rows {
        text.push_str(&format!(
            "  {:<4} {:>10.2} {:>8.3} {:>8.1} {:>12.4e}\n",
            r.axis.name(),
            100.0 * r.nrmse,
            r.tic,
            100.0 * r.r2,
            r.rmse
        ));
    }
    print_out(&text)?;
    if let Some(path) = json {
        let text = serde_json::to_string_pretty(
            &serde_json::json!({ "samples": validation.samples(), "axes": rows }),
        )
        .map_err(|e| Failure::fit(e.to_string()))?;
        write_atomically(path, text.as_bytes())
            .map_err(|e| Failure::input(format!("{}: cannot write: {e}", path.display())))?;
    }
    Ok(())
}

/// `mrsysid vehicle --from-log`: the vehicle skeleton from a PX4 ULog's
/// control-allocation parameters or an ArduPilot DataFlash log's frame (with
/// `arm_length`, m), to `out` or stdout; the notes (what to fill in, the layout check)
/// go to stderr.
pub fn vehicle_from_log(
    log: &Path,
    arm_length: Option<f64>,
    out: Option<&Path>,
) -> Result<(), Failure> {
    let outputs: Vec<(&str, &Path)> = out.iter().map(|p| ("--out", *p)).collect();
    check_outputs(&outputs, &[("log", log)])?;
    let format = io::log_format(log)
        .map_err(|e| Failure::input(format!("{}: cannot read: {e}", log.display())))?;
    match format {
        io::LogFormat::Dataflash => vehicle_from_dataflash(log, arm_length, out),
        io::LogFormat::Ulog => vehicle_from_ulog(log, out),
        _ => Err(Failure::input(format!(
            "{}: not a PX4 ULog or ArduPilot DataFlash log (`vehicle --from-log` reads the \
             autopilot's parameters from one)",
            io::display_name(log)
        ))),
    }
}

/// The ArduPilot skeleton of [`vehicle_from_log`], with the `RCOU` actuator map from the
/// `MOT_*` parameters in the notes.
fn vehicle_from_dataflash(
    log: &Path,
    arm_length: Option<f64>,
    out: Option<&Path>,
) -> Result<(), Failure> {
    let file = io::display_name(log);
    let arm = arm_length.ok_or_else(|| {
        Failure::input(format!(
            "{file}: an ArduPilot log holds the frame's motor angles (FRAME_CLASS, FRAME_TYPE) \
             but not its size: give --arm-length M (hub distance from the CG, m)"
        ))
    })?;
    let p = io::read_parameters(log)?;
    let (rotors, frame) = io::ardupilot_rotors(&p.parameters, arm)
        .map_err(|m| Failure::input(format!("{file}: {m}")))?;
    let name = p.firmware.clone().unwrap_or_else(|| file.clone());
    let text = io::ardupilot_skeleton(&rotors, frame, arm, &name, &file);
    write_or_print(out, &text)?;
    let actuator = match io::actuator_lines(&p.parameters) {
        Ok(lines) => format!(
            "note: without ESC telemetry, map RCOU C1..C{} as commanded speeds with:\n{lines}",
            rotors.len()
        ),
        Err(m) => format!("note: no actuator map from the MOT_* parameters: {m}"),
    };
    print_err(&format!(
        "note: {} rotors of ArduPilot's {frame} frame from {file}, arm length {arm} m; fill in \
         mass, inertia, rotor_radius and hub_height (ArduPilot does not log them) before \
         `mrsysid fit`.\n{actuator}",
        rotors.len()
    ));
    Ok(())
}

/// The text to `out` (atomically) or stdout.
fn write_or_print(out: Option<&Path>, text: &str) -> Result<(), Failure> {
    match out {
        Some(path) => {
            write_atomically(path, text.as_bytes())
                .map_err(|e| Failure::input(format!("cannot write {}: {e}", path.display())))?;
            print_err(&format!("wrote {}", path.display()));
        }
        None => print_out(text)?,
    }
    Ok(())
}

/// The PX4 skeleton of [`vehicle_from_log`].
fn vehicle_from_ulog(log: &Path, out: Option<&Path>) -> Result<(), Failure> {
    let defs = io::read_definitions(log)?;
    let file = io::display_name(log);
    let rotors = io::rotors_from_parameters(&defs.parameters)
        .map_err(|m| Failure::input(format!("{file}: {m}")))?;
    let name = match (defs.info.get("sys_name"), defs.info.get("ver_hw")) {
        (Some(s), Some(h)) => format!("{s} {h}"),
        (Some(s), None) => s.clone(),
        _ => file.clone(),
    };
    let text = io::vehicle_skeleton(&rotors, &name, &file);
    write_or_print(out, &text)?;
    print_err(&format!(
        "note: {} rotors from CA_ROTOR_* of {file}; fill in mass, inertia, rotor_radius and \
         rotor_inertia (PX4 does not log them) before `mrsysid fit`.\nnote: layout: {}",
        rotors.len(),
        io::layout_check(&rotors)
    ));
    Ok(())
}
