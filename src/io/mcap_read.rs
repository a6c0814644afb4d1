//! Reads a ROS 2 bag in MCAP (CDR messages, chunks plain or zstd/lz4) into a
//! [`Recording`]. Message types are recognised by schema name; topics come from
//! [`TopicConfig`]. Every problem is an [`InputError`] naming the file, the
//! topic and the message index (0-based, counted per topic).

use std::collections::HashMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::cdr::CdrError;
use super::ros_msgs::{
    ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg, PoseStampedMsg, RosMsg,
    TfMessage, Time,
};
use super::ros_schema::short_name;
use crate::error::InputError;
use crate::geom::{self, Pose2};
use crate::recording::{GyroSample, Recording, StampedPose, WheelSample};
use crate::robot::RobotConfig;
use crate::scan::LaserScan;

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

/// Reads an MCAP file into a [`Recording`] (streams sorted by stamp).
pub fn read_mcap(path: &Path, opts: &ReadOptions) -> Result<Recording, InputError> {
    let file = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| InputError::new(&file, format!("cannot read: {e}")))?;
    read_mcap_bytes(&bytes, &file, opts)
}

/// Like [`read_mcap`] for an MCAP already in memory; `file` names it in errors.
pub fn read_mcap_bytes(
    bytes: &[u8],
    file: &str,
    opts: &ReadOptions,
) -> Result<Recording, InputError> {
    let mcap_err = |e: mcap::McapError, after: usize| {
        let mut msg = format!("corrupt or truncated MCAP: {e}");
        if let Some(src) = std::error::Error::source(&e) {
            msg.push_str(&format!(" ({src})"));
        }
        InputError::new(file, msg).at(format!("after {after} messages"))
    };
    if let Err(e) = mcap::read::footer(bytes) {
        return Err(truncated(bytes, file, e));
    }
    let mut stream = mcap::read::RawMessageStream::new(bytes).map_err(|e| mcap_err(e, 0))?;
    let mut st = State::new(file, opts);
    let mut total = 0usize;
    let mut roles: HashMap<u16, (String, Vec<Role>)> = HashMap::new();
    let mut counts: HashMap<u16, usize> = HashMap::new();
    while let Some(msg) = stream.next() {
        let msg = msg.map_err(|e| mcap_err(e, total))?;
        total += 1;
        let id = msg.header.channel_id;
        if !roles.contains_key(&id) {
            let ch = stream.get_channel(id).ok_or_else(|| {
                InputError::new(file, format!("message refers to unknown channel {id}"))
                    .at(format!("after {total} messages"))
            })?;
            let r =
                channel_roles(&ch, opts).map_err(|m| InputError::new(file, m).topic(&ch.topic))?;
            roles.insert(id, (ch.topic.clone(), r));
        }
        let (topic, rs) = &roles[&id];
        let index = counts.entry(id).or_insert(0);
        let i = *index;
        *index += 1;
        for role in rs {
            st.handle(*role, &msg.data, msg.header.log_time)
                .map_err(|m| {
                    InputError::new(file, m)
                        .topic(topic)
                        .at(format!("message {i}"))
                })?;
        }
    }
    st.finish()
}

/// The error for a file without a valid footer: names the last message that
/// could still be read (topic and per-topic index), so the cut can be found.
fn truncated(bytes: &[u8], file: &str, e: mcap::McapError) -> InputError {
    let lenient = mcap::read::RawMessageStream::new_with_options(
        bytes,
        mcap::read::Options::IgnoreEndMagic.into(),
    );
    let mut last: Option<(String, usize)> = None;
    let mut counts: HashMap<u16, usize> = HashMap::new();
    if let Ok(mut stream) = lenient {
        while let Some(Ok(m)) = stream.next() {
            let id = m.header.channel_id;
            let c = counts.entry(id).or_insert(0);
            if let Some(ch) = stream.get_channel(id) {
                last = Some((ch.topic.clone(), *c));
            }
            *c += 1;
        }
    }
    let base = format!("truncated or corrupt MCAP (no valid footer: {e})");
    match last {
        Some((topic, i)) => InputError::new(
            file,
            format!("{base}; the last readable message is this one"),
        )
        .topic(topic)
        .at(format!("message {i}")),
        None => InputError::new(file, format!("{base}; no message is readable")),
    }
}

/// What a channel's messages become.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    Scan,
    Joints,
    Imu,
    Odom,
    RefOdometry,
    RefPose,
    RefPoint,
    TfStatic,
}

/// The roles a channel plays; a configured topic with an unexpected schema is
/// an error, other topics are ignored.
fn channel_roles(ch: &mcap::Channel<'_>, opts: &ReadOptions) -> Result<Vec<Role>, String> {
    let t = &opts.topics;
    let schema = ch
        .schema
        .as_ref()
        .map(|s| short_name(&s.name))
        .unwrap_or_default();
    let mut roles = Vec::new();
    let mut want = |topic: &str, accepted: &[(&str, Role)]| -> Result<(), String> {
        if ch.topic != topic {
            return Ok(());
        }
        match accepted.iter().find(|(n, _)| short_name(n) == schema) {
            Some((_, r)) => {
                roles.push(*r);
                Ok(())
            }
            None => {
                let names: Vec<&str> = accepted.iter().map(|(n, _)| *n).collect();
                Err(format!(
                    "schema '{}' where {} was expected",
                    if schema.is_empty() { "(none)" } else { &schema },
                    names.join(" or ")
                ))
            }
        }
    };
    want(&t.scan, &[(LaserScanMsg::TYPE, Role::Scan)])?;
    want(&t.joint_states, &[(JointStateMsg::TYPE, Role::Joints)])?;
    want(&t.imu, &[(ImuMsg::TYPE, Role::Imu)])?;
    want(&t.odom, &[(OdometryMsg::TYPE, Role::Odom)])?;
    want(
        &t.reference,
        &[
            (OdometryMsg::TYPE, Role::RefOdometry),
            (PoseStampedMsg::TYPE, Role::RefPose),
            (PointStampedMsg::TYPE, Role::RefPoint),
        ],
    )?;
    want(&t.tf_static, &[(TfMessage::TYPE, Role::TfStatic)])?;
    if !roles.is_empty() && ch.message_encoding != "cdr" {
        return Err(format!(
            "message encoding '{}' where cdr was expected",
            ch.message_encoding
        ));
    }
    Ok(roles)
}

/// Wheel readings before sorting: angles, or rates to integrate.
#[derive(Debug, Clone, Copy, PartialEq)]
enum WheelMode {
    Positions,
    Velocities,
}

/// Streams being collected, with the latest stamp seen per stream for the
/// time-order check.
struct State<'a> {
    file: &'a str,
    opts: &'a ReadOptions,
    rec: Recording,
    latest: HashMap<&'static str, f64>,
    wheel_mode: Option<WheelMode>,
    laser_frame: Option<String>,
    /// child → (parent, parent_from_child).
    tf: HashMap<String, (String, Pose2)>,
}

fn stamp_of(t: &Time, log_time: u64) -> f64 {
    if t.is_zero() {
        log_time as f64 * 1e-9
    } else {
        t.seconds()
    }
}

fn cdr(e: CdrError) -> String {
    e.to_string()
}

fn finite(what: &str, vals: &[f64]) -> Result<(), String> {
    if vals.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(format!("non-finite {what}: {vals:?}"))
    }
}

fn frame(f: &str) -> &str {
    f.trim_start_matches('/')
}

fn pose_of(p: &super::ros_msgs::Pose) -> Result<Pose2, String> {
    let yaw = p.orientation.yaw();
    finite("pose", &[p.position.x, p.position.y, yaw])?;
    Ok(geom::pose(p.position.x, p.position.y, yaw))
}

impl<'a> State<'a> {
    fn new(file: &'a str, opts: &'a ReadOptions) -> Self {
        Self {
            file,
            opts,
            rec: Recording {
                source: file.to_string(),
                ..Default::default()
            },
            latest: HashMap::new(),
            wheel_mode: None,
            laser_frame: None,
            tf: HashMap::new(),
        }
    }

    /// Refuses a stamp further back than the tolerance in its stream.
    fn check_order(&mut self, stream: &'static str, t: f64) -> Result<(), String> {
        if !t.is_finite() {
            return Err(format!("non-finite stamp {t}"));
        }
        let last = self.latest.entry(stream).or_insert(t);
        if t < *last - self.opts.reorder_tolerance {
            return Err(format!(
                "time goes backwards by {:.3} s (from {:.6} to {:.6}), more than the {} s tolerance",
                *last - t,
                *last,
                t,
                self.opts.reorder_tolerance
            ));
        }
        *last = last.max(t);
        Ok(())
    }

    fn handle(&mut self, role: Role, data: &[u8], log_time: u64) -> Result<(), String> {
        match role {
            Role::Scan => self.scan(data, log_time),
            Role::Joints => self.joints(data, log_time),
            Role::Imu => {
                let m = ImuMsg::decode(data).map_err(cdr)?;
                let t = stamp_of(&m.header.stamp, log_time);
                self.check_order("imu", t)?;
                let wz = m.angular_velocity.z;
                finite("angular_velocity.z", &[wz])?;
                self.rec.gyro.push(GyroSample { stamp: t, wz });
                Ok(())
            }
            Role::Odom | Role::RefOdometry => {
                let m = OdometryMsg::decode(data).map_err(cdr)?;
                let t = stamp_of(&m.header.stamp, log_time);
                let pose = pose_of(&m.pose)?;
                let sp = StampedPose {
                    stamp: t,
                    pose,
                    has_heading: true,
                };
                if role == Role::Odom {
                    self.check_order("odom", t)?;
                    self.rec.odom.push(sp);
                } else {
                    self.check_order("reference", t)?;
                    self.rec.reference.push(sp);
                }
                Ok(())
            }
            Role::RefPose => {
                let m = PoseStampedMsg::decode(data).map_err(cdr)?;
                let t = stamp_of(&m.header.stamp, log_time);
                self.check_order("reference", t)?;
                let pose = pose_of(&m.pose)?;
                self.rec.reference.push(StampedPose {
                    stamp: t,
                    pose,
                    has_heading: true,
                });
                Ok(())
            }
            Role::RefPoint => {
                let m = PointStampedMsg::decode(data).map_err(cdr)?;
                let t = stamp_of(&m.header.stamp, log_time);
                self.check_order("reference", t)?;
                finite("point", &[m.point.x, m.point.y])?;
                self.rec.reference.push(StampedPose {
                    stamp: t,
                    pose: geom::pose(m.point.x, m.point.y, 0.0),
                    has_heading: false,
                });
                Ok(())
            }
            Role::TfStatic => {
                let m = TfMessage::decode(data).map_err(cdr)?;
                for tr in m.transforms {
                    let yaw = tr.rotation.yaw();
                    finite("transform", &[tr.translation.x, tr.translation.y, yaw])?;
                    self.tf.insert(
                        frame(&tr.child_frame_id).to_string(),
                        (
                            frame(&tr.header.frame_id).to_string(),
                            geom::pose(tr.translation.x, tr.translation.y, yaw),
                        ),
                    );
                }
                Ok(())
            }
        }
    }

    fn scan(&mut self, data: &[u8], log_time: u64) -> Result<(), String> {
        let m = LaserScanMsg::decode(data).map_err(cdr)?;
        let t = stamp_of(&m.header.stamp, log_time);
        self.check_order("scan", t)?;
        if m.ranges.is_empty() {
            return Err("LaserScan with zero beams".into());
        }
        for (name, v) in [
            ("angle_min", m.angle_min),
            ("angle_increment", m.angle_increment),
            ("range_min", m.range_min),
            ("range_max", m.range_max),
        ] {
            if !v.is_finite() {
                return Err(format!("LaserScan {name} is {v}"));
            }
        }
        if m.angle_increment == 0.0 && m.ranges.len() > 1 {
            return Err("LaserScan angle_increment is 0 with several beams".into());
        }
        if self.laser_frame.is_none() {
            self.laser_frame = Some(frame(&m.header.frame_id).to_string());
        }
        self.rec.scans.push(LaserScan {
            stamp: t,
            angle_min: m.angle_min as f64,
            angle_increment: m.angle_increment as f64,
            time_increment: if m.time_increment.is_finite() {
                m.time_increment as f64
            } else {
                0.0
            },
            scan_time: if m.scan_time.is_finite() {
                m.scan_time as f64
            } else {
                0.0
            },
            range_min: m.range_min as f64,
            range_max: m.range_max as f64,
            ranges: m.ranges,
        });
        Ok(())
    }

    fn joints(&mut self, data: &[u8], log_time: u64) -> Result<(), String> {
        let m = JointStateMsg::decode(data).map_err(cdr)?;
        let t = stamp_of(&m.header.stamp, log_time);
        self.check_order("joint_states", t)?;
        let find = |name: &str| {
            m.name
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| format!("JointState has no joint '{name}' (names: {:?})", m.name))
        };
        let il = find(&self.opts.left_joint)?;
        let ir = find(&self.opts.right_joint)?;
        let has = |v: &Vec<f64>| v.len() == m.name.len();
        let mode = *self.wheel_mode.get_or_insert(if has(&m.position) {
            WheelMode::Positions
        } else {
            WheelMode::Velocities
        });
        let values = match mode {
            WheelMode::Positions if has(&m.position) => &m.position,
            WheelMode::Velocities if has(&m.velocity) => &m.velocity,
            _ => {
                return Err(format!(
                    "JointState has {} positions and {} velocities for {} names; \
                     the wheel {} are needed",
                    m.position.len(),
                    m.velocity.len(),
                    m.name.len(),
                    if mode == WheelMode::Positions {
                        "positions"
                    } else {
                        "velocities"
                    }
                ))
            }
        };
        let (left, right) = (values[il], values[ir]);
        finite("wheel joint value", &[left, right])?;
        self.rec.wheels.push(WheelSample {
            stamp: t,
            left,
            right,
        });
        Ok(())
    }

    /// Sorts, integrates wheel rates if needed and resolves the laser mount.
    fn finish(mut self) -> Result<Recording, InputError> {
        self.rec.sort_streams();
        if self.wheel_mode == Some(WheelMode::Velocities) {
            integrate_rates(&mut self.rec.wheels);
        }
        if let Some(laser) = &self.laser_frame {
            self.rec.base_from_laser = self
                .base_from(laser)
                .map_err(|m| InputError::new(self.file, m).topic(&self.opts.topics.tf_static))?;
        }
        Ok(self.rec)
    }

    /// `base_link_from_<frame>` by walking the static transforms up from
    /// `frame`; `None` when the chain does not reach `base_link`.
    fn base_from(&self, laser: &str) -> Result<Option<Pose2>, String> {
        if laser == "base_link" {
            return Ok(Some(Pose2::identity()));
        }
        let mut acc = Pose2::identity();
        let mut cur = laser;
        for _ in 0..32 {
            let Some((parent, p)) = self.tf.get(cur) else {
                return Ok(None);
            };
            acc = p * acc;
            if parent == "base_link" {
                return Ok(Some(acc));
            }
            cur = parent;
        }
        Err(format!("transform chain from '{laser}' loops"))
    }
}

/// Turns wheel rates (rad/s, stored in the angle fields) into angles (rad)
/// from 0 by the trapezoidal rule.
fn integrate_rates(w: &mut [WheelSample]) {
    let mut prev: Option<WheelSample> = None;
    let (mut l, mut r) = (0.0, 0.0);
    for s in w.iter_mut() {
        let rate = *s;
        if let Some(p) = prev {
            let dt = rate.stamp - p.stamp;
            l += 0.5 * (p.left + rate.left) * dt;
            r += 0.5 * (p.right + rate.right) * dt;
        }
        prev = Some(rate);
        s.left = l;
        s.right = r;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_integrate_to_angles() {
        let mut w: Vec<WheelSample> = (0..11)
            .map(|i| WheelSample {
                stamp: i as f64 * 0.1,
                left: 2.0,
                right: -1.0,
            })
            .collect();
        integrate_rates(&mut w);
        assert_eq!(w[0].left, 0.0);
        assert!((w[10].left - 2.0).abs() < 1e-12);
        assert!((w[10].right + 1.0).abs() < 1e-12);
    }

    #[test]
    fn topic_config_reads_partial_toml() {
        let t: TopicConfig = toml::from_str("reference = \"/reference\"").unwrap();
        assert_eq!(t.reference, "/reference");
        assert_eq!(t.scan, "/scan");
        assert!(toml::from_str::<TopicConfig>("bogus = 1").is_err());
    }
}
