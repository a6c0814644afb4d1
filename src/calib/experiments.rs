//! Monte Carlo experiments behind `odocal experiment` (seed 000's Tables I and
//! II on synthetic runs with random true radii): final radius errors, velocity
//! and odometry RMSE, time per iteration, convergence time.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::params::{CalibParams, Method};
use super::resample::Scheme;
use super::synth::{draw_truth, generate, SynthData, SynthParams};
use super::trigger::Trigger;
use super::{build, run, steps, CalibrationRun};
use crate::geom::{self, Pose2};
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

/// Metrics of one method on one run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RunMetrics {
    /// |final R_R − true| (m).
    pub err_r_right: f64,
    /// |final R_L − true| (m).
    pub err_r_left: f64,
    /// |final D − true| (m).
    pub err_wheel_base: f64,
    /// RMSE of the filter's V against the true mean V per step (m/s).
    pub rmse_v: f64,
    /// RMSE of the filter's W (rad/s).
    pub rmse_w: f64,
    /// RMSE of the calibrated odometry's position against the truth (m).
    pub rmse_xy: f64,
    /// RMSE of its heading (rad).
    pub rmse_theta: f64,
    /// Mean time per step (ms).
    pub mean_iteration_ms: f64,
    /// Time from the start (or the radius step) after which both radius
    /// errors stay below the convergence fraction; `None` if never.
    pub convergence_s: Option<f64>,
}

/// What a Monte Carlo run is scored against: the true parameters and motion.
pub trait RunTruth {
    /// True parameters in effect at `t` (s).
    fn params_at(&self, t: f64) -> DiffDrive;
    /// True mean (V, W) over `[t0, t1]` (m/s, rad/s).
    fn mean_velocity(&self, t0: f64, t1: f64) -> (f64, f64);
    /// True pose of the base at `t` (s), in any fixed frame.
    fn pose_at(&self, t: f64) -> Option<Pose2>;
    /// When the radii jump, if they do (convergence is measured from then).
    fn change_time(&self) -> Option<f64>;
}

impl RunTruth for SynthData {
    fn params_at(&self, t: f64) -> DiffDrive {
        self.truth_at(t)
    }
    fn mean_velocity(&self, t0: f64, t1: f64) -> (f64, f64) {
        SynthData::mean_velocity(self, t0, t1)
    }
    fn pose_at(&self, t: f64) -> Option<Pose2> {
        self.reference.pose_at(t)
    }
    fn change_time(&self) -> Option<f64> {
        self.radius_step.map(|s| s.time)
    }
}

/// Scores a finished run against its truth. The calibrated odometry starts
/// at the identity; the true trajectory is expressed in its own pose at
/// that first stamp before comparing.
pub fn score(r: &CalibrationRun, truth: &dyn RunTruth, fraction: f64) -> RunMetrics {
    let end = truth.params_at(f64::INFINITY);
    let f = r.summary.final_params;
    let (mut sv, mut sw, mut n) = (0.0, 0.0, 0usize);
    let mut t0 = r.trajectory.stamps.first().copied().unwrap_or(0.0);
    let mut conv_from: Option<f64> = Some(t0);
    let start = truth.change_time().unwrap_or(t0);
    for h in &r.history {
        let (v, w) = truth.mean_velocity(t0, h.t);
        t0 = h.t;
        sv += (h.v - v).powi(2);
        sw += (h.w - w).powi(2);
        n += 1;
        let k = truth.params_at(h.t);
        let ok = (h.r_right - k.r_right).abs() < fraction * k.r_right
            && (h.r_left - k.r_left).abs() < fraction * k.r_left;
        match (ok, conv_from) {
            (false, _) => conv_from = None,
            (true, None) => conv_from = Some(h.t),
            _ => {}
        }
    }
    let origin = r.trajectory.stamps.first().and_then(|&t| truth.pose_at(t));
    let (mut sxy, mut sth, mut m) = (0.0, 0.0, 0usize);
    for (t, p) in r.trajectory.stamps.iter().zip(&r.trajectory.poses) {
        if let (Some(o), Some(q)) = (origin, truth.pose_at(*t)) {
            let q = geom::between(&o, &q);
            let d = p.translation.vector - q.translation.vector;
            sxy += d.norm_squared();
            sth += geom::wrap_angle(geom::heading(p) - geom::heading(&q)).powi(2);
            m += 1;
        }
    }
    let rms = |s: f64, k: usize| if k > 0 { (s / k as f64).sqrt() } else { 0.0 };
    RunMetrics {
        err_r_right: (f.r_right - end.r_right).abs(),
        err_r_left: (f.r_left - end.r_left).abs(),
        err_wheel_base: (f.wheel_base - end.wheel_base).abs(),
        rmse_v: rms(sv, n),
        rmse_w: rms(sw, n),
        rmse_xy: rms(sxy, m),
        rmse_theta: rms(sth, m),
        mean_iteration_ms: r.summary.mean_iteration_ms,
        convergence_s: conv_from.map(|t| (t - start).max(0.0)),
    }
}

/// Median and mean of a metric over the runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stat {
    /// Median.
    pub median: f64,
    /// Mean.
    pub mean: f64,
}

/// Median (even count: mean of the middle two) and mean of `x`; NaN for none.
pub(crate) fn stat(mut x: Vec<f64>) -> Stat {
    if x.is_empty() {
        return Stat {
            median: f64::NAN,
            mean: f64::NAN,
        };
    }
    x.sort_by(f64::total_cmp);
    let k = x.len();
    let median = if k % 2 == 1 {
        x[k / 2]
    } else {
        0.5 * (x[k / 2 - 1] + x[k / 2])
    };
    Stat {
        median,
        mean: x.iter().sum::<f64>() / k as f64,
    }
}

/// One row of a Monte Carlo table: a configuration summarised over the runs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableRow {
    /// Configuration label (method, or scheme/trigger).
    pub label: String,
    /// Final R_R error (m).
    pub err_r_right: Stat,
    /// Final R_L error (m).
    pub err_r_left: Stat,
    /// Final D error (m).
    pub err_wheel_base: Stat,
    /// Velocity RMSE V (m/s).
    pub rmse_v: Stat,
    /// Velocity RMSE W (rad/s).
    pub rmse_w: Stat,
    /// Odometry RMSE x, y (m).
    pub rmse_xy: Stat,
    /// Odometry RMSE θ (rad).
    pub rmse_theta: Stat,
    /// Time per iteration (ms).
    pub mean_iteration_ms: Stat,
    /// Convergence time over the runs that converged (s).
    pub convergence_s: Stat,
    /// Convergence time with runs that never converged counted as the
    /// whole remaining duration (s): an upper bound of the true median.
    pub convergence_s_censored: Stat,
    /// Fraction of runs that converged.
    pub converged: f64,
    /// Every run's metrics.
    pub runs: Vec<RunMetrics>,
}

/// A Monte Carlo table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MonteCarloTable {
    /// Runs per configuration.
    pub runs: usize,
    /// One row per configuration.
    pub rows: Vec<TableRow>,
}

impl MonteCarloTable {
    /// Markdown table of medians (errors in mm, times in ms and s).
    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "Medians over {} runs (mean in parentheses).\n\n| config | err R_R (mm) | err R_L (mm) | err D (mm) | RMSE V (m/s) | RMSE W (rad/s) | RMSE x,y (m) | RMSE θ (rad) | ms/iter | convergence (s) | converged |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
            self.runs
        );
        for r in &self.rows {
            let mm = |x: &Stat| format!("{:.3} ({:.3})", 1e3 * x.median, 1e3 * x.mean);
            let g = |x: &Stat| format!("{:.4} ({:.4})", x.median, x.mean);
            s += &format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} | {:.4} | {:.2} | {:.0} % |\n",
                r.label,
                mm(&r.err_r_right),
                mm(&r.err_r_left),
                mm(&r.err_wheel_base),
                g(&r.rmse_v),
                g(&r.rmse_w),
                g(&r.rmse_xy),
                g(&r.rmse_theta),
                r.mean_iteration_ms.median,
                r.convergence_s_censored.median,
                100.0 * r.converged
            );
        }
        s
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
        let data = generate(&mc.synth, draw_truth(seed), seed);
        let st = steps(&data.obs, &data.wheels, &data.gyro, mc.synth.gyro_sigma);
        Ok((st, data))
    };
    match montecarlo_with(&runs, configs, &make) {
        Ok(t) => t,
        Err(never) => match never {},
    }
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
pub type PreparedRun<T> = (Vec<super::CalibStep>, T);

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
    let nominal = DiffDrive {
        r_right: mc.nominal[0],
        r_left: mc.nominal[1],
        wheel_base: mc.nominal[2],
    };
    let one = |k: usize| -> Result<Vec<RunMetrics>, E> {
        let (st, truth) = make(mc.seed.wrapping_add(k as u64))?;
        Ok(configs
            .iter()
            .map(|(_, p)| {
                let mut p = p.clone();
                p.seed = p.seed.wrapping_add(k as u64);
                let mut cal = build(&p, nominal).expect("experiment configs are valid");
                let r = run(cal.as_mut(), &st, nominal);
                score(&r, &truth, mc.convergence_fraction)
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
    let span = mc.span;
    let rows = configs
        .iter()
        .enumerate()
        .map(|(c, (label, _))| {
            let runs: Vec<RunMetrics> = per_run.iter().map(|r| r[c]).collect();
            let col = |f: &dyn Fn(&RunMetrics) -> f64| stat(runs.iter().map(f).collect());
            let conv: Vec<f64> = runs.iter().filter_map(|r| r.convergence_s).collect();
            TableRow {
                label: label.clone(),
                err_r_right: col(&|r| r.err_r_right),
                err_r_left: col(&|r| r.err_r_left),
                err_wheel_base: col(&|r| r.err_wheel_base),
                rmse_v: col(&|r| r.rmse_v),
                rmse_w: col(&|r| r.rmse_w),
                rmse_xy: col(&|r| r.rmse_xy),
                rmse_theta: col(&|r| r.rmse_theta),
                mean_iteration_ms: col(&|r| r.mean_iteration_ms),
                converged: conv.len() as f64 / runs.len().max(1) as f64,
                convergence_s: stat(conv),
                convergence_s_censored: col(&|r| r.convergence_s.unwrap_or(span)),
                runs,
            }
        })
        .collect();
    Ok(MonteCarloTable {
        runs: mc.runs,
        rows,
    })
}

/// Seed 000's Table II configurations: adaptive-pf, pf, dkf, akf, none.
pub fn table2_configs(base: &CalibParams) -> Vec<(String, CalibParams)> {
    Method::ALL
        .iter()
        .map(|&m| {
            (
                m.as_str().to_string(),
                CalibParams {
                    method: m,
                    ..base.clone()
                },
            )
        })
        .collect()
}

/// Seed 000's Table I configurations: the fixed PF with 4 schemes × 3 triggers.
pub fn table1_configs(base: &CalibParams) -> Vec<(String, CalibParams)> {
    let mut out = vec![];
    for s in Scheme::ALL {
        for t in Trigger::ALL {
            out.push((
                format!("{}/{}", s.as_str(), t.as_str()),
                CalibParams {
                    method: Method::Pf,
                    resampler: s,
                    trigger: t,
                    ..base.clone()
                },
            ));
        }
    }
    out
}
