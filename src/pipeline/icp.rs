//! `odocal icp`: scan matching over a whole recording, with the wheel (or the
//! recording's own) odometry as the initial guess of every pair. Files and
//! recordings in memory go through the same driver ([`super::drive`]).

use super::drive::{self, IcpRunSummary};
use super::observe::{Observers, RunObserver};
use super::outputs::{check_outputs, lock_outputs, Collect, IcpFiles};
use super::{Common, Mount, PipelineError};
use crate::icp::IcpParams;
use crate::io::{RecordingSource, SampleSource};
use crate::recording::Recording;
use crate::robot::RobotConfig;
use std::path::{Path, PathBuf};

pub use super::outputs::IcpOutput;

/// The laser mounting of `rec`: the one it states (/tf_static, /tf, a log's
/// laser pose), else the robot file's; neither is an error naming `[laser]`.
pub fn mount(rec: &Recording, robot: &RobotConfig) -> Result<Mount, PipelineError> {
    Mount::resolve(rec.into(), robot, &rec.source)
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
    let (cfg, nominal) = job.common.load_nominal()?;
    let read = super::read_options(&cfg, &nominal.robot);
    let mut source = crate::io::open(&job.input, &read)?;
    let info = source.info().clone();
    let params = nominal.icp_params(&cfg.icp, &info);
    let mut summary = run_source(source.as_mut(), &nominal.robot, &params, job, watch)?;
    summary.assumptions =
        nominal.icp_assumptions(&summary.mount, &summary.prior, cfg.icp.prior, &info);
    Ok(summary)
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
