//! The command handlers of the binary: read arguments, call the library, print and
//! write outputs (each output file written whole or not at all).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use mrsysid::Identification;
use mrsysid::estimate::{self, ResidualDiagnostics};
use mrsysid::identified::IdentifiedModel;
use mrsysid::io::{self, InvalidSamples, Mapping, ReadOptions};
use mrsysid::model::{ModelOptions, Workspace};
use mrsysid::pipeline::{FitOutcome, Holdout, PlotSeries};
use mrsysid::report::plots::{self, AxisSeries, NormalProbability, ResidualDensity};
use mrsysid::report::summary::AxisRow;
use mrsysid::report::tables;
use mrsysid::sample::Axis;
use mrsysid::stats::Accumulator;
use mrsysid::util::write_atomically;
use mrsysid::vehicle::Vehicle;
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

    fn fit(message: String) -> Self {
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

/// Everything `fit` and `diagnose` take from the command line.
pub struct FitCommand {
    pub logs: Vec<PathBuf>,
    pub vehicle: PathBuf,
    pub mapping: Option<PathBuf>,
    pub options: ModelOptions,
    pub drop_invalid: bool,
    pub validate: Vec<PathBuf>,
    pub holdout_segment: f64,
    pub json: Option<PathBuf>,
    pub model_out: Option<PathBuf>,
    pub plots: Option<PathBuf>,
    pub threads: Option<usize>,
    pub quiet: bool,
    pub diagnose: bool,
}

fn read_options(drop_invalid: bool) -> ReadOptions {
    ReadOptions {
        invalid: if drop_invalid {
            InvalidSamples::DropAndCount
        } else {
            InvalidSamples::Error
        },
        ..ReadOptions::default()
    }
}

fn load_mapping(path: Option<&Path>) -> Result<Option<Mapping>, Failure> {
    Ok(path.map(Mapping::from_toml_file).transpose()?)
}

/// `mrsysid fit` (and `diagnose`, which prints only the diagnosis).
pub fn fit(cmd: &FitCommand, diagnosis_only: bool) -> Result<(), Failure> {
    let vehicle = Vehicle::from_toml_file(&cmd.vehicle)?;
    if !cmd.quiet {
        for note in vehicle.notes() {
            eprintln!("note: {}: {note}", cmd.vehicle.display());
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
    let mut job = Identification::new(vehicle)
        .model_options(cmd.options)
        .logs(cmd.logs.iter().cloned())
        .read_options(read_options(cmd.drop_invalid))
        .holdout(Holdout {
            segment_seconds: cmd.holdout_segment,
            ..Holdout::default()
        })
        .diagnose(cmd.diagnose);
    for log in &cmd.validate {
        job = job.validate(log.clone());
    }
    if let Some(mapping) = load_mapping(cmd.mapping.as_deref())? {
        job = job.mapping(mapping);
    }
    if let Some(threads) = cmd.threads {
        job = job.threads(threads);
    }
    let results = with_progress(job, cmd.quiet, |job| job.run())?;
    let report = results.report();
    if !cmd.quiet {
        print_reader_notes(results.outcome());
        match (&report.diagnosis, diagnosis_only) {
            (Some(d), true) => print!("{}", tables::render_diagnosis(d)),
            (None, true) => println!("diagnosis skipped (--no-diagnose)"),
            (_, false) => print!("{}", tables::render(&report)),
        }
    }
    if let Some(path) = &cmd.json {
        let text =
            serde_json::to_string_pretty(&report).map_err(|e| Failure::fit(e.to_string()))?;
        write_atomically(path, text.as_bytes())
            .map_err(|e| Failure::input(format!("{}: cannot write: {e}", path.display())))?;
    }
    if let Some(path) = &cmd.model_out {
        results.to_identified_model().save(path)?;
    }
    if let Some(dir) = &cmd.plots {
        write_plots(dir, results.outcome()).map_err(|e| Failure::input(e.to_string()))?;
    }
    Ok(())
}

/// Runs `job`, showing a spinner with the samples read on stderr once it has taken more
/// than a second (not with `--quiet`, nor when stderr is not a terminal).
fn with_progress<T>(
    request: Identification,
    quiet: bool,
    job: impl FnOnce(&Identification) -> T,
) -> T {
    use std::io::IsTerminal;
    if quiet || !std::io::stderr().is_terminal() {
        return job(&request);
    }
    let count = Arc::new(AtomicU64::new(0));
    let request = request.progress(count.clone());
    let done = Arc::new(AtomicBool::new(false));
    let display = {
        let (count, done) = (count.clone(), done.clone());
        std::thread::spawn(move || {
            let start = std::time::Instant::now();
            let bar = indicatif::ProgressBar::hidden();
            while !done.load(Ordering::Relaxed) {
                if start.elapsed() > std::time::Duration::from_secs(1) && bar.is_hidden() {
                    bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
                    bar.set_style(
                        indicatif::ProgressStyle::with_template("{spinner} {elapsed} {msg}")
                            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
                    );
                }
                bar.set_message(format!(
                    "{} samples read (two passes)",
                    count.load(Ordering::Relaxed)
                ));
                bar.tick();
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
            bar.finish_and_clear();
        })
    };
    let result = job(&request);
    done.store(true, Ordering::Relaxed);
    let _ = display.join();
    result
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
        if s.segments > 1 {
            notes.push(format!("{} segments (gaps split the log)", s.segments));
        }
        if !s.dropouts.is_empty() {
            let ms: f64 = s.dropouts.iter().map(|d| d.duration).sum::<f64>() * 1e3;
            notes.push(format!(
                "{} logger dropouts ({ms:.0} ms in all), never bridged",
                s.dropouts.len()
            ));
        }
        notes.extend(
            s.derived
                .iter()
                .filter(|d| d.contains("COMMANDED"))
                .cloned(),
        );
        notes.extend(s.unit_warnings.iter().cloned());
        if !notes.is_empty() {
            eprintln!("note: {}: {}", s.file, notes.join("; "));
        }
    }
}

fn write_plots(dir: &Path, out: &FitOutcome) -> Result<(), plots::PlotError> {
    let series = |s: &PlotSeries| -> Vec<(Axis, Vec<f64>, Vec<f64>)> {
        Axis::ALL
            .iter()
            .map(|&a| {
                (
                    a,
                    s.measured[a as usize].clone(),
                    s.predicted[a as usize].clone(),
                )
            })
            .collect()
    };
    for (name, title, s) in [
        (
            "fit_time_histories",
            "Fit data: measured vs Eq. 22 model (before diagnosis)",
            &out.fit_series,
        ),
        (
            "validation_time_histories",
            "Validation data: measured vs Eq. 22 model (before diagnosis)",
            &out.validation_series,
        ),
    ] {
        if s.t.is_empty() {
            continue;
        }
        let cols = series(s);
        let axes: Vec<AxisSeries> = cols
            .iter()
            .map(|(axis, m, p)| AxisSeries {
                axis: *axis,
                t: &s.t,
                measured: m,
                predicted: p,
            })
            .collect();
        plots::time_histories(&dir.join(name), title, &axes)?;
    }
    if let Some(d) = &out.diagnostics {
        plots::residual_densities(
            &dir.join("residual_density"),
            "Residual probability density (fit data)",
            &densities(d),
        )?;
        plots::normal_probability(
            &dir.join("normal_probability"),
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

/// `mrsysid predict`: model output per sample of a log, as CSV.
pub fn predict(
    model: &Path,
    log: &Path,
    mapping: Option<&Path>,
    out: &Path,
) -> Result<(), Failure> {
    let m = IdentifiedModel::load(model)?;
    let mapping = load_mapping(mapping)?;
    let mut reader = io::open_log(log, &m.vehicle, mapping.as_ref(), &ReadOptions::default())
        .map_err(|e| Failure::input(e.to_string()))?;
    let mut text = String::from("t,fx,fy,fz,mx,my,mz\n");
    let mut ws = Workspace::default();
    while let Some(chunk) = reader.next_chunk() {
        let chunk = chunk?;
        let y = m
            .predict_chunk(chunk, &mut ws)
            .map_err(|e| Failure::input(format!("{}: {e}", log.display())))?;
        for k in 0..chunk.len() {
            text.push_str(&format!("{}", chunk.t[k]));
            for col in &y {
                text.push_str(&format!(",{}", col[k]));
            }
            text.push('\n');
        }
    }
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
    let m = IdentifiedModel::load(model)?;
    let mapping = load_mapping(mapping)?;
    let mut acc = Accumulator::new(&m.structure);
    let mut ws = Workspace::default();
    for log in logs {
        let mut reader = io::open_log(log, &m.vehicle, mapping.as_ref(), &ReadOptions::default())
            .map_err(|e| Failure::input(e.to_string()))?;
        while let Some(chunk) = reader.next_chunk() {
            let chunk = chunk?;
            acc.push(&m.structure, chunk, &mut ws)
                .map_err(|e| Failure::input(format!("{}: {e}", log.display())))?;
        }
    }
    if acc.count() == 0 {
        return Err(Failure::fit("no samples in the validation logs".into()));
    }
    let metrics = estimate::evaluate(&m.structure, &m.theta(), &acc)?;
    let rows: Vec<AxisRow> = metrics.iter().map(AxisRow::from).collect();
    println!("{} samples; model {}", acc.count(), model.display());
    println!(
        "  {:<4} {:>10} {:>8} {:>8} {:>12}",
        "axis", "NRMSE [%]", "TIC", "R2 [%]", "RMSE"
    );
    for r in &rows {
        println!(
            "  {:<4} {:>10.2} {:>8.3} {:>8.1} {:>12.4e}",
            r.axis.name(),
            100.0 * r.nrmse,
            r.tic,
            100.0 * r.r2,
            r.rmse
        );
    }
    if let Some(path) = json {
        let text = serde_json::to_string_pretty(
            &serde_json::json!({ "samples": acc.count(), "axes": rows }),
        )
        .map_err(|e| Failure::fit(e.to_string()))?;
        write_atomically(path, text.as_bytes())
            .map_err(|e| Failure::input(format!("{}: cannot write: {e}", path.display())))?;
    }
    Ok(())
}

/// `mrsysid vehicle --from-ulog`: the vehicle skeleton from PX4's control-allocation
/// parameters, to `out` or stdout; the notes (what to fill in, the layout check) go to
/// stderr.
pub fn vehicle_from_ulog(log: &Path, out: Option<&Path>) -> Result<(), Failure> {
    let defs = io::ulog::read_definitions(log)?;
    let file = io::error::display_name(log);
    let rotors = io::px4::rotors_from_parameters(&defs.parameters)
        .map_err(|m| Failure::input(format!("{file}: {m}")))?;
    let name = match (defs.info.get("sys_name"), defs.info.get("ver_hw")) {
        (Some(s), Some(h)) => format!("{s} {h}"),
        (Some(s), None) => s.clone(),
        _ => file.clone(),
    };
    let text = io::px4::vehicle_skeleton(&rotors, &name, &file);
    match out {
        Some(path) => {
            write_atomically(path, text.as_bytes())
                .map_err(|e| Failure::input(format!("cannot write {}: {e}", path.display())))?;
            eprintln!("wrote {}", path.display());
        }
        None => print!("{text}"),
    }
    eprintln!(
        "note: {} rotors from CA_ROTOR_* of {file}; fill in mass, inertia, rotor_radius and \
         rotor_inertia (PX4 does not log them) before `mrsysid fit`.\nnote: layout: {}",
        rotors.len(),
        io::px4::layout_check(&rotors)
    );
    Ok(())
}
