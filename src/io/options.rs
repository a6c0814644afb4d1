//! What a reader needs to know besides the file: topic names, where the
//! wheels are reported (joint names, odometry twist or tick counters), and
//! how far a stream may go back in time before it is corrupt.

use serde::{Deserialize, Serialize};

use super::ros_msgs::{JointStateMsg, OdometryMsg, RosMsg};
use crate::robot::{DiffDrive, RobotConfig, WheelSourceKind, WheelsConfig};

/// Topic names of each stream in a bag.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TopicConfig {
    /// `sensor_msgs/msg/LaserScan`.
    pub scan: String,
    /// `sensor_msgs/msg/JointState` with the wheel joints.
    pub joint_states: String,
    /// `sensor_msgs/msg/Imu` (z angular rate).
    pub imu: String,
    /// `nav_msgs/msg/Odometry`: the robot's own odometry.
    pub odom: String,
    /// Reference trajectory: Odometry, PoseStamped or PointStamped.
    pub reference: String,
    /// `tf2_msgs/msg/TFMessage` with `base_link` → laser.
    pub tf_static: String,
    /// `tf2_msgs/msg/TFMessage`: dynamic transforms, read for `base_link` →
    /// laser only when /tf_static does not link them.
    pub tf: String,
}

impl Default for TopicConfig {
    fn default() -> Self {
        Self {
            scan: "/scan".into(),
            joint_states: "/joint_states".into(),
            imu: "/imu".into(),
            odom: "/odom".into(),
            reference: "/ground_truth".into(),
            tf_static: "/tf_static".into(),
            tf: "/tf".into(),
        }
    }
}

/// How to read a recording: topics, wheel joint names and how far a stream
/// may go back in time (file order vs stamps) before it counts as corrupt.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReadOptions {
    /// Topic names.
    pub topics: TopicConfig,
    /// JointState name of the left wheel.
    pub left_joint: String,
    /// JointState name of the right wheel.
    pub right_joint: String,
    /// Largest backward stamp jump within one stream that is tolerated and
    /// fixed by sorting (s).
    pub reorder_tolerance: f64,
    /// Which stream carries the wheels, and how to read it.
    pub wheels: WheelsConfig,
    /// The nominal kinematics that turn an odometry twist back into wheel
    /// rates (the robot's own controller's configured radii and separation).
    pub nominal: DiffDrive,
    /// Encoder ticks per wheel revolution, for tick counters.
    pub ticks_per_rev: f64,
    /// Hand out every topic's messages, whatever their type, untouched (for
    /// `odocal inspect`'s survey); the streams above are then not decoded.
    #[serde(skip)]
    pub all_topics: bool,
    /// Whether a zero (unset) header stamp is replaced by the message's log
    /// time (a bag's: the recorder's clock); off for a live stream, whose
    /// only other time is its writer's clock, not the stamps'.
    #[serde(skip)]
    pub log_time_for_unset: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        let robot = RobotConfig::default();
        Self {
            topics: TopicConfig::default(),
            left_joint: robot.left_joint.clone(),
            right_joint: robot.right_joint.clone(),
            reorder_tolerance: 2.0,
            nominal: robot.diff_drive(),
            ticks_per_rev: robot.ticks_per_rev,
            wheels: robot.wheels,
            all_topics: false,
            log_time_for_unset: true,
        }
    }
}

impl ReadOptions {
    /// Default topics with the robot's wheel joint names.
    pub fn for_robot(robot: &RobotConfig) -> Self {
        Self {
            left_joint: robot.left_joint.clone(),
            right_joint: robot.right_joint.clone(),
            wheels: robot.wheels.clone(),
            nominal: robot.diff_drive(),
            ticks_per_rev: robot.ticks_per_rev,
            ..Self::default()
        }
    }

    /// The topic the wheels come from: `[wheels] topic`, else `[topics]
    /// joint_states` (JointState) or `[topics] odom` (Odometry).
    pub fn wheel_topic(&self) -> &str {
        match (&self.wheels.topic, self.wheels.source) {
            (Some(t), _) => t,
            (None, WheelSourceKind::Odometry) => &self.topics.odom,
            (None, _) => &self.topics.joint_states,
        }
    }

    /// The message type the wheel topic must have (`pkg/msg/Type`).
    pub fn wheel_type(&self) -> &'static str {
        match self.wheels.source {
            WheelSourceKind::JointStates => JointStateMsg::TYPE,
            WheelSourceKind::Odometry => OdometryMsg::TYPE,
            WheelSourceKind::Ticks => self
                .wheels
                .ticks_layout()
                .map_or("std_msgs/msg/Int32MultiArray", |l| l.ticks_type.type_name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn topic_config_reads_partial_toml() {
        let t: TopicConfig = toml::from_str("reference = \"/reference\"").unwrap();
        assert_eq!(t.reference, "/reference");
        assert_eq!(t.scan, "/scan");
        assert!(toml::from_str::<TopicConfig>("bogus = 1").is_err());
    }
}
