//! The ROS 2 messages odocal reads and writes, decoded from and encoded to
//! CDR field by field in schema order (see [`super::ros_schema`] for the texts).

use super::cdr::{CdrError, CdrReader, CdrWriter};

/// A ROS 2 message with a CDR codec.
pub trait RosMsg: Sized {
    /// Schema name as written in MCAP (`pkg/msg/Type`).
    const TYPE: &'static str;
    /// Reads the fields in schema order.
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError>;
    /// Writes the fields in schema order.
    fn write(&self, w: &mut CdrWriter);

    /// Decodes a whole message (encapsulation header included); trailing
    /// bytes beyond 3 bytes of padding are an error.
    fn decode(data: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(data)?;
        let m = Self::read(&mut r)?;
        r.finish()?;
        Ok(m)
    }

    /// Encodes a whole message (little endian).
    fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        self.write(&mut w);
        w.bytes().to_vec()
    }
}

/// `builtin_interfaces/Time`: seconds and nanoseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Time {
    /// As seconds (s).
    pub fn seconds(&self) -> f64 {
        self.sec as f64 + self.nanosec as f64 * 1e-9
    }

    /// From seconds (s), rounded to the nearest nanosecond.
    pub fn from_seconds(t: f64) -> Self {
        let mut sec = t.floor();
        let mut ns = ((t - sec) * 1e9).round();
        if ns >= 1e9 {
            sec += 1.0;
            ns -= 1e9;
        }
        Self {
            sec: sec as i32,
            nanosec: ns as u32,
        }
    }

    /// Whether both fields are zero (an unset stamp).
    pub fn is_zero(&self) -> bool {
        self.sec == 0 && self.nanosec == 0
    }

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            sec: r.i32()?,
            nanosec: r.u32()?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }
}

/// `std_msgs/Header`: stamp and frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// Frame the data is expressed in.
    pub frame_id: String,
}

impl Header {
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            stamp: Time::read(r)?,
            frame_id: r.string()?.to_string(),
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.stamp.write(w);
        w.string(&self.frame_id);
    }
}

/// `geometry_msgs/Vector3` and `geometry_msgs/Point` (same layout).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Vec3 {
    /// x (m or rad/s).
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl Vec3 {
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            x: r.f64()?,
            y: r.f64()?,
            z: r.f64()?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
    }
}

/// `geometry_msgs/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quat {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quat {
    fn default() -> Self {
        Self::from_yaw(0.0)
    }
}

impl Quat {
    /// A rotation about z by `yaw` (rad).
    pub fn from_yaw(yaw: f64) -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: (yaw / 2.0).sin(),
            w: (yaw / 2.0).cos(),
        }
    }

    /// Heading (rad) of the rotated x axis projected on the xy plane.
    pub fn yaw(&self) -> f64 {
        let Self { x, y, z, w } = *self;
        (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
    }

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            x: r.f64()?,
            y: r.f64()?,
            z: r.f64()?,
            w: r.f64()?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        w.f64(self.x);
        w.f64(self.y);
        w.f64(self.z);
        w.f64(self.w);
    }
}

/// `geometry_msgs/Pose`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pose {
    /// Position (m).
    pub position: Vec3,
    /// Orientation.
    pub orientation: Quat,
}

impl Pose {
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            position: Vec3::read(r)?,
            orientation: Quat::read(r)?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.position.write(w);
        self.orientation.write(w);
    }
}

/// `sensor_msgs/msg/LaserScan`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaserScanMsg {
    /// Stamp of the first beam, laser frame.
    pub header: Header,
    /// First beam angle (rad).
    pub angle_min: f32,
    /// Last beam angle (rad).
    pub angle_max: f32,
    /// Angle between beams (rad).
    pub angle_increment: f32,
    /// Time between beams (s).
    pub time_increment: f32,
    /// Time between scans (s).
    pub scan_time: f32,
    /// Smallest valid range (m).
    pub range_min: f32,
    /// Largest valid range (m).
    pub range_max: f32,
    /// Ranges (m).
    pub ranges: Vec<f32>,
    /// Intensities (device units), often empty.
    pub intensities: Vec<f32>,
}

impl RosMsg for LaserScanMsg {
    const TYPE: &'static str = "sensor_msgs/msg/LaserScan";

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        let header = Header::read(r)?;
        let mut m = Self {
            header,
            angle_min: r.f32()?,
            angle_max: r.f32()?,
            angle_increment: r.f32()?,
            time_increment: r.f32()?,
            scan_time: r.f32()?,
            range_min: r.f32()?,
            range_max: r.f32()?,
            ..Default::default()
        };
        r.f32_seq_into(&mut m.ranges)?;
        r.f32_seq_into(&mut m.intensities)?;
        Ok(m)
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        for v in [
            self.angle_min,
            self.angle_max,
            self.angle_increment,
            self.time_increment,
            self.scan_time,
            self.range_min,
            self.range_max,
        ] {
            w.f32(v);
        }
        w.f32_seq(&self.ranges);
        w.f32_seq(&self.intensities);
    }
}

/// `sensor_msgs/msg/JointState`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointStateMsg {
    /// Stamp.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad), empty or one per name.
    pub position: Vec<f64>,
    /// Velocities (rad/s), empty or one per name.
    pub velocity: Vec<f64>,
    /// Efforts (N·m), empty or one per name.
    pub effort: Vec<f64>,
}

impl RosMsg for JointStateMsg {
    const TYPE: &'static str = "sensor_msgs/msg/JointState";

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        let header = Header::read(r)?;
        let n = r.seq_len(5)?;
        let mut name = Vec::with_capacity(n);
        for _ in 0..n {
            name.push(r.string()?.to_string());
        }
        Ok(Self {
            header,
            name,
            position: r.f64_seq()?,
            velocity: r.f64_seq()?,
            effort: r.f64_seq()?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.seq_len(self.name.len());
        for n in &self.name {
            w.string(n);
        }
        w.f64_seq(&self.position);
        w.f64_seq(&self.velocity);
        w.f64_seq(&self.effort);
    }
}

/// `sensor_msgs/msg/Imu`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImuMsg {
    /// Stamp, IMU frame.
    pub header: Header,
    /// Orientation estimate.
    pub orientation: Quat,
    /// Its covariance (row-major 3×3; −1 in [0] = no estimate).
    pub orientation_covariance: [f64; 9],
    /// Angular velocity (rad/s).
    pub angular_velocity: Vec3,
    /// Its covariance.
    pub angular_velocity_covariance: [f64; 9],
    /// Linear acceleration (m/s²).
    pub linear_acceleration: Vec3,
    /// Its covariance.
    pub linear_acceleration_covariance: [f64; 9],
}

impl RosMsg for ImuMsg {
    const TYPE: &'static str = "sensor_msgs/msg/Imu";

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: Header::read(r)?,
            orientation: Quat::read(r)?,
            orientation_covariance: r.f64_array()?,
            angular_velocity: Vec3::read(r)?,
            angular_velocity_covariance: r.f64_array()?,
            linear_acceleration: Vec3::read(r)?,
            linear_acceleration_covariance: r.f64_array()?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        self.orientation.write(w);
        w.f64_array(&self.orientation_covariance);
        self.angular_velocity.write(w);
        w.f64_array(&self.angular_velocity_covariance);
        self.linear_acceleration.write(w);
        w.f64_array(&self.linear_acceleration_covariance);
    }
}

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

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: Header::read(r)?,
            child_frame_id: r.string()?.to_string(),
            pose: Pose::read(r)?,
            pose_covariance: r.f64_array()?,
            linear: Vec3::read(r)?,
            angular: Vec3::read(r)?,
            twist_covariance: r.f64_array()?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        w.string(&self.child_frame_id);
        self.pose.write(w);
        w.f64_array(&self.pose_covariance);
        self.linear.write(w);
        self.angular.write(w);
        w.f64_array(&self.twist_covariance);
    }
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

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: Header::read(r)?,
            pose: Pose::read(r)?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        self.pose.write(w);
    }
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

    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: Header::read(r)?,
            point: Vec3::read(r)?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.header.write(w);
        self.point.write(w);
    }
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
            transforms.push(TransformStamped {
                header: Header::read(r)?,
                child_frame_id: r.string()?.to_string(),
                translation: Vec3::read(r)?,
                rotation: Quat::read(r)?,
            });
        }
        Ok(Self { transforms })
    }

    fn write(&self, w: &mut CdrWriter) {
        w.seq_len(self.transforms.len());
        for t in &self.transforms {
            t.header.write(w);
            w.string(&t.child_frame_id);
            t.translation.write(w);
            t.rotation.write(w);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_round_trips_and_handles_negative() {
        let t = Time::from_seconds(1134864629.895182);
        assert_eq!(t.sec, 1134864629);
        assert_eq!(t.seconds(), 1134864629.895182);
        assert_eq!(Time::from_seconds(2.9999999999).sec, 3);
        let n = Time::from_seconds(-0.25);
        assert_eq!((n.sec, n.nanosec), (-1, 750_000_000));
        assert_eq!(n.seconds(), -0.25);
    }

    #[test]
    fn messages_round_trip() {
        let scan = LaserScanMsg {
            header: Header {
                stamp: Time { sec: 5, nanosec: 7 },
                frame_id: "laser".into(),
            },
            angle_min: -1.5,
            angle_increment: 0.01,
            range_max: 80.0,
            ranges: vec![1.0, f32::INFINITY, 2.5],
            ..Default::default()
        };
        let back = LaserScanMsg::decode(&scan.encode()).unwrap();
        assert_eq!(back.header, scan.header);
        assert_eq!(back.ranges[2], 2.5);
        let odom = OdometryMsg {
            child_frame_id: "base_link".into(),
            pose: Pose {
                position: Vec3 {
                    x: 1.0,
                    y: 2.0,
                    z: 0.0,
                },
                orientation: Quat::from_yaw(0.3),
            },
            ..Default::default()
        };
        let back = OdometryMsg::decode(&odom.encode()).unwrap();
        assert_eq!(back, odom);
        assert!((back.pose.orientation.yaw() - 0.3).abs() < 1e-15);
        let tf = TfMessage {
            transforms: vec![TransformStamped {
                child_frame_id: "laser".into(),
                translation: Vec3 {
                    x: 0.1,
                    y: 0.0,
                    z: 0.2,
                },
                ..Default::default()
            }],
        };
        assert_eq!(TfMessage::decode(&tf.encode()).unwrap(), tf);
        let js = JointStateMsg {
            name: vec!["l".into(), "r".into()],
            position: vec![1.0, 2.0],
            ..Default::default()
        };
        assert_eq!(JointStateMsg::decode(&js.encode()).unwrap(), js);
        let imu = ImuMsg::default();
        assert_eq!(ImuMsg::decode(&imu.encode()).unwrap(), imu);
    }

    #[test]
    fn truncated_message_is_an_error_at_every_cut() {
        let odom = OdometryMsg::default().encode();
        for cut in 0..odom.len() - 3 {
            assert!(OdometryMsg::decode(&odom[..cut]).is_err(), "cut {cut}");
        }
        // Trailing garbage beyond padding is refused too.
        let mut long = odom.clone();
        long.extend_from_slice(&[0; 8]);
        assert!(OdometryMsg::decode(&long).is_err());
    }
}
