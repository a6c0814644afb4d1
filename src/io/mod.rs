//! Reading and writing files: recordings (MCAP, CARMEN), trajectories, CSV
//! outputs. Every write goes through [`atomic`].

pub mod atomic;

mod columns;
pub mod relations;
