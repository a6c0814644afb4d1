//! A Monte Carlo table: each configuration's metrics summarised over the runs.

use super::score::RunMetrics;
use crate::experiments::stats::{stat, Stat};
use serde::Serialize;

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
    /// RMSE x, y of the odometry with the final parameters (m).
    pub rmse_xy_final: Stat,
    /// RMSE θ of the odometry with the final parameters (rad).
    pub rmse_theta_final: Stat,
    /// RMSE x, y of the odometry over 10 s windows, each with the estimate
    /// at its start (m).
    pub rmse_xy_window: Stat,
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

impl TableRow {
    /// Summarises one configuration's runs; a run that never converged
    /// counts as `span` (s) in the censored convergence time.
    pub fn summarise(label: &str, runs: Vec<RunMetrics>, span: f64) -> Self {
        let col = |f: &dyn Fn(&RunMetrics) -> f64| stat(runs.iter().map(f).collect());
        let conv: Vec<f64> = runs.iter().filter_map(|r| r.convergence_s).collect();
        TableRow {
            label: label.to_string(),
            err_r_right: col(&|r| r.err_r_right),
            err_r_left: col(&|r| r.err_r_left),
            err_wheel_base: col(&|r| r.err_wheel_base),
            rmse_v: col(&|r| r.rmse_v),
            rmse_w: col(&|r| r.rmse_w),
            rmse_xy: col(&|r| r.rmse_xy),
            rmse_theta: col(&|r| r.rmse_theta),
            rmse_xy_final: col(&|r| r.rmse_xy_final),
            rmse_theta_final: col(&|r| r.rmse_theta_final),
            rmse_xy_window: col(&|r| r.rmse_xy_window),
            mean_iteration_ms: col(&|r| r.mean_iteration_ms),
            converged: conv.len() as f64 / runs.len().max(1) as f64,
            convergence_s: stat(conv),
            convergence_s_censored: col(&|r| r.convergence_s.unwrap_or(span)),
            runs,
        }
    }
}

/// A Monte Carlo table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MonteCarloTable {
    /// Runs per configuration.
    pub runs: usize,
    /// One row per configuration.
    pub rows: Vec<TableRow>,
}

/// One lower-is-better figure of a run.
type Metric = fn(&RunMetrics) -> f64;

/// The metrics the paired comparison counts, each lower-is-better: name
/// and value of one run (a run that never converged counts as never).
const PAIRED: [(&str, Metric); 6] = [
    ("radius error", |r| 0.5 * (r.err_r_right + r.err_r_left)),
    ("convergence", |r| r.convergence_s.unwrap_or(f64::INFINITY)),
    ("RMSE x,y", |r| r.rmse_xy),
    ("RMSE θ", |r| r.rmse_theta),
    ("RMSE x,y, final parameters", |r| r.rmse_xy_final),
    ("RMSE x,y, 10 s windows", |r| r.rmse_xy_window),
];

/// Runs (of the same seeds) in which `a` is strictly better than `b` on `f`.
fn wins(a: &[RunMetrics], b: &[RunMetrics], f: Metric) -> usize {
    a.iter().zip(b).filter(|(x, y)| f(x) < f(y)).count()
}

impl MonteCarloTable {
    /// The paired comparison of the first row against every other: in how
    /// many runs (same data, same seeds) the first configuration is strictly
    /// better, per metric (`PAIRED`).
    pub fn paired_markdown(&self) -> String {
        let Some((first, rest)) = self.rows.split_first() else {
            return String::new();
        };
        let mut s = format!(
            "\nPaired: in how many of the {} runs {} is strictly better than each configuration (same data and seeds; a tie or two runs that never converge is not a win).\n\n| against |",
            self.runs, first.label
        );
        for (name, _) in PAIRED {
            s += &format!(" {name} |");
        }
        s += "\n|---|";
        s += &"---|".repeat(PAIRED.len());
        s += "\n";
        for r in rest {
            s += &format!("| {} |", r.label);
            for (_, f) in PAIRED {
                s += &format!(" {} / {} |", wins(&first.runs, &r.runs, f), self.runs);
            }
            s += "\n";
        }
        s
    }

    /// Markdown table of medians (errors in mm, times in ms and s).
    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "Medians over {} runs (mean in parentheses).\n\n| config | err R_R (mm) | err R_L (mm) | err D (mm) | RMSE V (m/s) | RMSE W (rad/s) | RMSE x,y (m) | RMSE θ (rad) | RMSE x,y, final params (m) | RMSE θ, final params (rad) | RMSE x,y, 10 s windows (m) | ms/iter | convergence (s) | converged |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
            self.runs
        );
        for r in &self.rows {
            let mm = |x: &Stat| format!("{:.3} ({:.3})", 1e3 * x.median, 1e3 * x.mean);
            let g = |x: &Stat| format!("{:.4} ({:.4})", x.median, x.mean);
            s += &format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.4} | {:.2} | {:.0} % |\n",
                r.label,
                mm(&r.err_r_right),
                mm(&r.err_r_left),
                mm(&r.err_wheel_base),
                g(&r.rmse_v),
                g(&r.rmse_w),
                g(&r.rmse_xy),
                g(&r.rmse_theta),
                g(&r.rmse_xy_final),
                g(&r.rmse_theta_final),
                g(&r.rmse_xy_window),
                r.mean_iteration_ms.median,
                r.convergence_s_censored.median,
                100.0 * r.converged
            );
        }
        s
    }
}
