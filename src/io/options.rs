//! What a reader needs to know besides the file: topic names, wheel joint
//! names, and how far a stream may go back in time before it is corrupt.

use serde::{Deserialize, Serialize};

use crate::robot::RobotConfig;

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
}

impl Default for ReadOptions {
    fn default() -> Self {
        let robot = RobotConfig::default();
        Self {
            topics: TopicConfig::default(),
            left_joint: robot.left_joint,
            right_joint: robot.right_joint,
            reorder_tolerance: 2.0,
        }
    }
}

impl ReadOptions {
    /// Default topics with the robot's wheel joint names.
    pub fn for_robot(robot: &RobotConfig) -> Self {
        Self {
            left_joint: robot.left_joint.clone(),
            right_joint: robot.right_joint.clone(),
            ..Self::default()
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
