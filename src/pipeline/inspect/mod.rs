//! `odocal inspect REC`: what a recording holds ([`crate::io::survey`]),
//! which of its topics each command would read and why (`choose`), the
//! base → laser transform found in its transforms (or not), what each
//! command would still miss, and a proposed robot file (`propose`) that
//! `--write-robot FILE` writes atomically.

mod choose;
mod choose_wheels;
mod mount;
mod propose;
mod uses;

use super::{Common, Nominal, PipelineError};
use crate::icp::{Prior, PriorChoice};
use crate::io::survey::{Survey, TfEdge, TopicSurvey};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

pub use mount::LaserFinding;
pub use uses::Use;

/// What `odocal inspect` is asked.
#[derive(Debug, Clone, Default)]
pub struct InspectJob {
    /// The recording (any format).
    pub input: PathBuf,
    /// `--config` (topic names) and `--robot` (joints, wheel source, laser).
    pub common: Common,
    /// Where to write the proposed robot file.
    pub write_robot: Option<PathBuf>,
}

/// The whole answer (`--json`).
#[derive(Debug, Clone, Serialize)]
pub struct Inspection {
    /// The file or folder.
    pub file: String,
    /// Its format.
    pub format: &'static str,
    /// First and last receive time over all topics, and the duration (s).
    pub span_s: Option<[f64; 3]>,
    /// Every topic.
    pub topics: Vec<TopicSurvey>,
    /// Every parent → child transform pair.
    pub transforms: Vec<TfEdge>,
    /// The laser frame and its mounting on `base_link`.
    pub laser: LaserFinding,
    /// Per stream (`scans`, `wheels`, `gyro`, `odom`, `reference`): the
    /// topic odocal would read, why, and the key to set.
    pub uses: BTreeMap<&'static str, Use>,
    /// The scan matcher's prior with the settings given (`[icp] prior`, the
    /// robot file): `wheels`, `odometry` or `none`, and why.
    pub prior: PriorFinding,
    /// Per command: what it would miss (empty: it runs).
    pub missing: BTreeMap<&'static str, Vec<String>>,
    /// The proposed robot file (TOML with comments).
    pub robot_toml: String,
    /// The `--config` `[topics]` table for topics other than the defaults.
    pub config_toml: Option<String>,
    /// Where the robot file was written (`--write-robot`).
    pub wrote_robot: Option<String>,
}

/// Runs `odocal inspect`.
pub fn run(job: &InspectJob) -> Result<Inspection, PipelineError> {
    if let Some(out) = &job.write_robot {
        super::outputs::check_outputs(&[], &[out])?;
        let same = |a: &std::path::Path, b: &std::path::Path| {
            a == b
                || std::fs::canonicalize(a)
                    .ok()
                    .is_some_and(|x| std::fs::canonicalize(b).ok() == Some(x))
        };
        if same(out, &job.input) {
            return Err(PipelineError::BadArgument(format!(
                "--write-robot {} is the input: choose another path",
                out.display()
            )));
        }
    }
    let (cfg, nominal) = job.common.load_nominal()?;
    let survey = crate::io::survey::survey(&job.input)?;
    let read = super::read_options(&cfg, &nominal.robot);
    let uses = choose::uses(&survey, &read, &nominal);
    let laser = mount::find(&survey, &uses, &nominal, &read.topics);
    let missing = choose::missing(&survey, &uses, &laser, &nominal);
    let prior = prior(&uses, &nominal, cfg.icp.prior);
    let robot_toml = propose::robot_toml(&survey, &uses, &laser, &nominal, &job.input);
    let config_toml = propose::config_toml(&uses);
    let wrote_robot = match &job.write_robot {
        Some(out) => {
            let _lock = super::outputs::lock_outputs(&[out.as_path()])?;
            crate::io::atomic::write_bytes_atomic(out, robot_toml.as_bytes())
                .map_err(|e| PipelineError::write(out, e))?;
            Some(out.display().to_string())
        }
        None => None,
    };
    Ok(Inspection {
        file: survey.file.clone(),
        format: survey.format,
        span_s: span(&survey),
        uses,
        laser,
        prior,
        missing,
        robot_toml,
        config_toml,
        wrote_robot,
        topics: survey.topics,
        transforms: survey.transforms,
    })
}

/// Which stream `icp` and `calibrate` would take as each pair's initial
/// guess (see [`crate::icp::PriorChoice`]).
#[derive(Debug, Clone, Serialize)]
pub struct PriorFinding {
    /// `wheels`, `odometry` or `none`; absent when the setting names a
    /// stream the recording lacks (the run would stop).
    pub stream: Option<&'static str>,
    /// Why that one, or what is missing.
    pub why: String,
}

/// The prior the settings give for the streams `uses` found readable as
/// configured.
fn prior(
    uses: &BTreeMap<&'static str, Use>,
    nominal: &Nominal,
    given: PriorChoice,
) -> PriorFinding {
    let read = |k: &str| {
        uses.get(k)
            .filter(|u| u.topic.is_some() && u.configured)
            .map_or(0, |u| u.messages)
    };
    let info = crate::io::StreamInfo {
        wheels: read("wheels"),
        odom: read("odom"),
        ..Default::default()
    };
    if read("scans") == 0 {
        return PriorFinding {
            stream: None,
            why: "no laser scans read: no scan matching".into(),
        };
    }
    let choice = nominal.prior_choice(given, &info);
    let (stream, why) =
        match Prior::choose(choice, info.wheels, info.odom, nominal.robot.diff_drive()) {
            Err(e) => (None, e),
            Ok(prior) => {
                let (value, why) = nominal.prior_reason(&prior, given, info.wheels);
                (Some(value), why)
            }
        };
    PriorFinding { stream, why }
}

fn span(s: &Survey) -> Option<[f64; 3]> {
    let first = s.topics.iter().map(|t| t.first_s).reduce(f64::min)?;
    let last = s.topics.iter().map(|t| t.last_s).reduce(f64::max)?;
    Some([first, last, last - first])
}
