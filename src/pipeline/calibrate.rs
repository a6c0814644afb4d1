//! `odocal calibrate`: ICP velocity observations (+ gyro) and wheel angles into
//! a calibrator, then the history CSV, the calibrated trajectory and a summary.

use super::PipelineError;
use crate::calib::{self, CalibParams, CalibrationRun, Ranges};
use crate::motion::VelocityObs;
use crate::recording::{GyroSample, WheelSample};
use crate::robot::RobotConfig;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How measurements other than ICP enter the calibration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeasurementConfig {
    /// Use the gyro's yaw rate as a W measurement when the recording has one.
    pub use_gyro: bool,
    /// σ of one gyro sample (rad/s).
    pub gyro_sigma: f64,
}

impl Default for MeasurementConfig {
    fn default() -> Self {
        Self {
            use_gyro: true,
            gyro_sigma: 0.003,
        }
    }
}

/// What a calibrator is fed: wheel angles, velocity observations, gyro.
#[derive(Debug, Clone, Default)]
pub struct CalibInput {
    /// Wheel angles (rad).
    pub wheels: Vec<WheelSample>,
    /// Velocity observations (ICP), each with its σ.
    pub observations: Vec<VelocityObs>,
    /// Gyro yaw rates (empty when unused).
    pub gyro: Vec<GyroSample>,
}

/// The calibrator settings for `robot`: the configured ones, except that the
/// initial ranges are re-centred (±5 %) on the nominal robot when the
/// configured ranges do not contain it (they default to the wheelchair's).
pub fn params_for_robot(params: &CalibParams, robot: &RobotConfig) -> CalibParams {
    let mut p = params.clone();
    let inside = |r: [f64; 2], x: f64| r[0] <= x && x <= r[1];
    let r = &p.ranges;
    if !(inside(r.r_right, robot.r_right)
        && inside(r.r_left, robot.r_left)
        && inside(r.wheel_base, robot.wheel_base))
    {
        p.ranges = Ranges::around(robot.r_right, robot.r_left, robot.wheel_base, 0.05);
    }
    p
}

/// Runs the configured calibrator over the input.
pub fn run(
    input: &CalibInput,
    robot: &RobotConfig,
    params: &CalibParams,
    meas: &MeasurementConfig,
) -> Result<CalibrationRun, PipelineError> {
    run_observed(input, robot, params, meas, &mut |_, _| {})
}

/// Like [`run`], calling `on_step` after every filter step with the estimate
/// and, for particle filters, a view of the particle cloud.
pub fn run_observed(
    input: &CalibInput,
    robot: &RobotConfig,
    params: &CalibParams,
    meas: &MeasurementConfig,
    on_step: &mut dyn FnMut(&calib::Estimate, Option<calib::CloudView<'_>>),
) -> Result<CalibrationRun, PipelineError> {
    let params = params_for_robot(params, robot);
    let nominal = robot.diff_drive();
    let gyro: &[GyroSample] = if meas.use_gyro { &input.gyro } else { &[] };
    let steps = calib::steps(&input.observations, &input.wheels, gyro, meas.gyro_sigma);
    if steps.is_empty() {
        return Err(PipelineError::BadArgument(
            "nothing to calibrate: no wheel data overlapping the velocity observations".into(),
        ));
    }
    let mut c =
        calib::build(&params, nominal).map_err(|e| PipelineError::BadArgument(e.to_string()))?;
    Ok(calib::run_observed(c.as_mut(), &steps, nominal, on_step))
}

/// Writes `DIR/calibration.csv`, `DIR/trajectory.tum` and `DIR/summary.json`.
pub fn write(dir: &Path, run: &CalibrationRun) -> Result<(), PipelineError> {
    let csv = dir.join("calibration.csv");
    let rows = run.history.iter().map(|h| {
        [
            h.t,
            h.r_right,
            h.r_left,
            h.wheel_base,
            h.std_r_right,
            h.std_r_left,
            h.std_wheel_base,
            h.particles as f64,
            h.process_sigma,
        ]
    });
    crate::io::csv::write_history(&csv, rows).map_err(|e| PipelineError::write(&csv, e))?;
    let tum = dir.join("trajectory.tum");
    crate::io::tum::write_tum_2d(&tum, &run.trajectory)
        .map_err(|e| PipelineError::write(&tum, e))?;
    let js = dir.join("summary.json");
    let text = serde_json::to_string_pretty(&run.summary).expect("summary serialises");
    crate::io::atomic::write_bytes_atomic(&js, text.as_bytes())
        .map_err(|e| PipelineError::write(&js, e))?;
    Ok(())
}

/// Streams the MCAP bag at `input` through ICP and the configured calibrator
/// in flat memory, writing what [`write`] writes into `dir`; same numbers as
/// [`run`] on the read recording (timings aside). `progress` gets the
/// fraction of scans read.
// Each argument is a separate stage input the callers hold apart.
#[allow(clippy::too_many_arguments)]
pub fn run_file(
    input: &Path,
    read: &crate::io::ReadOptions,
    robot: &RobotConfig,
    icp: &crate::icp::IcpParams,
    params: &CalibParams,
    meas: &MeasurementConfig,
    dir: &Path,
    progress: &mut dyn FnMut(f64),
    observer: &mut dyn crate::io::stream_run::RunObserver,
) -> Result<calib::CalibSummary, PipelineError> {
    let gyro = crate::io::stream_run::GyroUse {
        use_gyro: meas.use_gyro,
        gyro_sigma: meas.gyro_sigma,
    };
    let params = params_for_robot(params, robot);
    crate::io::stream_run::calibrate_file(
        input, read, robot, icp, &params, gyro, dir, progress, observer,
    )
    .map_err(super::icp::stream_error)
}
