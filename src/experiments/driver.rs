//! `odocal experiment NAME`: the experiment's name, settings and inputs in;
//! `NAME.md`, `NAME.json` and `NAME.png` out.

use super::blind::{blind_output, BlindParams};
use super::heading_pf::{heading_pf_output, PfExperimentParams};
use super::inputs::{bad, ExperimentInputs};
use super::literature::{literature_output, LiteratureParams};
use super::montecarlo::{monte_carlo, ScanMonteCarloParams};
use super::output::ExperimentOutput;
use super::square::{square_output, SquareExperimentParams};
use super::tachometer::tachometer_output;
use super::umbmark::{umbmark_output, UmbmarkParams};
use crate::error::InputError;
use crate::pipeline::PipelineError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Experiment names `odocal experiment` knows.
pub const EXPERIMENTS: [&str; 11] = [
    "resampling",
    "montecarlo",
    "montecarlo-scans",
    "changing",
    "literature",
    "square",
    "umbmark",
    "heading-pf",
    "tachometer",
    "diagnose",
    "fleet",
];

/// Settings of the experiments (`--settings FILE.toml`), one table each.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExperimentSettings {
    /// `literature`.
    pub literature: LiteratureParams,
    /// `square`.
    pub square: SquareExperimentParams,
    /// `umbmark`.
    pub umbmark: UmbmarkParams,
    /// `heading-pf` (its `trials` is replaced by `--runs`, its `seed` by `--seed`).
    pub heading_pf: PfExperimentParams,
    /// `montecarlo-scans`.
    pub scans: ScanMonteCarloParams,
    /// `diagnose` (the blind suite).
    pub diagnose: BlindParams,
    /// `fleet` (`--runs` robots).
    pub fleet: super::fleet::FleetSimParams,
}

impl ExperimentSettings {
    /// Loads `path`, or the defaults when `None`. Unknown keys are refused.
    pub fn load(path: Option<&Path>) -> Result<Self, PipelineError> {
        let Some(path) = path else {
            return Ok(Self::default());
        };
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| InputError::new(&name, format!("cannot read: {e}")))?;
        toml::from_str(&text).map_err(|e| InputError::new(&name, e.message().to_string()).into())
    }
}

fn write_text(out: &Path, file: String, text: &str) -> Result<(), PipelineError> {
    let p = out.join(file);
    crate::io::atomic::write_bytes_atomic(&p, text.as_bytes())
        .map_err(|e| PipelineError::write(&p, e))
}

/// What `odocal experiment NAME` is asked to do.
#[derive(Debug, Clone, Default)]
pub struct ExperimentJob {
    /// The experiment's name ([`EXPERIMENTS`]).
    pub name: String,
    /// Monte Carlo runs (or repetitions, robots, trials).
    pub runs: usize,
    /// The seed of run 0 (run k uses seed + k).
    pub seed: u64,
    /// The output directory.
    pub out: std::path::PathBuf,
    /// The experiment settings (TOML), if any.
    pub settings: Option<std::path::PathBuf>,
    /// The folder with the papers' published tables, if any.
    pub tables: Option<std::path::PathBuf>,
    /// Configuration and robot files.
    pub common: crate::pipeline::Common,
}

/// Runs `odocal experiment NAME`: loads the configuration, the robot and the
/// experiment settings, and runs the experiment into the output directory.
pub fn run(job: &ExperimentJob) -> Result<ExperimentOutput, PipelineError> {
    let (cfg, robot) = job.common.load()?;
    let settings = ExperimentSettings::load(job.settings.as_deref())?;
    let _lock = crate::pipeline::outputs::lock_outputs(&[&job.out])?;
    let inputs = ExperimentInputs {
        runs: job.runs,
        seed: job.seed,
        calib: &cfg.calib,
        robot: &robot,
        tables: job.tables.as_deref(),
        icp: &cfg.icp,
        diagnose: &cfg.diagnose,
    };
    run_experiment(&job.name, &inputs, &settings, &job.out)
}

/// Runs experiment `name` into `out` (`NAME.md`, `NAME.json`, `NAME.png`).
pub fn run_experiment(
    name: &str,
    inp: &ExperimentInputs<'_>,
    settings: &ExperimentSettings,
    out: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    if inp.runs == 0 {
        return Err(bad("--runs must be at least 1"));
    }
    if !EXPERIMENTS.contains(&name) {
        return Err(bad(format!(
            "unknown experiment '{name}' (known: {})",
            EXPERIMENTS.join(", ")
        )));
    }
    std::fs::create_dir_all(out).map_err(|e| PipelineError::write(out, e))?;
    let png = out.join(format!("{name}.png"));
    let res = match name {
        "literature" => literature_output(inp, &settings.literature, &png)?,
        "square" => square_output(inp, &settings.square, &png)?,
        "umbmark" => umbmark_output(inp, &settings.umbmark, &png)?,
        "heading-pf" => heading_pf_output(inp, &settings.heading_pf, &png)?,
        "tachometer" => tachometer_output(inp, &settings.square, &png)?,
        "diagnose" => blind_output(inp, &settings.diagnose, out, &png)?,
        "fleet" => super::fleet::fleet_output(inp, &settings.fleet, out, &png)?,
        _ => monte_carlo(name, inp, &settings.scans, &png)?,
    };
    write_text(out, format!("{name}.md"), &res.markdown)?;
    write_text(out, format!("{name}.json"), &res.json)?;
    Ok(res)
}
