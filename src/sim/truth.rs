//! What really happened in a simulated run, kept apart from the recording:
//! the effects, the true parameters over time, the true laser mount and the
//! true trajectory. Written as JSON by the caller.

use super::config::SimConfig;
use crate::effects::Effect;
use crate::geom;
use crate::robot::{DiffDrive, LaserMount, RobotConfig};
use crate::traj::Trajectory;
use serde::{Deserialize, Serialize};

/// True wheel radii and wheel base (m) at a time (s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrueParameters {
    /// Time (s).
    pub t: f64,
    /// True right wheel radius (m).
    pub r_right: f64,
    /// True left wheel radius (m).
    pub r_left: f64,
    /// True wheel base (m), without the turn-slip widening.
    pub wheel_base: f64,
}

/// A true pose `world_from_base` at a time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TruePose {
    /// Time (s).
    pub t: f64,
    /// x (m, world frame).
    pub x: f64,
    /// y (m, world frame).
    pub y: f64,
    /// Heading (rad) in (−π, π].
    pub theta: f64,
}

/// The truth of one simulated run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Scenario name.
    pub scenario: String,
    /// World name (`custom` for inline maps).
    pub world: String,
    /// The world's walls `[x0, y0, x1, y1]` (m), e.g. to draw the map.
    pub walls: Vec<[f64; 4]>,
    /// Seed of the run.
    pub seed: u64,
    /// Length of the run (s).
    pub duration_s: f64,
    /// The nominal robot (what the recording's reader is told).
    pub nominal: RobotConfig,
    /// Injected effects as SPEC strings (`NAME:key=value,...`).
    pub effect_specs: Vec<String>,
    /// Injected effects, structured.
    pub effects: Vec<Effect>,
    /// True parameters over time (10 Hz and at every radius step).
    pub parameters: Vec<TrueParameters>,
    /// True laser mounting `base_from_laser` (the recording states the nominal one).
    pub laser_mount: LaserMount,
    /// True trajectory of the base at 100 Hz.
    pub trajectory: Vec<TruePose>,
    /// The settings of the run (scenario, world, sensors, seed).
    pub settings: SimConfig,
}

impl Truth {
    /// The true trajectory as a [`Trajectory`].
    pub fn trajectory(&self) -> Trajectory {
        let mut t = Trajectory::with_capacity(self.trajectory.len());
        for p in &self.trajectory {
            t.push(p.t, geom::pose(p.x, p.y, p.theta));
        }
        t
    }

    /// True parameters in effect at time `t` (s): the last sample at or before `t`.
    pub fn parameters_at(&self, t: f64) -> Option<DiffDrive> {
        let k = self.parameters.partition_point(|p| p.t <= t);
        let p = self.parameters.get(k.checked_sub(1)?)?;
        Some(DiffDrive {
            r_right: p.r_right,
            r_left: p.r_left,
            wheel_base: p.wheel_base,
        })
    }

    /// Parses a truth file's text.
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The truth as pretty JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("truth is plain data")
    }
}
