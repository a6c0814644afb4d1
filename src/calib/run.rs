//! Drives a calibrator over the steps: parameter history, the calibrated
//! odometry, timing, and the multipliers for ROS `diff_drive_controller`.

use super::steps::CalibStep;
use super::{Calibrator, Estimate};
use crate::geom::Pose2;
use crate::robot::DiffDrive;
use crate::traj::Trajectory;
use serde::Serialize;
use std::time::Instant;

/// One row of the calibration history (design.md's calibration CSV columns,
/// in order: `t,r_right,r_left,wheel_base,std_r_right,std_r_left,
/// std_wheel_base,particles,process_sigma`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HistoryRow {
    /// Time (s).
    pub t: f64,
    /// Right wheel radius (m).
    pub r_right: f64,
    /// Left wheel radius (m).
    pub r_left: f64,
    /// Wheel base (m).
    pub wheel_base: f64,
    /// σ of the right radius (m).
    pub std_r_right: f64,
    /// σ of the left radius (m).
    pub std_r_left: f64,
    /// σ of the wheel base (m).
    pub std_wheel_base: f64,
    /// Particles (0 for Kalman filters and `none`).
    pub particles: usize,
    /// Process noise σ on the parameters (m).
    pub process_sigma: f64,
    /// Estimated forward velocity (m/s); not a CSV column.
    #[serde(skip)]
    pub v: f64,
    /// Estimated turn rate (rad/s); not a CSV column.
    #[serde(skip)]
    pub w: f64,
}

impl From<&Estimate> for HistoryRow {
    fn from(e: &Estimate) -> Self {
        Self {
            t: e.t,
            r_right: e.r_right,
            r_left: e.r_left,
            wheel_base: e.wheel_base,
            std_r_right: e.std_r_right,
            std_r_left: e.std_r_left,
            std_wheel_base: e.std_wheel_base,
            particles: e.particles,
            process_sigma: e.process_sigma,
            v: e.v,
            w: e.w,
        }
    }
}

/// Radii and wheel base (m), as JSON `{r_right, r_left, wheel_base}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Params3 {
    /// Right wheel radius (m).
    pub r_right: f64,
    /// Left wheel radius (m).
    pub r_left: f64,
    /// Wheel base (m).
    pub wheel_base: f64,
}

/// What a ROS `diff_drive_controller` user sets: estimate / nominal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Multipliers {
    /// `left_wheel_radius_multiplier`.
    pub left_wheel_radius: f64,
    /// `right_wheel_radius_multiplier`.
    pub right_wheel_radius: f64,
    /// `wheel_separation_multiplier`.
    pub wheel_separation: f64,
}

/// The summary design.md's `calibrate` JSON and `summary.json` carry.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibSummary {
    /// Method name.
    pub method: String,
    /// Final parameter estimate (m).
    #[serde(rename = "final")]
    pub final_params: Params3,
    /// Final standard deviations (m).
    pub std: Params3,
    /// Steps processed.
    pub iterations: usize,
    /// Mean wall time per step (ms).
    pub mean_iteration_ms: f64,
    /// Multipliers for ROS diff_drive_controller.
    pub multipliers: Multipliers,
}

/// Result of [`run`].
#[derive(Debug, Clone)]
pub struct CalibrationRun {
    /// Summary (serialises to design.md's keys).
    pub summary: CalibSummary,
    /// Estimate after every step.
    pub history: Vec<HistoryRow>,
    /// Odometry integrated with the parameters estimated so far, identity at
    /// the first step's start.
    pub trajectory: Trajectory,
    /// Steps whose weights all underflowed and were reset.
    pub weight_resets: usize,
}

impl CalibrationRun {
    /// The final estimate as kinematics.
    pub fn final_drive(&self) -> DiffDrive {
        let f = self.summary.final_params;
        DiffDrive {
            r_right: f.r_right,
            r_left: f.r_left,
            wheel_base: f.wheel_base,
        }
    }
}

impl CalibSummary {
    /// The summary of `method` after `iterations` steps that took `total_s`
    /// (s) in all, ending with the estimate `last`; without any step, the
    /// nominal parameters with zero std.
    pub fn after(
        method: &str,
        last: Option<&Estimate>,
        nominal: DiffDrive,
        iterations: usize,
        total_s: f64,
    ) -> Self {
        let (final_params, std) = match last {
            Some(e) => (
                Params3 {
                    r_right: e.r_right,
                    r_left: e.r_left,
                    wheel_base: e.wheel_base,
                },
                Params3 {
                    r_right: e.std_r_right,
                    r_left: e.std_r_left,
                    wheel_base: e.std_wheel_base,
                },
            ),
            None => (
                Params3 {
                    r_right: nominal.r_right,
                    r_left: nominal.r_left,
                    wheel_base: nominal.wheel_base,
                },
                Params3 {
                    r_right: 0.0,
                    r_left: 0.0,
                    wheel_base: 0.0,
                },
            ),
        };
        let ratio = |a: f64, b: f64| if b != 0.0 { a / b } else { f64::NAN };
        CalibSummary {
            method: method.to_string(),
            final_params,
            std,
            iterations,
            mean_iteration_ms: if iterations == 0 {
                0.0
            } else {
                1e3 * total_s / iterations as f64
            },
            multipliers: Multipliers {
                left_wheel_radius: ratio(final_params.r_left, nominal.r_left),
                right_wheel_radius: ratio(final_params.r_right, nominal.r_right),
                wheel_separation: ratio(final_params.wheel_base, nominal.wheel_base),
            },
        }
    }
}

/// Runs `cal` over `steps`. Each step's wheel increment (rate × the part of
/// its interval not already integrated, so overlapping intervals are not
/// counted twice) is integrated with `DiffDrive::increment` using the
/// estimate after that step — what an online system knows at the step's end.
/// With no steps the summary holds the nominal parameters and 0 iterations.
pub fn run(cal: &mut dyn Calibrator, steps: &[CalibStep], nominal: DiffDrive) -> CalibrationRun {
    run_observed(cal, steps, nominal, &mut |_, _| {})
}

/// Like [`run`], calling `on_step` after every step with the estimate and the
/// calibrator's particle cloud (if it has one), e.g. to show it in a viewer.
pub fn run_observed(
    cal: &mut dyn Calibrator,
    steps: &[CalibStep],
    nominal: DiffDrive,
    on_step: &mut dyn FnMut(&Estimate, Option<super::CloudView<'_>>),
) -> CalibrationRun {
    let mut history = Vec::with_capacity(steps.len());
    let mut trajectory = Trajectory::with_capacity(steps.len() + 1);
    let mut pose = Pose2::identity();
    let mut covered = steps.first().map_or(0.0, |s| s.t0);
    if let Some(s) = steps.first() {
        trajectory.push(s.t0, pose);
    }
    let mut total = 0.0f64;
    let mut resets = 0;
    let mut last: Option<Estimate> = None;
    for s in steps {
        let t = Instant::now();
        let e = cal.step(s);
        total += t.elapsed().as_secs_f64();
        resets += e.weights_reset as usize;
        let dt = s.t1 - s.t0.max(covered);
        if dt > 0.0 {
            pose *= e.drive().increment(s.omega_right * dt, s.omega_left * dt);
            trajectory.push(s.t1, pose);
            covered = s.t1;
        }
        history.push(HistoryRow::from(&e));
        on_step(&e, cal.cloud());
        last = Some(e);
    }
    let summary = CalibSummary::after(cal.name(), last.as_ref(), nominal, steps.len(), total);
    CalibrationRun {
        summary,
        history,
        trajectory,
        weight_resets: resets,
    }
}
