//! Scoring a method on the evaluation runs: RMSE of position and heading
//! against the truth, end-position error as % of the path, and parameter
//! errors when the truth is known.

use super::{ClassicMethod, ClassicResult};
use crate::classic::{ClassicError, SimRun};
use crate::geom::{self, Pose2};
use crate::robot::{wheel_odometry, DiffDrive};
use crate::traj::Trajectory;
use std::borrow::Borrow;

/// The evaluation runs and the truth the methods are scored against.
#[derive(Debug, Clone, Copy)]
pub struct Evaluation<'a> {
    /// True parameters, when known (for the parameter errors).
    pub truth: Option<&'a DiffDrive>,
    /// Held-out runs.
    pub runs: &'a [SimRun],
}

/// What a method ends with: its parameters (m), compute time (ms) and
/// method-specific figures.
#[derive(Debug, Clone)]
pub struct Calibrated {
    /// The method.
    pub method: ClassicMethod,
    /// Parameters it ends with (m).
    pub params: DiffDrive,
    /// Wall time of the calibration (ms).
    pub ms: f64,
    /// Method-specific figures.
    pub details: serde_json::Value,
}

impl Evaluation<'_> {
    /// Scores `c` by the odometry of its parameters on every evaluation run.
    pub fn odometry(&self, c: Calibrated) -> Result<ClassicResult, ClassicError> {
        let k = c.params;
        self.estimates(
            c,
            self.runs
                .iter()
                .map(|run| Ok(wheel_odometry(&k, &run.wheels, start_of(run)))),
        )
    }

    /// Scores `c` by its trajectories of the evaluation runs, in run order.
    pub fn estimates<T: Borrow<Trajectory>>(
        &self,
        c: Calibrated,
        estimates: impl IntoIterator<Item = Result<T, ClassicError>>,
    ) -> Result<ClassicResult, ClassicError> {
        let (mut sxy, mut sth, mut pct, mut n) = (0.0, 0.0, 0.0, 0usize);
        for (run, est) in self.runs.iter().zip(estimates) {
            let est = est?;
            let (xy, th, end, m) = errors(est.borrow(), &run.truth);
            sxy += xy * xy * m as f64;
            sth += th * th * m as f64;
            pct += end;
            n += m;
        }
        let nn = n.max(1) as f64;
        let k = c.params;
        Ok(ClassicResult {
            method: c.method,
            final_params: k,
            param_errors: self.truth.map(|t| DiffDrive {
                r_right: (k.r_right - t.r_right).abs(),
                r_left: (k.r_left - t.r_left).abs(),
                wheel_base: (k.wheel_base - t.wheel_base).abs(),
            }),
            rmse_xy: (sxy / nn).sqrt(),
            rmse_theta: (sth / nn).sqrt(),
            path_error_percent: pct / self.runs.len().max(1) as f64,
            compute_ms: c.ms,
            details: c.details,
        })
    }
}

/// RMSE of position (m) and heading (rad) of `est` against the truth at the
/// estimate's stamps, the end error as % of the true path length, and the
/// number of stamps compared.
fn errors(est: &Trajectory, truth: &Trajectory) -> (f64, f64, f64, usize) {
    let (mut sxy, mut sth, mut n) = (0.0, 0.0, 0usize);
    let mut last = None;
    for (t, p) in est.stamps.iter().zip(&est.poses) {
        if let Some(q) = truth.pose_at(*t) {
            sxy += (p.translation.vector - q.translation.vector).norm_squared();
            sth += geom::wrap_angle(geom::heading(p) - geom::heading(&q)).powi(2);
            n += 1;
            last = Some((p.translation.vector - q.translation.vector).norm());
        }
    }
    let nn = n.max(1) as f64;
    let pct = 100.0 * last.unwrap_or(0.0) / truth.path_length().max(1e-9);
    ((sxy / nn).sqrt(), (sth / nn).sqrt(), pct, n)
}

/// The true start pose of a run (identity if unknown).
pub fn start_of(run: &SimRun) -> Pose2 {
    run.wheels
        .first()
        .and_then(|s| run.truth.pose_at(s.stamp))
        .unwrap_or_else(Pose2::identity)
}
