//! Poses over time: `nav_msgs/Odometry`, `geometry_msgs` PoseStamped,
//! PointStamped and TransformStamped, `tf2_msgs/TFMessage`.

use super::{fields_in_order, Field, Header, Pose, Quat, RosMsg, Vec3};
use crate::io::cdr::{CdrError, CdrReader, CdrWriter};

/// `nav_msgs/msg/Odometry`.
#[derive(Debug, Clone, PartialEq)]
pub struct OdometryMsg {
    /// Stamp, parent frame (e.g. `odom`).
    pub header: Header,
    /// Child frame (e.g. `base_link`).
    pub child_frame_id: String,
    /// `parent_from_child` pose.
    pub pose: Pose,
    /// Pose covariance (6×6 row-major).
    pub pose_covariance: [f64; 36],
    /// Linear velocity in the child frame (m/s).
    pub linear: Vec3,
    /// Angular velocity in the child frame (rad/s).
    pub angular: Vec3,
    /// Twist covariance (6×6 row-major).
    pub twist_covariance: [f64; 36],
}

impl Default for OdometryMsg {
    fn default() -> Self {
        Self {
            header: Header::default(),
            child_frame_id: String::new(),
            pose: Pose::default(),
            pose_covariance: [0.0; 36],
            linear: Vec3::default(),
            angular: Vec3::default(),
            twist_covariance: [0.0; 36],
        }
    }
}

impl RosMsg for OdometryMsg {
    const TYPE: &'static str = "nav_msgs/msg/Odometry";

    fields_in_order!(
        header,
        child_frame_id,
        pose,
        pose_covariance,
        linear,
        angular,
        twist_covariance
    );
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseStampedMsg {
    /// Stamp and frame.
    pub header: Header,
    /// Pose in the header frame.
    pub pose: Pose,
}

impl RosMsg for PoseStampedMsg {
    const TYPE: &'static str = "geometry_msgs/msg/PoseStamped";

    fields_in_order!(header, pose);
}

/// `geometry_msgs/msg/PointStamped`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointStampedMsg {
    /// Stamp and frame.
    pub header: Header,
    /// Point in the header frame (m).
    pub point: Vec3,
}

impl RosMsg for PointStampedMsg {
    const TYPE: &'static str = "geometry_msgs/msg/PointStamped";

    fields_in_order!(header, point);
}

/// `geometry_msgs/TransformStamped`: `header.frame_id` from `child_frame_id`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// Child frame.
    pub child_frame_id: String,
    /// Translation (m).
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
}

impl Field for TransformStamped {
    fields_in_order!(header, child_frame_id, translation, rotation);
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

impl RosMsg for TfMessage {
    const TYPE: &'static str = "tf2_msgs/msg/TFMessage";

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        // A TransformStamped takes at least 4+4+4+4+8*7 bytes.
        let n = r.seq_len(72)?;
        let mut transforms = Vec::with_capacity(n);
        for _ in 0..n {
            transforms.push(TransformStamped::read(r)?);
        }
        Ok(Self { transforms })
    }

    fn read_into(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
        let n = r.seq_len(72)?;
        self.transforms.truncate(n);
        self.transforms.resize_with(n, Default::default);
        for t in &mut self.transforms {
            t.read_into(r)?;
        }
        Ok(())
    }

    fn write(&self, w: &mut CdrWriter) {
        w.seq_len(self.transforms.len());
        for t in &self.transforms {
            t.write(w);
        }
    }
}
