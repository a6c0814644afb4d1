//! The robot model: a differential drive with wheel radii and wheel base, its
//! nominal configuration (TOML) and dead-reckoning odometry from wheel angles.

pub mod bundled;
mod config;
mod kinematics;
mod odometry;
mod wheels;

pub use bundled::{bundled_robot, BUNDLED_ROBOTS};
pub use config::{LaserMount, RobotConfig, RobotConfigError, ScannerCorrection};
pub use kinematics::DiffDrive;
pub use odometry::{wheel_odometry, wheel_rates, WheelIntegrator, WheelRate};
pub use wheels::{TicksLayout, TicksType, WheelSourceKind, WheelsConfig};
