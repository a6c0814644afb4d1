//! `odocal fleet`: the local engine runs here on every core; `--engine ray`
//! hands the same job to the Python package's Ray engine
//! (`python3 -m odocal.fleet`, which calls this crate's fleet steps from
//! Ray tasks), so both engines produce the same table.

use super::args::Common;
use super::print::out;
use clap::{Args, ValueEnum};
use odocal::io::out_lock::OutputLock;
use odocal::pipeline::calibrate::CalibratorChoice;
use odocal::pipeline::fleet::{self, FleetJob, FleetSummary};
use odocal::pipeline::PipelineError;
use std::path::PathBuf;

/// Where the recordings are calibrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Engine {
    /// This machine, every core (rayon).
    Local,
    /// A Ray cluster (the Python package `odocal` with its `ray` extra).
    Ray,
}

#[derive(Args)]
pub struct FleetArgs {
    /// A fleet folder laid out ROBOT/…/REC (any recording, in any sub-folder; placed in time by
    /// its first stamp, or by a date YYYY-MM-DD in its path when its clock is not a date), or a
    /// manifest CSV with the columns robot,path,start.
    #[arg(value_name = "DIR|MANIFEST.csv")]
    pub source: PathBuf,
    /// local (every core here) or ray (the Python package's Ray engine).
    #[arg(long, value_enum, default_value = "local")]
    pub engine: Engine,
    /// The Ray cluster to join (`ray start --head` prints it); without it, a local Ray.
    #[arg(long, value_name = "RAY_ADDR")]
    pub address: Option<String>,
    /// Calibrator: adaptive-pf, pf, dkf, akf.
    #[arg(long)]
    pub method: Option<odocal::calib::Method>,
    /// Seed of every random draw.
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Output directory: fleet.csv, fleet.json, report.md, fleet.png, cache/, recordings/.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Record the fleet for the Rerun viewer: per robot its parameters over days with
    /// ±2σ bands, alarms marked.
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: Common,
}

impl FleetArgs {
    /// The job these arguments ask for.
    pub fn job(&self) -> FleetJob {
        FleetJob {
            source: self.source.clone(),
            out: self.out.clone(),
            choice: CalibratorChoice {
                method: self.method,
                seed: self.seed,
                ..Default::default()
            },
            common: self.common.files(),
        }
    }

    /// The Python engine's arguments for the same job.
    fn python_args(&self) -> Vec<String> {
        let mut a: Vec<String> = vec![
            "-m".into(),
            "odocal.fleet".into(),
            self.source.display().to_string(),
            "--out".into(),
            self.out.display().to_string(),
            "--engine".into(),
            "ray".into(),
        ];
        let mut opt = |k: &str, v: Option<String>| {
            if let Some(v) = v {
                a.push(k.into());
                a.push(v);
            }
        };
        opt("--address", self.address.clone());
        opt("--method", self.method.map(|m| m.as_str().to_string()));
        opt("--seed", self.seed.map(|s| s.to_string()));
        opt(
            "--robot",
            self.common.robot.as_ref().map(|p| p.display().to_string()),
        );
        opt(
            "--config",
            self.common.config.as_ref().map(|p| p.display().to_string()),
        );
        if self.json {
            a.push("--json".into());
        }
        a
    }
}

/// The Python that runs the Ray engine: `$ODOCAL_PYTHON`, else `python3`.
fn python() -> String {
    std::env::var("ODOCAL_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// Runs the job on Ray through the Python package; its exit code is ours.
fn on_ray(a: &FleetArgs) -> anyhow::Result<()> {
    let py = python();
    let probe = std::process::Command::new(&py)
        .args(["-c", "import odocal.fleet, ray"])
        .output();
    let missing = match &probe {
        Ok(o) if o.status.success() => None,
        Ok(o) => Some(
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("")
                .to_string(),
        ),
        Err(e) => Some(format!("cannot start {py}: {e}")),
    };
    if let Some(why) = missing {
        return Err(PipelineError::BadArgument(format!(
            "--engine ray needs the Python package odocal with Ray in {py} ({why}): \
             pip install './python[ray]' (or set ODOCAL_PYTHON to a Python that has them), \
             or use --engine local"
        ))
        .into());
    }
    let _lock = claim_rrd(a)?;
    let status = std::process::Command::new(&py)
        .args(a.python_args())
        .status()?;
    match status.code() {
        Some(0) => {}
        Some(code) => std::process::exit(code),
        None => anyhow::bail!("the Ray engine ({py}) was killed by a signal"),
    }
    if let Some(rrd) = &a.rrd {
        fleet::recording::write_from(rrd, &a.out)?;
        eprintln!("Rerun recording: {}", rrd.display());
    }
    Ok(())
}

/// Checks and locks `--rrd` before any work (`None` without it).
fn claim_rrd(a: &FleetArgs) -> Result<Option<Vec<OutputLock>>, PipelineError> {
    a.rrd
        .as_ref()
        .map(|rrd| fleet::recording::claim(rrd, &a.source, &a.out))
        .transpose()
}

fn print(s: &FleetSummary, a: &FleetArgs) {
    out!(
        "{} robots, {} recordings ({} calibrated now, {} cached), method {}; day 0 = {}",
        s.robot_count,
        s.recordings,
        s.processed,
        s.cached,
        s.method,
        s.epoch
    );
    if s.alarms.is_empty() {
        out!("no alarm");
    }
    for al in &s.alarms {
        out!(
            "{:<12} {:<12} day {:<6} {}",
            al.robot,
            al.kind.word(),
            al.day,
            al.evidence
        );
    }
    eprintln!(
        "outputs in {}: fleet.csv, fleet.json, report.md, fleet.png",
        a.out.display()
    );
}

/// Runs `odocal fleet`.
pub fn run(a: FleetArgs) -> anyhow::Result<()> {
    if a.engine == Engine::Ray {
        return on_ray(&a);
    }
    let _lock = claim_rrd(&a)?;
    let start = std::time::Instant::now();
    let pb = super::progress_bar("fleet");
    let summary = fleet::run(&a.job(), &|done, total| {
        pb.set_position((1000 * done / total.max(1)) as u64);
        pb.set_message(format!("fleet {done}/{total}"));
    })?;
    pb.finish_and_clear();
    if let Some(rrd) = &a.rrd {
        fleet::recording::write(rrd, &summary)?;
        eprintln!("Rerun recording: {}", rrd.display());
    }
    eprintln!("fleet: {:.1} s wall", start.elapsed().as_secs_f64());
    if a.json {
        return super::print_json(&summary);
    }
    print(&summary, &a);
    Ok(())
}
