//! Scoring one calibration run against its truth: final parameter errors,
//! velocity and odometry RMSE, time per iteration, convergence time.

use crate::calib::synth::SynthData;
use crate::calib::{CalibStep, CalibrationRun};
use crate::eval::{windowed_error, WheelIncrement};
use crate::geom::{self, Pose2};
use crate::robot::DiffDrive;
use serde::Serialize;

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
    /// RMSE of the position of the odometry dead-reckoned over the whole
    /// run with the method's final parameters (m): what the calibration is
    /// worth afterwards, free of how each step's estimate re-fits that
    /// step's measurements.
    pub rmse_xy_final: f64,
    /// RMSE of that odometry's heading (rad).
    pub rmse_theta_final: f64,
    /// RMSE of the position of the odometry dead-reckoned over 10 s windows,
    /// each with the estimate in effect at its start, relative to the
    /// window's start (m): the odometry a robot runs on while it calibrates
    /// ([`crate::eval::windowed`]); 0 when no window could be scored.
    pub rmse_xy_window: f64,
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

/// The odometry of `steps` dead-reckoned with fixed parameters `k`, from
/// the identity at the first step's start, integrated as the calibration
/// runner does (each step's part not yet covered, by its mean wheel rates).
pub fn fixed_odometry(steps: &[CalibStep], k: &DiffDrive) -> (Vec<f64>, Vec<Pose2>) {
    let mut pose = Pose2::identity();
    let Some(first) = steps.first() else {
        return (vec![], vec![]);
    };
    let (mut stamps, mut poses) = (vec![first.t0], vec![pose]);
    let mut covered = first.t0;
    for s in steps {
        let dt = s.t1 - s.t0.max(covered);
        if dt > 0.0 {
            pose *= k.increment(s.omega_right * dt, s.omega_left * dt);
            stamps.push(s.t1);
            poses.push(pose);
            covered = s.t1;
        }
    }
    (stamps, poses)
}

/// The window of [`RunMetrics::rmse_xy_window`] (s).
pub const WINDOW_S: f64 = 10.0;

/// The wheel rotation of `steps` as increments, each step's part not yet
/// covered by its mean wheel rates (as [`fixed_odometry`] integrates).
fn step_increments(steps: &[CalibStep]) -> Vec<WheelIncrement> {
    let mut covered = f64::NEG_INFINITY;
    let mut out = Vec::with_capacity(steps.len());
    for s in steps {
        let t0 = s.t0.max(covered);
        let dt = s.t1 - t0;
        if dt > 0.0 {
            out.push(WheelIncrement {
                t0,
                t1: s.t1,
                d_right: s.omega_right * dt,
                d_left: s.omega_left * dt,
            });
            covered = s.t1;
        }
    }
    out
}

/// The windowed odometry RMSE of a run (m; 0 when no window was scored).
fn window_rmse(r: &CalibrationRun, steps: &[CalibStep], truth: &dyn RunTruth) -> f64 {
    let estimates: Vec<(f64, DiffDrive)> = r
        .history
        .iter()
        .map(|h| {
            (
                h.t,
                DiffDrive {
                    r_right: h.r_right,
                    r_left: h.r_left,
                    wheel_base: h.wheel_base,
                },
            )
        })
        .collect();
    windowed_error(
        &step_increments(steps),
        &estimates,
        &|t| truth.pose_at(t),
        WINDOW_S,
    )
    .map_or(0.0, |e| e.rmse_m)
}

/// RMSE of position (m) and heading (rad) of poses against the truth, the
/// truth expressed in its own pose at the first stamp.
fn pose_rmse(stamps: &[f64], poses: &[Pose2], truth: &dyn RunTruth) -> (f64, f64) {
    let origin = stamps.first().and_then(|&t| truth.pose_at(t));
    let (mut sxy, mut sth, mut m) = (0.0, 0.0, 0usize);
    for (t, p) in stamps.iter().zip(poses) {
        if let (Some(o), Some(q)) = (origin, truth.pose_at(*t)) {
            let q = geom::between(&o, &q);
            let d = p.translation.vector - q.translation.vector;
            sxy += d.norm_squared();
            sth += geom::wrap_angle(geom::heading(p) - geom::heading(&q)).powi(2);
            m += 1;
        }
    }
    let rms = |s: f64| if m > 0 { (s / m as f64).sqrt() } else { 0.0 };
    (rms(sxy), rms(sth))
}

/// Scores a finished run of `steps` against its truth. The calibrated
/// odometry starts at the identity; the true trajectory is expressed in its
/// own pose at that first stamp before comparing.
pub fn score(
    r: &CalibrationRun,
    steps: &[CalibStep],
    truth: &dyn RunTruth,
    fraction: f64,
) -> RunMetrics {
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
    let (rmse_xy, rmse_theta) = pose_rmse(&r.trajectory.stamps, &r.trajectory.poses, truth);
    let (stamps, poses) = fixed_odometry(steps, &f);
    let (rmse_xy_final, rmse_theta_final) = pose_rmse(&stamps, &poses, truth);
    let rms = |s: f64, k: usize| if k > 0 { (s / k as f64).sqrt() } else { 0.0 };
    RunMetrics {
        err_r_right: (f.r_right - end.r_right).abs(),
        err_r_left: (f.r_left - end.r_left).abs(),
        err_wheel_base: (f.wheel_base - end.wheel_base).abs(),
        rmse_v: rms(sv, n),
        rmse_w: rms(sw, n),
        rmse_xy,
        rmse_theta,
        rmse_xy_final,
        rmse_theta_final,
        rmse_xy_window: window_rmse(r, steps, truth),
        mean_iteration_ms: r.summary.mean_iteration_ms,
        convergence_s: conv_from.map(|t| (t - start).max(0.0)),
    }
}
