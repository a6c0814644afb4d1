//! The ROS 2 messages odocal reads and writes, decoded from and encoded to
//! CDR field by field in schema order (see [`super::ros_schema`] for the texts).
//! Primitives here; sensor and geometry messages in their own files.

use super::cdr::{CdrError, CdrReader, CdrWriter};

mod diagnostic;
mod geometry;
mod int_arrays;
mod sensor;

pub use diagnostic::{DiagnosticArrayMsg, DiagnosticStatusMsg, KeyValueMsg};
pub use geometry::{OdometryMsg, PointStampedMsg, PoseStampedMsg, TfMessage, TransformStamped};
pub use int_arrays::read_int_array;
pub use sensor::{ImuMsg, JointStateMsg, LaserScanMsg};

/// A ROS 2 message with a CDR codec.
pub trait RosMsg: Sized {
    /// Schema name as written in MCAP (`pkg/msg/Type`).
    const TYPE: &'static str;
    /// Reads the fields in schema order.
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError>;
    /// Writes the fields in schema order.
    fn write(&self, w: &mut CdrWriter);

    /// Reads the fields in schema order into `self`, reusing its strings and
    /// vectors (a reader that decodes message after message into one value
    /// allocates only when a message is longer than any before it). Leaves
    /// `self` partly overwritten when it fails.
    fn read_into(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
        *self = Self::read(r)?;
        Ok(())
    }

    /// [`RosMsg::decode`] into `self` (see [`RosMsg::read_into`]); the same
    /// checks and errors.
    fn decode_into(&mut self, data: &[u8]) -> Result<(), CdrError> {
        let mut r = CdrReader::new(data)?;
        self.read_into(&mut r)?;
        r.finish()
    }

    /// [`RosMsg::decode_ros1`] into `self` (see [`RosMsg::read_into`]).
    fn decode_ros1_into(&mut self, data: &[u8]) -> Result<(), CdrError> {
        let mut r = CdrReader::ros1(data);
        self.read_into(&mut r)?;
        r.finish()
    }

    /// Decodes a whole message (encapsulation header included); trailing
    /// bytes beyond 3 bytes of padding are an error.
    fn decode(data: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(data)?;
        let m = Self::read(&mut r)?;
        r.finish()?;
        Ok(m)
    }

    /// Decodes a whole ROS 1 message (the same fields, ROS 1 serialisation,
    /// see [`CdrReader::ros1`]); trailing bytes are an error.
    fn decode_ros1(data: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::ros1(data);
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

/// A part of a message with a fixed CDR layout (primitives, arrays and the
/// nested types), read and written where it stands among the fields.
trait Field: Sized {
    /// Reads the value.
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError>;
    /// Writes the value.
    fn write(&self, w: &mut CdrWriter);
    /// Reads the value into `self`, reusing what it owns.
    #[inline]
    fn read_into(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
        *self = Self::read(r)?;
        Ok(())
    }
}

/// The `read` and `write` of a struct encoded as the listed fields one after
/// the other (schema order), each with its own [`Field`] codec.
macro_rules! fields_in_order {
    ($($field:ident),+ $(,)?) => {
        #[inline]
        fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
            Ok(Self {
                $($field: Field::read(r)?,)+
            })
        }

        fn write(&self, w: &mut CdrWriter) {
            $(Field::write(&self.$field, w);)+
        }

        #[inline]
        fn read_into(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
            $(Field::read_into(&mut self.$field, r)?;)+
            Ok(())
        }
    };
}
use fields_in_order;

/// [`Field`] for the primitives, each read and written by the CDR method
/// of its name.
macro_rules! primitive_fields {
    ($($t:ident),+) => {
        $(
            impl Field for $t {
                #[inline]
                fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
                    r.$t()
                }
                fn write(&self, w: &mut CdrWriter) {
                    w.$t(*self)
                }
            }
        )+
    };
}
primitive_fields!(i32, u32, f64);

impl Field for String {
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(r.string()?.to_string())
    }
    fn write(&self, w: &mut CdrWriter) {
        w.string(self)
    }
    fn read_into(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
        let s = r.string()?;
        self.clear();
        self.push_str(s);
        Ok(())
    }
}

/// Covariance matrices: fixed-size, no length prefix.
impl<const N: usize> Field for [f64; N] {
    #[inline]
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        r.f64_array()
    }
    fn write(&self, w: &mut CdrWriter) {
        w.f64_array(self)
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
}

impl Field for Time {
    fields_in_order!(sec, nanosec);
}

/// `std_msgs/Header`: stamp and frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// Frame the data is expressed in.
    pub frame_id: String,
}

impl Field for Header {
    /// ROS 1's Header starts with a `uint32 seq`, which ROS 2 dropped; it is
    /// read and not kept.
    fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        if r.is_ros1() {
            r.u32()?;
        }
        Ok(Self {
            stamp: Field::read(r)?,
            frame_id: Field::read(r)?,
        })
    }

    fn write(&self, w: &mut CdrWriter) {
        self.stamp.write(w);
        self.frame_id.write(w);
    }

    fn read_into(&mut self, r: &mut CdrReader<'_>) -> Result<(), CdrError> {
        if r.is_ros1() {
            r.u32()?;
        }
        self.stamp.read_into(r)?;
        self.frame_id.read_into(r)
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

impl Field for Vec3 {
    fields_in_order!(x, y, z);
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
}

impl Field for Quat {
    fields_in_order!(x, y, z, w);
}

/// `geometry_msgs/Pose`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pose {
    /// Position (m).
    pub position: Vec3,
    /// Orientation.
    pub orientation: Quat,
}

impl Field for Pose {
    fields_in_order!(position, orientation);
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
    fn decoding_into_a_used_message_equals_decoding_afresh() {
        let long = TfMessage {
            transforms: vec![
                TransformStamped {
                    child_frame_id: "a_long_child_frame".into(),
                    ..Default::default()
                };
                3
            ],
        };
        let short = TfMessage {
            transforms: vec![TransformStamped {
                header: Header {
                    stamp: Time { sec: 3, nanosec: 4 },
                    frame_id: "odom".into(),
                },
                child_frame_id: "b".into(),
                rotation: Quat::from_yaw(1.0),
                ..Default::default()
            }],
        };
        let mut m = TfMessage::default();
        m.decode_into(&long.encode()).unwrap();
        assert_eq!(m, long);
        m.decode_into(&short.encode()).unwrap();
        assert_eq!(m, short);
        let scan = LaserScanMsg {
            header: Header {
                stamp: Time { sec: 1, nanosec: 2 },
                frame_id: "laser".into(),
            },
            ranges: vec![1.0, 2.0],
            ..Default::default()
        };
        let mut s = LaserScanMsg {
            intensities: vec![5.0; 9],
            ..Default::default()
        };
        s.decode_into(&scan.encode()).unwrap();
        assert_eq!(s, scan);
        // Every cut of an odometry message fails as plain decoding does.
        let odom = OdometryMsg {
            child_frame_id: "base_link".into(),
            ..Default::default()
        }
        .encode();
        let mut o = OdometryMsg::default();
        for cut in 0..odom.len() - 3 {
            let fresh = OdometryMsg::decode(&odom[..cut]).unwrap_err();
            assert_eq!(o.decode_into(&odom[..cut]).unwrap_err(), fresh, "cut {cut}");
        }
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
