//! `odocal simulate`: run the simulator and write the ROS 2 bag (and the truth
//! JSON, kept apart so tools reading the bag never see the effects).

use super::{Common, PipelineError};
use crate::effects::Effect;
use crate::error::InputError;
use crate::geom::Pose2;
use crate::io::{self, BagSource, BagStream, TopicConfig, WheelRates, WriteOptions};
use crate::recording::{StampedPose, WheelSample};
use crate::robot::RobotConfig;
use crate::scan::LaserScan;
use crate::sim::{self, Clock, Encoders, Gyro, LaserSim, Reference, SensorStream, SimConfig};
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
    /// The bag's clock at the run's start (s since 1970-01-01, UTC); the
    /// truth file's times count from the start.
    pub clock_start_s: f64,
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
    /// The bag's clock at the run's start, `YYYY-MM-DD[THH:MM[:SS]]` (UTC);
    /// `None`: 0 s.
    pub start: Option<String>,
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
    let clock_start_s = job.start.as_deref().map(clock_start).transpose()?;
    simulate_at(
        &cfg.sim,
        &cfg.topics,
        &robot,
        &effects,
        clock_start_s.unwrap_or(0.0),
        (&job.out, job.truth.as_deref()),
        progress,
    )
}

/// The clock (s since 1970-01-01, UTC) of a date `YYYY-MM-DD[THH:MM[:SS]]`.
fn clock_start(date: &str) -> Result<f64, PipelineError> {
    super::fleet::inputs::find_date(date)
        .filter(|_| date.len() <= 25)
        .map(|day| day * 86_400.0)
        .ok_or_else(|| {
            PipelineError::BadArgument(format!(
                "--start '{date}' is not a date YYYY-MM-DD[THH:MM[:SS]] (UTC)"
            ))
        })
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
/// atomically and both streamed: every sensor is simulated sample by sample
/// while the bag is written (the scans block by block), and the truth's
/// series while its file is written, so memory does not grow with the run.
pub fn simulate(
    cfg: &SimConfig,
    topics: &TopicConfig,
    robot: &RobotConfig,
    effects: &[Effect],
    out: &Path,
    truth_path: Option<&Path>,
    progress: &mut dyn FnMut(f64),
) -> Result<SimulateSummary, PipelineError> {
    simulate_at(
        cfg,
        topics,
        robot,
        effects,
        0.0,
        (out, truth_path),
        progress,
    )
}

/// [`simulate`] with the bag's clock at `clock_start_s` (s since
/// 1970-01-01) when the run starts; the truth's times count from the start.
pub fn simulate_at(
    cfg: &SimConfig,
    topics: &TopicConfig,
    robot: &RobotConfig,
    effects: &[Effect],
    clock_start_s: f64,
    (out, truth_path): (&Path, Option<&Path>),
    progress: &mut dyn FnMut(f64),
) -> Result<SimulateSummary, PipelineError> {
    let run = sim::prepare(cfg, robot, effects)?;
    let mut opts = WriteOptions::for_robot(robot);
    opts.topics = topics.clone();
    opts.clock_start_s = clock_start_s;
    // The truth goes to its temporary file first and is renamed into place
    // right after the bag, so that a run killed while it writes never
    // leaves a new bag beside an old truth file.
    let truth = truth_path.map(|tp| write_truth(&run, tp)).transpose()?;
    let mut bag = SimBag::new(&run, progress);
    io::write_mcap_streaming(out, &mut bag, &opts).map_err(|e| PipelineError::write(out, e))?;
    let counts = bag.counts();
    if let (Some(file), Some(tp)) = (truth, truth_path) {
        file.commit().map_err(|e| PipelineError::write(tp, e))?;
    }
    progress(1.0);
    let header = run.truth_header();
    Ok(SimulateSummary {
        out: out.display().to_string(),
        truth: truth_path.map(|p| p.display().to_string()),
        scenario: header.scenario,
        seed: header.seed,
        duration_s: header.duration_s,
        clock_start_s,
        scans: counts[BagStream::Scan as usize],
        wheel_samples: counts[BagStream::Joints as usize],
        gyro_samples: counts[BagStream::Imu as usize],
        reference_poses: counts[BagStream::Reference as usize],
        path_length_m: sim::path_length(run.trajectory()),
        effects: header.effect_specs,
    })
}

/// Writes the truth file of `run` (pretty JSON, [`sim::Truth`]'s text) into
/// the temporary sibling of `path`, its series drawn while they are
/// written; the caller commits it.
fn write_truth(
    run: &sim::SimRun,
    path: &Path,
) -> Result<io::stream_out::AtomicWriter, PipelineError> {
    let truth = run.truth_header().with(
        sim::Drawn::new(run.parameters()),
        sim::Drawn::new(run.trajectory()),
    );
    let mut file =
        io::stream_out::AtomicWriter::create(path).map_err(|e| PipelineError::write(path, e))?;
    serde_json::to_writer_pretty(file.writer(), &truth)
        .map_err(|e| PipelineError::write(path, std::io::Error::from(e)))?;
    Ok(file)
}

/// A simulated run as the messages of its bag, made as the writer asks for
/// them: the scans cast one parallel block at a time, the other sensors
/// sample by sample.
struct SimBag<'p> {
    base_from_laser: Option<Pose2>,
    laser: LaserSim,
    /// The current block: scans `first .. first + block.len()`.
    block: Vec<LaserScan>,
    first: usize,
    wheels: WheelRates<SensorStream<Encoders>>,
    gyro: SensorStream<Gyro>,
    reference: SensorStream<Reference>,
    /// Sample times of the reference, gyro and wheels.
    clocks: [Clock; 3],
    progress: &'p mut dyn FnMut(f64),
}

impl<'p> SimBag<'p> {
    fn new(run: &sim::SimRun, progress: &'p mut dyn FnMut(f64)) -> Self {
        let (reference, gyro, wheels) = (run.reference(), run.gyro(), run.encoders());
        Self {
            base_from_laser: run.recording().base_from_laser,
            laser: run.laser(),
            block: Vec::new(),
            first: 0,
            clocks: [reference.clock(), gyro.clock(), wheels.clock()],
            wheels: WheelRates::new(wheels),
            gyro,
            reference,
            progress,
        }
    }

    /// Messages of each stream, indexed by [`BagStream`].
    fn counts(&self) -> [usize; 6] {
        let mut n = [0; 6];
        for s in [
            BagStream::Reference,
            BagStream::Imu,
            BagStream::Joints,
            BagStream::Scan,
        ] {
            n[s as usize] = self.count(s);
        }
        n
    }

    /// The clock of a sensor other than the laser.
    fn clock(&self, s: BagStream) -> Option<Clock> {
        match s {
            BagStream::Reference => Some(self.clocks[0]),
            BagStream::Imu => Some(self.clocks[1]),
            BagStream::Joints => Some(self.clocks[2]),
            _ => None,
        }
    }
}

/// The next sample of a stream the writer asks for in order.
fn next_of<T>(stream: &mut impl Iterator<Item = T>) -> T {
    stream
        .next()
        .expect("the writer asks for no more samples than the stream's clock has")
}

impl BagSource for SimBag<'_> {
    fn base_from_laser(&self) -> Option<Pose2> {
        self.base_from_laser
    }
    fn reference_has_heading(&self) -> bool {
        true
    }
    fn start(&self) -> f64 {
        let firsts = [
            BagStream::Reference,
            BagStream::Imu,
            BagStream::Joints,
            BagStream::Scan,
        ];
        firsts
            .into_iter()
            .filter(|&s| self.count(s) > 0)
            .map(|s| self.stamp(s, 0))
            .reduce(f64::min)
            .unwrap_or(0.0)
    }
    fn count(&self, s: BagStream) -> usize {
        match s {
            BagStream::Scan => self.laser.len(),
            _ => self.clock(s).map_or(0, |c| c.len()),
        }
    }
    fn stamp(&self, s: BagStream, j: usize) -> f64 {
        match s {
            BagStream::Scan => self.laser.stamp(j),
            _ => self.clock(s).map_or(0.0, |c| c.stamp(j)),
        }
    }
    fn reference(&mut self, _: usize) -> StampedPose {
        next_of(&mut self.reference)
    }
    fn odom(&mut self, _: usize) -> StampedPose {
        unreachable!("the simulator writes no wheel odometry")
    }
    fn gyro(&mut self, _: usize) -> f64 {
        next_of(&mut self.gyro).wz
    }
    fn wheel(&mut self, _: usize) -> (WheelSample, (f64, f64)) {
        next_of(&mut self.wheels)
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
