//! What a recording holds once read or simulated: time-sorted sensor streams in
//! plain structs, independent of the file format they came from.

use crate::geom::Pose2;
use crate::scan::LaserScan;

/// Wheel angles (rad) of the left and right wheel at one instant, as integrated
/// encoder counts (unbounded, not wrapped).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelSample {
    /// Time (s).
    pub stamp: f64,
    /// Left wheel angle (rad).
    pub left: f64,
    /// Right wheel angle (rad).
    pub right: f64,
}

/// One gyroscope reading of the yaw rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroSample {
    /// Time (s).
    pub stamp: f64,
    /// Angular rate about z (rad/s).
    pub wz: f64,
}

/// A pose at a time; `has_heading` is false for position-only sources
/// (PointStamped), whose heading is then 0 and meaningless.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    /// Time (s).
    pub stamp: f64,
    /// `world_from_base` (or `odom_from_base`).
    pub pose: Pose2,
    /// Whether the heading carries information.
    pub has_heading: bool,
}

/// Every stream of a recording, each sorted by stamp (non-decreasing).
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// Where it came from (file path or "simulated"), for messages.
    pub source: String,
    /// Laser scans.
    pub scans: Vec<LaserScan>,
    /// Wheel encoder angles.
    pub wheels: Vec<WheelSample>,
    /// Gyro yaw rates.
    pub gyro: Vec<GyroSample>,
    /// The robot's own integrated odometry (e.g. /odom, CARMEN ODOM).
    pub odom: Vec<StampedPose>,
    /// A reference trajectory (ground truth, LOAM, motion capture).
    pub reference: Vec<StampedPose>,
    /// `base_from_laser`, when the recording states it (/tf_static).
    pub base_from_laser: Option<Pose2>,
    /// Where `base_from_laser` came from.
    pub mount_origin: Option<crate::assumptions::Origin>,
    /// Why the recording states no mounting, when it could have (e.g. the
    /// scans' frame is not linked to `base_link`).
    pub mount_note: Option<String>,
}

impl Recording {
    /// Sorts every stream by stamp (stable, so equal stamps keep file order).
    pub fn sort_streams(&mut self) {
        self.scans.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
        self.wheels.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
        self.gyro.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
        self.odom.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
        self.reference.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
    }

    /// Earliest and latest stamp over all streams; `None` when empty.
    pub fn time_span(&self) -> Option<(f64, f64)> {
        let stamps = self
            .scans
            .iter()
            .map(|s| s.stamp)
            .chain(self.wheels.iter().map(|s| s.stamp))
            .chain(self.gyro.iter().map(|s| s.stamp))
            .chain(self.odom.iter().map(|s| s.stamp))
            .chain(self.reference.iter().map(|s| s.stamp));
        stamps.fold(None, |acc, t| match acc {
            None => Some((t, t)),
            Some((a, b)) => Some((a.min(t), b.max(t))),
        })
    }
}
