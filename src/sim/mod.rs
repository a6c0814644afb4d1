//! The LMS111 wheelchair simulator: a 2D world, a scenario driven by a
//! differential-drive chair whose true parameters depart from the nominal
//! ones by injected effects, and the sensors that observe it (laser, wheel
//! encoders, gyro, a LOAM-like reference). [`simulate`] produces a
//! [`Recording`] that never mentions the effects, and a [`Truth`] that holds them;
//! [`prepare`] gives the same run as streams drawn in time order (each
//! sensor reading the motion through its own [`Tape`]), for runs of any length.
//!
//! Semantics: the scenario commands body velocities (v, w); the chair's true
//! wheel rates realise them with the true radii and wheel base, so the body
//! follows the planned route whatever the effects; the encoders report those
//! wheel rates' angles, which the nominal model then misreads.
//!
//! [`Recording`]: crate::recording::Recording

mod config;
mod drive;
mod effects;
mod grid;
mod path;
mod run;
mod scenario;
mod sensors;
mod tape;
mod truth;
mod world;
pub mod worlds;

pub use config::{
    EncoderConfig, GyroConfig, LaserConfig, ReferenceConfig, ScenarioConfig, ScenarioSpec,
    SimConfig, WorldConfig, WorldRef,
};
pub use drive::{drive, Drive, Driver, Step};
pub use effects::TrueRobot;
pub use path::Path;
pub use run::{path_length, prepare, simulate, SimRun, TrueBase};
pub use scenario::{Route, Scenario, BUILTIN_SCENARIOS};
pub use sensors::{
    encoder_samples, Clock, Encoders, Gyro, LaserSim, Reference, Sensor, SensorStream, WheelTrack,
};
pub use tape::Tape;
pub use truth::{Drawn, TrueParameters, TruePose, Truth, TruthOf};
pub use world::{World, WorldSpec};

use rand::rngs::StdRng;
use rand::SeedableRng;

/// What can go wrong when setting up or running a simulation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A world that cannot be built (bad JSON, empty, degenerate walls).
    #[error("{0}")]
    World(String),
    /// A scenario that cannot be driven (unknown name, bad waypoints, too close to walls).
    #[error("{0}")]
    Scenario(String),
    /// A configuration value out of its valid range.
    #[error("simulation config: {0}")]
    Config(String),
}

/// Random streams: each sensor (and the scenario) has its own generator.
const STREAM_SCENARIO: u64 = 1;
const STREAM_LASER: u64 = 2;
const STREAM_ENCODER: u64 = 3;
const STREAM_GYRO: u64 = 4;
const STREAM_REFERENCE: u64 = 5;

/// SplitMix64 finaliser: decorrelates nearby seeds.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The generator of one stream (and one item of it, e.g. a scan index).
fn stream_rng(seed: u64, stream: u64, index: u64) -> StdRng {
    StdRng::seed_from_u64(mix(
        mix(seed) ^ mix(stream.wrapping_mul(0x1000_0000_01B3) ^ mix(index))
    ))
}
