//! The LMS111 wheelchair simulator: a 2D world, a scenario driven by a
//! differential-drive chair whose true parameters depart from the nominal
//! ones by injected effects, and the sensors that observe it (laser, wheel
//! encoders, gyro, a LOAM-like reference). It produces a [`Recording`] that
//! never mentions the effects, and a [`Truth`] that holds them.
//!
//! [`Recording`]: crate::recording::Recording

mod world;
pub mod worlds;

pub use world::{World, WorldSpec};

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
