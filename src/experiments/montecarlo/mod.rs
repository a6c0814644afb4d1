//! Monte Carlo experiments ([Farina, Tables I and II] on synthetic runs
//! with random true radii, the radii step of Fig. 6b, and Table II end to
//! end on simulated scans): final radius errors, velocity and odometry RMSE,
//! time per iteration, convergence time.

mod changing;
mod configs;
mod output;
mod scans;
mod score;
mod table;

pub use changing::{changing_figure, Fig5, RunFigures};
pub use configs::{
    changing_configs, fixed_count_label, table1_configs, table2_configs, FIG5_FIXED_PARTICLES,
};
pub(super) use output::monte_carlo;
pub use scans::{scan_montecarlo, ScanMonteCarloParams};
pub use score::{score, RunMetrics, RunTruth};
pub use table::{MonteCarloTable, TableRow};

use crate::calib::synth::{draw_truth, generate, SynthData, SynthParams};
use crate::calib::{build, run, steps, CalibParams, CalibStep};
use crate::robot::DiffDrive;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Settings of a Monte Carlo experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MonteCarloParams {
    /// Number of runs (each with its own true parameters and noise).
    pub runs: usize,
    /// Seed of run 0; run k uses `seed + k`.
    pub seed: u64,
    /// The synthetic run.
    pub synth: SynthParams,
    /// Nominal parameters (`none`, multipliers).
    pub nominal: [f64; 3],
    /// Convergence: radius error below this fraction of the truth (0.005).
    pub convergence_fraction: f64,
    /// Run the Monte Carlo runs on all cores (timings then include contention).
    pub parallel: bool,
}

impl Default for MonteCarloParams {
    fn default() -> Self {
        Self {
            runs: 30,
            seed: 1,
            synth: SynthParams::default(),
            nominal: [0.32, 0.32, 0.65],
            convergence_fraction: 0.005,
            parallel: false,
        }
    }
}

impl MonteCarloParams {
    /// The nominal kinematics the calibrators start from.
    pub fn nominal_drive(&self) -> DiffDrive {
        nominal_drive(self.nominal)
    }
}

fn nominal_drive(k: [f64; 3]) -> DiffDrive {
    DiffDrive {
        r_right: k[0],
        r_left: k[1],
        wheel_base: k[2],
    }
}

/// Runs every configuration on the same `mc.runs` synthetic runs (run k:
/// truth `draw_truth(seed + k)`, data `generate(.., seed + k)`, filter seed
/// `config.seed + k`) and summarises each.
pub fn montecarlo(mc: &MonteCarloParams, configs: &[(String, CalibParams)]) -> MonteCarloTable {
    let span = mc.synth.duration - mc.synth.radius_step.map_or(0.0, |s| s.time);
    let runs = MonteCarloRuns {
        runs: mc.runs,
        seed: mc.seed,
        nominal: mc.nominal,
        convergence_fraction: mc.convergence_fraction,
        parallel: mc.parallel,
        span,
    };
    let make = |seed: u64| -> Result<PreparedRun<SynthData>, std::convert::Infallible> {
        Ok(synthetic_run(mc, seed))
    };
    match montecarlo_with(&runs, configs, &make) {
        Ok(t) => t,
        Err(never) => match never {},
    }
}

/// The synthetic run of `seed`: data with true parameters `draw_truth(seed)`
/// and its calibrator steps.
fn synthetic_run(mc: &MonteCarloParams, seed: u64) -> PreparedRun<SynthData> {
    let data = generate(&mc.synth, draw_truth(seed), seed);
    let st = steps(&data.obs, &data.wheels, &data.gyro, mc.synth.gyro_sigma);
    (st, data)
}

/// The frame of a Monte Carlo experiment whatever its data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonteCarloRuns {
    /// Number of runs.
    pub runs: usize,
    /// Seed of run 0; run k uses `seed + k` (data and filter).
    pub seed: u64,
    /// Nominal parameters [R_R, R_L, D] (m) the calibrators start from.
    pub nominal: [f64; 3],
    /// Convergence: radius error below this fraction of the truth.
    pub convergence_fraction: f64,
    /// Run the runs on all cores.
    pub parallel: bool,
    /// Time a run that never converges counts as (s).
    pub span: f64,
}

/// The data of one run: filter steps and the truth that scores them.
pub type PreparedRun<T> = (Vec<CalibStep>, T);

/// Runs every configuration on the runs `make(seed + k)` prepares (filter
/// seed `config.seed + k`) and summarises each; the first error of `make`
/// stops the experiment.
pub fn montecarlo_with<T, E>(
    mc: &MonteCarloRuns,
    configs: &[(String, CalibParams)],
    make: &(dyn Fn(u64) -> Result<PreparedRun<T>, E> + Sync),
) -> Result<MonteCarloTable, E>
where
    T: RunTruth + Send,
    E: Send,
{
    let nominal = nominal_drive(mc.nominal);
    let one = |k: usize| -> Result<Vec<RunMetrics>, E> {
        let (st, truth) = make(mc.seed.wrapping_add(k as u64))?;
        Ok(configs
            .iter()
            .map(|(_, p)| {
                let mut p = p.clone();
                p.seed = p.seed.wrapping_add(k as u64);
                let mut cal = build(&p, nominal).expect("experiment configs are valid");
                let r = run(cal.as_mut(), &st, nominal);
                score(&r, &st, &truth, mc.convergence_fraction)
            })
            .collect())
    };
    let per_run: Vec<Vec<RunMetrics>> = if mc.parallel {
        (0..mc.runs)
            .into_par_iter()
            .map(one)
            .collect::<Result<_, E>>()?
    } else {
        (0..mc.runs).map(one).collect::<Result<_, E>>()?
    };
    let rows = configs
        .iter()
        .enumerate()
        .map(|(c, (label, _))| {
            TableRow::summarise(label, per_run.iter().map(|r| r[c]).collect(), mc.span)
        })
        .collect();
    Ok(MonteCarloTable {
        runs: mc.runs,
        rows,
    })
}
