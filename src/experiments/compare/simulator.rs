//! Runs for the comparison from the simulator: its `square` / `square-ccw`
//! scenarios trimmed to one loop, and `figure-eight` for evaluation. The
//! simulator's chair follows the planned route exactly while its encoders are
//! misread by the nominal model (the mirror image of a robot driving by
//! odometry); UMBmark's first-order formulas are the same in both cases.

use super::{compare_classic, ClassicResult, CompareParams, CompareScenario};
use crate::classic::{ClassicError, SimRun};
use crate::effects::Effect;
use crate::geom;
use crate::robot::RobotConfig;
use crate::sim::{simulate, SimConfig, SimError};

/// One run of the simulator for a comparison scenario, as wheel samples and
/// the true trajectory, both re-expressed from the start of the run (start
/// pose = identity, heading along +x). Laser and reference are thinned out:
/// the classic methods use only the wheels and the truth.
pub fn sim_run(
    robot: &RobotConfig,
    effects: &[Effect],
    scenario: CompareScenario,
    seed: u64,
) -> Result<SimRun, SimError> {
    let mut cfg = SimConfig {
        seed,
        ..SimConfig::default()
    };
    cfg.scenario.name = match scenario {
        CompareScenario::Square => "square",
        CompareScenario::SquareCcw => "square-ccw",
        CompareScenario::Evaluation => "figure-eight",
    }
    .into();
    cfg.duration_s = match scenario {
        CompareScenario::Evaluation => 60.0,
        _ => 75.0,
    };
    cfg.laser.rate_hz = 1.0;
    cfg.integration_hz = 200.0;
    let (rec, truth) = simulate(&cfg, robot, effects, &mut |_| {})?;
    let full = truth.trajectory().relative_to_start();
    // A square ends where the fourth turn brings the chair back to its start
    // heading at the start corner, after at least 20 m.
    let end = match scenario {
        CompareScenario::Evaluation => f64::INFINITY,
        _ => {
            let mut len = 0.0;
            let mut end = None;
            for i in 1..full.len() {
                len += (full.poses[i].translation.vector - full.poses[i - 1].translation.vector)
                    .norm();
                let p = &full.poses[i];
                if len > 20.0 && p.translation.vector.norm() < 0.05 && geom::heading(p).abs() < 1e-3
                {
                    end = Some(full.stamps[i]);
                    break;
                }
            }
            end.ok_or_else(|| {
                SimError::Scenario(format!(
                    "{}: no complete loop in {} s",
                    cfg.scenario.name, cfg.duration_s
                ))
            })?
        }
    };
    let wheels: Vec<_> = rec.wheels.into_iter().filter(|w| w.stamp <= end).collect();
    let mut t = crate::traj::Trajectory::with_capacity(full.len());
    for (s, p) in full.stamps.iter().zip(&full.poses) {
        if *s <= end {
            t.push(*s, *p);
        }
    }
    Ok(SimRun {
        wheels,
        truth: t,
        segment_ends: Vec::new(),
    })
}

/// [`compare_classic`] on the simulator: the chair is `robot` with `effects`
/// applied (their true parameters at t = 0 give the parameter errors).
pub fn compare_on_simulator(
    robot: &RobotConfig,
    effects: &[Effect],
    p: &CompareParams,
) -> Result<Vec<ClassicResult>, ClassicError> {
    let truth = crate::sim::TrueRobot::new(robot, effects).at(0.0);
    let p = CompareParams {
        ticks_per_rev: robot.ticks_per_rev,
        ..p.clone()
    };
    compare_classic(&robot.diff_drive(), Some(&truth), &p, |sc, seed| {
        sim_run(robot, effects, sc, seed)
    })
}
