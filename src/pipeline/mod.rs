//! Wires the stages for the command line: load inputs, run the math modules
//! through the one driver ([`drive`]), write outputs atomically, and return
//! summaries the binary prints. Each command is `pipeline::<command>::run`.

pub mod batch;
pub mod calibrate;
mod calibrate_job;
pub mod changes;
mod config;
pub mod demo;
pub mod diagnose;
pub mod drive;
mod error;
pub mod evaluate;
pub mod fleet;
pub mod icp;
pub mod inspect;
#[cfg(feature = "dds")]
pub mod live;
pub mod nominal;
pub mod observe;
pub mod odometry;
pub mod outputs;
pub mod paste;
#[cfg(feature = "dds")]
pub mod play;
pub mod recorder;
pub mod sense;
pub mod simulate;
pub mod start;
pub mod viewer;
pub mod wheels;

pub use config::{load_robot, Config};
pub use error::PipelineError;
pub use nominal::{Mount, Nominal};
pub use observe::{NoObserver, Observers, Progress, RunObserver};
pub use viewer::Viewer;

use crate::io::ReadOptions;
use crate::recording::Recording;
use crate::robot::RobotConfig;
use std::path::{Path, PathBuf};

/// The files every command may be given: stage settings and the nominal robot.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Common {
    /// Stage settings (TOML); `None`: the defaults.
    pub config: Option<PathBuf>,
    /// The nominal robot (TOML); `None`: the wheelchair.
    pub robot: Option<PathBuf>,
}

impl Common {
    /// Loads the configuration and the robot (without a robot file, the
    /// wheelchair's kinematics and no laser mounting: see [`Nominal`]).
    pub fn load(&self) -> Result<(Config, RobotConfig), PipelineError> {
        let (cfg, nominal) = self.load_nominal()?;
        Ok((cfg, nominal.robot))
    }

    /// Loads the configuration and the nominal robot with its sources.
    pub fn load_nominal(&self) -> Result<(Config, Nominal), PipelineError> {
        Ok((
            Config::load(self.config.as_deref())?,
            Nominal::load(self.robot.as_deref())?,
        ))
    }

    /// Like [`Self::load_nominal`], the robot file allowed to state no
    /// nominal kinematics ([`Nominal::load_open`]).
    pub fn load_nominal_open(&self) -> Result<(Config, Nominal), PipelineError> {
        Ok((
            Config::load(self.config.as_deref())?,
            Nominal::load_open(self.robot.as_deref())?,
        ))
    }
}

/// How recordings are read with these settings: the configured topics and
/// the robot's wheel joint names.
pub fn read_options(cfg: &Config, robot: &RobotConfig) -> ReadOptions {
    let mut read = ReadOptions::for_robot(robot);
    read.topics = cfg.topics.clone();
    read
}

/// Reads a whole recording with these settings.
pub fn read_recording(
    path: &Path,
    cfg: &Config,
    robot: &RobotConfig,
) -> Result<Recording, PipelineError> {
    Ok(crate::io::read_recording(path, &read_options(cfg, robot))?)
}
