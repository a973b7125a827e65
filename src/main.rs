//! The `mrsysid` command-line tool: a thin shell over the library.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use mrsysid::sim::Effect;
use mrsysid::sim::flight::FlightConfig;
use mrsysid::sim::run::{Mode, SimulateOptions, VehicleChoice, simulate_to_file};
use mrsysid::sim::test_matrix::Design;

/// Offline nonlinear system identification of multirotor aircraft.
#[derive(Parser)]
#[command(name = "mrsysid", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Generate truth data: a response-surface sweep or a flight log (CSV data contract).
    Simulate(SimulateArgs),
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
}

fn parse_effect(s: &str) -> Result<Effect, String> {
    s.parse()
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
        Command::Simulate(args) => simulate_to_file(&args.options(), &args.out)
            .map(|rows| eprintln!("wrote {rows} rows to {}", args.out.display())),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
