//! One simulation run: drive the scenario, integrate the true wheels, and let
//! every sensor observe the result.

use super::config::SimConfig;
use super::drive::Driver;
use super::effects::TrueRobot;
use super::scenario::Scenario;
use super::sensors::{
    sample_times, Clock, Encoders, Gyro, LaserSim, Reference, Sensor, SensorStream,
};
use super::tape::Tape;
use super::truth::{TrueParameters, TruePose, Truth, TruthOf};
use super::SimError;
use crate::effects::Effect;
use crate::geom::wrap_angle;
use crate::recording::Recording;
use crate::robot::RobotConfig;
use nalgebra::Vector2;

/// Simulates a run: returns the recording a reader would produce from the
/// bag (scans, wheel angles, gyro, reference, nominal `base_from_laser`) and
/// the truth (effects, true parameters, true trajectory). Same inputs give a
/// bitwise identical result. `progress` receives the fraction done (0–1).
pub fn simulate(
    cfg: &SimConfig,
    robot: &RobotConfig,
    effects: &[Effect],
    progress: &mut dyn FnMut(f64),
) -> Result<(Recording, Truth), SimError> {
    let run = prepare(cfg, robot, effects)?;
    let mut recording = run.recording();
    recording.wheels = run.encoders().collect();
    recording.gyro = run.gyro().collect();
    recording.reference = run.reference().collect();
    progress(0.1);
    recording.scans = run.laser().all(&mut |f| progress(0.1 + 0.9 * f));
    let truth = run.truth();
    progress(1.0);
    Ok((recording, truth))
}

/// A run ready to be observed: the scenario, the true robot and the
/// settings, from which every stream (each sensor, the true trajectory and
/// parameters) is drawn on demand, in time order, in memory that does not
/// grow with the run's length. Each stream drives the scenario on its own
/// tape; all of them see the same motion, bit for bit.
pub struct SimRun {
    cfg: SimConfig,
    nominal: RobotConfig,
    effects: Vec<Effect>,
    scenario: Scenario,
    true_robot: TrueRobot,
}

/// Checks the run's settings, robot and effects and resolves its scenario.
pub fn prepare(
    cfg: &SimConfig,
    robot: &RobotConfig,
    effects: &[Effect],
) -> Result<SimRun, SimError> {
    let true_robot = true_robot(cfg, robot, effects)?;
    let scenario = Scenario::from_config(cfg)?;
    Ok(SimRun {
        cfg: cfg.clone(),
        nominal: robot.clone(),
        effects: effects.to_vec(),
        scenario,
        true_robot,
    })
}

impl SimRun {
    /// Length of the run (s).
    pub fn duration(&self) -> f64 {
        self.cfg.duration_s
    }

    /// A fresh drive of the scenario, not yet started.
    fn driver(&self) -> Driver {
        let cfg = &self.cfg;
        Driver::new(
            &self.scenario,
            &cfg.scenario,
            cfg.duration_s,
            1.0 / cfg.integration_hz,
        )
    }

    /// The recording's description without any samples: its source and the
    /// nominal laser mounting it states.
    pub fn recording(&self) -> Recording {
        Recording {
            source: format!("simulated:{}", self.scenario.name),
            scans: Vec::new(),
            wheels: Vec::new(),
            gyro: Vec::new(),
            odom: Vec::new(),
            reference: Vec::new(),
            base_from_laser: Some(self.nominal.laser.unwrap_or_default().pose()),
            mount_origin: Some(crate::assumptions::Origin::TfStatic),
            mount_note: None,
            wheel_values: Some(crate::recording::WheelValues::Positions),
        }
    }

    /// The samples at `rate` Hz of the run, each from a fresh tape.
    fn stream<S: Sensor>(&self, sensor: S, tape: Tape, rate: f64) -> SensorStream<S> {
        SensorStream::new(sensor, tape, Clock::new(rate, self.cfg.duration_s, 0.0))
    }

    /// The encoders reading the true wheels.
    pub fn encoders(&self) -> SensorStream<Encoders> {
        let (c, robot) = (&self.cfg, &self.true_robot);
        let sensor = Encoders::new(self.nominal.ticks_per_rev, robot, c.seed);
        let tape = Tape::with_wheels(self.driver(), robot.clone());
        self.stream(sensor, tape, c.encoder.rate_hz)
    }

    /// The gyro observing the motion.
    pub fn gyro(&self) -> SensorStream<Gyro> {
        let c = &self.cfg;
        let sensor = Gyro::new(&c.gyro, &self.true_robot, c.seed);
        self.stream(sensor, Tape::new(self.driver()), c.gyro.rate_hz)
    }

    /// The LOAM-like reference observing the motion.
    pub fn reference(&self) -> SensorStream<Reference> {
        let c = &self.cfg;
        let sensor = Reference::new(&c.reference, c.seed);
        self.stream(sensor, Tape::new(self.driver()), c.reference.rate_hz)
    }

    /// The laser, casting its scans block by block.
    pub fn laser(&self) -> LaserSim {
        let c = &self.cfg;
        LaserSim::new(
            &c.laser,
            self.scenario.world.clone(),
            Tape::new(self.driver()),
            self.true_robot.clone(),
            c.seed,
            c.duration_s,
        )
    }

    /// The true trajectory of the base at 100 Hz.
    pub fn trajectory(&self) -> SensorStream<TrueBase> {
        self.stream(TrueBase, Tape::new(self.driver()), 100.0)
    }

    /// The true radii and wheel base at 10 Hz and at every radius step of the run.
    pub fn parameters(&self) -> impl Iterator<Item = TrueParameters> {
        true_parameters(self.true_robot.clone(), self.cfg.duration_s)
    }

    /// The truth without its series (true parameters and trajectory).
    pub fn truth_header(&self) -> TruthOf<(), ()> {
        let scenario = &self.scenario;
        TruthOf {
            scenario: scenario.name.clone(),
            world: scenario.world.name().to_string(),
            walls: scenario.world.segments().to_vec(),
            seed: self.cfg.seed,
            duration_s: self.cfg.duration_s,
            nominal: self.nominal.clone(),
            effect_specs: self
                .effects
                .iter()
                .map(|e| e.to_string())
                .chain(self.cfg.faults.iter().map(|f| f.to_string()))
                .collect(),
            effects: self.effects.clone(),
            parameters: (),
            laser_mount: self.true_robot.laser,
            trajectory: (),
            settings: self.cfg.clone(),
        }
    }

    /// The whole truth, in memory.
    pub fn truth(&self) -> Truth {
        self.truth_header()
            .with(self.parameters().collect(), self.trajectory().collect())
    }
}

/// The true base pose, as the truth file states it (heading wrapped).
pub struct TrueBase;

impl Sensor for TrueBase {
    type Sample = TruePose;
    fn sample(&mut self, t: f64, tape: &Tape) -> TruePose {
        let [x, y, th] = tape.pose_at(t);
        TruePose {
            t,
            x,
            y,
            theta: wrap_angle(th),
        }
    }
}

/// Length (m) of the path through `poses`, in order: the value of
/// [`crate::traj::Trajectory::path_length`] of the same poses.
pub fn path_length(poses: impl Iterator<Item = TruePose>) -> f64 {
    let mut last: Option<Vector2<f64>> = None;
    poses
        .filter_map(|p| {
            let at = Vector2::new(p.x, p.y);
            let step = last.map(|l| (at - l).norm());
            last = Some(at);
            step
        })
        .sum()
}

/// Checks the settings and the nominal robot, and applies the effects to it;
/// refuses effects that make the robot physically impossible during the run.
fn true_robot(
    cfg: &SimConfig,
    robot: &RobotConfig,
    effects: &[Effect],
) -> Result<TrueRobot, SimError> {
    cfg.validate()?;
    robot
        .validate()
        .map_err(|e| SimError::Config(e.to_string()))?;
    let true_robot = TrueRobot::new(robot, effects).with_faults(&cfg.faults);
    if !true_robot.radii_positive(cfg.duration_s) {
        return Err(SimError::Config(
            "the effects make a wheel radius or the wheel base non-positive (or loaded tyres \
             deflect more than a fifth of their radius standing)"
                .into(),
        ));
    }
    Ok(true_robot)
}

/// The true radii (loaded tyres' standing) and wheel base at 10 Hz and at
/// every radius step of the run, in time order (a step at a sample time
/// gives one row).
fn true_parameters(true_robot: TrueRobot, duration: f64) -> impl Iterator<Item = TrueParameters> {
    let mut steps: Vec<f64> = true_robot
        .departures()
        .step_times()
        .filter(|t| *t <= duration)
        .collect();
    steps.sort_by(f64::total_cmp);
    let mut steps = steps.into_iter().peekable();
    let mut samples = sample_times(10.0, duration, 0.0).peekable();
    let mut last: Option<f64> = None;
    std::iter::from_fn(move || loop {
        let t = match (samples.peek(), steps.peek()) {
            (Some(a), Some(b)) if b.total_cmp(a).is_lt() => steps.next(),
            (Some(_), _) => samples.next(),
            (None, _) => steps.next(),
        }?;
        if last == Some(t) {
            continue;
        }
        last = Some(t);
        let k = true_robot.rolling_at(t);
        return Some(TrueParameters {
            t,
            r_right: k.r_right,
            r_left: k.r_left,
            wheel_base: k.wheel_base,
        });
    })
}
