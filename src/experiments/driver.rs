//! `odocal experiment NAME`: the experiment's name, settings and inputs in;
//! `NAME.md`, `NAME.json` and `NAME.png` out.

use super::heading_pf::{heading_pf_output, PfExperimentParams};
use super::literature::{literature_output, LiteratureParams};
use super::montecarlo::{monte_carlo, ScanMonteCarloParams};
use super::output::ExperimentOutput;
use super::square::{square_output, SquareExperimentParams};
use super::tachometer::tachometer_output;
use super::umbmark::{umbmark_output, UmbmarkParams};
use crate::calib::CalibParams;
use crate::error::InputError;
use crate::io::seed_tables::{read_seed_table, SeedTable};
use crate::pipeline::PipelineError;
use crate::robot::RobotConfig;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Experiment names `odocal experiment` knows.
pub const EXPERIMENTS: [&str; 9] = [
    "resampling",
    "montecarlo",
    "montecarlo-scans",
    "changing",
    "literature",
    "square",
    "umbmark",
    "heading-pf",
    "tachometer",
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

/// What an experiment runs on besides its name and output directory.
#[derive(Debug, Clone, Copy)]
pub struct ExperimentInputs<'a> {
    /// Monte Carlo runs, repetitions or trials (`--runs`).
    pub runs: usize,
    /// Seed of run 0 (`--seed`).
    pub seed: u64,
    /// Calibrator settings (`--config`'s `[calib]`).
    pub calib: &'a CalibParams,
    /// Nominal robot (`--robot`).
    pub robot: &'a RobotConfig,
    /// Experiment settings (`--settings`).
    pub settings: &'a ExperimentSettings,
    /// Folder with the seed tables (`--tables`), for square, heading-pf, tachometer.
    pub tables: Option<&'a Path>,
    /// Scan matching settings (`--config`'s `[icp]`), for montecarlo-scans.
    pub icp: &'a crate::icp::IcpParams,
}

impl ExperimentInputs<'_> {
    /// A seed table from the `--tables` folder.
    pub(super) fn seed_table(&self, file: &str) -> Result<SeedTable, PipelineError> {
        let dir = self.tables.ok_or_else(|| {
            bad(format!(
                "this experiment reads the seed tables: give --tables DIR (the folder with {file})"
            ))
        })?;
        Ok(read_seed_table(&dir.join(file))?)
    }
}

/// An argument or setting the experiment cannot use.
pub(super) fn bad(e: impl std::fmt::Display) -> PipelineError {
    PipelineError::BadArgument(e.to_string())
}

fn write_text(out: &Path, file: String, text: &str) -> Result<(), PipelineError> {
    let p = out.join(file);
    crate::io::atomic::write_bytes_atomic(&p, text.as_bytes())
        .map_err(|e| PipelineError::write(&p, e))
}

/// Runs experiment `name` into `out` (`NAME.md`, `NAME.json`, `NAME.png`).
pub fn run(
    name: &str,
    inp: &ExperimentInputs<'_>,
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
        "literature" => literature_output(inp, &png)?,
        "square" => square_output(inp, &png)?,
        "umbmark" => umbmark_output(inp, &png)?,
        "heading-pf" => heading_pf_output(inp, &png)?,
        "tachometer" => tachometer_output(inp, &png)?,
        _ => monte_carlo(name, inp, &png)?,
    };
    write_text(out, format!("{name}.md"), &res.markdown)?;
    write_text(out, format!("{name}.json"), &res.json)?;
    Ok(res)
}
