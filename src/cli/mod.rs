//! The `odocal` command line: each command's arguments become a pipeline
//! job, whose summary is printed (one JSON object with `--json`).

pub mod args;
mod fleet;
mod inspect_print;
mod live;
mod print;

use args::{
    CalibrateArgs, Command, DemoArgs, DiagnoseArgs, EvalArgs, ExperimentArgs, IcpArgs, InspectArgs,
    SimulateArgs,
};
use odocal::pipeline::{self, Progress};
use print::out;

/// Runs one command.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Simulate(a) => simulate(a),
        Command::Demo(a) => demo(a),
        Command::Icp(a) => icp(a),
        Command::Calibrate(a) => calibrate(a),
        Command::Eval(a) => eval(a),
        Command::Diagnose(a) => diagnose(a),
        Command::Experiment(a) => experiment(a),
        Command::Inspect(a) => inspect(a),
        Command::Fleet(a) => fleet::run(a),
        Command::Live(a) => live::live(a),
        Command::Play(a) => live::play(a),
        Command::HelpMarkdown => {
            print!("{}", args::reference_markdown());
            Ok(())
        }
    }
}

fn inspect(a: InspectArgs) -> anyhow::Result<()> {
    let i = pipeline::inspect::run(&a.job())?;
    if a.json {
        return print_json(&i);
    }
    inspect_print::inspection(&i);
    Ok(())
}

fn print_json<T: serde::Serialize>(v: &T) -> anyhow::Result<()> {
    out!("{}", serde_json::to_string_pretty(v)?);
    Ok(())
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
    let pb = progress_bar("simulate");
    let summary = pipeline::simulate::run(&a.job(), &mut |f| pb.set_position((f * 1000.0) as u64))?;
    pb.finish_and_clear();
    if a.json {
        return print_json(&summary);
    }
    print::simulation(&summary);
    Ok(())
}

fn eval(a: EvalArgs) -> anyhow::Result<()> {
    let report = pipeline::evaluate::run(&a.job())?;
    if a.json {
        return print_json(&report);
    }
    if let Some(t) = &report.trajectory {
        print::trajectory_metrics(t);
    }
    if let Some(r) = &report.relations {
        print::relations(r);
    }
    Ok(())
}

fn icp(a: IcpArgs) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    let pb = progress_bar("icp");
    let run = pipeline::icp::run(
        &a.job(),
        &mut Progress::new(|f| pb.set_position((f * 1000.0) as u64)),
    )?;
    pb.finish_and_clear();
    let mut stats = run.stats;
    // Wall time of the whole command (decoding included), as users time it.
    stats.wall_s = start.elapsed().as_secs_f64();
    stats.pairs_per_s = stats.pairs as f64 / stats.wall_s.max(1e-9);
    if a.json {
        #[derive(serde::Serialize)]
        struct IcpJson<'a> {
            #[serde(flatten)]
            stats: &'a odocal::icp::IcpStats,
            assumptions: &'a odocal::assumptions::Assumptions,
        }
        return print_json(&IcpJson {
            stats: &stats,
            assumptions: &run.assumptions,
        });
    }
    print::assumptions(&run.assumptions);
    print::icp(&stats, run.path_length, &a.out, &run.prior);
    Ok(())
}

fn calibrate(a: CalibrateArgs) -> anyhow::Result<()> {
    let pb = progress_bar("calibrate");
    let done = pipeline::calibrate::run(
        &a.job()?,
        &mut Progress::new(|f| pb.set_position((f * 1000.0) as u64)),
    )?;
    pb.finish_and_clear();
    for n in &done.notes {
        eprintln!("note: {n}");
    }
    for c in &done.summary.changes {
        eprintln!("{}", pipeline::changes::describe(c));
    }
    if a.json {
        return print_json(&done.paste.with(&done.summary));
    }
    print::calibration(&done.summary, &a.out);
    print::paste(&done.paste, &a.out);
    Ok(())
}

fn demo(a: DemoArgs) -> anyhow::Result<()> {
    let pb = progress_bar("demo");
    let summary = pipeline::demo::run(&a.job(), &mut |stage, f| {
        pb.set_message(stage.to_string());
        pb.set_position((f * 1000.0) as u64);
    })?;
    pb.finish_and_clear();
    if a.json {
        return print_json(&summary);
    }
    print::demo(&summary, &a.out, a.connect.is_none() && !a.spawn);
    Ok(())
}

fn diagnose(a: DiagnoseArgs) -> anyhow::Result<()> {
    let d = pipeline::diagnose::run(&a.job())?;
    if a.json {
        return print_json(&d);
    }
    if let Some(w) = &d.wheel_source {
        eprintln!("{}", w.sentence());
    }
    out!("verdict: {}", pipeline::diagnose::verdict_word(&d));
    for c in &d.causes {
        out!(
            "  {}: {} (ΔBIC {:.1})",
            c.effect,
            pipeline::diagnose::cause_parameters(c),
            c.delta_bic
        );
    }
    for f in &d.faults {
        out!("  fault {}: {}", f.name, f.evidence);
        out!("    fix: {}", f.fix);
    }
    for r in &d.remaining {
        out!(
            "  left in {}: {}, {:.5} {} (p {:.1e}){}",
            r.stream,
            r.structure,
            r.size,
            r.unit,
            r.p_value,
            r.reason.as_ref().map_or_else(String::new, |why| {
                let whose = if r.is_robot() {
                    "the robot's"
                } else {
                    "the scan matcher's"
                };
                format!(", {whose}: {why}")
            })
        );
    }
    out!("held out from t = {:.1} s", d.series.split);
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
    let res = odocal::experiments::run(&a.job())?;
    if a.json {
        out!("{}", res.json);
        return Ok(());
    }
    out!("{}", res.summary);
    out!("written to {}", a.out.display());
    Ok(())
}
