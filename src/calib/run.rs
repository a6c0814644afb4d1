//! What a calibration run gives: the parameter history, the calibrated
//! odometry, and the summary with the multipliers for ROS
//! `diff_drive_controller`.

use super::Estimate;
use crate::assumptions::Assumptions;
use crate::robot::DiffDrive;
use crate::traj::Trajectory;
use serde::Serialize;

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

impl Multipliers {
    /// The scales of odometry computed with the nominal parameters against
    /// the calibrated ones, for multipliers m_R, m_L, m_D (calibrated /
    /// nominal): on a straight run the calibrated robot covers
    /// `linear = 2 / (1/m_R + 1/m_L)` times the nominal odometry's distance
    /// (the harmonic mean; m_R = m_L = m gives m), and turning in place it
    /// turns `angular = linear / m_D` times the nominal odometry's angle. They
    /// follow from V = (R_R ω_R + R_L ω_L)/2, W = (R_R ω_R − R_L ω_L)/D with
    /// R_R ω_R = R_L ω_L (straight) or R_R ω_R = −R_L ω_L (in place).
    pub fn odometry_scale(&self) -> OdometryScale {
        let linear = 2.0 / (1.0 / self.right_wheel_radius + 1.0 / self.left_wheel_radius);
        OdometryScale {
            linear,
            angular: linear / self.wheel_separation,
        }
    }
}

/// How far a robot's own odometry is off in scale (JSON `odometry_scale`):
/// true distance / reported distance on a straight run, true angle /
/// reported angle turning in place.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OdometryScale {
    /// Distance scale (the `wheel_radius_multiplier` of a controller with
    /// one radius multiplier).
    pub linear: f64,
    /// Heading scale.
    pub angular: f64,
}

/// The summary design.md's `calibrate` JSON and `summary.json` carry.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibSummary {
    /// Method name.
    pub method: String,
    /// Final parameter estimate (m).
    #[serde(rename = "final")]
    pub final_params: DiffDrive,
    /// Final standard deviations of the three parameters (m).
    pub std: DiffDrive,
    /// Steps processed.
    pub iterations: usize,
    /// Mean wall time per step (ms).
    pub mean_iteration_ms: f64,
    /// Multipliers for ROS diff_drive_controller.
    pub multipliers: Multipliers,
    /// Where every nominal value came from (set by the command that ran).
    #[serde(skip_serializing_if = "Assumptions::is_empty")]
    pub assumptions: Assumptions,
    /// Whether the run's motion determines each parameter (set by the
    /// command that ran, which refuses what it cannot).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observability: Option<super::Observability>,
    /// Which stream the wheels came from (set by the command that ran).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wheel_source: Option<crate::recording::WheelSource>,
    /// With the robot's own odometry as the wheel source: how far that
    /// odometry is off in distance and heading ([`Multipliers::odometry_scale`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub odometry_scale: Option<OdometryScale>,
    /// The batch calibration's estimate (`--method batch`): each unknown with
    /// its std, the laser mounting, the time offset and the correlations, as
    /// top-level keys.
    #[serde(flatten)]
    pub batch: Option<super::batch::BatchEstimate>,
    /// What the online front end used and found ([`super::online`]): the
    /// time offset, the laser mounting, the warm-up and every fit of the
    /// window, as top-level keys (`time_offset`, `laser`, `warmup`,
    /// `solves`, `route`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub online: Option<super::online::OnlineReport>,
    /// The batch estimate an online filter started from (`--init batch`),
    /// under `start`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<super::batch::BatchEstimate>,
    /// What changed at each firing of the change detector (set by the
    /// command that ran; `diagnose::onset`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub changes: Vec<crate::effects::change::NamedChange>,
    /// Times (s) at which the change detector fired against a belief still
    /// narrowing ([`super::change::Jump::settled`] false): the filter
    /// re-spread itself, as on a change, but no change of the robot is
    /// reported for it.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub respreads_s: Vec<f64>,
}

/// Result of [`crate::calib::run()`].
#[derive(Debug, Clone)]
pub struct CalibrationRun {
    /// Summary (serialises to design.md's keys).
    pub summary: CalibSummary,
    /// Estimate after every step.
    pub history: Vec<Estimate>,
    /// Odometry integrated with the parameters estimated so far, identity at
    /// the first step's start.
    pub trajectory: Trajectory,
    /// Steps whose weights all underflowed and were reset.
    pub weight_resets: usize,
}

impl CalibrationRun {
    /// The final estimate as kinematics.
    pub fn final_drive(&self) -> DiffDrive {
        self.summary.final_params
    }
}

impl CalibSummary {
    /// The multipliers against `nominal` (the robot file's values, when the
    /// run started elsewhere).
    pub fn rebase(&mut self, nominal: DiffDrive) {
        let f = self.final_params;
        self.multipliers.right_wheel_radius = f.r_right / nominal.r_right;
        self.multipliers.left_wheel_radius = f.r_left / nominal.r_left;
        self.multipliers.wheel_separation = f.wheel_base / nominal.wheel_base;
    }

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
            Some(e) => (e.drive(), e.std()),
            None => (
                nominal,
                DiffDrive {
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
            assumptions: Assumptions::default(),
            observability: None,
            wheel_source: None,
            odometry_scale: None,
            batch: None,
            online: None,
            start: None,
            changes: Vec::new(),
            respreads_s: Vec::new(),
            multipliers: Multipliers {
                left_wheel_radius: ratio(final_params.r_left, nominal.r_left),
                right_wheel_radius: ratio(final_params.r_right, nominal.r_right),
                wheel_separation: ratio(final_params.wheel_base, nominal.wheel_base),
            },
        }
    }
}
