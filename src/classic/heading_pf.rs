//! Seed 002's operation stage: a particle filter over the pose (x, y, θ)
//! propagated with calibrated odometry increments and weighted by an absolute
//! heading source (a camera's yaw, an IMU's integrated heading). Its figure of
//! merit is the end-position error as a percentage of the path length.

use super::drive::{drive_segments, irregular_path, DriveParams, Segment};
use super::error::{check_finite, ClassicError};
use super::ga::{ga_calibrate, GaParams, GaRun, TickParams};
use crate::geom::{self, Pose2};
use crate::recording::WheelSample;
use crate::robot::{wheel_odometry, DiffDrive};
use crate::traj::Trajectory;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// Filter settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HeadingPfParams {
    /// Number of particles.
    pub particles: usize,
    /// σ of the travelled distance per metre travelled (relative).
    pub sigma_dist_rel: f64,
    /// σ of the heading change per radian turned (relative).
    pub sigma_turn_rel: f64,
    /// σ of the heading change per metre travelled (rad/m).
    pub sigma_turn_per_m: f64,
    /// σ of the heading source (rad).
    pub heading_sigma: f64,
    /// Resample when N_eff < this fraction of the particles.
    pub resample_below: f64,
    /// Random seed.
    pub seed: u64,
}

impl Default for HeadingPfParams {
    /// 500 particles; odometry noise 1 % of distance, 2 % of turn, 0.01 rad/m;
    /// heading source σ = 0.01 rad; resample below N/2.
    fn default() -> Self {
        Self {
            particles: 500,
            sigma_dist_rel: 0.01,
            sigma_turn_rel: 0.02,
            sigma_turn_per_m: 0.01,
            heading_sigma: 0.01,
            resample_below: 0.5,
            seed: 1,
        }
    }
}

/// A heading reading: stamp (s) and absolute yaw (rad, world frame).
pub type HeadingReading = (f64, f64);

/// Runs the filter over a wheel stream from a known start pose; heading
/// readings (sorted by stamp) are applied at the first wheel sample at or
/// after their stamp. Returns the weighted-mean pose at every wheel sample.
pub fn heading_pf(
    model: &DiffDrive,
    wheels: &[WheelSample],
    headings: &[HeadingReading],
    start: &Pose2,
    p: &HeadingPfParams,
) -> Result<Trajectory, ClassicError> {
    const M: &str = "heading pf";
    check_finite(M, "heading", headings.iter().flat_map(|h| [h.0, h.1]))?;
    if p.particles == 0 || p.heading_sigma.is_nan() || p.heading_sigma <= 0.0 {
        return Err(ClassicError::invalid(
            M,
            "need particles > 0 and heading_sigma > 0",
        ));
    }
    let mut rng = StdRng::seed_from_u64(p.seed);
    let n = p.particles;
    let [x0, y0, t0] = geom::xyt(start);
    let mut parts = vec![[x0, y0, t0]; n];
    let mut logw = vec![0.0f64; n];
    let mut out = Trajectory::with_capacity(wheels.len());
    let Some(first) = wheels.first() else {
        return Ok(out);
    };
    out.push(first.stamp, *start);
    let mut prev = *first;
    let mut hi = headings.partition_point(|h| h.0 < first.stamp);
    for s in &wheels[1..] {
        if s.stamp.is_nan() || s.stamp <= prev.stamp {
            continue;
        }
        // Propagate: calibrated odometry increment plus noise ∝ distance and turn.
        let (ds, dth) = model.body_velocity(s.right - prev.right, s.left - prev.left);
        let sd = p.sigma_dist_rel * ds.abs();
        let st = p.sigma_turn_rel * dth.abs() + p.sigma_turn_per_m * ds.abs();
        for q in parts.iter_mut() {
            let a: f64 = rng.sample(StandardNormal);
            let b: f64 = rng.sample(StandardNormal);
            let (d, t) = (ds + sd * a, dth + st * b);
            let mid = q[2] + 0.5 * t;
            q[0] += d * mid.cos();
            q[1] += d * mid.sin();
            q[2] += t;
        }
        // Weight by every heading reading up to this stamp.
        let mut updated = false;
        while hi < headings.len() && headings[hi].0 <= s.stamp {
            let z = headings[hi].1;
            let k = 0.5 / (p.heading_sigma * p.heading_sigma);
            for (q, w) in parts.iter().zip(logw.iter_mut()) {
                let e = geom::wrap_angle(z - q[2]);
                *w -= k * e * e;
            }
            hi += 1;
            updated = true;
        }
        let w = normalised(&logw);
        if updated {
            let neff = 1.0 / w.iter().map(|v| v * v).sum::<f64>();
            if neff < p.resample_below * n as f64 {
                parts = systematic(&parts, &w, &mut rng);
                logw.iter_mut().for_each(|v| *v = 0.0);
            }
        }
        let w = normalised(&logw);
        out.push(s.stamp, mean_pose(&parts, &w));
        prev = *s;
    }
    Ok(out)
}

fn normalised(logw: &[f64]) -> Vec<f64> {
    let m = logw.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut w: Vec<f64> = logw.iter().map(|l| (l - m).exp()).collect();
    let s: f64 = w.iter().sum();
    w.iter_mut().for_each(|v| *v /= s);
    w
}

fn systematic(parts: &[[f64; 3]], w: &[f64], rng: &mut StdRng) -> Vec<[f64; 3]> {
    let n = parts.len();
    let u0 = rng.random_range(0.0..1.0 / n as f64);
    let mut out = Vec::with_capacity(n);
    let (mut c, mut i) = (w[0], 0);
    for j in 0..n {
        let u = u0 + j as f64 / n as f64;
        while u > c && i < n - 1 {
            i += 1;
            c += w[i];
        }
        out.push(parts[i]);
    }
    out
}

fn mean_pose(parts: &[[f64; 3]], w: &[f64]) -> Pose2 {
    let (mut x, mut y, mut c, mut s) = (0.0, 0.0, 0.0, 0.0);
    for (q, wi) in parts.iter().zip(w) {
        x += wi * q[0];
        y += wi * q[1];
        c += wi * q[2].cos();
        s += wi * q[2].sin();
    }
    geom::pose(x, y, s.atan2(c))
}

/// A simulated absolute heading source.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HeadingSourceParams {
    /// Reading rate (Hz).
    pub rate_hz: f64,
    /// White noise σ of each reading (rad).
    pub sigma: f64,
    /// Random-walk drift (rad/√s), as of an integrated IMU heading; 0 for a camera.
    pub drift_per_sqrt_s: f64,
}

impl Default for HeadingSourceParams {
    /// A camera yaw: 10 Hz, σ = 0.01 rad, no drift.
    fn default() -> Self {
        Self {
            rate_hz: 10.0,
            sigma: 0.01,
            drift_per_sqrt_s: 0.0,
        }
    }
}

/// Heading readings of the true trajectory with the source's noise.
pub fn simulate_heading(
    truth: &Trajectory,
    p: &HeadingSourceParams,
    seed: u64,
) -> Vec<HeadingReading> {
    let mut rng = StdRng::seed_from_u64(seed);
    let (Some(&t0), Some(&t1)) = (truth.stamps.first(), truth.stamps.last()) else {
        return Vec::new();
    };
    let dt = 1.0 / p.rate_hz;
    let mut out = Vec::new();
    let mut drift = 0.0;
    let mut t = t0 + dt;
    while t <= t1 {
        if let Some(q) = truth.pose_at(t) {
            let a: f64 = rng.sample(StandardNormal);
            let b: f64 = rng.sample(StandardNormal);
            drift += p.drift_per_sqrt_s * dt.sqrt() * a;
            out.push((t, geom::wrap_angle(geom::heading(&q) + drift + p.sigma * b)));
        }
        t += dt;
    }
    out
}

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
