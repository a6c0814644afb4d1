//! `odocal fleet`: every recording of a fleet calibrated (in parallel, each
//! result cached by the recording's content hash and the settings, so a
//! re-run only processes new files), then per robot the parameter history,
//! its trends and alarms ([`crate::fleet`]), written as a table (CSV and
//! JSON), a report (markdown and PNG) and, when asked, a Rerun recording
//! ([`recording`]).
//!
//! The run is three steps so that another engine can do the middle one:
//! [`plan`] lists the recordings and what the cache already holds,
//! [`calibrate_item`] calibrates one recording (a pure function of the file
//! and the settings), [`finish`] stores the new results and writes the
//! outputs. [`run`] does all three here, the middle one with rayon; the
//! Python package's Ray engine runs the middle one as Ray tasks.

mod cache;
pub mod inputs;
pub mod recording;
mod report;

use super::calibrate::{CalibSource, CalibrateJob, CalibratorChoice};
use super::{Common, PipelineError};
use crate::fleet::{self, Alarm, Entry, FleetParams, Outcome, Refusal, RobotAnalysis};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

pub use report::Row;

/// What `odocal fleet` is asked to do.
#[derive(Debug, Clone)]
pub struct FleetJob {
    /// A fleet folder (`ROBOT/…/REC`) or a manifest CSV (`robot,path,start`).
    pub source: PathBuf,
    /// The output folder: table, report, cache and each recording's outputs.
    pub out: PathBuf,
    /// Overrides of the configured calibrator.
    pub choice: CalibratorChoice,
    /// Configuration and robot files (the robot is every robot's nominal).
    pub common: Common,
}

/// One recording of the plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Item {
    /// The robot.
    pub robot: String,
    /// The recording's path.
    pub recording: String,
    /// When it started (days since 1970-01-01, UTC).
    pub unix_day: f64,
    /// Where that time was taken from.
    #[serde(default)]
    pub start_from: inputs::StartFrom,
    /// SHA-256 of its content.
    pub hash: String,
    /// The cached result, when the cache holds one for these settings.
    pub cached: Option<Outcome>,
    /// The earlier item of the plan with the same robot and content (a
    /// copied file): calibrated once, its result shared.
    #[serde(default)]
    pub same_as: Option<usize>,
}

impl Item {
    /// Whether an engine must calibrate it: neither cached nor a copy.
    pub fn to_calibrate(&self) -> bool {
        self.cached.is_none() && self.same_as.is_none()
    }
}

/// What [`plan`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Every recording, ordered by robot, time and path.
    pub items: Vec<Item>,
    /// SHA-256 of the settings that decide a result (odocal's version, the
    /// robot and configuration files, the calibrator choices).
    pub settings: String,
}

/// What `odocal fleet --json` prints (also `fleet.json`).
#[derive(Debug, Clone, Serialize)]
pub struct FleetSummary {
    /// The date of day 0 (the earliest recording's, UTC).
    pub epoch: String,
    /// The calibration method.
    pub method: String,
    /// Recordings in the fleet.
    pub recordings: usize,
    /// Of which calibrated in this run.
    pub processed: usize,
    /// Of which taken from the cache.
    pub cached: usize,
    /// Robots in the fleet.
    pub robot_count: usize,
    /// What each recording's std was multiplied by: the fleet's own scatter
    /// between recordings against the reported std ([`fleet::std_factors`]).
    pub std_factors: StdFactors,
    /// Every alarm, by robot and day.
    pub alarms: Vec<Alarm>,
    /// Per robot: trends and alarms.
    pub robots: Vec<RobotAnalysis>,
    /// One row per recording (as `fleet.csv`).
    pub table: Vec<Row>,
    /// When each recording started and where that was read, in the table's
    /// order.
    pub starts: Vec<RecordingStart>,
    /// The alarm thresholds used.
    pub thresholds: FleetParams,
    /// The files written.
    pub outputs: Vec<String>,
}

/// When a recording started, and where that time was read.
#[derive(Debug, Clone, Serialize)]
pub struct RecordingStart {
    /// The recording.
    pub recording: String,
    /// Its start, `YYYY-MM-DDTHH:MM:SSZ` (UTC).
    pub start: String,
    /// `recording` (its own first stamp), `path` (a date in its path: its
    /// clock is not a date) or `manifest`.
    pub from: inputs::StartFrom,
}

/// The factors the recordings' std were multiplied by.
#[derive(Debug, Clone, Serialize)]
pub struct StdFactors {
    /// Right radius.
    pub r_right: f64,
    /// Left radius.
    pub r_left: f64,
    /// Wheel base.
    pub wheel_base: f64,
}

/// Lists the fleet's recordings with their hashes and cached results.
pub fn plan(job: &FleetJob) -> Result<Plan, PipelineError> {
    job.common.load_nominal()?; // refuse bad settings before any work
    let settings = cache::settings_key(job)?;
    // Absolute paths, so that the table reads the same whichever engine or
    // working directory ran it.
    let source = std::path::absolute(&job.source).unwrap_or_else(|_| job.source.clone());
    let mut listed = inputs::list(&source)?;
    listed.sort_by(|a, b| {
        (a.robot.as_str(), a.unix_day, &a.path)
            .partial_cmp(&(b.robot.as_str(), b.unix_day, &b.path))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let items = listed
        .into_par_iter()
        .map(|l| {
            let hash = inputs::content_hash(&l.path)?;
            Ok(Item {
                cached: cache::load(&job.out, &hash, &settings),
                robot: l.robot,
                recording: l.path.display().to_string(),
                unix_day: l.unix_day,
                start_from: l.start_from,
                hash,
                same_as: None,
            })
        })
        .collect::<Result<Vec<Item>, PipelineError>>()?;
    let mut items = items;
    let mut first = std::collections::HashMap::new();
    for (i, item) in items.iter_mut().enumerate() {
        let j = *first
            .entry((item.robot.clone(), item.hash.clone()))
            .or_insert(i);
        item.same_as = (j != i).then_some(j);
    }
    Ok(Plan { items, settings })
}

/// Which alarm a refused calibration raises: the wiring check and the
/// plausibility check are faults of the robot; a motion that cannot
/// determine the parameters, or a recording that cannot be read or holds
/// nothing to calibrate, is insufficient data.
fn refusal_kind(message: &str) -> Refusal {
    if message.contains("wired wrongly") || message.contains("calibration refused") {
        Refusal::Fault
    } else {
        Refusal::Insufficient
    }
}

/// Where one recording's calibration outputs go: `OUT/recordings/ROBOT/HASH12`.
pub fn item_dir(out: &Path, item: &Item) -> PathBuf {
    out.join("recordings")
        .join(&item.robot)
        .join(&item.hash[..12.min(item.hash.len())])
}

/// Calibrates one recording as `odocal calibrate` would (its outputs in
/// [`item_dir`]); a refusal is an outcome, not an error. Only a failure to
/// write is an error.
pub fn calibrate_item(job: &FleetJob, item: &Item) -> Result<Outcome, PipelineError> {
    let calib = CalibrateJob {
        input: CalibSource::Recording(PathBuf::from(&item.recording)),
        out: item_dir(&job.out, item),
        choice: job.choice.clone(),
        viewer: None,
        common: job.common.clone(),
        // Each recording starts from the robot file's values, as the fleet's
        // cache key assumes.
        init: Default::default(),
    };
    match super::calibrate::run(&calib, &mut super::NoObserver) {
        Ok(done) => Ok(Outcome::Calibrated {
            params: done.summary.final_params,
            std: done.summary.std,
            mounting: done
                .summary
                .online
                .as_ref()
                .filter(|o| o.laser.contradicted)
                .and_then(|o| o.laser.check.clone()),
        }),
        Err(e @ PipelineError::Write { .. }) => Err(e),
        Err(e) => {
            let message = e.to_string();
            Ok(Outcome::Refused {
                kind: refusal_kind(&message),
                message,
            })
        }
    }
}

/// Stores the new results (`outcomes[i]` for `plan.items[i]`, `None` where
/// the cache held it), analyses every robot and writes the outputs.
pub fn finish(
    job: &FleetJob,
    plan: &Plan,
    outcomes: Vec<Option<Outcome>>,
) -> Result<FleetSummary, PipelineError> {
    if outcomes.len() != plan.items.len() {
        return Err(PipelineError::BadArgument(format!(
            "{} results for {} recordings",
            outcomes.len(),
            plan.items.len()
        )));
    }
    let (cfg, _) = job.common.load_nominal()?;
    let mut processed = 0;
    let mut resolved: Vec<Outcome> = Vec::with_capacity(outcomes.len());
    for (item, new) in plan.items.iter().zip(outcomes) {
        let outcome = match (new, &item.cached, item.same_as) {
            (Some(o), _, _) => {
                cache::store(&job.out, &item.hash, &plan.settings, &o)?;
                processed += 1;
                o
            }
            (None, Some(c), _) => c.clone(),
            (None, None, Some(j)) if j < resolved.len() => resolved[j].clone(),
            (None, None, _) => {
                return Err(PipelineError::BadArgument(format!(
                    "{}: neither calibrated nor cached",
                    item.recording
                )))
            }
        };
        resolved.push(outcome);
    }
    let epoch = plan
        .items
        .iter()
        .map(|i| i.unix_day.floor())
        .fold(f64::INFINITY, f64::min);
    let entries: Vec<(String, Entry)> = plan
        .items
        .iter()
        .zip(resolved)
        .map(|(i, outcome)| {
            let entry = Entry {
                recording: i.recording.clone(),
                day: i.unix_day - epoch,
                outcome,
            };
            (i.robot.clone(), entry)
        })
        .collect();
    let mut robots: Vec<String> = entries.iter().map(|(r, _)| r.clone()).collect();
    robots.dedup();
    let grouped: Vec<(String, Vec<Entry>)> = robots
        .iter()
        .map(|r| {
            let mine = entries
                .iter()
                .filter(|(robot, _)| robot == r)
                .map(|(_, e)| e.clone())
                .collect();
            (r.clone(), mine)
        })
        .collect();
    let (factors, analyses) = fleet::analyse_fleet(&grouped, &cfg.fleet);
    let mut summary = FleetSummary {
        epoch: inputs::date_of(epoch as i64),
        method: {
            let mut c = cfg.calib.clone();
            job.choice.apply(&mut c);
            c.method.as_str().to_string()
        },
        recordings: plan.items.len(),
        processed,
        cached: plan.items.len() - processed,
        robot_count: analyses.len(),
        std_factors: StdFactors {
            r_right: factors[0],
            r_left: factors[1],
            wheel_base: factors[2],
        },
        alarms: analyses.iter().flat_map(|a| a.alarms.clone()).collect(),
        table: report::rows(&entries, epoch),
        starts: plan
            .items
            .iter()
            .map(|i| RecordingStart {
                recording: i.recording.clone(),
                start: inputs::datetime_of(i.unix_day),
                from: i.start_from,
            })
            .collect(),
        robots: analyses,
        thresholds: cfg.fleet.clone(),
        outputs: Vec::new(),
    };
    summary.outputs = report::write(&job.out, &summary)?;
    Ok(summary)
}

/// Runs `odocal fleet` here: the recordings not in the cache calibrated in
/// parallel on every core; `progress(done, total)` after each.
pub fn run(
    job: &FleetJob,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<FleetSummary, PipelineError> {
    let _lock = super::outputs::lock_outputs(&[job.out.as_path()])?;
    let plan = plan(job)?;
    let todo = plan.items.iter().filter(|i| i.to_calibrate()).count();
    let done = AtomicUsize::new(0);
    progress(0, todo);
    let outcomes = plan
        .items
        .par_iter()
        .map(|item| {
            if !item.to_calibrate() {
                return Ok(None);
            }
            let o = calibrate_item(job, item)?;
            progress(done.fetch_add(1, Ordering::SeqCst) + 1, todo);
            Ok(Some(o))
        })
        .collect::<Result<Vec<_>, PipelineError>>()?;
    finish(job, &plan, outcomes)
}
