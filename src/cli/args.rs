//! The command line's arguments (clap) and the pipeline job each asks for.

use clap::{Args, Parser, Subcommand};
use odocal::eval::{Alignment, DeltaUnit};
use odocal::experiments::ExperimentJob;
use odocal::pipeline::calibrate::{CalibSource, CalibrateJob, CalibratorChoice};
use odocal::pipeline::demo::DemoJob;
use odocal::pipeline::diagnose::DiagnoseJob;
use odocal::pipeline::evaluate::EvalJob;
use odocal::pipeline::icp::IcpJob;
use odocal::pipeline::inspect::InspectJob;
use odocal::pipeline::simulate::SimulateJob;
use odocal::pipeline::{self, PipelineError, Viewer};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "odocal",
    version,
    about = "Calibrated wheel odometry from 2D laser scans and wheel encoders"
)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// The main job: the whole pipeline on the bundled recording, into odocal-demo/.
    Demo(DemoArgs),
    /// Simulate the wheelchair in a 2D world and write a ROS 2 bag (MCAP).
    Simulate(SimulateArgs),
    /// Scan matching: consecutive scans into motions with covariance, and a trajectory.
    Icp(IcpArgs),
    /// Estimate wheel radii and wheel base online (Adaptive-PF, PF, DKF, AKF, none).
    Calibrate(CalibrateArgs),
    /// Evaluate a trajectory against a reference and/or relations (evo's numbers).
    Eval(EvalArgs),
    /// Find what the nominal model gets wrong against the measurements, name the cause.
    Diagnose(DiagnoseArgs),
    /// What a recording holds and what odocal would read from it: topics, transforms,
    /// the laser mounting, what each command misses, a proposed robot file.
    Inspect(InspectArgs),
    /// Regenerate the papers' tables: resampling, montecarlo, changing, literature,
    /// square, umbmark, heading-pf, tachometer.
    Experiment(ExperimentArgs),
    /// Calibrate a fleet's recordings; per robot the parameter history and its alarms.
    Fleet(super::fleet::FleetArgs),
}

#[derive(Args)]
pub struct ExperimentArgs {
    /// resampling (Table I), montecarlo (Table II), montecarlo-scans (Table II on simulated scans through ICP), changing (radii step at 55 s),
    /// literature (every method side by side), square, umbmark, heading-pf, tachometer.
    pub name: String,
    /// Monte Carlo runs (literature: repetitions; umbmark: robots; heading-pf: trials).
    #[arg(long, default_value_t = 30, allow_negative_numbers = true)]
    pub runs: usize,
    /// Seed of run 0 (run k uses seed + k).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Output directory (NAME.md, NAME.json, NAME.png).
    #[arg(long, value_name = "DIR", default_value = "odocal-experiments")]
    pub out: PathBuf,
    /// Experiment settings (TOML tables: literature, square, umbmark, heading_pf, scans).
    #[arg(long, value_name = "FILE.toml")]
    pub settings: Option<PathBuf>,
    /// Folder with the papers' published tables (square_path.csv, encoder_vs_tachometer.csv, ...).
    #[arg(long, value_name = "DIR")]
    pub tables: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args)]
pub struct DiagnoseArgs {
    /// Recording with wheel encoders (or its own odometry) and laser scans
    /// (ROS 2 MCAP or CARMEN log), or Censi et al.'s calibration tuples (.tuple).
    #[arg(long, value_name = "REC")]
    pub measured: PathBuf,
    /// Fraction of the recording (at its end) held out to measure the gain.
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true)]
    pub holdout: Option<f64>,
    /// Directory for report.md and the residual plots.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args)]
pub struct DemoArgs {
    /// Output directory (report.md, plots, trajectories, demo.rrd).
    #[arg(long, value_name = "DIR", default_value = "odocal-demo")]
    pub out: PathBuf,
    /// Another recording instead of the bundled one.
    #[arg(long, value_name = "REC")]
    pub input: Option<PathBuf>,
    /// The simulator's truth file of the recording (radii to compare with).
    #[arg(long, value_name = "TRUTH.json")]
    pub truth: Option<PathBuf>,
    /// Stream to a running Rerun viewer at this address instead of writing demo.rrd.
    #[arg(long, value_name = "ADDR", conflicts_with = "spawn")]
    pub connect: Option<String>,
    /// Spawn the Rerun viewer (when installed) and stream to it.
    #[arg(long)]
    pub spawn: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args)]
pub struct IcpArgs {
    /// Recording (ROS 2 MCAP or CARMEN log).
    #[arg(long, value_name = "REC")]
    pub input: PathBuf,
    /// Trajectory output (TUM).
    #[arg(long, value_name = "TRAJ.tum")]
    pub out: PathBuf,
    /// Per-pair motions with covariance and quality (CSV).
    #[arg(long, value_name = "MOTIONS.csv")]
    pub motions: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args)]
pub struct CalibrateArgs {
    /// Recording (ROS 2 MCAP or CARMEN log); ICP runs inside.
    #[arg(long, value_name = "REC", required_unless_present = "motions_csv")]
    pub input: Option<PathBuf>,
    /// Instead of a recording: ICP motions (CSV, as `odocal icp --motions` writes)...
    #[arg(
        long = "motions",
        value_name = "MOTIONS.csv",
        requires = "wheels_csv",
        conflicts_with = "input"
    )]
    pub motions_csv: Option<PathBuf>,
    /// ...and wheel angles `t,left,right` or rates `t0,t1,omega_right,omega_left` (CSV).
    #[arg(long = "wheels", value_name = "WHEELS.csv", requires = "motions_csv")]
    pub wheels_csv: Option<PathBuf>,
    /// Calibrator: adaptive-pf, pf, dkf, akf, none.
    #[arg(long)]
    pub method: Option<odocal::calib::Method>,
    /// Resampling scheme: multinomial, stratified, systematic, residual.
    #[arg(long)]
    pub resampler: Option<odocal::calib::Scheme>,
    /// When to resample: every, neff, max-weight.
    #[arg(long)]
    pub trigger: Option<odocal::calib::Trigger>,
    /// Initial particle count.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = particle_count)]
    pub particles: Option<usize>,
    /// Seed of every random draw.
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Where an online filter starts: nominal (the robot file) or batch (the joint batch
    /// estimate of the same recording: radii, wheel base, laser mounting, time offset).
    #[arg(long, value_name = "nominal|batch", default_value = "nominal")]
    pub init: odocal::pipeline::start::Start,
    /// Output directory: calibration.csv, trajectory.tum, summary.json.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Record the run for the Rerun viewer: trajectories, scans, particle cloud, estimates.
    #[arg(long, value_name = "FILE.rrd", conflicts_with_all = ["connect", "spawn"])]
    pub rrd: Option<PathBuf>,
    /// Stream the run to a running Rerun viewer at this address.
    #[arg(long, value_name = "ADDR", conflicts_with = "spawn")]
    pub connect: Option<String>,
    /// Spawn the Rerun viewer (when installed) and stream the run to it.
    #[arg(long)]
    pub spawn: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args)]
pub struct InspectArgs {
    /// Recording: ROS 2 MCAP, ROS 1 bag, rosbag2 SQLite or folder, CARMEN log.
    pub input: PathBuf,
    /// Write the proposed robot file here (TOML, atomically).
    #[arg(long, value_name = "FILE")]
    pub write_robot: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

impl InspectArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> InspectJob {
        InspectJob {
            input: self.input.clone(),
            common: self.common.files(),
            write_robot: self.write_robot.clone(),
        }
    }
}

#[derive(Args)]
pub struct Common {
    /// Stage settings (TOML tables: topics, sim, eval, ...).
    #[arg(long, value_name = "CFG.toml")]
    pub config: Option<PathBuf>,
    /// Nominal robot: a TOML file, or a bundled name (wheelchair, lego-robot, mines-rover,
    /// khepera; default: the LMS111 wheelchair).
    #[arg(long, value_name = "ROBOT.toml")]
    pub robot: Option<PathBuf>,
}

#[derive(Args)]
pub struct SimulateArgs {
    /// Built-in scenario name (corridor-loop, hall, square, square-ccw,
    /// figure-eight, random-walk) or a JSON scenario file.
    #[arg(long, value_name = "NAME|FILE")]
    pub scenario: Option<String>,
    /// Seed of every random process.
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Length of the run (s).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Effect injected into the true robot, `NAME` or `NAME:key=value,...` (repeatable).
    #[arg(long = "effect", value_name = "SPEC")]
    pub effects: Vec<String>,
    /// Output bag.
    #[arg(long, value_name = "REC.mcap")]
    pub out: PathBuf,
    /// Truth file (JSON): scenario, effects, true parameters and trajectory.
    #[arg(long, value_name = "TRUTH.json")]
    pub truth: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

#[derive(Args)]
pub struct EvalArgs {
    /// Trajectory under test (TUM, KITTI with --estimate-times, or MCAP).
    #[arg(long, value_name = "TRAJ")]
    pub estimate: PathBuf,
    /// Reference trajectory (TUM, KITTI with --reference-times, or an MCAP's reference topic).
    #[arg(long, value_name = "REF")]
    pub reference: Option<PathBuf>,
    /// Kümmerle et al. relations file.
    #[arg(long, value_name = "FILE")]
    pub relations: Option<PathBuf>,
    /// Timestamps file for a KITTI estimate.
    #[arg(long, value_name = "FILE")]
    pub estimate_times: Option<PathBuf>,
    /// Timestamps file for a KITTI reference.
    #[arg(long, value_name = "FILE")]
    pub reference_times: Option<PathBuf>,
    /// Alignment: auto (default: none, or se2 against a position-only reference), none,
    /// origin (heading of the first metre for a position-only reference), se2, sim2, se3, sim3.
    #[arg(long, value_name = "KIND")]
    pub align: Option<Alignment>,
    /// Maximum time difference for association (s).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub t_max_diff: Option<f64>,
    /// Time offset added to the estimate's stamps (s).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub t_offset: Option<f64>,
    /// evo's interpolation: the denser trajectory interpolated at the pairs found within --t-max-diff.
    #[arg(long)]
    pub interpolate: bool,
    /// Interpolate the reference at every estimate stamp inside its span (default: only for a
    /// position-only reference); `--resample-reference false` pairs nearest stamps.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true")]
    pub resample_reference: Option<bool>,
    /// Largest reference gap (s) that resampling bridges.
    #[arg(long, value_name = "S")]
    pub max_gap: Option<f64>,
    /// RPE step.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub rpe_delta: Option<f64>,
    /// RPE step unit: frames, m or s.
    #[arg(long, value_name = "UNIT")]
    pub rpe_unit: Option<DeltaUnit>,
    /// Write a PNG: trajectories overlaid and the error over time (needs --reference).
    #[arg(long, value_name = "PNG")]
    pub plot: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

impl Common {
    /// The pipeline's view of these options.
    pub fn files(&self) -> pipeline::Common {
        pipeline::Common {
            config: self.config.clone(),
            robot: self.robot.clone(),
        }
    }
}

/// The Rerun destination named by `--rrd`, `--connect` or `--spawn`.
pub fn viewer(file: Option<&PathBuf>, connect: Option<&String>, spawn: bool) -> Option<Viewer> {
    match (connect, spawn, file) {
        (Some(addr), _, _) => Some(Viewer::Connect(addr.clone())),
        (None, true, _) => Some(Viewer::Spawn),
        (None, false, Some(f)) => Some(Viewer::File(f.clone())),
        (None, false, None) => None,
    }
}

impl IcpArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> IcpJob {
        IcpJob {
            input: self.input.clone(),
            out: self.out.clone(),
            motions: self.motions.clone(),
            common: self.common.files(),
        }
    }
}

impl CalibrateArgs {
    /// The job these arguments ask for; an error when they name no input
    /// (clap already requires --input, or --motions with --wheels).
    pub fn job(&self) -> Result<CalibrateJob, PipelineError> {
        let input = match (&self.input, &self.motions_csv, &self.wheels_csv) {
            (Some(rec), _, _) => CalibSource::Recording(rec.clone()),
            (None, Some(m), Some(w)) => CalibSource::Csv {
                motions: m.clone(),
                wheels: w.clone(),
            },
            _ => {
                return Err(PipelineError::BadArgument(
                    "calibrate needs --input REC, or --motions and --wheels".into(),
                ))
            }
        };
        Ok(CalibrateJob {
            input,
            out: self.out.clone(),
            choice: CalibratorChoice {
                method: self.method,
                resampler: self.resampler,
                trigger: self.trigger,
                particles: self.particles,
                seed: self.seed,
            },
            viewer: viewer(self.rrd.as_ref(), self.connect.as_ref(), self.spawn),
            common: self.common.files(),
            init: self.init,
        })
    }
}

impl SimulateArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> SimulateJob {
        SimulateJob {
            scenario: self.scenario.clone(),
            seed: self.seed,
            duration_s: self.duration,
            effects: self.effects.clone(),
            out: self.out.clone(),
            truth: self.truth.clone(),
            common: self.common.files(),
        }
    }
}

impl EvalArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> EvalJob {
        EvalJob {
            estimate: self.estimate.clone(),
            reference: self.reference.clone(),
            relations: self.relations.clone(),
            estimate_times: self.estimate_times.clone(),
            reference_times: self.reference_times.clone(),
            align: self.align,
            t_max_diff: self.t_max_diff,
            t_offset: self.t_offset,
            interpolate: self.interpolate,
            resample: self.resample_reference,
            max_gap: self.max_gap,
            rpe_delta: self.rpe_delta,
            rpe_unit: self.rpe_unit,
            plot: self.plot.clone(),
            common: self.common.files(),
        }
    }
}

impl DemoArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> DemoJob {
        DemoJob {
            out: self.out.clone(),
            input: self.input.clone(),
            truth: self.truth.clone(),
            viewer: viewer(None, self.connect.as_ref(), self.spawn),
            common: self.common.files(),
        }
    }
}

impl DiagnoseArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> DiagnoseJob {
        DiagnoseJob {
            measured: self.measured.clone(),
            holdout: self.holdout,
            report: self.report.clone(),
            common: self.common.files(),
        }
    }
}

impl ExperimentArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> ExperimentJob {
        ExperimentJob {
            name: self.name.clone(),
            runs: self.runs,
            seed: self.seed,
            out: self.out.clone(),
            settings: self.settings.clone(),
            tables: self.tables.clone(),
            common: self.common.files(),
        }
    }
}

/// `--particles N`: a whole number from 1 to the cap
/// ([`odocal::calib::MAX_PARTICLES`]); anything else is refused naming the cap.
fn particle_count(text: &str) -> Result<usize, String> {
    let cap = odocal::calib::MAX_PARTICLES;
    match text.trim().parse::<i128>() {
        Ok(n) if n >= 1 && n <= cap as i128 => Ok(n as usize),
        _ => Err(format!(
            "{text} particles: the count must be a whole number from 1 to the cap of {cap}"
        )),
    }
}
