//! What a recording holds, whatever odocal is configured to read: every
//! topic with its type, message count, receive-time span, rate and gaps; the
//! transforms of every `tf2_msgs/TFMessage` topic; and what the first
//! message of each topic odocal could use says (the scan frame, the joint
//! names, an odometry's frames and whether its twist ever moves). It reads
//! every bag format through the same raw readers as the streams
//! (`bag_stream::RawMessages`) with [`ReadOptions::all_topics`]
//! set, and a CARMEN log through its reader. `odocal inspect` builds on it.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::bag_stream::{Fail, Raw, RawMessages};
use super::format::{sniff, Format};
use super::mcap_streams::Wire;
use super::options::ReadOptions;
use super::ros_msgs::{JointStateMsg, LaserScanMsg, OdometryMsg, RosMsg, TfMessage};
use super::ros_schema::short_name;
use crate::error::InputError;

/// A gap counts when it is longer than this many median periods of its
/// topic (and longer than [`GAP_MIN_S`]).
pub const GAP_PERIODS: f64 = 5.0;
/// Shortest interval between two messages that counts as a gap (s).
pub const GAP_MIN_S: f64 = 0.5;

/// One topic of a recording.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TopicSurvey {
    /// Topic name (a CARMEN log: the record kind, e.g. `FLASER`).
    pub topic: String,
    /// Message type as the file names it, in ROS 2 form (`pkg/msg/Type`).
    #[serde(rename = "type")]
    pub type_name: String,
    /// Messages.
    pub count: usize,
    /// Receive time of the first and last message (s).
    pub first_s: f64,
    /// See `first_s`.
    pub last_s: f64,
    /// Median message rate (Hz): 1 / the median interval; `None` with
    /// fewer than 2 messages or all at one instant.
    pub rate_hz: Option<f64>,
    /// Intervals longer than [`GAP_PERIODS`] median periods and [`GAP_MIN_S`].
    pub gaps: usize,
    /// The longest interval between two messages (s) and when it started (s).
    pub longest_gap_s: Option<[f64; 2]>,
    /// What the first message says (types odocal reads), if decoded.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub detail: Option<Detail>,
}

/// What the messages of a type odocal reads say.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Detail {
    /// `sensor_msgs/LaserScan`: its frame and geometry (first message).
    Scan {
        /// `header.frame_id`.
        frame: String,
        /// Beams per scan.
        beams: usize,
        /// Field of view (rad).
        fov_rad: f64,
        /// `range_max` (m).
        range_max: f64,
    },
    /// `sensor_msgs/JointState`: the joints of the first message and
    /// which values it carries.
    JointState {
        /// Joint names.
        names: Vec<String>,
        /// Positions given.
        positions: bool,
        /// Velocities given.
        velocities: bool,
    },
    /// `nav_msgs/Odometry`: frames, and whether the twist or the pose ever
    /// changes over all messages.
    Odometry {
        /// `header.frame_id`.
        frame: String,
        /// `child_frame_id`.
        child_frame: String,
        /// Some message has a non-zero `linear.x` or `angular.z`.
        twist_moves: bool,
        /// Some message's position differs from the first one's.
        pose_moves: bool,
    },
    /// Any other message with a header: its frame (first message).
    Frame {
        /// `header.frame_id`.
        frame: String,
    },
}

/// One transform: `parent_from_child` in the plane.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TfEdge {
    /// Parent frame (leading `/` removed).
    pub parent: String,
    /// Child frame.
    pub child: String,
    /// The topic it came on.
    pub topic: String,
    /// Whether it is on a static topic (`/tf_static`, by name).
    #[serde(rename = "static")]
    pub is_static: bool,
    /// Translation x, y, z (m) of the first transform of this pair.
    pub xyz: [f64; 3],
    /// Yaw (rad) of that transform.
    pub yaw: f64,
    /// How many times this pair was sent.
    pub count: usize,
}

/// What a recording holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Survey {
    /// The file or folder.
    pub file: String,
    /// The format, as [`format_word`] names it.
    pub format: &'static str,
    /// Every topic, by name.
    pub topics: Vec<TopicSurvey>,
    /// Every parent → child pair of the transform topics.
    pub transforms: Vec<TfEdge>,
    /// A CARMEN log: the laser mounting its laser lines state, `[x, y, yaw]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log_mount: Option<[f64; 3]>,
    /// A CARMEN log: why it states no mounting.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log_mount_note: Option<String>,
}

impl Survey {
    /// The topic named `name`.
    pub fn topic(&self, name: &str) -> Option<&TopicSurvey> {
        self.topics.iter().find(|t| t.topic == name)
    }

    /// The topics of type `ty` (`pkg/msg/Type`), most messages first.
    pub fn of_type(&self, ty: &str) -> Vec<&TopicSurvey> {
        let mut v: Vec<&TopicSurvey> = self
            .topics
            .iter()
            .filter(|t| short_name(&t.type_name) == short_name(ty))
            .collect();
        v.sort_by(|a, b| b.count.cmp(&a.count).then(a.topic.cmp(&b.topic)));
        v
    }

    /// Whether the input is a bag (it has topics and transforms).
    pub fn is_bag(&self) -> bool {
        self.format != FORMAT_WORDS[4] && self.format != FORMAT_WORDS[5]
    }
}

const FORMAT_WORDS: [&str; 6] = [
    "ROS 2 bag (MCAP)",
    "ROS 1 bag (format 2.0)",
    "rosbag2 SQLite (.db3)",
    "rosbag2 folder",
    "CARMEN log",
    "Censi et al. calibration tuples",
];

/// How a format is named in a survey.
pub fn format_word(f: Format) -> &'static str {
    match f {
        Format::Mcap => FORMAT_WORDS[0],
        Format::Ros1Bag => FORMAT_WORDS[1],
        Format::Rosbag2Sqlite => FORMAT_WORDS[2],
        Format::Rosbag2Dir => FORMAT_WORDS[3],
        Format::Text => FORMAT_WORDS[4],
        Format::CensiTuples => FORMAT_WORDS[5],
    }
}

/// Surveys the recording at `path` (any format [`sniff`] knows).
pub fn survey(path: &Path) -> Result<Survey, InputError> {
    let format = sniff(path)?;
    let file = path.display().to_string();
    let opts = ReadOptions {
        all_topics: true,
        ..ReadOptions::default()
    };
    let mut s = Survey {
        file: file.clone(),
        format: format_word(format),
        topics: Vec::new(),
        transforms: Vec::new(),
        log_mount: None,
        log_mount_note: None,
    };
    match format {
        Format::Mcap => walk(super::mcap_stream::raw_messages(path, &opts)?, &mut s),
        Format::Ros1Bag => walk(super::ros1_bag::Ros1Messages::open(path, &opts)?, &mut s),
        Format::Rosbag2Sqlite => walk(super::rosbag2_db3::Db3Messages::open(path, &opts)?, &mut s),
        Format::Rosbag2Dir => walk(super::rosbag2_dir::DirMessages::open(path, &opts)?, &mut s),
        Format::Text => carmen(path, &mut s),
        Format::CensiTuples => tuples(path, &mut s),
    }?;
    Ok(s)
}

/// Messages of a bag read by [`first_stamp`]: its first stamp is the
/// earliest receive time among them (a bag's chunks are written about in
/// time order, not exactly).
const FIRST_STAMP_MESSAGES: usize = 256;

/// When a recording began (s since 1970-01-01, UTC, as its clock says): the
/// earliest receive time of a bag's first messages, a CARMEN log's first
/// record; `None` when it holds no message or no clock (Censi et al.'s
/// tuples). Whether the clock is a date is the caller's call (a simulated
/// or boot-time clock starts near 0).
pub fn first_stamp(path: &Path) -> Result<Option<f64>, InputError> {
    let opts = ReadOptions {
        all_topics: true,
        ..ReadOptions::default()
    };
    match sniff(path)? {
        Format::Mcap => earliest(super::mcap_stream::raw_messages(path, &opts)?),
        Format::Ros1Bag => earliest(super::ros1_bag::Ros1Messages::open(path, &opts)?),
        Format::Rosbag2Sqlite => earliest(super::rosbag2_db3::Db3Messages::open(path, &opts)?),
        Format::Rosbag2Dir => earliest(super::rosbag2_dir::DirMessages::open(path, &opts)?),
        Format::Text => {
            let rec = super::carmen::read_carmen(path, &opts)?;
            let firsts = [
                rec.scans.first().map(|s| s.stamp),
                rec.odom.first().map(|o| o.stamp),
            ];
            Ok(firsts.into_iter().flatten().reduce(f64::min))
        }
        Format::CensiTuples => Ok(None),
    }
}

/// The earliest receive time (s) of the first [`FIRST_STAMP_MESSAGES`].
fn earliest<M: RawMessages>(mut m: M) -> Result<Option<f64>, InputError> {
    let mut first: Option<u64> = None;
    for _ in 0..FIRST_STAMP_MESSAGES {
        match m.next_raw() {
            Ok(Some(raw)) => first = Some(first.map_or(raw.log_time, |f| f.min(raw.log_time))),
            Ok(None) => break,
            Err(f) => return Err(fail(f, m.name())),
        }
    }
    Ok(first.map(|ns| ns as f64 * 1e-9))
}

/// Per-topic tallies while the messages go by.
#[derive(Default)]
struct Tally {
    type_name: String,
    times: Vec<f64>,
    detail: Option<Detail>,
    first_position: Option<[f64; 2]>,
}

/// Reads every message of a bag into `s`.
fn walk<M: RawMessages>(mut m: M, s: &mut Survey) -> Result<(), InputError> {
    let wire = m.wire();
    let mut topics: BTreeMap<String, Tally> = BTreeMap::new();
    let mut edges: BTreeMap<(String, String, String), TfEdge> = BTreeMap::new();
    loop {
        let raw = match m.next_raw() {
            Ok(Some(r)) => r,
            Ok(None) => break,
            Err(f) => return Err(fail(f, m.name())),
        };
        let tally = topics.entry(raw.topic.clone()).or_default();
        if tally.times.is_empty() {
            tally.type_name = ros2_type(&raw.type_name);
        }
        tally.times.push(raw.log_time as f64 * 1e-9);
        let located = |e: String| {
            InputError::new(m.name(), e)
                .topic(raw.topic.as_str())
                .at(raw.at.to_string())
        };
        look(tally, &raw, wire, &mut edges).map_err(located)?;
    }
    s.topics = topics
        .into_iter()
        .map(|(topic, t)| summarise(topic, t.type_name, &t.times, t.detail))
        .collect();
    s.transforms = edges.into_values().collect();
    Ok(())
}

fn fail(f: Fail, name: &str) -> InputError {
    match f {
        Fail::Input(e) => e,
        Fail::Format(m) => InputError::new(name, format!("corrupt or truncated: {m}")),
    }
}

/// `pkg/Type` (ROS 1) as `pkg/msg/Type`; ROS 2 names unchanged.
fn ros2_type(t: &str) -> String {
    match t.split_once('/') {
        Some((pkg, name)) if !name.contains('/') => format!("{pkg}/msg/{name}"),
        _ => t.to_string(),
    }
}

fn decode<M: RosMsg>(wire: Wire, data: &[u8]) -> Result<M, String> {
    match wire {
        Wire::Cdr => M::decode(data),
        Wire::Ros1 => M::decode_ros1(data),
    }
    .map_err(|e| format!("{} does not decode: {e}", short_name(M::TYPE)))
}

/// Decodes what a message of a known type says into its topic's tally.
fn look(
    tally: &mut Tally,
    raw: &Raw,
    wire: Wire,
    edges: &mut BTreeMap<(String, String, String), TfEdge>,
) -> Result<(), String> {
    let ty = short_name(&tally.type_name);
    let first = tally.times.len() == 1;
    if ty == short_name(TfMessage::TYPE) {
        let m: TfMessage = decode(wire, &raw.data)?;
        transforms(m, &raw.topic, edges);
    } else if ty == short_name(LaserScanMsg::TYPE) && first {
        let m: LaserScanMsg = decode(wire, &raw.data)?;
        tally.detail = Some(Detail::Scan {
            frame: m.header.frame_id.trim_start_matches('/').to_string(),
            beams: m.ranges.len(),
            fov_rad: (m.angle_max - m.angle_min) as f64,
            range_max: m.range_max as f64,
        });
    } else if ty == short_name(JointStateMsg::TYPE) && first {
        let m: JointStateMsg = decode(wire, &raw.data)?;
        tally.detail = Some(Detail::JointState {
            positions: !m.position.is_empty() && m.position.len() == m.name.len(),
            velocities: !m.velocity.is_empty() && m.velocity.len() == m.name.len(),
            names: m.name,
        });
    } else if ty == short_name(OdometryMsg::TYPE) {
        let m: OdometryMsg = decode(wire, &raw.data)?;
        odometry(tally, &m);
    } else if first && has_header(&ty) {
        let frame = header_frame(wire, &raw.data);
        tally.detail = frame.map(|frame| Detail::Frame { frame });
    }
    Ok(())
}

/// Message types (short names) that start with a `std_msgs/Header`.
fn has_header(ty: &str) -> bool {
    [
        "sensor_msgs/Imu",
        "geometry_msgs/PoseStamped",
        "geometry_msgs/PointStamped",
        "geometry_msgs/TwistStamped",
        "geometry_msgs/PoseWithCovarianceStamped",
        "sensor_msgs/PointCloud2",
    ]
    .contains(&ty)
}

/// The `header.frame_id` of a message that starts with a header.
fn header_frame(wire: Wire, data: &[u8]) -> Option<String> {
    let mut r = match wire {
        Wire::Cdr => super::cdr::CdrReader::new(data).ok()?,
        Wire::Ros1 => super::cdr::CdrReader::ros1(data),
    };
    if r.is_ros1() {
        r.u32().ok()?;
    }
    r.u32().ok()?;
    r.u32().ok()?;
    Some(r.string().ok()?.trim_start_matches('/').to_string())
}

fn odometry(tally: &mut Tally, m: &OdometryMsg) {
    let p = [m.pose.position.x, m.pose.position.y];
    let first = *tally.first_position.get_or_insert(p);
    let twist = m.linear.x != 0.0 || m.angular.z != 0.0;
    let moved = p != first;
    match &mut tally.detail {
        Some(Detail::Odometry {
            twist_moves,
            pose_moves,
            ..
        }) => {
            *twist_moves |= twist;
            *pose_moves |= moved;
        }
        _ => {
            tally.detail = Some(Detail::Odometry {
                frame: m.header.frame_id.trim_start_matches('/').to_string(),
                child_frame: m.child_frame_id.trim_start_matches('/').to_string(),
                twist_moves: twist,
                pose_moves: moved,
            })
        }
    }
}

fn transforms(m: TfMessage, topic: &str, edges: &mut BTreeMap<(String, String, String), TfEdge>) {
    for tr in m.transforms {
        let parent = tr.header.frame_id.trim_start_matches('/').to_string();
        let child = tr.child_frame_id.trim_start_matches('/').to_string();
        let key = (topic.to_string(), parent.clone(), child.clone());
        edges
            .entry(key)
            .and_modify(|e| e.count += 1)
            .or_insert_with(|| TfEdge {
                parent,
                child,
                topic: topic.to_string(),
                is_static: topic.trim_start_matches('/').ends_with("tf_static"),
                xyz: [tr.translation.x, tr.translation.y, tr.translation.z],
                yaw: tr.rotation.yaw(),
                count: 1,
            });
    }
}

/// A topic's figures from its receive times (s, in file order).
fn summarise(
    topic: String,
    type_name: String,
    times: &[f64],
    detail: Option<Detail>,
) -> TopicSurvey {
    let mut sorted = times.to_vec();
    sorted.sort_by(f64::total_cmp);
    let dts: Vec<f64> = sorted.windows(2).map(|w| w[1] - w[0]).collect();
    let median = {
        let mut d = dts.clone();
        d.sort_by(f64::total_cmp);
        d.get(d.len() / 2).copied()
    };
    let rate_hz = median.filter(|m| *m > 0.0).map(|m| 1.0 / m);
    let limit = median.map_or(f64::INFINITY, |m| (GAP_PERIODS * m).max(GAP_MIN_S));
    let gaps = dts.iter().filter(|d| **d > limit).count();
    let longest_gap_s = dts
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, d)| [*d, sorted[i]]);
    TopicSurvey {
        topic,
        type_name,
        count: times.len(),
        first_s: sorted.first().copied().unwrap_or(f64::NAN),
        last_s: sorted.last().copied().unwrap_or(f64::NAN),
        rate_hz,
        gaps,
        longest_gap_s,
        detail,
    }
}

/// A CARMEN log: its scans and odometry as two pseudo-topics, and the
/// mounting its laser lines state.
fn carmen(path: &Path, s: &mut Survey) -> Result<(), InputError> {
    let rec = super::carmen::read_carmen(path, &ReadOptions::default())?;
    let scans: Vec<f64> = rec.scans.iter().map(|x| x.stamp).collect();
    let odom: Vec<f64> = rec.odom.iter().map(|x| x.stamp).collect();
    if !scans.is_empty() {
        let first = &rec.scans[0];
        let detail = Detail::Scan {
            frame: String::new(),
            beams: first.ranges.len(),
            fov_rad: first.angle_increment * (first.ranges.len().max(1) - 1) as f64,
            range_max: first.range_max,
        };
        s.topics.push(summarise(
            "FLASER / ROBOTLASER1".into(),
            "carmen laser line".into(),
            &scans,
            Some(detail),
        ));
    }
    if !odom.is_empty() {
        s.topics.push(summarise(
            "ODOM".into(),
            "carmen odometry line".into(),
            &odom,
            None,
        ));
    }
    s.log_mount = rec.base_from_laser.map(|p| crate::geom::xyt(&p));
    s.log_mount_note = rec.mount_note;
    Ok(())
}

/// Censi et al.'s tuples: one pseudo-topic with their count.
fn tuples(path: &Path, s: &mut Survey) -> Result<(), InputError> {
    let t = super::censi::read(path)?;
    let times: Vec<f64> = t
        .iter()
        .scan(0.0, |acc, x| {
            *acc += x.t;
            Some(*acc)
        })
        .collect();
    s.topics.push(summarise(
        "tuples".into(),
        "censi tuple".into(),
        &times,
        None,
    ));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros1_names_become_ros2_names() {
        assert_eq!(
            ros2_type("sensor_msgs/LaserScan"),
            "sensor_msgs/msg/LaserScan"
        );
        assert_eq!(
            ros2_type("sensor_msgs/msg/LaserScan"),
            "sensor_msgs/msg/LaserScan"
        );
    }

    #[test]
    fn gaps_are_counted_against_the_median_period() {
        let mut t: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        t.extend((0..10).map(|i| 12.0 + i as f64 * 0.1));
        let s = summarise("/a".into(), "x/msg/Y".into(), &t, None);
        assert_eq!(s.count, 110);
        assert!((s.rate_hz.unwrap() - 10.0).abs() < 1e-6);
        assert_eq!(s.gaps, 1);
        let [len, at] = s.longest_gap_s.unwrap();
        assert!((len - 2.1).abs() < 1e-9 && (at - 9.9).abs() < 1e-9);
    }
}
