//! The commands of statistics as data: `mrsysid accumulate` (logs' first passes into a
//! statistics file) and `mrsysid fit --from-stats` (the fit from such files).

use std::path::PathBuf;

use crate::commands::{
    Failure, check_fit_outputs, check_outputs, load_mapping, model_inputs, print_err, print_out,
    write_report_and_model,
};
use crate::progress_bar::with_progress;
use crate::{AccumulateArgs, FitArgs, LowPassArg};
use mrsysid::report::tables;
use mrsysid::{StatsPart, Vehicle};

/// `mrsysid accumulate`: the logs' first passes into one statistics file.
pub fn accumulate(cmd: &AccumulateArgs) -> Result<(), Failure> {
    let logs = cmd.logs.iter().map(|p| ("log", p.as_path()));
    check_outputs(
        &[("--out", cmd.out.as_path())],
        &model_inputs(&cmd.model, logs),
    )?;
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
    check_fit_outputs(cmd, ("statistics file", "statistics file"))?;
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
    write_report_and_model(cmd, &results, &report)?;
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
