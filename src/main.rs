//! The `mrsysid` command-line tool: a thin shell over the library.

mod commands;
mod progress_bar;
mod stats_commands;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use mrsysid::simulate::{
    Design, Effect, EffectError, FlightConfig, Mode, SimulateOptions, VehicleChoice,
    simulate_to_file,
};
use mrsysid::{
    Holdout, Identification, InflowCorrection, InvalidSamples, Mapping, ModelOptions, ReadOptions,
    RotorInertiaTerms, Vehicle,
};

/// Offline nonlinear system identification of multirotor aircraft.
#[derive(Parser)]
#[command(name = "mrsysid", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Identify the Eq. 22 model from logs: FSOA tables, MMR estimates, fit metrics on
    /// held-out data, residual diagnostics, and the effects the model lacks.
    #[command(after_help = FIT_EXAMPLES)]
    Fit(FitArgs),
    /// Like `fit`, but print only the closing-the-loop diagnosis.
    Diagnose(FitArgs),
    /// Read logs once and write their first-pass statistics to a file, for
    /// `fit --from-stats` (statistics as data: one task per log or group of logs, on any
    /// machine or engine, then one fit).
    Accumulate(AccumulateArgs),
    /// Pass a log again for a diagnosis from statistics: its second pass with a plan
    /// written by `fit --from-stats --plan-out`, or with `--model` its remainder pass
    /// (docs/stats-format.md).
    Pass(PassArgs),
    /// Predict force and moment per sample of a log with a saved model (CSV out).
    Predict(PredictArgs),
    /// NRMSE, TIC and R² of a saved model on logs it was not fitted to.
    Validate(ValidateArgs),
    /// Generate truth data: a response-surface sweep or a flight log (CSV data contract).
    Simulate(SimulateArgs),
    /// Write a vehicle TOML skeleton from a PX4 ULog's control-allocation parameters or an
    /// ArduPilot DataFlash log's FRAME_CLASS/FRAME_TYPE (rotor positions and spins); mass,
    /// inertia and rotor size are left to fill in.
    Vehicle(VehicleArgs),
}

#[derive(clap::Args)]
struct VehicleArgs {
    /// PX4 ULog (CA_ROTOR_* parameters) or ArduPilot DataFlash `.bin` log
    /// (FRAME_CLASS/FRAME_TYPE) whose parameters give the rotor layout.
    #[arg(long, alias = "from-ulog")]
    from_log: PathBuf,
    /// Arm length, m (hub distance from the CG): needed for ArduPilot logs, which hold
    /// the frame's motor angles but not its size.
    #[arg(long)]
    arm_length: Option<f64>,
    /// Output TOML file (written atomically; stdout when absent).
    #[arg(long)]
    out: Option<PathBuf>,
}

const FIT_EXAMPLES: &str = "Examples:
  mrsysid fit data/quad_x_sweep.csv --vehicle data/vehicles/quad_x.toml
  mrsysid fit a.csv b.csv --vehicle v.toml --validate c.csv --json report.json --model-out model.toml --plots plots/
  mrsysid fit log.csv --vehicle v.toml --mapping examples/neurobem.toml

Exit codes: 0 success; 1 the fit failed or the data cannot support it; 2 bad input or usage.";

#[derive(clap::Args)]
struct ModelArgs {
    /// Vehicle TOML file.
    #[arg(long)]
    vehicle: PathBuf,
    /// Mapping file (TOML) for logs that do not follow the CSV contract, and for MCAP.
    #[arg(long)]
    mapping: Option<PathBuf>,
    /// Inflow-correction terms of Eq. 22.
    #[arg(long, value_enum, default_value_t = InflowCorrection::Derived)]
    inflow: InflowCorrection,
    /// Leave out the terms linear in V_h (the seed's simulation-study variant).
    #[arg(long)]
    no_linear_vh: bool,
    /// Treatment of the J_z gyroscopic and motor-torque terms.
    #[arg(long, value_enum, default_value_t = RotorInertiaTerms::Known)]
    rotor_inertia: RotorInertiaTerms,
    /// Drop invalid samples (NaN, out of range, time going back) and count them,
    /// instead of stopping at the first.
    #[arg(long)]
    drop_invalid: bool,
    /// Keep every sample: by default samples on the ground (rotors stopped or idling,
    /// for a second or more) are left out and each flight is a segment of its own.
    #[arg(long)]
    keep_ground: bool,
}

#[derive(clap::Args)]
struct FitArgs {
    /// Logs to fit (CSV contract, mapped CSV, or MCAP with --mapping).
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    #[command(flatten)]
    model: ModelArgs,
    /// Logs for the validation figures only: no decision (term selection, candidate
    /// effects) sees them (help text: [`validate_help`]).
    #[arg(long, num_args = 1.., help = validate_help())]
    validate: Vec<PathBuf>,
    /// Cross-validation groups, one name per fit log in the order given (with
    /// --from-stats, per log inside the statistics files, in order), comma-separated: the
    /// logs of a group are left out together, e.g. `--groups day1,day1,day2` for one group
    /// per flight day. Without it each log is left out on its own.
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    groups: Vec<String>,
    /// Contiguous blocks a single fit log is cut into to cross-validate it (at least 2):
    /// each is predicted by the model fitted on the others.
    #[arg(long, default_value_t = Holdout::DEFAULT.blocks)]
    holdout_blocks: usize,
    /// Time on each side of a held-out block of a single fit log that its fold neither
    /// fits nor scores, s (breaks the serial correlation between fitted and held-out
    /// samples).
    #[arg(long, default_value_t = Holdout::DEFAULT.guard_seconds)]
    holdout_guard: f64,
    /// The logs' forces and moments were low-passed at this cut-off (Hz) when they were
    /// made (e.g. from accelerations through a zero-phase filter, or a smoothing
    /// spline): the regressor signals pass through the same kind of filter (consistent
    /// filtering; as `[loads] low_pass_hz` in a mapping file). The model file keeps it.
    /// `estimate`: the cut-off is not known; the fit is repeated at cut-offs from 64 Hz
    /// down to 2 Hz and the one predicting held-out loads best is kept (or none).
    #[arg(long, value_name = "HZ|estimate", value_parser = low_pass_arg)]
    loads_low_pass: Option<LowPassArg>,
    /// Write the JSON report here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the identified model (TOML) here.
    #[arg(long)]
    model_out: Option<PathBuf>,
    /// Write plots (SVG and PNG) into this directory.
    #[arg(long)]
    plots: Option<PathBuf>,
    /// Threads for reading, accumulating and the diagnosis's trial fits, at least 1
    /// (default: available cores; the report does not depend on it).
    #[arg(long, value_parser = parse_threads)]
    threads: Option<usize>,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
    /// Skip the residual diagnosis (closing the loop).
    #[arg(long)]
    no_diagnose: bool,
    /// The logs (and `--validate` logs) are statistics files written by `mrsysid
    /// accumulate` with the same vehicle, mapping and options: the Eq. 22 fit with
    /// leave-one-log-out cross-validation runs on them without reading any log (no
    /// plots; the residual pass and the diagnosis with --plan-out and --passes).
    #[arg(long)]
    from_stats: bool,
    /// With --from-stats: fit Eq. 22, write the plan of the logs' second pass here and
    /// stop (each log is then passed with `mrsysid pass LOG --plan FILE`).
    #[arg(long, value_name = "FILE", requires = "from_stats")]
    plan_out: Option<PathBuf>,
    /// With --from-stats: the logs' second-pass files (`mrsysid pass`, one per fit and
    /// validation log, any order): the residual pass and the diagnosis run on them.
    #[arg(long, num_args = 1.., value_name = "FILES", requires = "from_stats")]
    passes: Vec<PathBuf>,
    /// With --passes, when the fit logs are time series: write the final model here for
    /// the remainder pass of each fit log (`mrsysid pass LOG --plan P --model FILE`) and
    /// stop; run again with --remainders.
    #[arg(long, value_name = "FILE", requires = "passes")]
    remainder_plan_out: Option<PathBuf>,
    /// With --passes: the fit logs' remainder-pass files (one per fit log).
    #[arg(long, num_args = 1.., value_name = "FILES", requires = "passes")]
    remainders: Vec<PathBuf>,
}

#[derive(clap::Args)]
struct AccumulateArgs {
    /// Logs to read (CSV contract, mapped CSV, MCAP, ULog or DataFlash with --mapping).
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    #[command(flatten)]
    model: ModelArgs,
    /// The logs' loads were low-passed at this cut-off (Hz): as `fit --loads-low-pass`.
    #[arg(long, value_name = "HZ")]
    loads_low_pass: Option<f64>,
    /// Threads for reading and accumulating, at least 1 (default: available cores).
    #[arg(long, value_parser = parse_threads)]
    threads: Option<usize>,
    /// The statistics file to write (whole or not at all).
    #[arg(long, short)]
    out: PathBuf,
    /// Keep each log's thinned samples too (up to 20 000 a log), which a diagnosis from
    /// statistics needs (`fit --from-stats --plan-out`, `--passes`).
    #[arg(long)]
    for_diagnosis: bool,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
}

#[derive(clap::Args)]
struct PassArgs {
    /// The log to pass (as `accumulate` read it: the same file name).
    log: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// The logs' loads were low-passed at this cut-off (Hz): as `fit --loads-low-pass`.
    #[arg(long, value_name = "HZ")]
    loads_low_pass: Option<f64>,
    /// The second-pass plan, written by `fit --from-stats --plan-out`.
    #[arg(long)]
    plan: PathBuf,
    /// The final model, written by `fit --from-stats --passes … --remainder-plan-out`:
    /// pass the (fit) log for the remainder of the final model instead.
    #[arg(long = "model", value_name = "FILE")]
    final_model: Option<PathBuf>,
    /// Threads for reading the log, at least 1 (default: available cores).
    #[arg(long, value_parser = parse_threads)]
    threads: Option<usize>,
    /// The pass file to write (whole or not at all).
    #[arg(long, short)]
    out: PathBuf,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
}

#[derive(clap::Args)]
struct PredictArgs {
    /// Model file written by `fit --model-out`.
    #[arg(long)]
    model: PathBuf,
    /// Log to predict (CSV contract, mapped CSV, or MCAP with --mapping).
    log: PathBuf,
    /// Mapping file for logs that do not follow the CSV contract, and for MCAP.
    #[arg(long)]
    mapping: Option<PathBuf>,
    /// Output CSV (t, fx, fy, fz, mx, my, mz); written whole or not at all.
    #[arg(long)]
    out: PathBuf,
}

#[derive(clap::Args)]
struct ValidateArgs {
    /// Model file written by `fit --model-out`.
    #[arg(long)]
    model: PathBuf,
    /// Logs the model was not fitted to.
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    /// Mapping file for logs that do not follow the CSV contract, and for MCAP.
    #[arg(long)]
    mapping: Option<PathBuf>,
    /// Write the metrics as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModeArg {
    /// Test matrix of independent states (wind-tunnel style).
    Sweep,
    /// Time-domain flight with controller and sensors.
    Flight,
}

#[derive(Clone, Copy, ValueEnum)]
enum DesignArg {
    /// Independent uniform draws.
    Uniform,
    /// Latin hypercube.
    Lhs,
}

#[derive(clap::Args)]
struct SimulateArgs {
    /// Vehicle TOML file.
    #[arg(long, conflicts_with = "preset", required_unless_present = "preset")]
    vehicle: Option<PathBuf>,
    /// A shipped example vehicle instead of a file: quad_x, quad_plus, hexa_x.
    #[arg(long)]
    preset: Option<String>,
    /// Rotor and airframe description (TOML; see data/README.md).
    #[arg(long)]
    rotor: Option<PathBuf>,
    /// Sweep (test matrix) or flight.
    #[arg(long, value_enum)]
    mode: ModeArg,
    /// Undeclared effect NAME[=p1,p2,...]; repeat for several.
    #[arg(long = "effect", value_parser = parse_effect)]
    effects: Vec<Effect>,
    /// Random seed (output is a function of the options and the seed).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output CSV file (written atomically).
    #[arg(long)]
    out: PathBuf,
    /// Sweep: number of test points.
    #[arg(long, default_value_t = 4000)]
    points: usize,
    /// Sweep: sampling design.
    #[arg(long, value_enum, default_value_t = DesignArg::Lhs)]
    design: DesignArg,
    /// Flight: duration, s.
    #[arg(long, default_value_t = 60.0)]
    duration: f64,
    /// Flight: RK4 step, s.
    #[arg(long, default_value_t = 0.002)]
    step: f64,
    /// Flight: log rate, Hz.
    #[arg(long, default_value_t = 100.0)]
    log_rate: f64,
    /// Flight: omit the true force/moment columns (IMU-only log).
    #[arg(long)]
    imu_only: bool,
    /// Flight: seconds flown low at the start (rotor plane 1–4 diameters above the
    /// ground), then the usual altitude.
    #[arg(long, default_value_t = 0.0)]
    near_ground: f64,
}

fn parse_effect(s: &str) -> Result<Effect, EffectError> {
    s.parse()
}

/// `--loads-low-pass`: a cut-off in Hz, or `estimate`.
#[derive(Clone, Copy)]
enum LowPassArg {
    Hz(f64),
    Estimate,
}

fn low_pass_arg(s: &str) -> Result<LowPassArg, String> {
    if s == "estimate" {
        return Ok(LowPassArg::Estimate);
    }
    s.parse::<f64>()
        .map(LowPassArg::Hz)
        .map_err(|_| format!("expected a cut-off in Hz or `estimate`, got `{s}`"))
}

fn parse_threads(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("the thread count must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}

impl SimulateArgs {
    fn options(&self) -> SimulateOptions {
        let vehicle = match (&self.vehicle, &self.preset) {
            (Some(p), _) => VehicleChoice::File(p.clone()),
            (None, Some(name)) => VehicleChoice::Example(name.clone()),
            (None, None) => unreachable!("clap requires --vehicle or --preset"),
        };
        let mode = match self.mode {
            ModeArg::Sweep => Mode::Sweep {
                design: match self.design {
                    DesignArg::Uniform => Design::Uniform,
                    DesignArg::Lhs => Design::LatinHypercube,
                },
                points: self.points,
            },
            ModeArg::Flight => Mode::Flight(FlightConfig {
                duration: self.duration,
                step: self.step,
                log_rate: self.log_rate,
                imu_only: self.imu_only,
                near_ground: self.near_ground,
                ..FlightConfig::default()
            }),
        };
        SimulateOptions {
            vehicle,
            rotor_file: self.rotor.clone(),
            mode,
            effects: self.effects.clone(),
            seed: self.seed,
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Fit(args) if args.from_stats => stats_commands::fit_from_stats(&args, false),
        Command::Diagnose(args) if args.from_stats => stats_commands::fit_from_stats(&args, true),
        Command::Fit(args) => commands::fit(&args, false),
        Command::Diagnose(args) => commands::fit(&args, true),
        Command::Accumulate(args) => stats_commands::accumulate(&args),
        Command::Pass(args) => stats_commands::pass(&args),
        Command::Predict(args) => {
            commands::predict(&args.model, &args.log, args.mapping.as_deref(), &args.out)
        }
        Command::Validate(args) => commands::validate(
            &args.model,
            &args.logs,
            args.mapping.as_deref(),
            args.json.as_deref(),
        ),
        Command::Simulate(args) => simulate(&args),
        Command::Vehicle(args) => {
            commands::vehicle_from_log(&args.from_log, args.arm_length, args.out.as_deref())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            commands::print_err(&format!("error: {}", e.message));
            ExitCode::from(e.code)
        }
    }
}

/// `mrsysid simulate`: refuses an output that is the vehicle or rotor file, then writes.
fn simulate(args: &SimulateArgs) -> Result<(), commands::Failure> {
    let mut inputs = Vec::new();
    inputs.extend(args.vehicle.iter().map(|p| ("vehicle file", p.as_path())));
    inputs.extend(args.rotor.iter().map(|p| ("rotor file", p.as_path())));
    commands::check_outputs(&[("--out", args.out.as_path())], &inputs)?;
    let rows = simulate_to_file(&args.options(), &args.out)
        .map_err(|e| commands::Failure::input(e.to_string()))?;
    commands::print_err(&format!("wrote {rows} rows to {}", args.out.display()));
    Ok(())
}

/// The help of `fit --validate`, with the hold-out default of a single log as the library
/// defines it ([`Holdout::DEFAULT`]).
fn validate_help() -> String {
    let h = Holdout::DEFAULT;
    format!(
        "Logs for the validation figures only: no decision (term selection, candidate \
         effects) sees them. Decisions are cross-validated on the fit logs: with two or \
         more, each log is predicted by the model fitted on the others; a single log is \
         cut into {} contiguous blocks, each predicted by the model fitted on the others \
         less {} s on each side of it",
        h.blocks, h.guard_seconds
    )
}

impl ModelArgs {
    /// The library's builder with the model and reading options of the arguments, for
    /// `vehicle` and `mapping` (loaded from `--vehicle` and `--mapping`).
    fn identification(&self, vehicle: Vehicle, mapping: Option<Mapping>) -> Identification {
        let job = Identification::new(vehicle)
            .model_options(ModelOptions {
                inflow: self.inflow,
                linear_vh_terms: !self.no_linear_vh,
                rotor_inertia: self.rotor_inertia,
            })
            .read_options(ReadOptions {
                airborne_only: !self.keep_ground,
                invalid: if self.drop_invalid {
                    InvalidSamples::DropAndCount
                } else {
                    InvalidSamples::Error
                },
                ..ReadOptions::default()
            });
        match mapping {
            Some(mapping) => job.mapping(mapping),
            None => job,
        }
    }
}

impl AccumulateArgs {
    /// The builder of the logs' first passes.
    fn identification(&self, vehicle: Vehicle, mapping: Option<Mapping>) -> Identification {
        let job = self
            .model
            .identification(vehicle, mapping)
            .logs(self.logs.iter().cloned())
            // The screening sample only for a diagnosis from these files.
            .diagnose(self.for_diagnosis);
        with_threads_and_low_pass(job, self.threads, self.loads_low_pass)
    }
}

impl PassArgs {
    /// The builder the plan is prepared with.
    fn identification(&self, vehicle: Vehicle, mapping: Option<Mapping>) -> Identification {
        let job = self.model.identification(vehicle, mapping);
        with_threads_and_low_pass(job, self.threads, self.loads_low_pass)
    }
}

/// `job` with `--threads` and `--loads-low-pass HZ` when given.
fn with_threads_and_low_pass(
    mut job: Identification,
    threads: Option<usize>,
    loads_low_pass: Option<f64>,
) -> Identification {
    if let Some(threads) = threads {
        job = job.threads(threads);
    }
    if let Some(hz) = loads_low_pass {
        job = job.loads_low_pass(hz);
    }
    job
}

impl FitArgs {
    /// The fit request, the library's builder set straight from the arguments (the
    /// vehicle and mapping loaded from `--vehicle` and `--mapping`).
    fn identification(&self, vehicle: Vehicle, mapping: Option<Mapping>) -> Identification {
        let mut job = self
            .model
            .identification(vehicle, mapping)
            .logs(self.logs.iter().cloned())
            .holdout(Holdout {
                blocks: self.holdout_blocks,
                guard_seconds: self.holdout_guard,
            })
            .diagnose(!self.no_diagnose);
        if !self.groups.is_empty() {
            job = job.groups(self.groups.iter().cloned());
        }
        for log in &self.validate {
            job = job.validate(log.clone());
        }
        if let Some(threads) = self.threads {
            job = job.threads(threads);
        }
        match self.loads_low_pass {
            Some(LowPassArg::Hz(hz)) => job = job.loads_low_pass(hz),
            Some(LowPassArg::Estimate) => job = job.estimate_loads_low_pass(),
            None => {}
        }
        job
    }
}
