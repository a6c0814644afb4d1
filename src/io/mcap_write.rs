//! Writes a [`Recording`] as a ROS 2 bag in MCAP, as rosbag2 would: schema
//! encoding `ros2msg` with full definitions, CDR messages, zstd chunks,
//! `offered_qos_profiles` channel metadata. Same recording → same bytes.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::atomic::write_bytes_atomic;
use super::cdr::CdrWriter;
use super::mcap_canon::canonicalize_summary;
use super::mcap_read::TopicConfig;
use super::ros_msgs::{
    Header, ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg, Pose, Quat, RosMsg,
    TfMessage, Time, TransformStamped, Vec3,
};
use super::ros_schema::schema_text;
use crate::geom::{self, Pose2};
use crate::recording::{Recording, StampedPose, WheelSample};
use crate::robot::RobotConfig;

/// Topic, joint and frame names of a written bag.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WriteOptions {
    /// Topic names (the reference goes to `topics.reference`).
    pub topics: TopicConfig,
    /// JointState name of the left wheel.
    pub left_joint: String,
    /// JointState name of the right wheel.
    pub right_joint: String,
    /// Robot body frame (child of odometry and reference, parent of the laser).
    pub base_frame: String,
    /// Laser frame (`/scan` frame_id).
    pub laser_frame: String,
    /// Parent frame of `/odom`.
    pub odom_frame: String,
    /// Parent frame of the reference.
    pub world_frame: String,
}

impl Default for WriteOptions {
    fn default() -> Self {
        let robot = RobotConfig::default();
        Self {
            topics: TopicConfig::default(),
            left_joint: robot.left_joint,
            right_joint: robot.right_joint,
            base_frame: "base_link".into(),
            laser_frame: "laser".into(),
            odom_frame: "odom".into(),
            world_frame: "map".into(),
        }
    }
}

impl WriteOptions {
    /// Default names with the robot's wheel joint names.
    pub fn for_robot(robot: &RobotConfig) -> Self {
        Self {
            left_joint: robot.left_joint.clone(),
            right_joint: robot.right_joint.clone(),
            ..Self::default()
        }
    }
}

/// A bag that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The MCAP encoder failed.
    #[error("writing MCAP {file}: {source}")]
    Mcap {
        /// Target file.
        file: String,
        /// Cause.
        source: mcap::McapError,
    },
    /// The file could not be written.
    #[error("writing {file}: {source}")]
    Io {
        /// Target file.
        file: String,
        /// Cause.
        source: std::io::Error,
    },
}

/// QoS of a latched topic (`/tf_static`), as rosbag2 records it.
const LATCHED_QOS: &str =
    "- avoid_ros_namespace_conventions: false\n  deadline: {nsec: 0, sec: 0}\n  \
depth: 1\n  durability: 1\n  history: 1\n  lifespan: {nsec: 0, sec: 0}\n  liveliness: 1\n  \
liveliness_lease_duration: {nsec: 0, sec: 0}\n  reliability: 1";

/// The streams in the order their channels are declared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Stream {
    TfStatic,
    Reference,
    Imu,
    Joints,
    Scan,
    Odom,
}

/// Writes `rec` to `path` (atomically).
pub fn write_mcap(path: &Path, rec: &Recording, opts: &WriteOptions) -> Result<(), WriteError> {
    let file = path.display().to_string();
    let bytes = encode_mcap(rec, opts).map_err(|source| WriteError::Mcap {
        file: file.clone(),
        source,
    })?;
    write_bytes_atomic(path, &bytes).map_err(|source| WriteError::Io { file, source })
}

/// The MCAP bytes [`write_mcap`] writes.
pub fn encode_mcap(rec: &Recording, opts: &WriteOptions) -> Result<Vec<u8>, mcap::McapError> {
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .library("odocal")
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .create(Cursor::new(Vec::new()))?;
    let t = &opts.topics;
    let reference_has_heading = rec.reference.iter().any(|p| p.has_heading);
    let ref_type = if reference_has_heading || rec.reference.is_empty() {
        OdometryMsg::TYPE
    } else {
        PointStampedMsg::TYPE
    };
    let mut streams: Vec<(Stream, &str, &str, usize)> = Vec::new();
    if rec.base_from_laser.is_some() {
        streams.push((Stream::TfStatic, &t.tf_static, TfMessage::TYPE, 1));
    }
    for (s, topic, ty, n) in [
        (
            Stream::Reference,
            &t.reference,
            ref_type,
            rec.reference.len(),
        ),
        (Stream::Imu, &t.imu, ImuMsg::TYPE, rec.gyro.len()),
        (
            Stream::Joints,
            &t.joint_states,
            JointStateMsg::TYPE,
            rec.wheels.len(),
        ),
        (Stream::Scan, &t.scan, LaserScanMsg::TYPE, rec.scans.len()),
        (Stream::Odom, &t.odom, OdometryMsg::TYPE, rec.odom.len()),
    ] {
        if n > 0 {
            streams.push((s, topic, ty, n));
        }
    }
    // Channel ids indexed by Stream.
    let mut channel = [0u16; 6];
    for &(s, topic, ty, _) in &streams {
        let text = schema_text(ty).unwrap_or_default();
        let schema = w.add_schema(ty, "ros2msg", text.as_bytes())?;
        let qos = if s == Stream::TfStatic {
            LATCHED_QOS
        } else {
            ""
        };
        let meta = BTreeMap::from([("offered_qos_profiles".to_string(), qos.to_string())]);
        channel[s as usize] = w.add_channel(schema, topic, "cdr", &meta)?;
    }
    let start = rec.time_span().map(|(a, _)| a).unwrap_or(0.0);
    // Every message as (stamp, stream, index), merged in stamp order.
    let mut order: Vec<(f64, Stream, usize)> = Vec::new();
    for &(s, _, _, n) in &streams {
        for i in 0..n {
            let stamp = match s {
                Stream::TfStatic => start,
                Stream::Reference => rec.reference[i].stamp,
                Stream::Imu => rec.gyro[i].stamp,
                Stream::Joints => rec.wheels[i].stamp,
                Stream::Scan => rec.scans[i].stamp,
                Stream::Odom => rec.odom[i].stamp,
            };
            order.push((stamp, s, i));
        }
    }
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let velocities = wheel_velocities(&rec.wheels);
    let mut seq = [0u32; 6];
    let mut cdr = CdrWriter::new();
    for (stamp, s, i) in order {
        cdr.clear();
        let header = |frame: &str| Header {
            stamp: Time::from_seconds(stamp),
            frame_id: frame.to_string(),
        };
        match s {
            Stream::TfStatic => {
                let b = rec.base_from_laser.unwrap_or_else(Pose2::identity);
                TfMessage {
                    transforms: vec![TransformStamped {
                        header: header(&opts.base_frame),
                        child_frame_id: opts.laser_frame.clone(),
                        translation: Vec3 {
                            x: b.translation.vector.x,
                            y: b.translation.vector.y,
                            z: 0.0,
                        },
                        rotation: Quat::from_yaw(geom::heading(&b)),
                    }],
                }
                .write(&mut cdr)
            }
            Stream::Reference if ref_type == PointStampedMsg::TYPE => {
                let p = &rec.reference[i].pose.translation.vector;
                PointStampedMsg {
                    header: header(&opts.world_frame),
                    point: Vec3 {
                        x: p.x,
                        y: p.y,
                        z: 0.0,
                    },
                }
                .write(&mut cdr)
            }
            Stream::Reference => {
                odometry(header(&opts.world_frame), opts, &rec.reference[i]).write(&mut cdr)
            }
            Stream::Odom => odometry(header(&opts.odom_frame), opts, &rec.odom[i]).write(&mut cdr),
            Stream::Imu => {
                let mut cov = [0.0; 9];
                cov[0] = -1.0; // no orientation estimate (REP 145)
                ImuMsg {
                    header: header(&opts.base_frame),
                    orientation: Quat::default(),
                    orientation_covariance: cov,
                    angular_velocity: Vec3 {
                        x: 0.0,
                        y: 0.0,
                        z: rec.gyro[i].wz,
                    },
                    ..Default::default()
                }
                .write(&mut cdr)
            }
            Stream::Joints => {
                let ws = &rec.wheels[i];
                let (vl, vr) = velocities[i];
                JointStateMsg {
                    header: header(""),
                    name: vec![opts.left_joint.clone(), opts.right_joint.clone()],
                    position: vec![ws.left, ws.right],
                    velocity: vec![vl, vr],
                    effort: Vec::new(),
                }
                .write(&mut cdr)
            }
            Stream::Scan => {
                let sc = &rec.scans[i];
                let n = sc.ranges.len();
                LaserScanMsg {
                    header: header(&opts.laser_frame),
                    angle_min: sc.angle_min as f32,
                    angle_max: sc.beam_angle(n.saturating_sub(1)) as f32,
                    angle_increment: sc.angle_increment as f32,
                    time_increment: sc.time_increment as f32,
                    scan_time: sc.scan_time as f32,
                    range_min: sc.range_min as f32,
                    range_max: sc.range_max as f32,
                    ranges: sc.ranges.clone(),
                    intensities: Vec::new(),
                }
                .write(&mut cdr)
            }
        }
        let k = s as usize;
        let log_time = (stamp.max(0.0) * 1e9).round() as u64;
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: channel[k],
                sequence: seq[k],
                log_time,
                publish_time: log_time,
            },
            cdr.bytes(),
        )?;
        seq[k] += 1;
    }
    w.finish()?;
    let mut bytes = w.into_inner().into_inner();
    canonicalize_summary(&mut bytes);
    Ok(bytes)
}

fn odometry(header: Header, opts: &WriteOptions, p: &StampedPose) -> OdometryMsg {
    let [x, y, th] = geom::xyt(&p.pose);
    OdometryMsg {
        header,
        child_frame_id: opts.base_frame.clone(),
        pose: Pose {
            position: Vec3 { x, y, z: 0.0 },
            orientation: Quat::from_yaw(th),
        },
        ..Default::default()
    }
}

/// Wheel rates (rad/s) by central differences (one-sided at the ends; 0 where
/// the stamps do not advance).
fn wheel_velocities(w: &[WheelSample]) -> Vec<(f64, f64)> {
    (0..w.len())
        .map(|i| {
            let a = &w[i.saturating_sub(1)];
            let b = &w[(i + 1).min(w.len() - 1)];
            let dt = b.stamp - a.stamp;
            if dt > 0.0 {
                ((b.left - a.left) / dt, (b.right - a.right) / dt)
            } else {
                (0.0, 0.0)
            }
        })
        .collect()
}
