//! The `odocal` command line: parses arguments, calls the pipeline, prints.
//! Exit codes: 0 success, 2 bad input or arguments, 1 any other failure.

use clap::{Args, Parser, Subcommand};
use odocal::effects::Effect;
use odocal::eval::{Alignment, DeltaUnit, EvalOptions, RpeDelta};
use odocal::pipeline::{self, Config, PipelineError};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
    /// Simulate the wheelchair in a 2D world and write a ROS 2 bag (MCAP).
    Simulate(SimulateArgs),
    /// Evaluate a trajectory against a reference and/or relations (evo's numbers).
    Eval(EvalArgs),
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
        Command::Eval(a) => eval(a),
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
    println!("{}", serde_json::to_string_pretty(v)?);
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
    let report = pipeline::evaluate::run(&est, reference.as_ref(), a.relations.as_deref(), &opts)?;
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
        println!(
            "relations {name:<6} n={:<5} trans {:.3} ± {:.3} m   rot {:.2} ± {:.2} deg",
            s.count, s.trans_mean, s.trans_std, s.rot_mean_deg, s.rot_std_deg
        )
    };
    line("all", &r.all);
    if let Some(l) = &r.local {
        line("local", l);
    }
    if r.skipped > 0 {
        println!("relations skipped {} (outside the trajectory)", r.skipped);
    }
}

fn print_stats(name: &str, s: Option<&odocal::eval::Stats>) {
    match s {
        Some(s) => println!(
            "{name:<16} rmse {:.4}  mean {:.4}  median {:.4}  std {:.4}  min {:.4}  max {:.4}",
            s.rmse, s.mean, s.median, s.std, s.min, s.max
        ),
        None => println!("{name:<16} n/a (position-only reference)"),
    }
}

fn print_trajectory_metrics(t: &odocal::eval::TrajectoryMetrics) {
    println!("matched poses    {}", t.matched);
    print_stats("APE (m)", Some(&t.ape));
    print_stats("APE rot (deg)", t.ape_rot_deg.as_ref());
    print_stats("RPE (m)", Some(&t.rpe));
    print_stats("RPE rot (deg)", t.rpe_rot_deg.as_ref());
    println!("RMSE x,y (m)     {:.4}", t.rmse_xy);
    if let Some(r) = t.rmse_theta {
        println!("RMSE θ (rad)     {r:.4}");
    }
    match t.drift_percent {
        Some(d) => println!("drift            {d:.3} % of {:.1} m", t.path_length),
        None => println!("drift            n/a (reference does not move)"),
    }
    println!("final error (m)  {:.4}", t.final_error);
}
