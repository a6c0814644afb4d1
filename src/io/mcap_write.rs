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
    /// Added to every stamp (s): the clock at the source's time 0 (e.g. a
    /// date as seconds since 1970-01-01).
    pub clock_start_s: f64,
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
            clock_start_s: 0.0,
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

/// The streams of a bag, in the order their channels are declared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum BagStream {
    /// The static base-to-laser transform (one message).
    TfStatic,
    /// Reference poses.
    Reference,
    /// Gyro samples.
    Imu,
    /// Wheel joint states.
    Joints,
    /// Laser scans.
    Scan,
    /// Wheel odometry.
    Odom,
}

/// The streams that carry samples, in declaration order.
const SAMPLE_STREAMS: [BagStream; 5] = [
    BagStream::Reference,
    BagStream::Imu,
    BagStream::Joints,
    BagStream::Scan,
    BagStream::Odom,
];

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
    let mut src = InMemory::new(rec);
    let mut bytes = encode_into(Cursor::new(Vec::new()), &mut src, opts)?.into_inner();
    canonicalize_summary(&mut bytes);
    Ok(bytes)
}

/// The messages of a bag handed to the writer: each stream's messages in
/// their order in the file (stamps non-decreasing), asked for one by one in
/// that order, so that a source may make them on demand (a simulator) and a
/// long recording need not fit in memory. The writer interleaves the streams
/// by stamp (ties in [`BagStream`] order).
pub trait BagSource {
    /// The `base_from_laser` the static transform states, if any.
    fn base_from_laser(&self) -> Option<Pose2>;
    /// Whether any reference pose has a heading (the reference is then
    /// written as odometry, else as points).
    fn reference_has_heading(&self) -> bool;
    /// The earliest stamp (s) of any message: the static transform's.
    fn start(&self) -> f64;
    /// Number of messages of sample stream `s`.
    fn count(&self, s: BagStream) -> usize;
    /// Stamp (s) of message `j` of sample stream `s`, non-decreasing in `j`.
    fn stamp(&self, s: BagStream, j: usize) -> f64;
    /// Reference pose `j`.
    fn reference(&mut self, j: usize) -> StampedPose;
    /// Odometry pose `j`.
    fn odom(&mut self, j: usize) -> StampedPose;
    /// Gyro rate `j` (rad/s).
    fn gyro(&mut self, j: usize) -> f64;
    /// Wheel sample `j` and its rates (rad/s, left and right).
    fn wheel(&mut self, j: usize) -> (WheelSample, (f64, f64));
    /// Laser scan `j`.
    fn scan(&mut self, j: usize) -> &LaserScan;
}

/// A recording in memory as a [`BagSource`]: each stream in stamp order
/// (a stable sort, so that its messages keep their order at equal stamps).
struct InMemory<'a> {
    rec: &'a Recording,
    /// For each stream, its indices in `rec` in stamp order.
    order: [Vec<usize>; 6],
    velocities: Vec<(f64, f64)>,
}

impl<'a> InMemory<'a> {
    fn new(rec: &'a Recording) -> Self {
        let mut order: [Vec<usize>; 6] = Default::default();
        for s in SAMPLE_STREAMS {
            let mut idx: Vec<usize> = (0..Self::len(rec, s)).collect();
            idx.sort_by(|&a, &b| Self::stamp_of(rec, s, a).total_cmp(&Self::stamp_of(rec, s, b)));
            order[s as usize] = idx;
        }
        Self {
            rec,
            order,
            velocities: WheelRates::new(rec.wheels.iter().copied())
                .map(|(_, v)| v)
                .collect(),
        }
    }

    /// Messages of sample stream `s` in `rec`.
    fn len(rec: &Recording, s: BagStream) -> usize {
        match s {
            BagStream::TfStatic => 0,
            BagStream::Reference => rec.reference.len(),
            BagStream::Imu => rec.gyro.len(),
            BagStream::Joints => rec.wheels.len(),
            BagStream::Scan => rec.scans.len(),
            BagStream::Odom => rec.odom.len(),
        }
    }

    /// Stamp of message `i` of sample stream `s` in `rec`.
    fn stamp_of(rec: &Recording, s: BagStream, i: usize) -> f64 {
        match s {
            BagStream::TfStatic => f64::NAN,
            BagStream::Reference => rec.reference[i].stamp,
            BagStream::Imu => rec.gyro[i].stamp,
            BagStream::Joints => rec.wheels[i].stamp,
            BagStream::Scan => rec.scans[i].stamp,
            BagStream::Odom => rec.odom[i].stamp,
        }
    }

    /// Index in `rec` of message `j` of stream `s`.
    fn at(&self, s: BagStream, j: usize) -> usize {
        self.order[s as usize][j]
    }
}

impl BagSource for InMemory<'_> {
    fn base_from_laser(&self) -> Option<Pose2> {
        self.rec.base_from_laser
    }
    fn reference_has_heading(&self) -> bool {
        self.rec.reference.iter().any(|p| p.has_heading)
    }
    fn start(&self) -> f64 {
        self.rec.time_span().map_or(0.0, |(a, _)| a)
    }
    fn count(&self, s: BagStream) -> usize {
        self.order[s as usize].len()
    }
    fn stamp(&self, s: BagStream, j: usize) -> f64 {
        Self::stamp_of(self.rec, s, self.at(s, j))
    }
    fn reference(&mut self, j: usize) -> StampedPose {
        self.rec.reference[self.at(BagStream::Reference, j)]
    }
    fn odom(&mut self, j: usize) -> StampedPose {
        self.rec.odom[self.at(BagStream::Odom, j)]
    }
    fn gyro(&mut self, j: usize) -> f64 {
        self.rec.gyro[self.at(BagStream::Imu, j)].wz
    }
    fn wheel(&mut self, j: usize) -> (WheelSample, (f64, f64)) {
        let i = self.at(BagStream::Joints, j);
        (self.rec.wheels[i], self.velocities[i])
    }
    fn scan(&mut self, j: usize) -> &LaserScan {
        &self.rec.scans[self.at(BagStream::Scan, j)]
    }
}

/// Writes the messages of `src` to `path`, streaming: the file grows
/// message by message in a temporary sibling that is renamed over `path`
/// once complete. The bytes equal those of [`write_mcap`] for a recording
/// holding the same messages.
pub fn write_mcap_streaming(
    path: &Path,
    src: &mut dyn BagSource,
    opts: &WriteOptions,
) -> Result<(), WriteError> {
    let file = path.display().to_string();
    let io_err = |source| WriteError::Io {
        file: file.clone(),
        source,
    };
    let mut out = AtomicWriter::create(path).map_err(io_err)?;
    encode_into(out.writer(), src, opts).map_err(|source| WriteError::Mcap {
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

/// Writes the messages of `src` as an MCAP file into `out`, and returns it
/// once the file is finished (summary not yet canonical).
fn encode_into<W: Write + Seek>(
    out: W,
    src: &mut dyn BagSource,
    opts: &WriteOptions,
) -> Result<W, mcap::McapError> {
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .library("odocal")
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .create(out)?;
    let ref_type = reference_type(src);
    let streams = streams(src, &opts.topics, ref_type);
    let channel = declare_channels(&mut w, &streams)?;
    let mut order = MessageOrder::new(&streams);
    let mut seq = [0u32; 6];
    let mut cdr = CdrWriter::new();
    while let Some((stamp, s, j)) = order.next(src) {
        let stamp = stamp + opts.clock_start_s;
        cdr.clear();
        encode(&mut cdr, src, opts, ref_type, (s, j, stamp));
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
type StreamDecl<'a> = (BagStream, &'a str, &'static str, usize);

/// Message type of the reference: odometry when any pose has a heading (or
/// there is none), points otherwise.
fn reference_type(src: &dyn BagSource) -> &'static str {
    if src.reference_has_heading() || src.count(BagStream::Reference) == 0 {
        OdometryMsg::TYPE
    } else {
        PointStampedMsg::TYPE
    }
}

/// The streams with messages, in the order their channels are declared.
fn streams<'a>(
    src: &dyn BagSource,
    t: &'a TopicConfig,
    ref_type: &'static str,
) -> Vec<StreamDecl<'a>> {
    let mut streams: Vec<StreamDecl<'a>> = Vec::new();
    if src.base_from_laser().is_some() {
        streams.push((BagStream::TfStatic, &t.tf_static, TfMessage::TYPE, 1));
    }
    for (s, topic, ty) in [
        (BagStream::Reference, &t.reference, ref_type),
        (BagStream::Imu, &t.imu, ImuMsg::TYPE),
        (BagStream::Joints, &t.joint_states, JointStateMsg::TYPE),
        (BagStream::Scan, &t.scan, LaserScanMsg::TYPE),
        (BagStream::Odom, &t.odom, OdometryMsg::TYPE),
    ] {
        let n = src.count(s);
        if n > 0 {
            streams.push((s, topic, ty, n));
        }
    }
    streams
}

/// Adds each stream's schema and channel; returns the channel ids indexed by
/// [`BagStream`].
fn declare_channels<W: Write + Seek>(
    w: &mut mcap::Writer<W>,
    streams: &[StreamDecl<'_>],
) -> Result<[u16; 6], mcap::McapError> {
    let mut channel = [0u16; 6];
    for &(s, topic, ty, _) in streams {
        let text = schema_text(ty).unwrap_or_default();
        let schema = w.add_schema(ty, "ros2msg", text.as_bytes())?;
        let qos = if s == BagStream::TfStatic {
            LATCHED_QOS
        } else {
            ""
        };
        let meta = BTreeMap::from([("offered_qos_profiles".to_string(), qos.to_string())]);
        channel[s as usize] = w.add_channel(schema, topic, "cdr", &meta)?;
    }
    Ok(channel)
}

/// Every message as (stamp, stream, index), merged from the streams (each
/// in its own stamp order) by stamp, ties in [`BagStream`] order: the order of
/// a sort of all messages by (stamp, stream, index), without holding them.
/// The static transform is stamped with the earliest stamp.
struct MessageOrder {
    /// Messages of each stream.
    count: [usize; 6],
    /// The next message of each stream to write.
    next: [usize; 6],
}

impl MessageOrder {
    fn new(streams: &[StreamDecl<'_>]) -> Self {
        let mut count = [0; 6];
        for &(s, _, _, n) in streams {
            count[s as usize] = n;
        }
        Self {
            count,
            next: [0; 6],
        }
    }

    /// The next message to write, if any.
    fn next(&mut self, src: &dyn BagSource) -> Option<(f64, BagStream, usize)> {
        let mut best: Option<(f64, BagStream, usize)> = None;
        for s in std::iter::once(BagStream::TfStatic).chain(SAMPLE_STREAMS) {
            let j = self.next[s as usize];
            if j >= self.count[s as usize] {
                continue;
            }
            let stamp = match s {
                BagStream::TfStatic => src.start(),
                _ => src.stamp(s, j),
            };
            if best.is_none_or(|(b, _, _)| stamp.total_cmp(&b).is_lt()) {
                best = Some((stamp, s, j));
            }
        }
        let (_, s, _) = best?;
        self.next[s as usize] += 1;
        best
    }
}

/// Writes message `j` of stream `s` of `src`, stamped `stamp`, into `cdr`;
/// the reference as `ref_type`.
fn encode(
    cdr: &mut CdrWriter,
    src: &mut dyn BagSource,
    opts: &WriteOptions,
    ref_type: &'static str,
    (s, j, stamp): (BagStream, usize, f64),
) {
    let header = |frame: &str| Header {
        stamp: Time::from_seconds(stamp),
        frame_id: frame.to_string(),
    };
    match s {
        BagStream::TfStatic => {
            tf_static(header(&opts.base_frame), opts, src.base_from_laser()).write(cdr)
        }
        BagStream::Reference if ref_type == PointStampedMsg::TYPE => {
            let p = src.reference(j).pose.translation.vector;
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
        BagStream::Reference => {
            odometry(header(&opts.world_frame), opts, &src.reference(j)).write(cdr)
        }
        BagStream::Odom => odometry(header(&opts.odom_frame), opts, &src.odom(j)).write(cdr),
        BagStream::Imu => imu(header(&opts.base_frame), src.gyro(j)).write(cdr),
        BagStream::Joints => {
            let (ws, rates) = src.wheel(j);
            joint_state(header(""), opts, &ws, rates).write(cdr)
        }
        BagStream::Scan => laser_scan(header(&opts.laser_frame), src.scan(j)).write(cdr),
    }
}

/// The base-to-laser transform (identity when the recording has none).
fn tf_static(header: Header, opts: &WriteOptions, base_from_laser: Option<Pose2>) -> TfMessage {
    let b = base_from_laser.unwrap_or_else(Pose2::identity);
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

/// Wheel samples with their rates (rad/s, left and right) by central
/// differences (one-sided at the ends; 0 where the stamps do not advance),
/// drawn one sample ahead of the samples given.
pub struct WheelRates<I: Iterator<Item = WheelSample>> {
    samples: std::iter::Peekable<I>,
    last: Option<WheelSample>,
}

impl<I: Iterator<Item = WheelSample>> WheelRates<I> {
    /// The rates of `samples`, in order.
    pub fn new(samples: I) -> Self {
        Self {
            samples: samples.peekable(),
            last: None,
        }
    }
}

impl<I: Iterator<Item = WheelSample>> Iterator for WheelRates<I> {
    type Item = (WheelSample, (f64, f64));

    fn next(&mut self) -> Option<Self::Item> {
        let now = self.samples.next()?;
        let a = self.last.unwrap_or(now);
        let b = self.samples.peek().copied().unwrap_or(now);
        self.last = Some(now);
        let dt = b.stamp - a.stamp;
        let rates = if dt > 0.0 {
            ((b.left - a.left) / dt, (b.right - a.right) / dt)
        } else {
            (0.0, 0.0)
        };
        Some((now, rates))
    }
}
