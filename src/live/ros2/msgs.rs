//! The ROS 2 messages `odocal live` publishes, as serde structs in ROS 2's
//! field order (ros2-client's publishers serialise them to CDR). Each is
//! checked field by field against odocal's own CDR decoder
//! ([`crate::io::ros_msgs`]) in the tests below, so that the two cannot
//! drift apart. What odocal receives is decoded by `io` directly.

use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// `builtin_interfaces/msg/Time`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, below 10⁹.
    pub nanosec: u32,
}

impl Time {
    /// `t` (s) as seconds and nanoseconds (floor, so that the nanoseconds
    /// stay below 10⁹ for negative times too).
    pub fn from_seconds(t: f64) -> Self {
        let sec = t.floor();
        let nanosec = ((t - sec) * 1e9).round().min(999_999_999.0) as u32;
        Self {
            sec: sec as i32,
            nanosec,
        }
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Stamp.
    pub stamp: Time,
    /// Frame.
    pub frame_id: String,
}

/// `geometry_msgs/msg/Vector3` (and `Point`, the same layout).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Quaternion {
    /// A rotation by `yaw` (rad) about z.
    pub fn from_yaw(yaw: f64) -> Self {
        let h = 0.5 * yaw;
        Self {
            x: 0.0,
            y: 0.0,
            z: h.sin(),
            w: h.cos(),
        }
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position (m).
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

/// A 6×6 row-major covariance, as CDR has it: 36 doubles, no length (serde
/// derives arrays up to 32 only, hence by hand).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Covariance(pub [f64; 36]);

impl Serialize for Covariance {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(36)?;
        for v in &self.0 {
            t.serialize_element(v)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Covariance {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Covariance;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("36 doubles")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<Covariance, A::Error> {
                let mut c = [0.0; 36];
                for (i, v) in c.iter_mut().enumerate() {
                    *v = a
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                Ok(Covariance(c))
            }
        }
        d.deserialize_tuple(36, V)
    }
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// Pose.
    pub pose: Pose,
    /// Its covariance (x, y, z, roll, pitch, yaw).
    pub covariance: Covariance,
}

/// `geometry_msgs/msg/Twist`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity (m/s).
    pub linear: Vector3,
    /// Angular velocity (rad/s).
    pub angular: Vector3,
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// Twist.
    pub twist: Twist,
    /// Its covariance.
    pub covariance: Covariance,
}

/// `nav_msgs/msg/Odometry`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    /// Stamp and parent frame (`odom`).
    pub header: Header,
    /// Child frame (`base_link`).
    pub child_frame_id: String,
    /// `parent_from_child`.
    pub pose: PoseWithCovariance,
    /// Velocity in the child frame.
    pub twist: TwistWithCovariance,
}

/// `diagnostic_msgs/msg/KeyValue`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyValue {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// OK 0, WARN 1, ERROR 2, STALE 3 (`byte`).
    pub level: u8,
    /// What is described.
    pub name: String,
    /// One line.
    pub message: String,
    /// The hardware.
    pub hardware_id: String,
    /// Values.
    pub values: Vec<KeyValue>,
}

/// `diagnostic_msgs/msg/DiagnosticArray`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    /// Stamp.
    pub header: Header,
    /// Statuses.
    pub status: Vec<DiagnosticStatus>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::ros_msgs::{DiagnosticArrayMsg, OdometryMsg, RosMsg};
    use ros2_client::dds::rustdds::no_key::SerializerAdapter;
    use ros2_client::dds::rustdds::CDRSerializerAdapter;

    /// What ros2-client's publisher sends: RustDDS's serde CDR payload
    /// behind a little-endian encapsulation header.
    fn wire<T: Serialize>(m: &T) -> Vec<u8> {
        let body = CDRSerializerAdapter::<T, byteorder::LittleEndian>::to_bytes(m).unwrap();
        [&[0u8, 1, 0, 0][..], &body[..]].concat()
    }

    fn cov(k: f64) -> Covariance {
        let mut c = [0.0; 36];
        for (i, v) in c.iter_mut().enumerate() {
            *v = k * (i as f64 + 1.0);
        }
        Covariance(c)
    }

    #[test]
    fn odometry_reads_back_field_by_field_through_the_io_decoder() {
        let m = Odometry {
            header: Header {
                stamp: Time {
                    sec: 1_700_000_123,
                    nanosec: 456_789_012,
                },
                frame_id: "odom".into(),
            },
            child_frame_id: "base_link".into(),
            pose: PoseWithCovariance {
                pose: Pose {
                    position: Vector3 {
                        x: 1.25,
                        y: -2.5,
                        z: 0.125,
                    },
                    orientation: Quaternion::from_yaw(0.7),
                },
                covariance: cov(0.01),
            },
            twist: TwistWithCovariance {
                twist: Twist {
                    linear: Vector3 {
                        x: 0.5,
                        y: 0.0625,
                        z: -0.25,
                    },
                    angular: Vector3 {
                        x: 0.001,
                        y: -0.002,
                        z: 0.3,
                    },
                },
                covariance: cov(-0.5),
            },
        };
        let got = OdometryMsg::decode(&wire(&m)).unwrap();
        assert_eq!(got.header.stamp.sec, 1_700_000_123);
        assert_eq!(got.header.stamp.nanosec, 456_789_012);
        assert_eq!(got.header.frame_id, "odom");
        assert_eq!(got.child_frame_id, "base_link");
        let p = m.pose.pose;
        assert_eq!(
            [
                got.pose.position.x,
                got.pose.position.y,
                got.pose.position.z
            ],
            [p.position.x, p.position.y, p.position.z]
        );
        let q = p.orientation;
        let gq = got.pose.orientation;
        assert_eq!([gq.x, gq.y, gq.z, gq.w], [q.x, q.y, q.z, q.w]);
        assert!((gq.yaw() - 0.7).abs() < 1e-12);
        assert_eq!(got.pose_covariance, m.pose.covariance.0);
        let t = m.twist.twist;
        assert_eq!(
            [got.linear.x, got.linear.y, got.linear.z],
            [t.linear.x, t.linear.y, t.linear.z]
        );
        assert_eq!(
            [got.angular.x, got.angular.y, got.angular.z],
            [t.angular.x, t.angular.y, t.angular.z]
        );
        assert_eq!(got.twist_covariance, m.twist.covariance.0);
    }

    #[test]
    fn diagnostics_read_back_field_by_field_through_the_io_decoder() {
        let m = DiagnosticArray {
            header: Header {
                stamp: Time::from_seconds(12.5),
                frame_id: String::new(),
            },
            status: vec![
                DiagnosticStatus {
                    level: 1,
                    name: "odocal: calibration".into(),
                    message: "radius_step right −4.9 mm at 40.0 s".into(),
                    hardware_id: "wheelchair".into(),
                    values: vec![
                        KeyValue {
                            key: "r_right".into(),
                            value: "0.171000".into(),
                        },
                        KeyValue {
                            key: "time_offset".into(),
                            value: "0.0125".into(),
                        },
                    ],
                },
                DiagnosticStatus {
                    level: 2,
                    name: "x".into(),
                    ..Default::default()
                },
            ],
        };
        let got = DiagnosticArrayMsg::decode(&wire(&m)).unwrap();
        assert_eq!(got.header.stamp.sec, 12);
        assert_eq!(got.header.stamp.nanosec, 500_000_000);
        assert_eq!(got.status.len(), 2);
        for (g, s) in got.status.iter().zip(&m.status) {
            assert_eq!(g.level, s.level);
            assert_eq!(g.name, s.name);
            assert_eq!(g.message, s.message);
            assert_eq!(g.hardware_id, s.hardware_id);
            let kv: Vec<(&str, &str)> = g
                .values
                .iter()
                .map(|v| (v.key.as_str(), v.value.as_str()))
                .collect();
            let want: Vec<(&str, &str)> = s
                .values
                .iter()
                .map(|v| (v.key.as_str(), v.value.as_str()))
                .collect();
            assert_eq!(kv, want);
        }
    }

    #[test]
    fn negative_times_keep_nanoseconds_below_a_second() {
        let t = Time::from_seconds(-1.25);
        assert_eq!((t.sec, t.nanosec), (-2, 750_000_000));
    }
}
