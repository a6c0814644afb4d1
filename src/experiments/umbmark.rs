//! UMBmark as an experiment: a simulated robot runs the benchmark (CW/CCW ×
//! n), gets corrected, and runs it again on fresh runs; over several robots,
//! each with its own hidden radius and wheel-base errors, E_max,syst before
//! and after and the improvement factor (\[Borenstein1996\] report about
//! 10–20×).

use super::inputs::{bad, ExperimentInputs};
use super::output::{draw_bars, ExperimentOutput};
use super::repetitions::{at_least_one, draw_hidden_truth};
use super::stats::{finite_stat, Stat};
use crate::classic::{umbmark, umbmark_runs, ClassicError, DriveParams, UmbmarkResult, UmbmarkRun};
use crate::pipeline::PipelineError;
use crate::robot::DiffDrive;
use crate::viz::plot::BarChart;
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::Path;

/// Settings of the UMBmark experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UmbmarkParams {
    /// Side of the square (m); the benchmark's 4 m.
    pub side: f64,
    /// Runs per direction (the benchmark's 5).
    pub runs_per_direction: usize,
    /// Hidden radius errors uniform in ± this (relative).
    pub radius_error: f64,
    /// Hidden wheel-base error uniform in ± this (relative).
    pub wheel_base_error: f64,
    /// Correction passes (the paper: 1).
    pub passes: usize,
    /// Driving and slip.
    pub drive: DriveParams,
}

impl Default for UmbmarkParams {
    /// 4 m, 5 runs each way, radii ± 1 %, wheel base ± 3 %, one pass,
    /// 0.2 % wheel slip per 50 ms step, 8800 ticks/rev.
    fn default() -> Self {
        Self {
            side: 4.0,
            runs_per_direction: 5,
            radius_error: 0.01,
            wheel_base_error: 0.03,
            passes: 1,
            drive: DriveParams {
                slip_sigma: 0.002,
                ticks_per_rev: 8800.0,
                ..DriveParams::default()
            },
        }
    }
}

/// A full UMBmark cycle on a simulated robot: runs before, correction, fresh
/// runs after with the corrected model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UmbmarkExperiment {
    /// Correction passes applied.
    pub passes: usize,
    /// The model after the last pass.
    pub corrected: DiffDrive,
    /// Benchmark with the nominal model.
    pub before: UmbmarkResult,
    /// Benchmark on fresh runs driven and computed with the corrected model
    /// (its own correction factors would be the next pass).
    pub after: UmbmarkResult,
    /// E_max,syst before / after.
    pub improvement: f64,
    /// Run errors before.
    pub runs_before: Vec<UmbmarkRun>,
    /// Run errors after.
    pub runs_after: Vec<UmbmarkRun>,
}

/// Runs UMBmark on a simulated robot, applies the correction and measures
/// the improvement factor on fresh runs (different seeds). The paper applies
/// the correction once (`passes = 1`); its formulas are first order, so with
/// large errors a residual of order α·β remains, which further passes (each on
/// fresh runs with the model corrected so far) remove.
pub fn umbmark_experiment(
    nominal: &DiffDrive,
    truth: &DiffDrive,
    side: f64,
    n: usize,
    drive: &DriveParams,
    passes: usize,
    seed: u64,
) -> Result<UmbmarkExperiment, ClassicError> {
    let runs_before = umbmark_runs(nominal, truth, side, n, drive, seed);
    let before = umbmark(&runs_before, side, nominal)?;
    let mut model = before.corrected();
    for pass in 1..passes {
        let s = seed.wrapping_add(7_000_003 * pass as u64);
        model = umbmark(
            &umbmark_runs(&model, truth, side, n, drive, s),
            side,
            &model,
        )?
        .corrected();
    }
    let runs_after = umbmark_runs(&model, truth, side, n, drive, seed.wrapping_add(1_000_003));
    let after = umbmark(&runs_after, side, &model)?;
    let improvement = if after.e_max_syst > 0.0 {
        before.e_max_syst / after.e_max_syst
    } else {
        f64::MAX
    };
    Ok(UmbmarkExperiment {
        passes,
        corrected: model,
        before,
        after,
        improvement,
        runs_before,
        runs_after,
    })
}

/// One robot's benchmark cycle.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UmbmarkCycle {
    /// Seed of the cycle.
    pub seed: u64,
    /// Hidden true parameters (m).
    pub truth: DiffDrive,
    /// Before, correction, after.
    pub result: UmbmarkExperiment,
}

/// All cycles and the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UmbmarkCycles {
    /// Settings.
    pub params: UmbmarkParams,
    /// E_max,syst before correction (m).
    pub e_max_before: Stat,
    /// E_max,syst after correction, fresh runs (m).
    pub e_max_after: Stat,
    /// Improvement factor before / after.
    pub improvement: Stat,
    /// Every cycle.
    pub cycles: Vec<UmbmarkCycle>,
}

/// `runs` benchmark cycles (cycle i: seed `seed + i`, its own hidden truth).
pub fn umbmark_cycles(
    nominal: &DiffDrive,
    p: &UmbmarkParams,
    runs: usize,
    seed: u64,
) -> Result<UmbmarkCycles, ClassicError> {
    at_least_one(
        "umbmark",
        "runs, runs per direction and passes",
        &[runs, p.runs_per_direction, p.passes],
    )?;
    let cycles: Vec<UmbmarkCycle> = (0..runs)
        .map(|i| {
            let s = seed.wrapping_add(i as u64);
            let truth = draw_hidden_truth(nominal, p.radius_error, p.wheel_base_error, s);
            let result = umbmark_experiment(
                nominal,
                &truth,
                p.side,
                p.runs_per_direction,
                &p.drive,
                p.passes,
                s.wrapping_mul(1_000_003),
            )?;
            Ok(UmbmarkCycle {
                seed: s,
                truth,
                result,
            })
        })
        .collect::<Result<_, ClassicError>>()?;
    let col = |f: &dyn Fn(&UmbmarkExperiment) -> f64| {
        finite_stat(cycles.iter().map(|c| f(&c.result)).collect())
    };
    Ok(UmbmarkCycles {
        params: p.clone(),
        e_max_before: col(&|r| r.before.e_max_syst),
        e_max_after: col(&|r| r.after.e_max_syst),
        improvement: col(&|r| r.improvement.min(1e6)),
        cycles,
    })
}

impl UmbmarkCycles {
    /// Markdown: one row per cycle and the medians.
    pub fn markdown(&self) -> String {
        let p = &self.params;
        let mut s = format!(
            "{} robots, hidden radii ± {:.1} %, wheel base ± {:.1} %; {} m square, {} runs each \
             way, wheel slip σ {} per step; {} correction pass(es); after = fresh runs with the \
             corrected model.\n\n",
            self.cycles.len(),
            100.0 * p.radius_error,
            100.0 * p.wheel_base_error,
            p.side,
            p.runs_per_direction,
            p.drive.slip_sigma,
            p.passes
        );
        s.push_str("| robot | true R_R (m) | true R_L (m) | true D (m) | E_max,syst before (m) | α (deg) | β (deg) | E_d | E_b | E_max,syst after (m) | improvement |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
        for c in &self.cycles {
            let r = &c.result;
            let _ = writeln!(
                s,
                "| {} | {:.5} | {:.5} | {:.4} | {:.4} | {:.3} | {:.3} | {:.5} | {:.5} | {:.4} | {:.1} |",
                c.seed,
                c.truth.r_right,
                c.truth.r_left,
                c.truth.wheel_base,
                r.before.e_max_syst,
                r.before.alpha_rad.to_degrees(),
                r.before.beta_rad.to_degrees(),
                r.before.e_d,
                r.before.e_b,
                r.after.e_max_syst,
                r.improvement
            );
        }
        let _ = writeln!(
            s,
            "\nMedian E_max,syst {:.4} m before, {:.4} m after: improvement ×{:.1} (median; \
             Borenstein & Feng report ×10–20 on real robots).",
            self.e_max_before.median, self.e_max_after.median, self.improvement.median
        );
        s
    }
}

/// `odocal experiment umbmark`: `--runs` robots, E_max,syst before and after
/// correction drawn into `png`.
pub(super) fn umbmark_output(
    inp: &ExperimentInputs<'_>,
    params: &UmbmarkParams,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let c = umbmark_cycles(&inp.robot.diff_drive(), params, inp.runs, inp.seed).map_err(bad)?;
    let cats: Vec<String> = c
        .cycles
        .iter()
        .map(|k| format!("robot {}", k.seed))
        .collect();
    let chart = BarChart::new(
        format!(
            "UMBmark: E_max,syst before and after correction ({} robots)",
            c.cycles.len()
        ),
        cats,
        vec!["before".into(), "after (fresh runs)".into()],
    )
    .panel(
        "E_max,syst (m)",
        vec![
            c.cycles
                .iter()
                .map(|k| k.result.before.e_max_syst)
                .collect(),
            c.cycles.iter().map(|k| k.result.after.e_max_syst).collect(),
        ],
        None,
    );
    draw_bars(png, &chart)?;
    let title = "UMBmark (Borenstein & Feng 1996)";
    Ok(ExperimentOutput::titled(title, c.markdown(), &c))
}
