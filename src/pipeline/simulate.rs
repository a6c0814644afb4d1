//! `odocal simulate`: run the simulator and write the ROS 2 bag (and the truth
//! JSON, kept apart so tools reading the bag never see the effects).

use super::{Common, PipelineError};
use crate::effects::Effect;
use crate::error::InputError;
use crate::io::{self, ScanFeed, TopicConfig, WriteOptions};
use crate::robot::RobotConfig;
use crate::scan::LaserScan;
use crate::sim::{self, LaserSim, SimConfig, Truth};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What `odocal simulate --json` prints.
#[derive(Debug, Clone, Serialize)]
pub struct SimulateSummary {
    /// The bag written.
    pub out: String,
    /// The truth file written, if any.
    pub truth: Option<String>,
    /// Scenario name.
    pub scenario: String,
    /// Seed of every random process.
    pub seed: u64,
    /// Length of the run (s).
    pub duration_s: f64,
    /// Laser scans written.
    pub scans: usize,
    /// Encoder samples written.
    pub wheel_samples: usize,
    /// Gyro samples written.
    pub gyro_samples: usize,
    /// Reference poses written.
    pub reference_poses: usize,
    /// True path length (m).
    pub path_length_m: f64,
    /// Injected effects as SPECs.
    pub effects: Vec<String>,
}

/// What `odocal simulate` is asked to do.
#[derive(Debug, Clone, Default)]
pub struct SimulateJob {
    /// A built-in scenario's name, or a JSON scenario file.
    pub scenario: Option<String>,
    /// The seed of every random process (else the configuration's).
    pub seed: Option<u64>,
    /// The length of the run (s) (else the configuration's).
    pub duration_s: Option<f64>,
    /// Effect SPECs, `NAME` or `NAME:key=value,...`.
    pub effects: Vec<String>,
    /// The bag to write.
    pub out: PathBuf,
    /// The truth file to write, if any.
    pub truth: Option<PathBuf>,
    /// Configuration and robot files.
    pub common: Common,
}

/// The laser mounting to simulate: the robot file's `[laser]`; without a
/// robot file, the wheelchair's (the simulator's default robot is the whole
/// wheelchair). A robot file without `[laser]` is refused, naming the key.
fn simulated_mount(
    robot: &crate::robot::RobotConfig,
    file: Option<&Path>,
) -> Result<crate::robot::LaserMount, PipelineError> {
    match (robot.laser, file) {
        (Some(l), _) => Ok(l),
        (None, None) => Ok(crate::robot::LaserMount::default()),
        (None, Some(f)) => Err(crate::error::InputError::new(
            f.display().to_string(),
            "no [laser] table: the simulator needs the laser mounting (x, y, yaw: base_from_laser in m, m, rad)",
        )
        .into()),
    }
}

/// Runs `odocal simulate`: the configuration with the job's scenario, seed,
/// duration and effects, into the bag and truth file.
pub fn run(
    job: &SimulateJob,
    progress: &mut dyn FnMut(f64),
) -> Result<SimulateSummary, PipelineError> {
    let outputs: Vec<&Path> = std::iter::once(job.out.as_path())
        .chain(job.truth.as_deref())
        .collect();
    super::outputs::check_outputs(&[], &outputs)?;
    let _lock = super::outputs::lock_outputs(&outputs)?;
    let (mut cfg, mut robot) = job.common.load()?;
    robot.laser = Some(simulated_mount(&robot, job.common.robot.as_deref())?);
    if let Some(s) = &job.scenario {
        set_scenario(&mut cfg.sim, s)?;
    }
    if let Some(seed) = job.seed {
        cfg.sim.seed = seed;
    }
    if let Some(d) = job.duration_s {
        cfg.sim.duration_s = d;
    }
    let mut effects = Vec::new();
    for spec in &job.effects {
        match parse_effect(spec)? {
            Hidden::Effect(e) => effects.push(e),
            Hidden::Fault(f) => cfg.sim.faults.push(f),
        }
    }
    let (summary, _) = simulate(
        &cfg.sim,
        &cfg.topics,
        &robot,
        &effects,
        &job.out,
        job.truth.as_deref(),
        progress,
    )?;
    Ok(summary)
}

/// What a SPEC of `simulate --effect` hides: a table effect or a fault
/// outside the table.
enum Hidden {
    Effect(Effect),
    Fault(crate::effects::FaultEffect),
}

/// Parses a SPEC as a table effect, else as a fault outside the table.
fn parse_effect(spec: &str) -> Result<Hidden, PipelineError> {
    let name = spec.split(':').next().unwrap_or("").trim();
    if crate::effects::FAULT_NAMES.contains(&name) {
        return crate::effects::FaultEffect::parse(spec)
            .map(Hidden::Fault)
            .map_err(|e| PipelineError::BadArgument(e.to_string()));
    }
    Effect::parse(spec).map(Hidden::Effect).map_err(|e| {
        PipelineError::BadArgument(format!(
            "{e} (faults outside the table: {})",
            crate::effects::FAULT_NAMES.join(", ")
        ))
    })
}

/// A built-in scenario by name, or a JSON scenario file (a path ending in
/// `.json` or naming a file).
fn set_scenario(sim: &mut SimConfig, s: &str) -> Result<(), PipelineError> {
    let p = Path::new(s);
    if s.ends_with(".json") || p.is_file() {
        let text = std::fs::read_to_string(p)
            .map_err(|e| InputError::new(s, format!("cannot read: {e}")))?;
        let spec =
            sim::ScenarioSpec::from_json(&text).map_err(|e| InputError::new(s, e.to_string()))?;
        sim.scenario.custom = Some(spec);
    } else {
        sim.scenario.name = s.to_string();
    }
    Ok(())
}

/// Simulates and writes `out` (MCAP) and optionally `truth_path` (JSON), both
/// atomically. The scans are cast block by block while the bag is written,
/// so memory does not grow with the number of scans.
pub fn simulate(
    cfg: &SimConfig,
    topics: &TopicConfig,
    robot: &RobotConfig,
    effects: &[Effect],
    out: &Path,
    truth_path: Option<&Path>,
    progress: &mut dyn FnMut(f64),
) -> Result<(SimulateSummary, Truth), PipelineError> {
    let sim::SimRun {
        recording: rec,
        truth,
        laser,
    } = sim::prepare(cfg, robot, effects, progress)?;
    let mut opts = WriteOptions::for_robot(robot);
    opts.topics = topics.clone();
    let mut feed = CastScans {
        laser: &laser,
        block: Vec::new(),
        first: 0,
        progress,
    };
    io::write_mcap_streaming(out, &rec, &mut feed, &opts)
        .map_err(|e| PipelineError::write(out, e))?;
    if let Some(tp) = truth_path {
        io::atomic::write_bytes_atomic(tp, truth.to_json().as_bytes())
            .map_err(|e| PipelineError::write(tp, e))?;
    }
    (feed.progress)(1.0);
    let summary = SimulateSummary {
        out: out.display().to_string(),
        truth: truth_path.map(|p| p.display().to_string()),
        scenario: truth.scenario.clone(),
        seed: truth.seed,
        duration_s: truth.duration_s,
        scans: laser.len(),
        wheel_samples: rec.wheels.len(),
        gyro_samples: rec.gyro.len(),
        reference_poses: rec.reference.len(),
        path_length_m: truth.trajectory().path_length(),
        effects: effects.iter().map(|e| e.to_string()).collect(),
    };
    Ok((summary, truth))
}

/// Scans cast on demand for the writer, one parallel block at a time.
struct CastScans<'a, 'p> {
    laser: &'a LaserSim,
    /// The current block: scans `first .. first + block.len()`.
    block: Vec<LaserScan>,
    first: usize,
    progress: &'p mut dyn FnMut(f64),
}

impl ScanFeed for CastScans<'_, '_> {
    fn len(&self) -> usize {
        self.laser.len()
    }
    fn stamp(&self, i: usize) -> f64 {
        self.laser.stamps()[i]
    }
    fn scan(&mut self, i: usize) -> &LaserScan {
        if i < self.first || i >= self.first + self.block.len() {
            let end = (i + LaserSim::BLOCK).min(self.laser.len());
            self.block = self.laser.scans(i..end);
            self.first = i;
            (self.progress)(0.1 + 0.9 * end as f64 / self.laser.len() as f64);
        }
        &self.block[i - self.first]
    }
}
