//! odocal: calibrated wheel odometry for differential-drive robots from 2D
//! laser scans and wheel encoders.
//!
//! The pipeline, one scan at a time:
//! 1. [`io`] reads any recording (ROS 2 or ROS 1 bag, rosbag2, CARMEN) as one stream of samples;
//! 2. [`icp`] matches each scan against a local map: a base motion with its covariance;
//! 3. [`motion`] turns that motion into a velocity observation beside the [`robot`]'s wheel rates;
//! 4. [`calib`] estimates the wheel radii and the wheel base, online or in batch;
//! 5. [`eval`] scores the calibrated odometry, [`diagnose`] names what the nominal model misses.
//!
//! [`pipeline`] wires these stages through one driver for every command, and
//! [`live`] feeds it a robot's topics over ROS 2 instead of a recording; the
//! manual is `docs/` in the repository.
//!
//! Math modules (`geom`, `scan`, `robot`, `icp`, `calib`, `classic`, `sim`,
//! `eval`, `diagnose`) know nothing of files, the command line or Rerun; `io`
//! reads and writes formats and nothing else; `pipeline` wires the stages
//! through one driver, `viz` draws them, and `experiments` regenerates the
//! implemented papers' tables on top of all of them.
#![warn(missing_docs)]
// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod assumptions;
pub mod calib;
pub mod classic;
pub mod diagnose;
pub mod effects;
pub mod error;
pub mod eval;
pub mod experiments;
pub mod fleet;
pub mod geom;
pub mod icp;
pub mod io;
pub mod live;
pub mod motion;
pub mod pipeline;
pub mod recording;
pub mod robot;
pub mod scan;
pub mod sim;
pub mod stats;
pub mod traj;
pub mod viz;

pub use error::InputError;
