//! Reading and writing files: recordings (MCAP, CARMEN), trajectories, CSV
//! outputs. Every write goes through [`atomic`].

pub mod atomic;
/// The tables transcribed from the seed papers.
pub mod seed_tables;
