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

/// What a recording's wheel messages carried before they became wheel
/// angles: how the angles were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WheelValues {
    /// Joint positions (rad), used as they are.
    Positions,
    /// Joint velocities (rad/s), integrated by the trapezoidal rule.
    Velocities,
    /// A body twist (m/s, rad/s) turned into wheel rates with the nominal
    /// robot, then integrated.
    Twist,
    /// Encoder tick counters, unwrapped and scaled by 2π / ticks per revolution.
    Ticks,
}

/// Which stream carries the wheel motion (the robot file's `[wheels]
/// source`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WheelSourceKind {
    /// `sensor_msgs/msg/JointState`: the wheel joints' positions (rad), or
    /// their velocities (rad/s) when the messages carry no positions.
    #[default]
    JointStates,
    /// `nav_msgs/msg/Odometry`: the robot's own odometry, whose twist
    /// (V m/s, W rad/s) is turned back into wheel rates with the nominal robot.
    Odometry,
    /// Encoder tick counters in a `std_msgs` integer array.
    Ticks,
}

impl WheelSourceKind {
    /// The word the robot file uses.
    pub fn word(self) -> &'static str {
        match self {
            WheelSourceKind::JointStates => "joint_states",
            WheelSourceKind::Odometry => "odometry",
            WheelSourceKind::Ticks => "ticks",
        }
    }
}

/// Which stream a run's wheel samples came from, and what that stream
/// cannot show (JSON `wheel_source`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct WheelSource {
    /// `joint_states`, `odometry` or `ticks`.
    pub kind: WheelSourceKind,
    /// The topic read.
    pub topic: String,
    /// Its message type (`pkg/msg/Type`).
    #[serde(rename = "type")]
    pub type_name: String,
    /// What the messages carried (`None`: no message was read).
    pub values: Option<WheelValues>,
    /// Wheel messages read.
    pub messages: usize,
    /// Where the choice came from: the robot file's `[wheels]`, or the default.
    pub source: crate::assumptions::Origin,
    /// What the user should know: how the values became wheel angles and
    /// what this source cannot show.
    pub notes: Vec<String>,
}

impl WheelSource {
    /// One line for the human output, e.g. "wheels from /odom twist
    /// (nav_msgs/msg/Odometry), robot file \[wheels\] source".
    pub fn sentence(&self) -> String {
        let what = match self.values {
            Some(WheelValues::Positions) => "joint positions",
            Some(WheelValues::Velocities) => "joint velocities",
            Some(WheelValues::Twist) => "twist",
            Some(WheelValues::Ticks) => "encoder ticks",
            None => "(no message)",
        };
        let whence = match self.source {
            crate::assumptions::Origin::RobotFile => "robot file [wheels] source",
            _ => "default source (no [wheels] in the robot file)",
        };
        format!(
            "wheels from {} {what} ({}), {whence}",
            self.topic, self.type_name
        )
    }
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
    /// How the wheel angles were obtained (`None`: no wheel samples).
    pub wheel_values: Option<WheelValues>,
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
