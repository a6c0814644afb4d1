//! `odocal icp`: scan matching over a whole recording, with the wheel (or the
//! recording's own) odometry as the initial guess of every pair.

use super::PipelineError;
use crate::eval::trajectory_from_stamped;
use crate::geom::Pose2;
use crate::icp::{self, IcpParams, IcpStats};
use crate::motion::{Motion, VelocityObs};
use crate::recording::Recording;
use crate::robot::{wheel_odometry, RobotConfig};
use crate::traj::Trajectory;
use std::path::Path;

/// Motions, their summary and the chained trajectory of one ICP run.
#[derive(Debug, Clone)]
pub struct IcpOutput {
    /// One motion per consecutive scan pair (base frame).
    pub motions: Vec<Motion>,
    /// Counts, iterations and timing.
    pub stats: IcpStats,
    /// Motions chained from the identity at the first scan.
    pub trajectory: Trajectory,
}

impl IcpOutput {
    /// Velocity observations of the valid pairs (failed pairs give none).
    pub fn observations(&self) -> Vec<VelocityObs> {
        self.motions
            .iter()
            .filter_map(VelocityObs::from_motion)
            .collect()
    }
}

/// `base_from_laser`: the recording's /tf_static when present, else the robot file's.
pub fn base_from_laser(rec: &Recording, robot: &RobotConfig) -> Pose2 {
    rec.base_from_laser.unwrap_or_else(|| robot.laser.pose())
}

/// The odometry used as ICP prior: wheel odometry with the nominal model when
/// the recording has encoders, else the recording's own odometry, else none.
pub fn odometry_prior(rec: &Recording, robot: &RobotConfig) -> Option<Trajectory> {
    if rec.wheels.len() >= 2 {
        return Some(wheel_odometry(
            &robot.diff_drive(),
            &rec.wheels,
            Pose2::identity(),
        ));
    }
    (rec.odom.len() >= 2).then(|| trajectory_from_stamped(&rec.odom).0)
}

/// Matches every consecutive scan pair of the recording.
pub fn run(
    rec: &Recording,
    robot: &RobotConfig,
    params: &IcpParams,
) -> Result<IcpOutput, PipelineError> {
    if rec.scans.len() < 2 {
        return Err(crate::error::InputError::new(
            &rec.source,
            format!(
                "{} laser scans: scan matching needs at least 2",
                rec.scans.len()
            ),
        )
        .into());
    }
    let prior = odometry_prior(rec, robot);
    let (motions, stats) = icp::match_recording(
        &rec.scans,
        base_from_laser(rec, robot),
        prior.as_ref(),
        params,
    )
    .map_err(|e| PipelineError::BadArgument(e.to_string()))?;
    let trajectory = icp::integrate(&motions);
    Ok(IcpOutput {
        motions,
        stats,
        trajectory,
    })
}

/// Writes the trajectory (TUM) and, if asked, the motions CSV, atomically.
pub fn write(out: &IcpOutput, tum: &Path, motions_csv: Option<&Path>) -> Result<(), PipelineError> {
    crate::io::tum::write_tum_2d(tum, &out.trajectory).map_err(|e| PipelineError::write(tum, e))?;
    if let Some(p) = motions_csv {
        crate::io::csv::write_motions(p, &out.motions).map_err(|e| PipelineError::write(p, e))?;
    }
    Ok(())
}

/// Streams the MCAP bag at `input` through ICP in flat memory and writes the
/// trajectory (TUM) and, if asked, the motions CSV as [`write`] does; same
/// numbers as [`run`] on the read recording. `progress` gets the fraction
/// of scans read.
pub fn run_file(
    input: &Path,
    read: &crate::io::ReadOptions,
    robot: &RobotConfig,
    params: &IcpParams,
    tum: &Path,
    motions_csv: Option<&Path>,
    progress: &mut dyn FnMut(f64),
) -> Result<crate::io::stream_run::IcpRunSummary, PipelineError> {
    crate::io::stream_run::icp_file(input, read, robot, params, tum, motions_csv, progress)
        .map_err(stream_error)
}

/// The pipeline error for a streamed run's failure.
pub(crate) fn stream_error(e: crate::io::stream_run::StreamError) -> PipelineError {
    use crate::io::stream_run::StreamError;
    match e {
        StreamError::Input(e) => PipelineError::Input(e),
        StreamError::BadArgument(m) => PipelineError::BadArgument(m),
        StreamError::Write { path, source } => PipelineError::write(&path, source),
    }
}
