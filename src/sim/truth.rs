//! What really happened in a simulated run, kept apart from the recording:
//! the effects, the true parameters over time, the true laser mount and the
//! true trajectory. Written as JSON by the caller: held whole ([`Truth`]), or
//! with the series drawn on demand ([`TruthOf`] with [`Drawn`] series), so
//! that a long run's truth file is written in flat memory, byte for byte
//! the same text.

use super::config::SimConfig;
use crate::effects::Effect;
use crate::geom;
use crate::robot::{DiffDrive, LaserMount, RobotConfig};
use crate::traj::Trajectory;
use serde::{Deserialize, Serialize, Serializer};
use std::cell::RefCell;

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

/// The truth of one simulated run, with every series in memory.
pub type Truth = TruthOf<Vec<TrueParameters>, Vec<TruePose>>;

/// The truth of one simulated run, its two series (true parameters `P`, true
/// trajectory `T`) of any kind: vectors ([`Truth`]), nothing (`()`, the
/// part of the truth that does not grow with the run), or [`Drawn`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthOf<P, T> {
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
    pub parameters: P,
    /// True laser mounting `base_from_laser` (the recording states the nominal one).
    pub laser_mount: LaserMount,
    /// True trajectory of the base at 100 Hz.
    pub trajectory: T,
    /// The settings of the run (scenario, world, sensors, seed).
    pub settings: SimConfig,
}

impl<P, T> TruthOf<P, T> {
    /// The same truth with the series `parameters` and `trajectory`.
    pub fn with<P2, T2>(self, parameters: P2, trajectory: T2) -> TruthOf<P2, T2> {
        TruthOf {
            scenario: self.scenario,
            world: self.world,
            walls: self.walls,
            seed: self.seed,
            duration_s: self.duration_s,
            nominal: self.nominal,
            effect_specs: self.effect_specs,
            effects: self.effects,
            parameters,
            laser_mount: self.laser_mount,
            trajectory,
            settings: self.settings,
        }
    }
}

/// A series serialised as a JSON array from an iterator drawn while it is
/// written, never held: serialises once (a second time, as an empty array).
pub struct Drawn<I>(RefCell<Option<I>>);

impl<I> Drawn<I> {
    /// The series of `items`.
    pub fn new(items: I) -> Self {
        Self(RefCell::new(Some(items)))
    }
}

impl<I> Serialize for Drawn<I>
where
    I: Iterator,
    I::Item: Serialize,
{
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.0.borrow_mut().take() {
            Some(items) => s.collect_seq(items),
            None => s.collect_seq(std::iter::empty::<I::Item>()),
        }
    }
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

    /// Parses a truth file as it is read, without holding its text (a long
    /// run's file is some 14 kB per simulated second).
    pub fn from_reader(r: impl std::io::Read) -> Result<Self, serde_json::Error> {
        serde_json::from_reader(r)
    }

    /// The truth as pretty JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("truth is plain data")
    }
}
