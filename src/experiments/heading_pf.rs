//! [GAHeading, Table 2] regenerated on simulated runs: a vehicle calibrated by
//! the GA on short runs follows irregular 22, 47 and 100 m paths; the
//! end-position error of uncalibrated odometry, calibrated odometry and
//! calibrated odometry fused with a heading source, as % of the path length.

use super::inputs::{bad, ExperimentInputs};
use super::output::{draw_bars, ExperimentOutput};
use super::stats::sample_std;
use crate::classic::{
    drive_segments, ga_calibrate, heading_pf, irregular_path, simulate_heading, ClassicError,
    DriveParams, GaParams, GaRun, HeadingPfParams, HeadingSourceParams, Segment, TickParams,
};
use crate::error::InputError;
use crate::geom::Pose2;
use crate::io::seed_tables::SeedTable;
use crate::pipeline::PipelineError;
use crate::robot::{wheel_odometry, DiffDrive};
use crate::viz::plot::BarChart;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One of the numbers of [GAHeading, Table 2] (empty = the vehicle could not finish).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeedPathError {
    /// `uncalibrated`, `calibrated_odometry` or `calibrated_odometry_vo_pf`.
    pub scenario: String,
    /// Path length (m).
    pub length_m: f64,
    /// Mean absolute end-position error (% of length), if reported.
    pub error_percent: Option<f64>,
}

/// Our figure next to the paper's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathErrorRow {
    /// Scenario name (the paper's names).
    pub scenario: String,
    /// Path length (m).
    pub length_m: f64,
    /// Mean end-position error over the trials (% of length).
    pub error_percent: f64,
    /// Standard deviation over the trials (% of length).
    pub error_std: f64,
    /// The paper's number for the same cell, when given.
    pub seed_error_percent: Option<f64>,
}

/// Settings of the Table 2 experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PfExperimentParams {
    /// Path lengths (m).
    pub lengths: Vec<f64>,
    /// Trials per length.
    pub trials: usize,
    /// Encoder pulses per wheel revolution.
    pub ticks_per_rev: f64,
    /// The vehicle's true parameters.
    pub truth: TickParams,
    /// The parameters it believes before calibration.
    pub uncalibrated: TickParams,
    /// Number of short calibration runs (1.5–3 m).
    pub calibration_runs: usize,
    /// Driving and slip.
    pub drive: DriveParams,
    /// The heading source.
    pub heading: HeadingSourceParams,
    /// The filter.
    pub pf: HeadingPfParams,
    /// The GA.
    pub ga: GaParams,
    /// Master seed.
    pub seed: u64,
}

impl Default for PfExperimentParams {
    /// The AGV of \[GAHeading\]: true k1, k2, b = its GA result; believed k = 3.75e-4
    /// m/pulse (mid-box), b = 0.37 m; 1000 pulses/rev; 0.5 % wheel slip per
    /// 50 ms step (the level at which calibrated odometry comes nearest the paper's).
    fn default() -> Self {
        Self {
            lengths: vec![22.0, 47.0, 100.0],
            trials: 10,
            ticks_per_rev: 1000.0,
            truth: TickParams {
                k_left: 3.9447008587e-4,
                k_right: 3.9698427203e-4,
                wheel_base: 0.3688034,
            },
            uncalibrated: TickParams {
                k_left: 3.75e-4,
                k_right: 3.75e-4,
                wheel_base: 0.37,
            },
            calibration_runs: 15,
            drive: DriveParams {
                slip_sigma: 0.005,
                ..DriveParams::default()
            },
            heading: HeadingSourceParams::default(),
            pf: HeadingPfParams::default(),
            ga: GaParams::default(),
            seed: 1,
        }
    }
}

/// Short calibration runs: straights and arcs of 1.5–3 m driven by the believed
/// model, with the true start and end poses.
pub fn calibration_runs(
    believed: &DiffDrive,
    truth: &DiffDrive,
    n: usize,
    ticks_per_rev: f64,
    drive: &DriveParams,
    seed: u64,
) -> Vec<GaRun> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let length = rng.random_range(1.5..3.0);
            let angle = [0.0, 1.0, -1.0][i % 3] * rng.random_range(0.5..1.6);
            let seg = if angle == 0.0 {
                Segment::Straight { length }
            } else {
                Segment::Arc { length, angle }
            };
            let run = drive_segments(
                believed,
                truth,
                &[seg],
                drive,
                seed.wrapping_add(1 + i as u64),
            );
            let end = *run.truth.poses.last().unwrap_or(&Pose2::identity());
            GaRun::from_wheels(&run.wheels, ticks_per_rev, Pose2::identity(), end)
        })
        .collect()
}

/// The scenarios of [GAHeading, Table 2], in its order.
const SCENARIOS: [&str; 3] = [
    "uncalibrated",
    "calibrated_odometry",
    "calibrated_odometry_vo_pf",
];

/// Regenerates [GAHeading, Table 2] on simulated runs: the vehicle follows random
/// irregular paths; each estimator's end-position error is reported as % of
/// the path length (mean of `trials`), next to the paper's numbers. Returns the
/// rows and the GA-calibrated parameters.
pub fn heading_pf_experiment(
    p: &PfExperimentParams,
    seed_table: &[SeedPathError],
) -> Result<(Vec<PathErrorRow>, TickParams), ClassicError> {
    let truth = p.truth.to_diff_drive(p.ticks_per_rev);
    let believed = p.uncalibrated.to_diff_drive(p.ticks_per_rev);
    let runs = calibration_runs(
        &believed,
        &truth,
        p.calibration_runs,
        p.ticks_per_rev,
        &p.drive,
        p.seed,
    );
    let ga = ga_calibrate(&runs, &p.ga)?;
    let models = [believed, ga.params.to_diff_drive(p.ticks_per_rev)];
    let mut rows = Vec::new();
    for &length in &p.lengths {
        let errs = path_errors(p, length, &truth, &models)?;
        for (name, e) in SCENARIOS.iter().zip(&errs) {
            rows.push(PathErrorRow {
                scenario: name.to_string(),
                length_m: length,
                error_percent: e.iter().sum::<f64>() / e.len().max(1) as f64,
                error_std: sample_std(e),
                seed_error_percent: seed_table
                    .iter()
                    .find(|r| r.scenario == *name && (r.length_m - length).abs() < 1e-9)
                    .and_then(|r| r.error_percent),
            });
        }
    }
    Ok((rows, ga.params))
}

/// End-position errors (% of the path length) of every trial on paths of
/// `length` (m), per scenario: odometry with the believed model, with the
/// calibrated one (`models`), and the calibrated odometry fused with the
/// heading source.
fn path_errors(
    p: &PfExperimentParams,
    length: f64,
    truth: &DiffDrive,
    [believed, calibrated]: &[DiffDrive; 2],
) -> Result<[Vec<f64>; 3], ClassicError> {
    let mut errs: [Vec<f64>; 3] = Default::default();
    for trial in 0..p.trials {
        let s = p
            .seed
            .wrapping_mul(1_000_003)
            .wrapping_add((length * 1000.0) as u64 * 131 + trial as u64);
        let segs = irregular_path(length, s);
        let run = drive_segments(truth, truth, &segs, &p.drive, s ^ 0x5eed);
        let Some(end) = run.truth.poses.last().copied() else {
            continue;
        };
        let plen = run.truth.path_length().max(1e-9);
        let id = Pose2::identity();
        let headings = simulate_heading(&run.truth, &p.heading, s ^ 0xbeef);
        let pf = heading_pf(
            calibrated,
            &run.wheels,
            &headings,
            &id,
            &HeadingPfParams { seed: s, ..p.pf },
        )?;
        let ends = [
            wheel_odometry(believed, &run.wheels, id)
                .poses
                .last()
                .copied(),
            wheel_odometry(calibrated, &run.wheels, id)
                .poses
                .last()
                .copied(),
            pf.poses.last().copied(),
        ];
        for (e, est) in errs.iter_mut().zip(ends) {
            let est = est.unwrap_or(id);
            e.push(100.0 * (est.translation.vector - end.translation.vector).norm() / plen);
        }
    }
    Ok(errs)
}

/// The rows as a markdown table in the layout of [GAHeading, Table 2], ours
/// next to the paper's (`*` = the paper's vehicle could not complete the path).
pub fn path_error_markdown(rows: &[PathErrorRow]) -> String {
    let mut s = String::from("| scenario | length (m) | error (% of length), odocal | ± std | paper |\n|---|---|---|---|---|\n");
    for r in rows {
        let seed = r
            .seed_error_percent
            .map_or("*".to_string(), |v| format!("{v}"));
        s.push_str(&format!(
            "| {} | {} | {:.3} | {:.3} | {} |\n",
            r.scenario, r.length_m, r.error_percent, r.error_std, seed
        ));
    }
    s
}

/// `ga_path_errors.csv`: scenario,length_m,error_percent (empty = not completed).
pub fn ga_path_errors(t: &SeedTable) -> Result<Vec<SeedPathError>, InputError> {
    let (s, l, e) = (
        t.text("scenario")?,
        t.numbers("length_m")?,
        t.optional_numbers("error_percent")?,
    );
    Ok((0..s.len())
        .map(|i| SeedPathError {
            scenario: s[i].clone(),
            length_m: l[i],
            error_percent: e[i],
        })
        .collect())
}

/// `odocal experiment heading-pf`: Table 2 with `--runs` trials per length,
/// next to the paper's numbers when `--tables` gives them, drawn into `png`.
pub(super) fn heading_pf_output(
    inp: &ExperimentInputs<'_>,
    params: &PfExperimentParams,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let seed_rows = match inp.tables {
        Some(_) => ga_path_errors(&inp.seed_table("ga_path_errors.csv")?)?,
        None => Vec::new(),
    };
    let p = PfExperimentParams {
        trials: inp.runs,
        seed: inp.seed,
        ..params.clone()
    };
    let (rows, ga) = heading_pf_experiment(&p, &seed_rows).map_err(bad)?;
    draw_bars(png, &table_chart(&p, &rows, !seed_rows.is_empty()))?;
    let md = format!(
        "{} trials per length; GA-calibrated k_left {:.6e}, k_right {:.6e} m/pulse, b {:.5} m \
         (truth {:.6e}, {:.6e}, {:.5}).\n\n{}",
        p.trials,
        ga.k_left,
        ga.k_right,
        ga.wheel_base,
        p.truth.k_left,
        p.truth.k_right,
        p.truth.wheel_base,
        path_error_markdown(&rows)
    );
    Ok(ExperimentOutput::titled(
        "GA calibration and heading fusion, Table 2 of the paper",
        md,
        &serde_json::json!({ "rows": rows, "ga": ga, "params": p }),
    ))
}

/// Bars per length and scenario: our errors with their spread and, when
/// `with_seed`, the paper's numbers.
fn table_chart(p: &PfExperimentParams, rows: &[PathErrorRow], with_seed: bool) -> BarChart {
    let cats: Vec<String> = p.lengths.iter().map(|l| format!("{l} m")).collect();
    let cell = |n: &str, l: f64, f: &dyn Fn(&PathErrorRow) -> f64| {
        rows.iter()
            .find(|r| r.scenario == n && r.length_m == l)
            .map_or(0.0, f)
    };
    let grid = |f: &dyn Fn(&PathErrorRow) -> f64| -> Vec<Vec<f64>> {
        SCENARIOS
            .iter()
            .map(|n| p.lengths.iter().map(|&l| cell(n, l, f)).collect())
            .collect()
    };
    let mut chart = BarChart::new(
        format!(
            "GA and heading fusion, Table 2: end-position error ({} trials)",
            p.trials
        ),
        cats,
        SCENARIOS.iter().map(|s| s.to_string()).collect(),
    )
    .panel(
        "odocal: error (% of length)",
        grid(&|r| r.error_percent),
        Some(grid(&|r| r.error_std)),
    );
    if with_seed {
        chart = chart.panel(
            "paper (0 = not completed)",
            grid(&|r| r.seed_error_percent.unwrap_or(0.0)),
            None,
        );
    }
    chart
}
