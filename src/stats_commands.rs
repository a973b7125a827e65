//! The commands of statistics as data: `mrsysid accumulate` (logs' first passes into a
//! statistics file), `mrsysid fit --from-stats` (the fit from such files; with
//! `--plan-out`, `--passes` and `--remainders` the diagnosis from them) and
//! `mrsysid pass` (a log's second or remainder pass with a plan).

use std::path::PathBuf;

use crate::commands::{
    Failure, check_fit_outputs, check_outputs, load_mapping, model_inputs, print_err, print_out,
    write_report_and_model,
};
use crate::progress_bar::with_progress;
use crate::{AccumulateArgs, FitArgs, LowPassArg, PassArgs};
use mrsysid::report::tables;
use mrsysid::{
    Identification, LogSource, PassPart, PassPlan, RemainderPart, RemainderPlan, Results,
    StatsPart, Vehicle,
};

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

/// `mrsysid pass`: a log's second pass with a plan, or its remainder pass with the final
/// model too.
pub fn pass(cmd: &PassArgs) -> Result<(), Failure> {
    let mut inputs = vec![("log", cmd.log.as_path()), ("plan", cmd.plan.as_path())];
    inputs.extend(cmd.final_model.iter().map(|m| ("final model", m.as_path())));
    check_outputs(
        &[("--out", cmd.out.as_path())],
        &model_inputs(&cmd.model, inputs),
    )?;
    let start = std::time::Instant::now();
    let vehicle = Vehicle::from_toml_file(&cmd.model.vehicle)?;
    let job = cmd.identification(vehicle, load_mapping(cmd.model.mapping.as_deref())?);
    let prepared = job.prepare_pass(PassPlan::load(&cmd.plan)?)?;
    let log = LogSource::from(cmd.log.clone());
    let what = match &cmd.final_model {
        Some(model) => {
            let model = RemainderPlan::load(model)?;
            prepared.remainder_part(&model, &log)?.save(&cmd.out)?;
            "remainder pass"
        }
        None => {
            prepared.pass_part(&log)?.save(&cmd.out)?;
            "second pass"
        }
    };
    if !cmd.quiet {
        print_err(&format!(
            "{what} of {} written to {} in {:.1} s",
            cmd.log.display(),
            cmd.out.display(),
            start.elapsed().as_secs_f64()
        ));
    }
    Ok(())
}

/// The fit and diagnosis from statistics files and the logs' pass files: `None` when it
/// stopped after writing the plan (`--plan-out`) or the final model for the remainder
/// pass (`--remainder-plan-out`).
fn diagnose_from_stats(
    cmd: &FitArgs,
    job: &Identification,
    fit: &StatsPart,
    validate: Option<&StatsPart>,
) -> Result<Option<Results>, Failure> {
    let planned = job.plan_from_stats(fit, validate)?;
    if let Some(path) = &cmd.plan_out {
        planned.plan().save(path)?;
        if !cmd.quiet {
            print_err(&format!(
                "second-pass plan written to {}: pass each log with `mrsysid pass LOG --plan {}`, then fit with --passes",
                path.display(),
                path.display()
            ));
        }
        return Ok(None);
    }
    let passes = (cmd.passes.iter().map(|p| PassPart::load(p))).collect::<Result<Vec<_>, _>>()?;
    let remainders =
        (cmd.remainders.iter().map(|p| RemainderPart::load(p))).collect::<Result<Vec<_>, _>>()?;
    let pending = planned.diagnose(passes)?;
    if let (Some((model, logs)), true) = (pending.remainder_plan(), remainders.is_empty()) {
        let Some(path) = &cmd.remainder_plan_out else {
            return Err(Failure::input(format!(
                "the fit logs are time series, so the diagnosis needs their remainder pass: \
                 give --remainder-plan-out FILE, pass each of the {} fit logs with \
                 `mrsysid pass LOG --plan PLAN --model FILE`, then run again with --remainders",
                logs.len()
            )));
        };
        model.save(path)?;
        if !cmd.quiet {
            print_err(&format!(
                "final model written to {}: pass each of the {} fit logs with `mrsysid pass LOG --plan PLAN --model {}`, then run again with --remainders",
                path.display(),
                logs.len(),
                path.display()
            ));
        }
        return Ok(None);
    }
    Ok(Some(job.finish_from_stats(pending, &remainders)?))
}

/// `mrsysid fit --from-stats`: the fit from statistics files, without reading a log;
/// with `--plan-out` / `--passes` the diagnosis from them and the logs' pass files.
pub fn fit_from_stats(cmd: &FitArgs, diagnosis_only: bool) -> Result<(), Failure> {
    let from_passes = cmd.plan_out.is_some() || !cmd.passes.is_empty();
    let refused = [
        (diagnosis_only && !from_passes, "`diagnose`"),
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
    let results = if from_passes {
        match diagnose_from_stats(cmd, &job, &fit, validate.as_ref())? {
            Some(results) => results,
            None => return Ok(()),
        }
    } else {
        job.run_from_stats(&fit, validate.as_ref())?
    };
    let report = results.report();
    if !cmd.quiet {
        print_out(&match (&report.diagnosis, diagnosis_only) {
            (Some(d), true) => tables::render_diagnosis(d),
            _ => tables::render(&report),
        })?;
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
