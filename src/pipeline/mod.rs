//! Wires the stages for the command line: load inputs, run the math modules,
//! write outputs atomically, and return summaries the binary prints.

pub mod calibrate;
mod config;
pub mod demo;
pub mod diagnose;
mod error;
pub mod evaluate;
pub mod experiment;
pub mod icp;
pub mod record;
pub mod record_stream;
pub mod simulate;

pub use config::{load_robot, Config};
pub use error::PipelineError;
