//! One simulation run: drive the scenario, integrate the true wheels, and let
//! every sensor observe the result.

use super::config::SimConfig;
use super::drive::{drive, Drive};
use super::effects::TrueRobot;
use super::scenario::Scenario;
use super::sensors::{
    encoder_samples, gyro_samples, reference_poses, sample_times, LaserSim, WheelTrack,
};
use super::truth::{TrueParameters, TruePose, Truth};
use super::SimError;
use crate::effects::Effect;
use crate::geom::wrap_angle;
use crate::recording::Recording;
use crate::robot::RobotConfig;

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
    let SimRun {
        mut recording,
        truth,
        laser,
    } = prepare(cfg, robot, effects, progress)?;
    recording.scans = laser.all(&mut |f| progress(0.1 + 0.9 * f));
    progress(1.0);
    Ok((recording, truth))
}

/// A run ready to be written: the truth and every stream but the laser's,
/// whose scans [`LaserSim`] casts on demand (so that a long run need not be
/// held in memory).
pub struct SimRun {
    /// The recording without its scans (`scans` is empty).
    pub recording: Recording,
    /// What really happened.
    pub truth: Truth,
    /// The laser of the run; scan k of it is scan k of [`simulate`]'s recording.
    pub laser: LaserSim,
}

/// Drives the scenario and simulates every sensor but the laser (progress up to 0.1).
pub fn prepare(
    cfg: &SimConfig,
    robot: &RobotConfig,
    effects: &[Effect],
    progress: &mut dyn FnMut(f64),
) -> Result<SimRun, SimError> {
    let true_robot = true_robot(cfg, robot, effects)?;
    let duration = cfg.duration_s;
    let scenario = Scenario::from_config(cfg)?;
    let motion = drive(&scenario, &cfg.scenario, duration, 1.0 / cfg.integration_hz);
    progress(0.05);
    let recording = recording(cfg, robot, &scenario, &motion, &true_robot);
    progress(0.1);
    let truth = Truth {
        scenario: scenario.name.clone(),
        world: scenario.world.name().to_string(),
        walls: scenario.world.segments().to_vec(),
        seed: cfg.seed,
        duration_s: duration,
        nominal: robot.clone(),
        effect_specs: effects
            .iter()
            .map(|e| e.to_string())
            .chain(cfg.faults.iter().map(|f| f.to_string()))
            .collect(),
        effects: effects.to_vec(),
        parameters: true_parameters(&true_robot, duration),
        laser_mount: true_robot.laser,
        trajectory: true_trajectory(&motion, duration),
        settings: cfg.clone(),
    };
    let laser = LaserSim::new(
        &cfg.laser,
        scenario.world,
        motion,
        true_robot,
        cfg.seed,
        duration,
    );
    Ok(SimRun {
        recording,
        truth,
        laser,
    })
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
            "the effects make a wheel radius or the wheel base non-positive".into(),
        ));
    }
    Ok(true_robot)
}

/// The recording of every stream but the laser: the encoders read the true
/// wheels, the gyro and the reference observe the motion.
fn recording(
    cfg: &SimConfig,
    robot: &RobotConfig,
    scenario: &Scenario,
    motion: &Drive,
    true_robot: &TrueRobot,
) -> Recording {
    let duration = cfg.duration_s;
    let track = WheelTrack::new(motion, true_robot);
    let wheels = encoder_samples(
        &cfg.encoder,
        robot.ticks_per_rev,
        &track,
        true_robot,
        cfg.seed,
        duration,
    );
    let gyro = gyro_samples(&cfg.gyro, motion, true_robot, cfg.seed, duration);
    let reference = reference_poses(&cfg.reference, motion, cfg.seed, duration);
    Recording {
        source: format!("simulated:{}", scenario.name),
        scans: Vec::new(),
        wheels,
        gyro,
        odom: Vec::new(),
        reference,
        base_from_laser: Some(robot.laser.unwrap_or_default().pose()),
        mount_origin: Some(crate::assumptions::Origin::TfStatic),
        mount_note: None,
        wheel_values: Some(crate::recording::WheelValues::Positions),
    }
}

/// The true trajectory of the base at 100 Hz.
fn true_trajectory(motion: &Drive, duration: f64) -> Vec<TruePose> {
    sample_times(100.0, duration, 0.0)
        .map(|t| {
            let [x, y, th] = motion.pose_at(t);
            TruePose {
                t,
                x,
                y,
                theta: wrap_angle(th),
            }
        })
        .collect()
}

/// The true radii and wheel base at 10 Hz and at every radius step of the run.
fn true_parameters(true_robot: &TrueRobot, duration: f64) -> Vec<TrueParameters> {
    let mut times: Vec<f64> = sample_times(10.0, duration, 0.0).collect();
    times.extend(
        true_robot
            .departures()
            .step_times()
            .filter(|t| *t <= duration),
    );
    times.sort_by(f64::total_cmp);
    times.dedup();
    times
        .into_iter()
        .map(|t| {
            let k = true_robot.at(t);
            TrueParameters {
                t,
                r_right: k.r_right,
                r_left: k.r_left,
                wheel_base: k.wheel_base,
            }
        })
        .collect()
}
