//! Where the online filters start (`calibrate --init`): the robot file's
//! nominal values, or the joint batch estimate of the same recording
//! ([`super::batch`]). Starting from the batch, a filter runs with the
//! batch's radii and wheel base as its prior centre, the batch's laser
//! mounting in place of the recording's or the robot file's, and the wheel
//! stamps moved onto the laser clock by the batch's time offset
//! (`t_laser = t_wheel − δ`): a latency the filters cannot estimate
//! themselves biases their radii low, since ICP speeds are compared with
//! wheel rates of another instant. The gyro keeps its own stamps.

use super::batch::{recording_problem, solve};
use super::{Config, Nominal, PipelineError};
use crate::assumptions::{Assumptions, Origin};
use crate::calib::batch::BatchEstimate;
use crate::calib::CalibParams;
use crate::recording::{Recording, WheelSource};
use crate::robot::{LaserMount, RobotConfig};
use std::path::Path;

pub use super::calibrate_job::Start;

/// A recording made ready for the filters from its batch estimate.
pub struct FromBatch {
    /// The recording: wheel stamps on the laser clock, the estimated
    /// mounting as its stated one.
    pub rec: Recording,
    /// The robot the filters start from: the estimated kinematics and
    /// mounting, the rest from the robot file.
    pub robot: RobotConfig,
    /// The batch estimate.
    pub est: BatchEstimate,
    /// Where the wheels came from.
    pub wheels: WheelSource,
}

/// Runs the batch calibration on `path` and prepares its recording and
/// robot for the filters; a refusal of the batch refuses the run.
pub fn from_batch(
    path: &Path,
    cfg: &Config,
    nominal: &Nominal,
    params: &CalibParams,
) -> Result<FromBatch, PipelineError> {
    if crate::io::sniff(path)? == crate::io::Format::CensiTuples {
        return Err(crate::error::InputError::new(
            path.display().to_string(),
            "--init batch needs a recording with scans and wheels for the filters; Censi \
             tuples carry neither (use --method batch)",
        )
        .into());
    }
    let (mut rec, problem, wheels) = recording_problem(path, cfg, nominal, &params.batch)?;
    let est = solve(path, &problem, &nominal.robot, params, Some(&wheels))?;
    let delta = est.time_offset.map_or(0.0, |t| t.value);
    for w in &mut rec.wheels {
        w.stamp -= delta;
    }
    let l = &est.laser;
    let laser = LaserMount {
        x: l.x.value,
        y: l.y.value,
        yaw: l.yaw.value,
    };
    rec.base_from_laser = Some(laser.pose());
    rec.mount_origin = Some(Origin::Estimated);
    rec.mount_note = Some(format!(
        "batch estimate ± {:.4} m, {:.4} m, {:.4} rad",
        l.x.std, l.y.std, l.yaw.std
    ));
    let robot = RobotConfig {
        r_right: est.r_right.value,
        r_left: est.r_left.value,
        wheel_base: est.wheel_base.value,
        laser: Some(laser),
        ..nominal.robot.clone()
    };
    Ok(FromBatch {
        rec,
        robot,
        est,
        wheels,
    })
}

/// States the started values in `a`: the kinematics and the time offset as
/// estimated, with the robot file's values in the notes.
pub fn state(a: &mut Assumptions, est: &BatchEstimate, file: &RobotConfig) {
    for (k, v, nominal) in [
        ("r_right", est.r_right, file.r_right),
        ("r_left", est.r_left, file.r_left),
        ("wheel_base", est.wheel_base, file.wheel_base),
    ] {
        let note = format!(
            "the batch estimate ± {:.5} m, where the filter starts; the robot file states {nominal}",
            v.std
        );
        a.set(k, v.value, Origin::Estimated, Some(note));
    }
    let (value, note) = match est.time_offset {
        Some(t) => (
            t.value,
            format!(
                "batch estimate ± {:.4} s: the wheel stamps were moved onto the laser clock \
                 (t_laser = t_wheel {:+.4} s)",
                t.std, -t.value
            ),
        ),
        None => (
            0.0,
            "not estimated (the input carries no wheel time)".into(),
        ),
    };
    a.set("time_offset", value, Origin::Estimated, Some(note));
}
