//! The commands of statistics as data: `mrsysid accumulate` (logs' first passes into a
//! statistics file) and `mrsysid fit --from-stats` (the fit from such files).

use std::path::{Path, PathBuf};

use crate::commands::{Failure, check_outputs, fit_outputs, load_mapping, print_err, print_out};
use crate::progress_bar::with_progress;
use crate::{AccumulateArgs, FitArgs, LowPassArg};
use mrsysid::report::tables;
use mrsysid::{StatsPart, Vehicle, write_atomically};

/// `mrsysid accumulate`: the logs' first passes into one statistics file.
pub fn accumulate(cmd: &AccumulateArgs) -> Result<(), Failure> {
    let mut inputs: Vec<(&str, &Path)> = vec![("vehicle file", cmd.model.vehicle.as_path())];
    inputs.extend(
        cmd.model
            .mapping
            .iter()
            .map(|p| ("mapping file", p.as_path())),
    );
    inputs.extend(cmd.logs.iter().map(|p| ("log", p.as_path())));
    check_outputs(&[("--out", cmd.out.as_path())], &inputs)?;
    let vehicle = Vehicle::from_toml_file(&cmd.model.vehicle)?;
    let job = cmd.identification(vehicle, load_mapping(cmd.model.mapping.as_deref())?);
    let (part, finished) = with_progress(job, cmd.quiet, |job| job.accumulate());
    let part = part?;
    part.save(&cmd.out)?;
    if !cmd.quiet {
        print_err(&format!(
            "{}; statistics of {} samples written to {}",
            finished.line("accumulate", cmd.logs.len()),
            part.samples(),
            cmd.out.display(),
        ));
    }
    Ok(())
}

/// `mrsysid fit --from-stats`: the fit from statistics files, without reading a log.
pub fn fit_from_stats(cmd: &FitArgs, diagnosis_only: bool) -> Result<(), Failure> {
    let refused = [
        (diagnosis_only, "`diagnose`"),
        (cmd.plots.is_some(), "--plots"),
        (
            matches!(cmd.loads_low_pass, Some(LowPassArg::Estimate)),
            "--loads-low-pass estimate",
        ),
    ];
    if let Some((_, what)) = refused.iter().find(|(on, _)| *on) {
        return Err(Failure::input(format!(
            "{what} needs the samples: not available with --from-stats"
        )));
    }
    let outputs = fit_outputs(cmd);
    let outputs: Vec<(&str, &Path)> = outputs.iter().map(|(o, p)| (*o, p.as_path())).collect();
    let mut inputs: Vec<(&str, &Path)> = vec![("vehicle file", cmd.model.vehicle.as_path())];
    inputs.extend(
        cmd.model
            .mapping
            .iter()
            .map(|p| ("mapping file", p.as_path())),
    );
    inputs.extend(cmd.logs.iter().map(|p| ("statistics file", p.as_path())));
    inputs.extend(
        cmd.validate
            .iter()
            .map(|p| ("statistics file", p.as_path())),
    );
    check_outputs(&outputs, &inputs)?;
    let load = |paths: &[PathBuf]| -> Result<Option<StatsPart>, Failure> {
        let mut merged: Option<StatsPart> = None;
        for path in paths {
            let part = StatsPart::load(path)?;
            match merged.as_mut() {
                Some(m) => m.merge(&part)?,
                None => merged = Some(part),
            }
        }
        Ok(merged)
    };
    let start = std::time::Instant::now();
    let (fit, validate) = (load(&cmd.logs)?, load(&cmd.validate)?);
    let Some(fit) = fit else {
        return Err(Failure::input("no statistics file to fit".into()));
    };
    let vehicle = Vehicle::from_toml_file(&cmd.model.vehicle)?;
    let job = cmd.identification(vehicle, load_mapping(cmd.model.mapping.as_deref())?);
    let results = job.run_from_stats(&fit, validate.as_ref())?;
    let report = results.report();
    if !cmd.quiet {
        print_out(&tables::render(&report))?;
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
    if !cmd.quiet {
        let logs = fit.log_names().len() + validate.as_ref().map_or(0, |v| v.log_names().len());
        print_err(&format!(
            "fit from statistics: {logs} logs, {} samples, {:.1} s",
            fit.samples() + validate.as_ref().map_or(0, StatsPart::samples),
            start.elapsed().as_secs_f64()
        ));
    }
    Ok(())
}
