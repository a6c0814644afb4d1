//! `odocal icp`: scan matching over a whole recording, with the wheel (or the
//! recording's own) odometry as the initial guess of every pair. Files and
//! recordings in memory go through the same driver ([`super::drive`]).

use super::drive::{self, IcpRunSummary};
use super::observe::{Observers, RunObserver};
use super::outputs::{check_outputs, lock_outputs, Collect, IcpFiles};
use super::{Common, PipelineError};
use crate::geom::Pose2;
use crate::icp::IcpParams;
use crate::io::{RecordingSource, SampleSource};
use crate::recording::Recording;
use crate::robot::RobotConfig;
use std::path::{Path, PathBuf};

pub use super::outputs::IcpOutput;

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
    let outputs: Vec<&Path> = std::iter::once(job.out.as_path())
        .chain(job.motions.as_deref())
        .collect();
    check_outputs(&[&job.input], &outputs)?;
    let _lock = lock_outputs(&outputs)?;
    let (cfg, robot) = job.common.load()?;
    let read = super::read_options(&cfg, &robot);
    let mut source = crate::io::open(&job.input, &read)?;
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
