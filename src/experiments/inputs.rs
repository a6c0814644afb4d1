//! What every experiment runs on besides its own settings: the run count and
//! seed, the nominal robot, the calibrator and ICP settings, the papers' published tables.

use crate::calib::CalibParams;
use crate::io::seed_tables::{read_seed_table, SeedTable};
use crate::pipeline::PipelineError;
use crate::robot::RobotConfig;
use std::path::Path;

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
    /// Folder with the papers' published tables (`--tables`), for square, heading-pf, tachometer.
    pub tables: Option<&'a Path>,
    /// Scan matching settings (`--config`'s `[icp]`), for montecarlo-scans.
    pub icp: &'a crate::icp::IcpParams,
    /// Diagnosis settings (`--config`'s `[diagnose]`), for `diagnose`.
    pub diagnose: &'a crate::diagnose::DiagnoseParams,
}

impl ExperimentInputs<'_> {
    /// A published table from the `--tables` folder.
    pub(crate) fn seed_table(&self, file: &str) -> Result<SeedTable, PipelineError> {
        let dir = self.tables.ok_or_else(|| {
            bad(format!(
                "this experiment reads the papers' published tables: give --tables DIR (the folder with {file})"
            ))
        })?;
        Ok(read_seed_table(&dir.join(file))?)
    }
}

/// An argument or setting the experiment cannot use.
pub(crate) fn bad(e: impl std::fmt::Display) -> PipelineError {
    PipelineError::BadArgument(e.to_string())
}
