//! `odocal play`: any recording odocal reads put on a ROS 2 domain as its
//! robot published it ([`crate::live::ros2::play`]). A ROS 2 bag (MCAP,
//! rosbag2) is played as stored, every topic with its type and payload;
//! any other format (ROS 1 bag, CARMEN, text) is first written to a
//! temporary MCAP with the configured topics, as `odocal simulate` writes
//! its bags, and that is played.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use super::{Common, PipelineError};
use crate::error::InputError;
use crate::io::stored::{stored_messages, StoredMessages};
use crate::io::ReadOptions;
use crate::live::ros2::play::{PlayOptions, Played};
use crate::live::ros2::Ros2Node;

/// What `odocal play` is asked to do.
#[derive(Debug, Clone)]
pub struct PlayJob {
    /// The recording.
    pub input: PathBuf,
    /// Speed against the log times.
    pub rate: f64,
    /// Start again at the end until stopped.
    pub looped: bool,
    /// Wait before the first message (s).
    pub delay_s: f64,
    /// Configuration (`[topics]`, `[live]`) and robot files.
    pub common: Common,
}

/// A temporary MCAP removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Plays `job` until its end (or, looping, until `stop`).
pub fn run(job: &PlayJob, stop: &AtomicBool) -> Result<Played, PipelineError> {
    if !(job.rate.is_finite() && job.rate > 0.0) {
        return Err(PipelineError::BadArgument(format!(
            "--rate must be a positive factor, got {}",
            job.rate
        )));
    }
    let (cfg, nominal) = job.common.load_nominal_open()?;
    let mut read = super::read_options(&cfg, &nominal.robot);
    // Every topic, whatever its type, as stored.
    read.all_topics = true;
    let (path, _scratch) = playable(&job.input, &cfg, &nominal.robot)?;
    // Opened once here so that a bad file is refused before joining.
    drop(open(&path, &read)?);
    let (domain, localhost) = super::live::network(&cfg.live)?;
    let node = Ros2Node::join("odocal_play", domain, localhost, false)
        .map_err(|e| PipelineError::Network(e.to_string()))?;
    let opts = PlayOptions {
        rate: job.rate,
        looped: job.looped,
        latched: vec![cfg.topics.tf_static.clone()],
        delay_s: job.delay_s,
    };
    let mut opener = || open(&path, &read);
    crate::live::ros2::play::play(&node, &mut opener, &opts, stop).map_err(|e| match e {
        crate::live::ros2::play::PlayError::Input(i) => i.into(),
        crate::live::ros2::play::PlayError::Network(n) => PipelineError::Network(n.to_string()),
    })
}

/// The stored messages of `path` (a ROS 2 bag).
fn open<'o>(path: &Path, read: &'o ReadOptions) -> Result<StoredMessages<'o>, InputError> {
    stored_messages(path, read)?.ok_or_else(|| {
        InputError::new(
            path.display().to_string(),
            "stores no ROS 2 messages (it should have been converted)",
        )
    })
}

/// The ROS 2 bag to play for `input`: itself, or its conversion to a
/// temporary MCAP (removed with the guard).
fn playable(
    input: &Path,
    cfg: &super::Config,
    robot: &crate::robot::RobotConfig,
) -> Result<(PathBuf, Option<Scratch>), PipelineError> {
    use crate::io::Format;
    match crate::io::sniff(input)? {
        Format::Mcap | Format::Rosbag2Sqlite | Format::Rosbag2Dir => {
            return Ok((input.to_path_buf(), None))
        }
        Format::CensiTuples => {
            return Err(InputError::new(
                input.display().to_string(),
                "Censi's tuples are displacements, not messages: there is nothing to publish",
            )
            .into())
        }
        _ => {}
    }
    let rec = super::read_recording(input, cfg, robot)?;
    let scratch = Scratch(std::env::temp_dir().join(format!(
        "odocal-play-{}-{}.mcap",
        std::process::id(),
        input.file_name().map_or("rec".into(), |n| {
            n.to_string_lossy().replace(['/', ' '], "_")
        })
    )));
    let mut opts = crate::io::WriteOptions::for_robot(robot);
    opts.topics = cfg.topics.clone();
    crate::io::write_mcap(&scratch.0, &rec, &opts)
        .map_err(|e| PipelineError::write(&scratch.0, e))?;
    Ok((scratch.0.clone(), Some(scratch)))
}
