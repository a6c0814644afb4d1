//! Writes a [`Recording`] as a ROS 2 bag in MCAP, as rosbag2 would: schema
//! encoding `ros2msg` with full definitions, CDR messages, zstd chunks,
//! `offered_qos_profiles` channel metadata. Same recording → same bytes.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Cursor, Read, Seek, SeekFrom, Write};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::atomic::write_bytes_atomic;
use super::cdr::CdrWriter;
use super::mcap_canon::{canonicalize_summary, canonicalize_summary_tail};
use super::options::{ReadOptions, TopicConfig};
use super::ros_msgs::{
    Header, ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg, Pose, Quat, RosMsg,
    TfMessage, Time, TransformStamped, Vec3,
};
use super::ros_schema::schema_text;
use super::stream_out::AtomicWriter;
use crate::geom::{self, Pose2};
use crate::recording::{Recording, StampedPose, WheelSample};
use crate::robot::RobotConfig;
use crate::scan::LaserScan;

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
        Self::for_robot(&RobotConfig::default())
    }
}

impl WriteOptions {
    /// Default names with the robot's wheel joint names.
    pub fn for_robot(robot: &RobotConfig) -> Self {
        Self::read_back_with(&ReadOptions::for_robot(robot))
    }

    /// The topics and wheel joints `read` looks for, with the default frames:
    /// a bag written with these options reads back with `read`.
    fn read_back_with(read: &ReadOptions) -> Self {
        Self {
            topics: read.topics.clone(),
            left_joint: read.left_joint.clone(),
            right_joint: read.right_joint.clone(),
            base_frame: "base_link".into(),
            laser_frame: "laser".into(),
            odom_frame: "odom".into(),
            world_frame: "map".into(),
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
    let mut feed = SliceFeed(&rec.scans);
    let mut bytes = encode_into(Cursor::new(Vec::new()), rec, &mut feed, opts)?.into_inner();
    canonicalize_summary(&mut bytes);
    Ok(bytes)
}

/// Laser scans handed to the writer in stamp order: held in memory, or cast
/// on demand by a simulator, so that a long recording need not fit in memory.
pub trait ScanFeed {
    /// Number of scans.
    fn len(&self) -> usize;
    /// Whether there are no scans.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Stamp of scan `i` (s); stamps must not decrease.
    fn stamp(&self, i: usize) -> f64;
    /// Scan `i`; the writer asks for `i = 0, 1, 2, …` in turn.
    fn scan(&mut self, i: usize) -> &LaserScan;
}

/// Scans already in memory.
struct SliceFeed<'a>(&'a [LaserScan]);

impl ScanFeed for SliceFeed<'_> {
    fn len(&self) -> usize {
        self.0.len()
    }
    fn stamp(&self, i: usize) -> f64 {
        self.0[i].stamp
    }
    fn scan(&mut self, i: usize) -> &LaserScan {
        &self.0[i]
    }
}

/// Writes `rec` (its `scans` ignored: they come from `feed`) to `path`,
/// streaming: the file grows message by message in a temporary sibling
/// that is renamed over `path` once complete. The bytes equal those of
/// [`write_mcap`] for the same recording with the feed's scans in it.
pub fn write_mcap_streaming(
    path: &Path,
    rec: &Recording,
    feed: &mut dyn ScanFeed,
    opts: &WriteOptions,
) -> Result<(), WriteError> {
    let file = path.display().to_string();
    let io_err = |source| WriteError::Io {
        file: file.clone(),
        source,
    };
    let mut out = AtomicWriter::create(path).map_err(io_err)?;
    encode_into(out.writer(), rec, feed, opts).map_err(|source| WriteError::Mcap {
        file: file.clone(),
        source,
    })?;
    canonicalize_file_summary(out.writer()).map_err(io_err)?;
    out.commit().map_err(io_err)
}

/// Canonicalises the summary of the MCAP file written so far by `w`
/// (see [`canonicalize_summary_tail`]): reads the summary back, sorts it and
/// writes it in place.
fn canonicalize_file_summary(w: &mut BufWriter<File>) -> std::io::Result<()> {
    w.flush()?;
    let f = w.get_mut();
    let len = f.seek(SeekFrom::End(0))?;
    let tail_len = 8 + 29; // footer record + magic
    if len < tail_len as u64 {
        return Ok(());
    }
    let mut tail = vec![0u8; tail_len];
    f.seek(SeekFrom::Start(len - tail_len as u64))?;
    f.read_exact(&mut tail)?;
    let start = u64::from_le_bytes(tail[9..17].try_into().expect("8 bytes"));
    if start == 0 || start >= len {
        return Ok(());
    }
    let mut summary = vec![0u8; (len - start) as usize];
    f.seek(SeekFrom::Start(start))?;
    f.read_exact(&mut summary)?;
    if canonicalize_summary_tail(&mut summary, start as usize) {
        f.seek(SeekFrom::Start(start))?;
        f.write_all(&summary)?;
    }
    f.seek(SeekFrom::End(0))?;
    Ok(())
}

/// Writes the recording's messages (scans from `feed`) as an MCAP file into
/// `out`, and returns it once the file is finished (summary not yet canonical).
fn encode_into<W: Write + Seek>(
    out: W,
    rec: &Recording,
    feed: &mut dyn ScanFeed,
    opts: &WriteOptions,
) -> Result<W, mcap::McapError> {
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .library("odocal")
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .create(out)?;
    let messages = Messages {
        rec,
        opts,
        ref_type: reference_type(rec),
        velocities: wheel_velocities(&rec.wheels),
    };
    let streams = streams(rec, feed, &opts.topics, messages.ref_type);
    let channel = declare_channels(&mut w, &streams)?;
    let order = message_order(&streams, rec, feed);
    let mut seq = [0u32; 6];
    let mut cdr = CdrWriter::new();
    for (stamp, s, i) in order {
        cdr.clear();
        messages.encode(&mut cdr, feed, s, i, stamp);
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
    Ok(w.into_inner())
}

/// One stream of the bag: which, its topic, message type and message count.
type StreamDecl<'a> = (Stream, &'a str, &'static str, usize);

/// Message type of the reference: odometry when any pose has a heading (or
/// there is none), points otherwise.
fn reference_type(rec: &Recording) -> &'static str {
    let reference_has_heading = rec.reference.iter().any(|p| p.has_heading);
    if reference_has_heading || rec.reference.is_empty() {
        OdometryMsg::TYPE
    } else {
        PointStampedMsg::TYPE
    }
}

/// The streams with messages, in the order their channels are declared.
fn streams<'a>(
    rec: &Recording,
    feed: &dyn ScanFeed,
    t: &'a TopicConfig,
    ref_type: &'static str,
) -> Vec<StreamDecl<'a>> {
    let mut streams: Vec<StreamDecl<'a>> = Vec::new();
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
        (Stream::Scan, &t.scan, LaserScanMsg::TYPE, feed.len()),
        (Stream::Odom, &t.odom, OdometryMsg::TYPE, rec.odom.len()),
    ] {
        if n > 0 {
            streams.push((s, topic, ty, n));
        }
    }
    streams
}

/// Adds each stream's schema and channel; returns the channel ids indexed by
/// [`Stream`].
fn declare_channels<W: Write + Seek>(
    w: &mut mcap::Writer<W>,
    streams: &[StreamDecl<'_>],
) -> Result<[u16; 6], mcap::McapError> {
    let mut channel = [0u16; 6];
    for &(s, topic, ty, _) in streams {
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
    Ok(channel)
}

/// Every message as (stamp, stream, index), merged in stamp order; the
/// static transform is stamped with the earliest stamp of the recording.
fn message_order(
    streams: &[StreamDecl<'_>],
    rec: &Recording,
    feed: &dyn ScanFeed,
) -> Vec<(f64, Stream, usize)> {
    let first_scan = (!feed.is_empty()).then(|| feed.stamp(0));
    let start = match (rec.time_span().map(|(a, _)| a), first_scan) {
        (Some(a), Some(b)) => a.min(b),
        (a, b) => a.or(b).unwrap_or(0.0),
    };
    let mut order: Vec<(f64, Stream, usize)> = Vec::new();
    for &(s, _, _, n) in streams {
        for i in 0..n {
            let stamp = match s {
                Stream::TfStatic => start,
                Stream::Reference => rec.reference[i].stamp,
                Stream::Imu => rec.gyro[i].stamp,
                Stream::Joints => rec.wheels[i].stamp,
                Stream::Scan => feed.stamp(i),
                Stream::Odom => rec.odom[i].stamp,
            };
            order.push((stamp, s, i));
        }
    }
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    order
}

/// What the messages are made of: the recording, the names, the reference's
/// message type and the wheel rates of the joint states.
struct Messages<'a> {
    rec: &'a Recording,
    opts: &'a WriteOptions,
    ref_type: &'static str,
    velocities: Vec<(f64, f64)>,
}

impl Messages<'_> {
    /// Writes message `i` of stream `s`, stamped `stamp`, into `cdr`.
    fn encode(
        &self,
        cdr: &mut CdrWriter,
        feed: &mut dyn ScanFeed,
        s: Stream,
        i: usize,
        stamp: f64,
    ) {
        let (rec, opts) = (self.rec, self.opts);
        let header = |frame: &str| Header {
            stamp: Time::from_seconds(stamp),
            frame_id: frame.to_string(),
        };
        match s {
            Stream::TfStatic => tf_static(header(&opts.base_frame), opts, rec).write(cdr),
            Stream::Reference if self.ref_type == PointStampedMsg::TYPE => {
                let p = &rec.reference[i].pose.translation.vector;
                PointStampedMsg {
                    header: header(&opts.world_frame),
                    point: Vec3 {
                        x: p.x,
                        y: p.y,
                        z: 0.0,
                    },
                }
                .write(cdr)
            }
            Stream::Reference => {
                odometry(header(&opts.world_frame), opts, &rec.reference[i]).write(cdr)
            }
            Stream::Odom => odometry(header(&opts.odom_frame), opts, &rec.odom[i]).write(cdr),
            Stream::Imu => imu(header(&opts.base_frame), rec.gyro[i].wz).write(cdr),
            Stream::Joints => {
                joint_state(header(""), opts, &rec.wheels[i], self.velocities[i]).write(cdr)
            }
            Stream::Scan => laser_scan(header(&opts.laser_frame), feed.scan(i)).write(cdr),
        }
    }
}

/// The base-to-laser transform (identity when the recording has none).
fn tf_static(header: Header, opts: &WriteOptions, rec: &Recording) -> TfMessage {
    let b = rec.base_from_laser.unwrap_or_else(Pose2::identity);
    TfMessage {
        transforms: vec![TransformStamped {
            header,
            child_frame_id: opts.laser_frame.clone(),
            translation: Vec3 {
                x: b.translation.vector.x,
                y: b.translation.vector.y,
                z: 0.0,
            },
            rotation: Quat::from_yaw(geom::heading(&b)),
        }],
    }
}

/// A gyro sample: the z rate `wz` (rad/s) only.
fn imu(header: Header, wz: f64) -> ImuMsg {
    let mut cov = [0.0; 9];
    cov[0] = -1.0; // no orientation estimate (REP 145)
    ImuMsg {
        header,
        orientation: Quat::default(),
        orientation_covariance: cov,
        angular_velocity: Vec3 {
            x: 0.0,
            y: 0.0,
            z: wz,
        },
        ..Default::default()
    }
}

/// Wheel angles `ws` with their rates `(left, right)`.
fn joint_state(
    header: Header,
    opts: &WriteOptions,
    ws: &WheelSample,
    (vl, vr): (f64, f64),
) -> JointStateMsg {
    JointStateMsg {
        header,
        name: vec![opts.left_joint.clone(), opts.right_joint.clone()],
        position: vec![ws.left, ws.right],
        velocity: vec![vl, vr],
        effort: Vec::new(),
    }
}

/// A laser scan (angles and limits in `f32`, as the message has them).
fn laser_scan(header: Header, sc: &LaserScan) -> LaserScanMsg {
    let n = sc.ranges.len();
    LaserScanMsg {
        header,
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
