//! Seed 002's Table 2 regenerated on simulated runs: a vehicle calibrated by
//! the GA on short runs follows irregular 22, 47 and 100 m paths; the
//! end-position error of uncalibrated odometry, calibrated odometry and
//! calibrated odometry fused with a heading source, as % of the path length.

use super::drive::{drive_segments, irregular_path, DriveParams, Segment};
use super::error::ClassicError;
use super::ga::{ga_calibrate, GaParams, GaRun, TickParams};
use super::heading_pf::{heading_pf, simulate_heading, HeadingPfParams, HeadingSourceParams};
use crate::geom::Pose2;
use crate::robot::{wheel_odometry, DiffDrive};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};

/// One of the seed's Table 2 numbers (empty = the vehicle could not finish).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeedPathError {
    /// `uncalibrated`, `calibrated_odometry` or `calibrated_odometry_vo_pf`.
    pub scenario: String,
    /// Path length (m).
    pub length_m: f64,
    /// Mean absolute end-position error (% of length), if reported.
    pub error_percent: Option<f64>,
}

/// Our figure next to the seed's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathErrorRow {
    /// Scenario name (the seed's names).
    pub scenario: String,
    /// Path length (m).
    pub length_m: f64,
    /// Mean end-position error over the trials (% of length).
    pub error_percent: f64,
    /// Standard deviation over the trials (% of length).
    pub error_std: f64,
    /// The seed's number for the same cell, when given.
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
    /// The seed's AGV: true k1, k2, b = its GA result; believed k = 3.75e-4
    /// m/pulse (mid-box), b = 0.37 m; 1000 pulses/rev; 0.5 % wheel slip per
    /// 50 ms step (the level at which calibrated odometry comes nearest the seed's).
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

/// Regenerates seed 002's Table 2 on simulated runs: the vehicle follows random
/// irregular paths; each estimator's end-position error is reported as % of
/// the path length (mean of `trials`), next to the seed's numbers. Returns the
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
    let calibrated = ga.params.to_diff_drive(p.ticks_per_rev);
    let names = [
        "uncalibrated",
        "calibrated_odometry",
        "calibrated_odometry_vo_pf",
    ];
    let mut rows = Vec::new();
    for &length in &p.lengths {
        let mut errs: [Vec<f64>; 3] = Default::default();
        for trial in 0..p.trials {
            let s = p
                .seed
                .wrapping_mul(1_000_003)
                .wrapping_add((length * 1000.0) as u64 * 131 + trial as u64);
            let segs = irregular_path(length, s);
            let run = drive_segments(&truth, &truth, &segs, &p.drive, s ^ 0x5eed);
            let Some(end) = run.truth.poses.last().copied() else {
                continue;
            };
            let plen = run.truth.path_length().max(1e-9);
            let id = Pose2::identity();
            let headings = simulate_heading(&run.truth, &p.heading, s ^ 0xbeef);
            let pf = heading_pf(
                &calibrated,
                &run.wheels,
                &headings,
                &id,
                &HeadingPfParams { seed: s, ..p.pf },
            )?;
            let ends = [
                wheel_odometry(&believed, &run.wheels, id)
                    .poses
                    .last()
                    .copied(),
                wheel_odometry(&calibrated, &run.wheels, id)
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
        for (name, e) in names.iter().zip(&errs) {
            let m = e.iter().sum::<f64>() / e.len().max(1) as f64;
            let sd = (e.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (e.len().max(2) - 1) as f64)
                .sqrt();
            rows.push(PathErrorRow {
                scenario: name.to_string(),
                length_m: length,
                error_percent: m,
                error_std: sd,
                seed_error_percent: seed_table
                    .iter()
                    .find(|r| r.scenario == *name && (r.length_m - length).abs() < 1e-9)
                    .and_then(|r| r.error_percent),
            });
        }
    }
    Ok((rows, ga.params))
}

/// The rows as a markdown table in the layout of seed 002's Table 2, ours
/// next to the seed's (`*` = the seed's vehicle could not complete the path).
pub fn path_error_markdown(rows: &[PathErrorRow]) -> String {
    let mut s = String::from("| scenario | length (m) | error (% of length), odocal | ± std | seed 002 |\n|---|---|---|---|---|\n");
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
