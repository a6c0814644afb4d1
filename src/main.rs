//! The `odocal` command line: parses arguments, calls the pipeline, prints.
//! Exit codes: 0 success, 2 bad input or arguments, 1 any other failure.

use clap::{Args, Parser, Subcommand};
use odocal::effects::Effect;
use odocal::eval::{Alignment, DeltaUnit, EvalOptions, RpeDelta};
use odocal::pipeline::{self, Config, PipelineError};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Prints a line on stdout; a closed pipe (`odocal ... | head`) is not an error.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

#[derive(Parser)]
#[command(
    name = "odocal",
    version,
    about = "Calibrated wheel odometry from 2D laser scans and wheel encoders"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
    /// Regenerate the seeds' tables: resampling, montecarlo, changing, literature,
    /// square, umbmark, heading-pf, tachometer.
    Experiment(ExperimentArgs),
}

#[derive(Args)]
struct ExperimentArgs {
    /// resampling (Table I), montecarlo (Table II), montecarlo-scans (Table II on simulated scans through ICP), changing (radii step at 55 s),
    /// literature (every method side by side), square, umbmark, heading-pf, tachometer.
    name: String,
    /// Monte Carlo runs (literature: repetitions; umbmark: robots; heading-pf: trials).
    #[arg(long, default_value_t = 30)]
    runs: usize,
    /// Seed of run 0 (run k uses seed + k).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory (NAME.md, NAME.json, NAME.png).
    #[arg(long, value_name = "DIR", default_value = "odocal-experiments")]
    out: PathBuf,
    /// Experiment settings (TOML tables: literature, square, umbmark, heading_pf, scans).
    #[arg(long, value_name = "FILE.toml")]
    settings: Option<PathBuf>,
    /// Folder with the seed tables (square_path.csv, encoder_vs_tachometer.csv, ...).
    #[arg(long, value_name = "DIR")]
    tables: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
struct DiagnoseArgs {
    /// Recording with wheel encoders (or its own odometry) and laser scans
    /// (ROS 2 MCAP or CARMEN log), or Censi et al.'s calibration tuples (.tuple).
    #[arg(long, value_name = "REC")]
    measured: PathBuf,
    /// Fraction of the recording (at its end) held out to measure the gain.
    #[arg(long, value_name = "FRACTION")]
    holdout: Option<f64>,
    /// Directory for report.md and the residual plots.
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
struct DemoArgs {
    /// Output directory (report.md, plots, trajectories, demo.rrd).
    #[arg(long, value_name = "DIR", default_value = "odocal-demo")]
    out: PathBuf,
    /// Another recording instead of the bundled one.
    #[arg(long, value_name = "REC")]
    input: Option<PathBuf>,
    /// The simulator's truth file of the recording (radii to compare with).
    #[arg(long, value_name = "TRUTH.json")]
    truth: Option<PathBuf>,
    /// Stream to a running Rerun viewer at this address instead of writing demo.rrd.
    #[arg(long, value_name = "ADDR", conflicts_with = "spawn")]
    connect: Option<String>,
    /// Spawn the Rerun viewer (when installed) and stream to it.
    #[arg(long)]
    spawn: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
struct IcpArgs {
    /// Recording (ROS 2 MCAP or CARMEN log).
    #[arg(long, value_name = "REC")]
    input: PathBuf,
    /// Trajectory output (TUM).
    #[arg(long, value_name = "TRAJ.tum")]
    out: PathBuf,
    /// Per-pair motions with covariance and quality (CSV).
    #[arg(long, value_name = "MOTIONS.csv")]
    motions: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
struct CalibrateArgs {
    /// Recording (ROS 2 MCAP or CARMEN log); ICP runs inside.
    #[arg(long, value_name = "REC", required_unless_present = "motions_csv")]
    input: Option<PathBuf>,
    /// Instead of a recording: ICP motions (CSV, as `odocal icp --motions` writes)...
    #[arg(
        long = "motions",
        value_name = "MOTIONS.csv",
        requires = "wheels_csv",
        conflicts_with = "input"
    )]
    motions_csv: Option<PathBuf>,
    /// ...and wheel angles `t,left,right` or rates `t0,t1,omega_right,omega_left` (CSV).
    #[arg(long = "wheels", value_name = "WHEELS.csv", requires = "motions_csv")]
    wheels_csv: Option<PathBuf>,
    /// Calibrator: adaptive-pf, pf, dkf, akf, none.
    #[arg(long)]
    method: Option<odocal::calib::Method>,
    /// Resampling scheme: multinomial, stratified, systematic, residual.
    #[arg(long)]
    resampler: Option<odocal::calib::Scheme>,
    /// When to resample: every, neff, max-weight.
    #[arg(long)]
    trigger: Option<odocal::calib::Trigger>,
    /// Initial particle count.
    #[arg(long, value_name = "N")]
    particles: Option<usize>,
    /// Seed of every random draw.
    #[arg(long)]
    seed: Option<u64>,
    /// Output directory: calibration.csv, trajectory.tum, summary.json.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Record the run for the Rerun viewer: trajectories, scans, particle cloud, estimates.
    #[arg(long, value_name = "FILE.rrd", conflicts_with_all = ["connect", "spawn"])]
    rrd: Option<PathBuf>,
    /// Stream the run to a running Rerun viewer at this address.
    #[arg(long, value_name = "ADDR", conflicts_with = "spawn")]
    connect: Option<String>,
    /// Spawn the Rerun viewer (when installed) and stream the run to it.
    #[arg(long)]
    spawn: bool,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
struct Common {
    /// Stage settings (TOML tables: topics, sim, eval, ...).
    #[arg(long, value_name = "CFG.toml")]
    config: Option<PathBuf>,
    /// Nominal robot (default: the LMS111 wheelchair).
    #[arg(long, value_name = "ROBOT.toml")]
    robot: Option<PathBuf>,
}

#[derive(Args)]
struct SimulateArgs {
    /// Built-in scenario name (corridor-loop, hall, square, square-ccw,
    /// figure-eight, random-walk) or a JSON scenario file.
    #[arg(long, value_name = "NAME|FILE")]
    scenario: Option<String>,
    /// Seed of every random process.
    #[arg(long)]
    seed: Option<u64>,
    /// Length of the run (s).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Effect injected into the true robot, `NAME` or `NAME:key=value,...` (repeatable).
    #[arg(long = "effect", value_name = "SPEC")]
    effects: Vec<String>,
    /// Output bag.
    #[arg(long, value_name = "REC.mcap")]
    out: PathBuf,
    /// Truth file (JSON): scenario, effects, true parameters and trajectory.
    #[arg(long, value_name = "TRUTH.json")]
    truth: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    common: Common,
}

#[derive(Args)]
struct EvalArgs {
    /// Trajectory under test (TUM, KITTI with --estimate-times, or MCAP).
    #[arg(long, value_name = "TRAJ")]
    estimate: PathBuf,
    /// Reference trajectory (TUM, KITTI with --reference-times, or an MCAP's reference topic).
    #[arg(long, value_name = "REF")]
    reference: Option<PathBuf>,
    /// Kümmerle et al. relations file.
    #[arg(long, value_name = "FILE")]
    relations: Option<PathBuf>,
    /// Timestamps file for a KITTI estimate.
    #[arg(long, value_name = "FILE")]
    estimate_times: Option<PathBuf>,
    /// Timestamps file for a KITTI reference.
    #[arg(long, value_name = "FILE")]
    reference_times: Option<PathBuf>,
    /// Alignment: none, origin, se2, sim2, se3, sim3.
    #[arg(long, value_name = "KIND")]
    align: Option<Alignment>,
    /// Maximum time difference for association (s).
    #[arg(long, value_name = "S")]
    t_max_diff: Option<f64>,
    /// Time offset added to the estimate's stamps (s).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    t_offset: Option<f64>,
    /// Interpolate the reference at the estimate's stamps.
    #[arg(long)]
    interpolate: bool,
    /// RPE step.
    #[arg(long, value_name = "X")]
    rpe_delta: Option<f64>,
    /// RPE step unit: frames, m or s.
    #[arg(long, value_name = "UNIT")]
    rpe_unit: Option<DeltaUnit>,
    /// Write a PNG: trajectories overlaid and the error over time (needs --reference).
    #[arg(long, value_name = "PNG")]
    plot: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    common: Common,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            // clap: help/version are success, everything else is a bad argument.
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    let result = match cli.command {
        Command::Simulate(a) => simulate(a),
        Command::Demo(a) => demo(a),
        Command::Icp(a) => icp(a),
        Command::Calibrate(a) => calibrate(a),
        Command::Eval(a) => eval(a),
        Command::Diagnose(a) => diagnose(a),
        Command::Experiment(a) => experiment(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("odocal: {e:#}");
            let code = e
                .downcast_ref::<PipelineError>()
                .map(|p| p.exit_code())
                .unwrap_or(1);
            ExitCode::from(code as u8)
        }
    }
}

fn bad(msg: impl Into<String>) -> anyhow::Error {
    PipelineError::BadArgument(msg.into()).into()
}

fn print_json<T: serde::Serialize>(v: &T) -> anyhow::Result<()> {
    out!("{}", serde_json::to_string_pretty(v)?);
    Ok(())
}

fn load_common(c: &Common) -> Result<(Config, odocal::robot::RobotConfig), PipelineError> {
    Ok((
        Config::load(c.config.as_deref())?,
        pipeline::load_robot(c.robot.as_deref())?,
    ))
}

fn progress_bar(what: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new(1000);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{msg:>12} [{bar:40}] {percent:>3}% {elapsed}")
            .expect("static template")
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

fn simulate(a: SimulateArgs) -> anyhow::Result<()> {
    let (mut cfg, robot) = load_common(&a.common)?;
    if let Some(s) = &a.scenario {
        let p = Path::new(s);
        if s.ends_with(".json") || p.is_file() {
            let text = std::fs::read_to_string(p).map_err(|e| {
                PipelineError::Input(odocal::InputError::new(
                    s.clone(),
                    format!("cannot read: {e}"),
                ))
            })?;
            cfg.sim.scenario.custom =
                Some(odocal::sim::ScenarioSpec::from_json(&text).map_err(|e| {
                    PipelineError::Input(odocal::InputError::new(s.clone(), e.to_string()))
                })?);
        } else {
            cfg.sim.scenario.name = s.clone();
        }
    }
    if let Some(seed) = a.seed {
        cfg.sim.seed = seed;
    }
    if let Some(d) = a.duration {
        cfg.sim.duration_s = d;
    }
    let effects = a
        .effects
        .iter()
        .map(|s| Effect::parse(s).map_err(|e| bad(e.to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    let pb = progress_bar("simulate");
    let (summary, _) = pipeline::simulate::run(
        &cfg.sim,
        &cfg.topics,
        &robot,
        &effects,
        &a.out,
        a.truth.as_deref(),
        &mut |f| pb.set_position((f * 1000.0) as u64),
    )?;
    pb.finish_and_clear();
    if a.json {
        return print_json(&summary);
    }
    eprintln!(
        "wrote {} ({} scans, {:.0} s, {:.1} m of {}){}",
        summary.out,
        summary.scans,
        summary.duration_s,
        summary.path_length_m,
        summary.scenario,
        summary
            .truth
            .as_deref()
            .map(|t| format!("; truth in {t}"))
            .unwrap_or_default()
    );
    Ok(())
}

fn eval(a: EvalArgs) -> anyhow::Result<()> {
    let (cfg, robot) = load_common(&a.common)?;
    if a.reference.is_none() && a.relations.is_none() {
        return Err(bad("eval needs --reference, --relations, or both"));
    }
    let mut opts: EvalOptions = cfg.eval;
    if let Some(al) = a.align {
        opts.align = al;
    }
    if let Some(t) = a.t_max_diff {
        opts.sync.max_diff = t;
    }
    if let Some(t) = a.t_offset {
        opts.sync.offset = t;
    }
    if a.interpolate {
        opts.sync.interpolate = true;
    }
    if let Some(d) = a.rpe_delta {
        opts.rpe_delta = RpeDelta {
            value: d,
            unit: a.rpe_unit.unwrap_or(opts.rpe_delta.unit),
        };
    } else if let Some(u) = a.rpe_unit {
        opts.rpe_delta.unit = u;
    }
    let mut read = odocal::io::ReadOptions::for_robot(&robot);
    read.topics = cfg.topics.clone();
    let (est, _) =
        pipeline::evaluate::load_trajectory(&a.estimate, a.estimate_times.as_deref(), &read)?;
    let reference = match &a.reference {
        Some(r) => {
            let (t, position_only) =
                pipeline::evaluate::load_trajectory(r, a.reference_times.as_deref(), &read)?;
            opts.position_only |= position_only;
            Some(t)
        }
        None => None,
    };
    if a.plot.is_some() && reference.is_none() {
        return Err(bad("--plot needs --reference"));
    }
    let report = pipeline::evaluate::run(&est, reference.as_ref(), a.relations.as_deref(), &opts)?;
    if let Some(png) = &a.plot {
        pipeline::evaluate::write_plot(png, &report, opts.position_only)?;
    }
    if a.json {
        return print_json(&report);
    }
    if let Some(t) = &report.trajectory {
        print_trajectory_metrics(t);
    }
    if let Some(r) = &report.relations {
        print_relations(r);
    }
    Ok(())
}

fn print_relations(r: &odocal::eval::RelationStats) {
    let line = |name: &str, s: &odocal::eval::RelationSummary| {
        out!(
            "relations {name:<6} n={:<5} trans {:.3} ± {:.3} m   rot {:.2} ± {:.2} deg",
            s.count,
            s.trans_mean,
            s.trans_std,
            s.rot_mean_deg,
            s.rot_std_deg
        )
    };
    line("all", &r.all);
    if let Some(l) = &r.local {
        line("local", l);
    }
    if r.skipped > 0 {
        out!("relations skipped {} (outside the trajectory)", r.skipped);
    }
}

fn print_stats(name: &str, s: Option<&odocal::eval::Stats>) {
    match s {
        Some(s) => out!(
            "{name:<16} rmse {:.4}  mean {:.4}  median {:.4}  std {:.4}  min {:.4}  max {:.4}",
            s.rmse,
            s.mean,
            s.median,
            s.std,
            s.min,
            s.max
        ),
        None => out!("{name:<16} n/a (position-only reference)"),
    }
}

fn print_trajectory_metrics(t: &odocal::eval::TrajectoryMetrics) {
    out!("matched poses    {}", t.matched);
    print_stats("APE (m)", Some(&t.ape));
    print_stats("APE rot (deg)", t.ape_rot_deg.as_ref());
    print_stats("RPE (m)", Some(&t.rpe));
    print_stats("RPE rot (deg)", t.rpe_rot_deg.as_ref());
    out!("RMSE x,y (m)     {:.4}", t.rmse_xy);
    if let Some(r) = t.rmse_theta {
        out!("RMSE θ (rad)     {r:.4}");
    }
    match t.drift_percent {
        Some(d) => out!("drift            {d:.3} % of {:.1} m", t.path_length),
        None => out!("drift            n/a (reference does not move)"),
    }
    out!("final error (m)  {:.4}", t.final_error);
}

fn read_recording(
    path: &Path,
    cfg: &Config,
    robot: &odocal::robot::RobotConfig,
) -> Result<odocal::recording::Recording, PipelineError> {
    Ok(odocal::io::read_recording(path, &read_options(cfg, robot))?)
}

fn read_options(cfg: &Config, robot: &odocal::robot::RobotConfig) -> odocal::io::ReadOptions {
    let mut read = odocal::io::ReadOptions::for_robot(robot);
    read.topics = cfg.topics.clone();
    read
}

fn icp(a: IcpArgs) -> anyhow::Result<()> {
    let (cfg, robot) = load_common(&a.common)?;
    let start = std::time::Instant::now();
    let (mut stats, path_length) = if odocal::io::stream::is_mcap(&a.input) {
        // Bags stream through in flat memory, however long.
        let pb = progress_bar("icp");
        let out = pipeline::icp::run_file(
            &a.input,
            &read_options(&cfg, &robot),
            &robot,
            &cfg.icp,
            &a.out,
            a.motions.as_deref(),
            &mut |f| pb.set_position((f * 1000.0) as u64),
        )?;
        pb.finish_and_clear();
        (out.stats, out.path_length)
    } else {
        let rec = read_recording(&a.input, &cfg, &robot)?;
        let out = pipeline::icp::run(&rec, &robot, &cfg.icp)?;
        pipeline::icp::write(&out, &a.out, a.motions.as_deref())?;
        (out.stats, out.trajectory.path_length())
    };
    // Wall time of the whole command (decoding included), as users time it.
    stats.wall_s = start.elapsed().as_secs_f64();
    stats.pairs_per_s = stats.pairs as f64 / stats.wall_s.max(1e-9);
    if a.json {
        return print_json(&stats);
    }
    eprintln!(
        "{} pairs ({} failed), {:.1} iterations on average, {:.2} s ({:.0} pairs/s); trajectory {:.1} m -> {}",
        stats.pairs,
        stats.failed_pairs,
        stats.mean_iterations,
        stats.wall_s,
        stats.pairs_per_s,
        path_length,
        a.out.display()
    );
    Ok(())
}

fn calibrate(a: CalibrateArgs) -> anyhow::Result<()> {
    let (mut cfg, robot) = load_common(&a.common)?;
    if let Some(m) = a.method {
        cfg.calib.method = m;
    }
    if let Some(r) = a.resampler {
        cfg.calib.resampler = r;
    }
    if let Some(t) = a.trigger {
        cfg.calib.trigger = t;
    }
    if let Some(n) = a.particles {
        cfg.calib.particles = Some(n);
    }
    if let Some(s) = a.seed {
        cfg.calib.seed = s;
    }
    let mut logger = rerun_logger(a.rrd.clone(), &a.connect, a.spawn)?;
    if let Some(rec_path) = a.input.as_ref().filter(|p| odocal::io::stream::is_mcap(p)) {
        // Bags stream through in flat memory, however long, also when the
        // run is recorded for Rerun (the recorder bounds what it keeps).
        use odocal::io::stream_run::{NoObserver, RunObserver};
        use pipeline::record_stream::{RecorderOptions, StreamRecorder};
        let pb = progress_bar("calibrate");
        let mut quiet = NoObserver;
        let mut recorder = logger.as_deref_mut().map(|l| {
            StreamRecorder::new(
                l,
                RecorderOptions::default(),
                robot.diff_drive(),
                robot.laser.pose(),
            )
        });
        let observer: &mut dyn RunObserver = match recorder.as_mut() {
            Some(r) => r,
            None => &mut quiet,
        };
        let summary = pipeline::calibrate::run_file(
            rec_path,
            &read_options(&cfg, &robot),
            &robot,
            &cfg.icp,
            &cfg.calib,
            &cfg.measurements,
            &a.out,
            &mut |f| pb.set_position((f * 1000.0) as u64),
            observer,
        )?;
        pb.finish_and_clear();
        if let Some(r) = recorder {
            let notes = r.finish().map_err(|e| PipelineError::Write {
                path: "rerun recording".into(),
                message: e.to_string(),
            })?;
            for n in notes {
                eprintln!("note: {n}");
            }
        }
        return print_calibration(&summary, a.json, &a.out);
    }
    let (input, rec, icp_out) = match (&a.input, &a.motions_csv, &a.wheels_csv) {
        (Some(rec_path), _, _) => {
            let rec = read_recording(rec_path, &cfg, &robot)?;
            let out = pipeline::icp::run(&rec, &robot, &cfg.icp)?;
            let input = pipeline::calibrate::CalibInput {
                observations: out.observations(),
                wheels: rec.wheels.clone(),
                gyro: rec.gyro.clone(),
            };
            (input, Some(rec), Some(out))
        }
        (None, Some(m), Some(w)) => {
            let motions = odocal::io::csv::read_motions(m).map_err(PipelineError::from)?;
            let input = pipeline::calibrate::CalibInput {
                observations: motions
                    .iter()
                    .filter_map(odocal::motion::VelocityObs::from_motion)
                    .collect(),
                wheels: odocal::io::csv::read_wheels(w).map_err(PipelineError::from)?,
                gyro: Vec::new(),
            };
            (input, None, None)
        }
        _ => {
            return Err(bad(
                "calibrate needs --input REC, or --motions and --wheels",
            ))
        }
    };
    if input.wheels.len() < 2 {
        return Err(bad(
            "the input has no wheel encoder data (JointState) to calibrate",
        ));
    }
    let run = match logger.as_deref_mut() {
        None => pipeline::calibrate::run(&input, &robot, &cfg.calib, &cfg.measurements)?,
        Some(logger) => {
            use pipeline::record::{particle_logger, record, RunRecord};
            // The `scan` timeline: the scans, or the motions' ends without a recording.
            let scan_stamps: Vec<f64> = match &rec {
                Some(r) => r.scans.iter().map(|s| s.stamp).collect(),
                None => input.observations.iter().map(|o| o.t1).collect(),
            };
            let t_start = rec
                .as_ref()
                .and_then(|r| r.time_span())
                .map(|s| s.0)
                .unwrap_or(input.wheels[0].stamp);
            let mut log_error = None;
            let run = {
                let mut on_step = particle_logger(logger, &scan_stamps, t_start, &mut log_error);
                pipeline::calibrate::run_observed(
                    &input,
                    &robot,
                    &cfg.calib,
                    &cfg.measurements,
                    &mut on_step,
                )?
            };
            if let Some(e) = log_error {
                return Err(PipelineError::Write {
                    path: "rerun recording".into(),
                    message: e.to_string(),
                }
                .into());
            }
            let raw = odocal::robot::wheel_odometry(
                &robot.diff_drive(),
                &input.wheels,
                odocal::geom::Pose2::identity(),
            );
            let reference = rec.as_ref().and_then(|r| {
                (r.reference.len() >= 2)
                    .then(|| odocal::eval::trajectory_from_stamped(&r.reference).0)
            });
            record(
                &RunRecord {
                    recording: rec.as_ref(),
                    robot: &robot,
                    walls: None,
                    icp: icp_out.as_ref(),
                    raw: Some(&raw),
                    calibrated: &run,
                    reference: reference.as_ref(),
                    t_start,
                    scan_stamps: &scan_stamps,
                },
                logger,
            )?;
            run
        }
    };
    pipeline::calibrate::write(&a.out, &run)?;
    print_calibration(&run.summary, a.json, &a.out)
}

fn print_calibration(
    s: &odocal::calib::CalibSummary,
    json: bool,
    out: &Path,
) -> anyhow::Result<()> {
    if json {
        return print_json(s);
    }
    eprintln!(
        "{}: R_R {:.5} ± {:.5} m, R_L {:.5} ± {:.5} m, D {:.5} ± {:.5} m after {} steps ({:.3} ms/step)",
        s.method,
        s.final_params.r_right,
        s.std.r_right,
        s.final_params.r_left,
        s.std.r_left,
        s.final_params.wheel_base,
        s.std.wheel_base,
        s.iterations,
        s.mean_iteration_ms
    );
    eprintln!(
        "diff_drive_controller multipliers: right_wheel_radius {:.5}, left_wheel_radius {:.5}, wheel_separation {:.5}; outputs in {}",
        s.multipliers.right_wheel_radius,
        s.multipliers.left_wheel_radius,
        s.multipliers.wheel_separation,
        out.display()
    );
    Ok(())
}

/// The bundled recording `odocal demo` runs on by default.
const DEMO_RECORDING: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);
/// Its truth file.
const DEMO_TRUTH: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.truth.json"
);

/// The Rerun logger asked for: a file, a running viewer, or a spawned one;
/// `None` when none is asked for.
#[cfg(feature = "rerun")]
fn rerun_logger(
    file: Option<PathBuf>,
    connect: &Option<String>,
    spawn: bool,
) -> anyhow::Result<Option<Box<dyn odocal::viz::Logger>>> {
    use odocal::viz::{RerunLogger, RerunOptions, RerunSink};
    let sink = match (connect, spawn, file) {
        (Some(addr), _, _) => RerunSink::Connect(addr.clone()),
        (None, true, _) => RerunSink::Spawn,
        (None, false, Some(f)) => RerunSink::File(f),
        (None, false, None) => return Ok(None),
    };
    Ok(Some(Box::new(RerunLogger::new(
        sink,
        RerunOptions::default(),
    )?)))
}

#[cfg(not(feature = "rerun"))]
fn rerun_logger(
    file: Option<PathBuf>,
    connect: &Option<String>,
    spawn: bool,
) -> anyhow::Result<Option<Box<dyn odocal::viz::Logger>>> {
    if file.is_some() || connect.is_some() || spawn {
        return Err(bad(
            "this odocal was built without the `rerun` feature: no Rerun recording",
        ));
    }
    Ok(None)
}

fn demo_logger(a: &DemoArgs) -> anyhow::Result<Box<dyn odocal::viz::Logger>> {
    // Without the `rerun` feature the demo still runs, with nothing recorded.
    let file = cfg!(feature = "rerun").then(|| a.out.join("demo.rrd"));
    Ok(rerun_logger(file, &a.connect, a.spawn)?
        .unwrap_or_else(|| Box::new(odocal::viz::NullLogger)))
}

fn demo(a: DemoArgs) -> anyhow::Result<()> {
    let (cfg, robot) = load_common(&a.common)?;
    let (input, truth_path) = match &a.input {
        Some(p) => (p.clone(), a.truth.clone()),
        None => (
            PathBuf::from(DEMO_RECORDING),
            Some(a.truth.clone().unwrap_or_else(|| PathBuf::from(DEMO_TRUTH))),
        ),
    };
    let truth = match &truth_path {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| {
                PipelineError::Input(odocal::InputError::new(
                    p.display().to_string(),
                    format!("cannot read: {e}"),
                ))
            })?;
            Some(odocal::sim::Truth::from_json(&text).map_err(|e| {
                PipelineError::Input(odocal::InputError::new(
                    p.display().to_string(),
                    e.to_string(),
                ))
            })?)
        }
        None => None,
    };
    let rec = read_recording(&input, &cfg, &robot)?;
    std::fs::create_dir_all(&a.out).map_err(|e| PipelineError::write(&a.out, e))?;
    let mut logger = demo_logger(&a)?;
    let pb = progress_bar("demo");
    let name = input.display().to_string();
    let summary = pipeline::demo::run(
        &pipeline::demo::DemoInput {
            recording: &rec,
            name: &name,
            truth: truth.as_ref(),
            robot: &robot,
            config: &cfg,
        },
        &a.out,
        logger.as_mut(),
        &mut |stage, f| {
            pb.set_message(stage.to_string());
            pb.set_position((f * 1000.0) as u64);
        },
    )?;
    pb.finish_and_clear();
    if a.json {
        return print_json(&summary);
    }
    out!(
        "odocal demo on {} ({} scans, {:.0} s) in {:.1} s",
        summary.input,
        summary.scans,
        summary.duration_s,
        summary.wall_s
    );
    out!(
        "ICP: {} pairs, {} flagged, {:.1} iterations on average",
        summary.icp.pairs,
        summary.icp.failed_pairs,
        summary.icp.mean_iterations
    );
    for m in &summary.methods {
        let err = m
            .final_errors
            .map(|e| {
                format!(
                    "  error R_R {:+.2} mm, R_L {:+.2} mm, D {:+.1} mm",
                    e[0] * 1e3,
                    e[1] * 1e3,
                    e[2] * 1e3
                )
            })
            .unwrap_or_default();
        let ape = m
            .eval
            .as_ref()
            .map(|e| format!("  APE {:.3} m", e.ape.rmse))
            .unwrap_or_default();
        out!(
            "{:<12} R_R {:.5} m  R_L {:.5} m  D {:.4} m{err}{ape}",
            m.method,
            m.final_params[0],
            m.final_params[1],
            m.final_params[2]
        );
    }
    out!("report: {}", a.out.join("report.md").display());
    if cfg!(feature = "rerun") && a.connect.is_none() && !a.spawn {
        out!(
            "open the recording with: rerun {}",
            a.out.join("demo.rrd").display()
        );
    }
    Ok(())
}

fn diagnose(a: DiagnoseArgs) -> anyhow::Result<()> {
    let (mut cfg, robot) = load_common(&a.common)?;
    if let Some(h) = a.holdout {
        if !(h > 0.0 && h < 1.0) {
            return Err(bad(format!(
                "--holdout must be a fraction in (0, 1), got {h}"
            )));
        }
        cfg.diagnose.holdout = h;
    }
    let d = if a.measured.extension().is_some_and(|e| e == "tuple") {
        let tuples = odocal::io::censi::read(&a.measured).map_err(PipelineError::from)?;
        pipeline::diagnose::run_tuples(&tuples, &robot, &cfg.diagnose)?
    } else {
        let rec = read_recording(&a.measured, &cfg, &robot)?;
        pipeline::diagnose::run(&rec, &robot, &cfg.icp, &cfg.diagnose)?
    };
    if let Some(dir) = &a.report {
        pipeline::diagnose::write_report(dir, &a.measured.display().to_string(), &d)?;
    }
    if a.json {
        return print_json(&d);
    }
    out!("verdict: {}", pipeline::diagnose::verdict_word(&d));
    for c in &d.causes {
        let params: Vec<String> = c
            .parameters
            .iter()
            .map(|(k, v)| match c.stderr.get(k) {
                Some(e) => format!("{k} = {v:.6} ± {e:.6}"),
                None => format!("{k} = {v:.6}"),
            })
            .collect();
        out!(
            "  {}: {} (ΔBIC {:.1})",
            c.effect,
            params.join(", "),
            c.delta_bic
        );
    }
    out!(
        "held-out residual RMSE {:.4} -> {:.4} ({:+.1} %)",
        d.gain.heldout_rmse_before,
        d.gain.heldout_rmse_after,
        -100.0 * d.gain.relative
    );
    if let Some(dir) = &a.report {
        out!("report: {}", dir.join("report.md").display());
    }
    Ok(())
}

fn experiment(a: ExperimentArgs) -> anyhow::Result<()> {
    let (cfg, robot) = load_common(&a.common)?;
    let settings = pipeline::experiment::ExperimentSettings::load(a.settings.as_deref())?;
    let inputs = pipeline::experiment::ExperimentInputs {
        runs: a.runs,
        seed: a.seed,
        calib: &cfg.calib,
        robot: &robot,
        settings: &settings,
        tables: a.tables.as_deref(),
        icp: &cfg.icp,
    };
    let res = pipeline::experiment::run(&a.name, &inputs, &a.out)?;
    if a.json {
        out!("{}", res.json);
        return Ok(());
    }
    out!("{}", res.summary);
    out!("written to {}", a.out.display());
    Ok(())
}
