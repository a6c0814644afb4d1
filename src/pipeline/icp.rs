//! `odocal icp`: scan matching over a whole recording, with the wheel (or the
//! recording's own) odometry as the initial guess of every pair. Files and
//! recordings in memory go through the same driver ([`super::drive`]).

use super::drive::{self, IcpRunSummary};
use super::observe::{Observers, RunObserver};
use super::outputs::{Collect, IcpFiles};
use super::{Common, PipelineError};
use crate::geom::Pose2;
use crate::icp::{IcpParams, IcpStats};
use crate::io::{RecordingSource, SampleSource};
use crate::motion::{Motion, VelocityObs};
use crate::recording::Recording;
use crate::robot::RobotConfig;
use crate::traj::Trajectory;
use std::path::PathBuf;

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

/// Matches every consecutive scan pair of a recording in memory.
pub fn match_recording(
    rec: &Recording,
    robot: &RobotConfig,
    params: &IcpParams,
) -> Result<IcpOutput, PipelineError> {
    let mut collect = Collect::default();
    let summary = drive::run_icp(&mut RecordingSource::new(rec), robot, params, &mut collect)?;
    Ok(collect.icp(summary.stats))
}

/// What `odocal icp` is asked to do.
#[derive(Debug, Clone, Default)]
pub struct IcpJob {
    /// The recording (any format [`crate::io::sniff`] knows).
    pub input: PathBuf,
    /// The trajectory output (TUM).
    pub out: PathBuf,
    /// The per-pair motions output (CSV), if asked for.
    pub motions: Option<PathBuf>,
    /// Configuration and robot files.
    pub common: Common,
}

/// Runs `odocal icp`: streams the recording through ICP and writes the
/// trajectory and motions atomically. `watch` sees the run (e.g. progress).
/// The summary's timing is the matching loop's.
pub fn run(job: &IcpJob, watch: &mut dyn RunObserver) -> Result<IcpRunSummary, PipelineError> {
    let (cfg, robot) = job.common.load()?;
    let read = super::read_options(&cfg, &robot);
    let mut source = crate::io::source::open(&job.input, &read)?;
    run_source(source.as_mut(), &robot, &cfg.icp, job, watch)
}

fn run_source(
    source: &mut dyn SampleSource,
    robot: &RobotConfig,
    params: &IcpParams,
    job: &IcpJob,
    watch: &mut dyn RunObserver,
) -> Result<IcpRunSummary, PipelineError> {
    let mut files = IcpFiles::create(&job.out, job.motions.as_deref())?;
    let summary = drive::run_icp(
        source,
        robot,
        params,
        &mut Observers(vec![&mut files, watch]),
    )?;
    files.commit()?;
    Ok(summary)
}
