//! Turns decoded ROS messages into the streams of a [`Recording`]: stamps,
//! the time-order check, the wheels from the source the robot file names
//! ([`super::wheel_msgs`]), scan validation, and the laser mount from the
//! static transforms.

use std::collections::HashMap;

use super::cdr::{CdrError, CdrReader};
use super::options::ReadOptions;
use super::ros_msgs::{
    read_int_array, ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg,
    PoseStampedMsg, RosMsg, TfMessage, Time,
};
use super::ros_schema::short_name;
use super::wheel_msgs::WheelDecoder;
use crate::assumptions::Origin;
use crate::error::InputError;
use crate::geom::{self, Pose2};
use crate::recording::{GyroSample, Recording, StampedPose, WheelSample};
use crate::robot::WheelSourceKind;
use crate::scan::LaserScan;

/// `base_from_laser`, where it came from, and why there is none.
pub type StreamMount = (Option<Pose2>, Option<Origin>, Option<String>);

/// What a channel's messages become.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Role {
    /// LaserScan → `scans`.
    Scan,
    /// The robot file's wheel source (JointState, Odometry twist or tick
    /// counters) → `wheels`.
    Wheels,
    /// Imu → `gyro`.
    Imu,
    /// Odometry → `odom`.
    Odom,
    /// Odometry → `reference`.
    RefOdometry,
    /// PoseStamped → `reference`.
    RefPose,
    /// PointStamped → `reference` without heading.
    RefPoint,
    /// TFMessage → `base_from_laser`.
    TfStatic,
    /// TFMessage on /tf → `base_from_laser` when /tf_static has none (the
    /// first transform of each child frame).
    Tf,
    /// Any topic, whatever its type, for a survey of the whole bag
    /// ([`ReadOptions::all_topics`]); decoded by [`super::survey`], not here.
    Survey,
}

/// How a bag serialises its messages: CDR (ROS 2) or ROS 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Wire {
    /// ROS 2: CDR with its encapsulation header (MCAP, rosbag2 SQLite).
    Cdr,
    /// ROS 1 bags: packed little endian, `Header` with `seq`.
    Ros1,
}

impl Wire {
    /// The message encoding a channel of this wire must declare.
    fn encoding(self) -> &'static str {
        match self {
            Wire::Cdr => "cdr",
            Wire::Ros1 => "ros1",
        }
    }
}

/// Streams being collected, with the latest stamp seen per stream (and
/// whether it was a log time) for the time-order check.
pub(crate) struct State<'a> {
    file: String,
    opts: &'a ReadOptions,
    wire: Wire,
    rec: Recording,
    /// Per stream name (a handful): latest stamp (s), from a log time.
    latest: Vec<(&'static str, (f64, bool))>,
    wheels: WheelDecoder,
    laser_frame: Option<String>,
    /// child → (parent, parent_from_child).
    tf: HashMap<String, (String, Pose2)>,
    /// The same from /tf: the first transform seen of each child frame.
    tf_dynamic: HashMap<String, (String, Pose2)>,
    /// The messages decoded into, one after the other.
    bufs: Buffers,
}

/// The messages of the busiest streams, each decoded into again and again
/// ([`RosMsg::read_into`]), so that decoding one allocates nothing but what
/// its sample keeps (a scan's ranges).
#[derive(Default)]
struct Buffers {
    odom: OdometryMsg,
    scan: LaserScanMsg,
    tf: TfMessage,
}

/// Decodes `data`, serialised as `wire`, into `m`.
fn decode_into<M: RosMsg>(wire: Wire, m: &mut M, data: &[u8]) -> Result<(), String> {
    match wire {
        Wire::Cdr => m.decode_into(data),
        Wire::Ros1 => m.decode_ros1_into(data),
    }
    .map_err(cdr)
}

/// The stamp (s) of a message: its header stamp, or its log time when the
/// header stamp is zero (unset); `true` when the log time was used. A negative
/// stamp or nanoseconds ≥ 10⁹ are not a valid `builtin_interfaces/Time`.
fn stamp_of(t: &Time, log_time: u64) -> Result<(f64, bool), String> {
    if t.is_zero() {
        return Ok((log_time as f64 * 1e-9, true));
    }
    if t.sec < 0 {
        return Err(format!("invalid header stamp: negative sec {}", t.sec));
    }
    if t.nanosec >= 1_000_000_000 {
        return Err(format!(
            "invalid header stamp: nanosec {} is not below 10⁹",
            t.nanosec
        ));
    }
    Ok((t.seconds(), false))
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

/// A planar pose and whether it has a heading: an all-zero quaternion (the
/// usual "orientation unknown") gives none, and heading 0.
fn pose_of(p: &super::ros_msgs::Pose) -> Result<(Pose2, bool), String> {
    let q = &p.orientation;
    let has_heading = [q.x, q.y, q.z, q.w].iter().any(|&c| c != 0.0);
    let yaw = if has_heading { q.yaw() } else { 0.0 };
    finite("pose", &[p.position.x, p.position.y, yaw])?;
    Ok((geom::pose(p.position.x, p.position.y, yaw), has_heading))
}

impl<'a> State<'a> {
    pub(crate) fn new(file: &str, opts: &'a ReadOptions) -> Self {
        Self::with_wire(file, opts, Wire::Cdr)
    }

    /// A state that decodes messages serialised as `wire`.
    pub(crate) fn with_wire(file: &str, opts: &'a ReadOptions, wire: Wire) -> Self {
        Self {
            file: file.to_string(),
            opts,
            wire,
            rec: Recording {
                source: file.to_string(),
                ..Default::default()
            },
            latest: Vec::new(),
            wheels: WheelDecoder::default(),
            laser_frame: None,
            tf: HashMap::new(),
            tf_dynamic: HashMap::new(),
            bufs: Buffers::default(),
        }
    }

    /// Decodes one message in this state's wire format.
    fn decode<M: RosMsg>(&self, data: &[u8]) -> Result<M, String> {
        match self.wire {
            Wire::Cdr => M::decode(data),
            Wire::Ros1 => M::decode_ros1(data),
        }
        .map_err(cdr)
    }

    /// The stamp of a message in `stream` (see [`stamp_of`]); refuses one
    /// further back than the tolerance from the latest stamp of its stream.
    fn stamp(&mut self, stream: &'static str, stamp: &Time, log_time: u64) -> Result<f64, String> {
        if stamp.is_zero() && !self.opts.log_time_for_unset {
            return Err(
                "header stamp unset (zero), and no log time on the stamps' clock to \
                 stand in for it (a live stream's timestamps are its writer's clock)"
                    .into(),
            );
        }
        let (t, from_log) = stamp_of(stamp, log_time)?;
        self.in_order(stream, t, from_log)
    }

    /// `t` (s), checked against the latest stamp of `stream`; `from_log`:
    /// a log time stood in for an unset header stamp.
    fn in_order(&mut self, stream: &'static str, t: f64, from_log: bool) -> Result<f64, String> {
        let i = match self.latest.iter().position(|(s, _)| *s == stream) {
            Some(i) => i,
            None => {
                self.latest.push((stream, (t, from_log)));
                self.latest.len() - 1
            }
        };
        let (last, last_from_log) = self.latest[i].1;
        if t < last - self.opts.reorder_tolerance {
            let hint = if from_log || last_from_log {
                "; a zero (unset) header stamp was replaced by the log time, and the \
                 header and log clocks differ"
            } else {
                ""
            };
            return Err(format!(
                "time goes backwards by {:.3} s (from {:.6} to {:.6}), more than the {} s \
                 tolerance{hint}",
                last - t,
                last,
                t,
                self.opts.reorder_tolerance
            ));
        }
        if t >= last {
            self.latest[i].1 = (t, from_log);
        }
        Ok(t)
    }

    pub(crate) fn handle(&mut self, role: Role, data: &[u8], log_time: u64) -> Result<(), String> {
        match role {
            Role::Scan => self.scan(data, log_time),
            Role::Wheels => self.wheels(data, log_time),
            Role::Imu => {
                let m: ImuMsg = self.decode(data)?;
                let t = self.stamp("imu", &m.header.stamp, log_time)?;
                let wz = m.angular_velocity.z;
                finite("angular_velocity.z", &[wz])?;
                self.rec.gyro.push(GyroSample { stamp: t, wz });
                Ok(())
            }
            Role::Odom | Role::RefOdometry => self.odometry(role, data, log_time),
            Role::RefPose => {
                let m: PoseStampedMsg = self.decode(data)?;
                let t = self.stamp("reference", &m.header.stamp, log_time)?;
                let (pose, has_heading) = pose_of(&m.pose)?;
                self.rec.reference.push(StampedPose {
                    stamp: t,
                    pose,
                    has_heading,
                });
                Ok(())
            }
            Role::RefPoint => {
                let m: PointStampedMsg = self.decode(data)?;
                let t = self.stamp("reference", &m.header.stamp, log_time)?;
                finite("point", &[m.point.x, m.point.y])?;
                self.rec.reference.push(StampedPose {
                    stamp: t,
                    pose: geom::pose(m.point.x, m.point.y, 0.0),
                    has_heading: false,
                });
                Ok(())
            }
            Role::Survey => Ok(()),
            Role::TfStatic | Role::Tf => self.transforms(role, data),
        }
    }

    /// An Odometry message: the odometry stream (`role` Odom) or the
    /// reference (RefOdometry).
    fn odometry(&mut self, role: Role, data: &[u8], log_time: u64) -> Result<(), String> {
        decode_into(self.wire, &mut self.bufs.odom, data)?;
        let m = &self.bufs.odom;
        let (stamp, posed) = (m.header.stamp, pose_of(&m.pose));
        let stream = if role == Role::Odom {
            "odom"
        } else {
            "reference"
        };
        let t = self.stamp(stream, &stamp, log_time)?;
        let (pose, has_heading) = posed?;
        let sp = StampedPose {
            stamp: t,
            pose,
            has_heading,
        };
        if role == Role::Odom {
            if !has_heading {
                return Err("odometry with an all-zero orientation quaternion".into());
            }
            self.rec.odom.push(sp);
        } else {
            self.rec.reference.push(sp);
        }
        Ok(())
    }

    /// A TFMessage on /tf (`role` Tf: the first transform of each child
    /// kept) or /tf_static.
    fn transforms(&mut self, role: Role, data: &[u8]) -> Result<(), String> {
        decode_into(self.wire, &mut self.bufs.tf, data)?;
        let map = if role == Role::Tf {
            &mut self.tf_dynamic
        } else {
            &mut self.tf
        };
        for tr in &self.bufs.tf.transforms {
            let yaw = tr.rotation.yaw();
            finite("transform", &[tr.translation.x, tr.translation.y, yaw])?;
            let child = frame(&tr.child_frame_id);
            if role == Role::Tf && map.contains_key(child) {
                continue;
            }
            map.insert(
                child.to_string(),
                (
                    frame(&tr.header.frame_id).to_string(),
                    geom::pose(tr.translation.x, tr.translation.y, yaw),
                ),
            );
        }
        Ok(())
    }

    fn scan(&mut self, data: &[u8], log_time: u64) -> Result<(), String> {
        decode_into(self.wire, &mut self.bufs.scan, data)?;
        let stamp = self.bufs.scan.header.stamp;
        let t = self.stamp("scan", &stamp, log_time)?;
        let m = &mut self.bufs.scan;
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
        let scan = LaserScan {
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
            ranges: std::mem::take(&mut m.ranges),
        };
        scan.check_geometry(Some(m.angle_max as f64))?;
        if self.laser_frame.is_none() {
            self.laser_frame = Some(frame(&m.header.frame_id).to_string());
        }
        self.rec.scans.push(scan);
        Ok(())
    }

    /// A wheel message of the robot file's source: its stamp (the log time
    /// for tick arrays, which have no header) and the wheel values.
    fn wheels(&mut self, data: &[u8], log_time: u64) -> Result<(), String> {
        let opts = self.opts;
        let (t, (left, right)) = match opts.wheels.source {
            WheelSourceKind::JointStates => {
                let m: JointStateMsg = self.decode(data)?;
                let t = self.stamp("wheels", &m.header.stamp, log_time)?;
                (t, self.wheels.joint_state(&m, opts)?)
            }
            WheelSourceKind::Odometry => {
                decode_into(self.wire, &mut self.bufs.odom, data)?;
                let stamp = self.bufs.odom.header.stamp;
                let t = self.stamp("wheels", &stamp, log_time)?;
                (t, self.wheels.twist(&self.bufs.odom, opts)?)
            }
            WheelSourceKind::Ticks => {
                let ty = opts.wheels.ticks_layout().map(|l| l.ticks_type);
                let ty = ty.ok_or("[wheels] source = \"ticks\" without ticks_type")?;
                let mut r = match self.wire {
                    Wire::Cdr => CdrReader::new(data).map_err(cdr)?,
                    Wire::Ros1 => CdrReader::ros1(data),
                };
                let counts = read_int_array(&mut r, ty).map_err(cdr)?;
                let t = self.in_order("wheels", log_time as f64 * 1e-9, false)?;
                (t, self.wheels.ticks(&counts, opts)?)
            }
        };
        self.rec.wheel_values = self.wheels.values();
        self.rec.wheels.push(WheelSample {
            stamp: t,
            left,
            right,
        });
        Ok(())
    }

    /// The samples decoded so far, for a streaming reader to drain after
    /// each message.
    pub(crate) fn decoded(&mut self) -> &mut Recording {
        &mut self.rec
    }

    /// `base_from_laser` as the transforms decoded so far give it (with its
    /// origin, or a note saying why there is none), for a stream that does
    /// not end: see [`Self::finish`].
    pub(crate) fn mount_so_far(&mut self) -> Result<StreamMount, InputError> {
        if let Some(laser) = self.laser_frame.clone() {
            self.resolve_mount(&laser)?;
        }
        Ok((
            self.rec.base_from_laser,
            self.rec.mount_origin,
            self.rec.mount_note.clone(),
        ))
    }

    /// What the wheel messages carry, once one was decoded.
    pub(crate) fn wheel_values(&self) -> Option<crate::recording::WheelValues> {
        self.wheels.values()
    }

    /// Whether the wheel values are rates (rad/s) rather than angles.
    pub(crate) fn wheel_rates(&self) -> bool {
        self.wheels.rates()
    }

    /// Sorts, integrates wheel rates if needed and resolves the laser mount;
    /// refuses a wheel topic whose messages together say nothing of the
    /// wheels (an odometry twist that is zero throughout).
    pub(crate) fn finish(mut self) -> Result<Recording, InputError> {
        self.rec.sort_streams();
        self.wheels
            .check_end(self.opts)
            .map_err(|m| InputError::new(&self.file, m).topic(self.opts.wheel_topic()))?;
        if self.wheels.rates() {
            integrate_rates(&mut self.rec.wheels);
            if let Some(w) = self
                .rec
                .wheels
                .iter()
                .find(|w| !(w.left.is_finite() && w.right.is_finite()))
            {
                return Err(InputError::new(
                    self.file,
                    format!(
                        "wheel rates integrate to a non-finite angle at {} s",
                        w.stamp
                    ),
                )
                .topic(self.opts.wheel_topic()));
            }
        }
        if let Some(laser) = self.laser_frame.clone() {
            self.resolve_mount(&laser)?;
        }
        Ok(self.rec)
    }

    /// `base_from_laser` for scans in frame `laser`: from /tf_static, else
    /// from the first transforms on /tf; when neither links the frame to
    /// `base_link`, a note says what the recording has instead.
    fn resolve_mount(&mut self, laser: &str) -> Result<(), InputError> {
        let topics = &self.opts.topics;
        let sources = [
            (&self.tf, Origin::TfStatic, &topics.tf_static),
            (&self.tf_dynamic, Origin::Tf, &topics.tf),
        ];
        for (map, origin, topic) in sources {
            let found = base_from(map, laser)
                .map_err(|m| InputError::new(&self.file, m).topic(topic.as_str()))?;
            if let Some(p) = found {
                self.rec.base_from_laser = Some(p);
                self.rec.mount_origin = Some(origin);
                return Ok(());
            }
        }
        let mut linked: Vec<&str> = self.tf.keys().map(String::as_str).collect();
        linked.sort_unstable();
        self.rec.mount_note = Some(if linked.is_empty() {
            format!(
                "the scans are in frame '{laser}' and neither {} nor {} links it to base_link",
                topics.tf_static, topics.tf
            )
        } else {
            format!(
                "the scans are in frame '{laser}', which {} does not link to base_link \
                 (it has frames: {})",
                topics.tf_static,
                linked.join(", ")
            )
        });
        Ok(())
    }
}

/// `base_link_from_<frame>` by walking the transforms `tf` up from `frame`;
/// `None` when the chain does not reach `base_link`.
fn base_from(tf: &HashMap<String, (String, Pose2)>, laser: &str) -> Result<Option<Pose2>, String> {
    if laser == "base_link" {
        return Ok(Some(Pose2::identity()));
    }
    let mut acc = Pose2::identity();
    let mut cur = laser;
    for _ in 0..32 {
        let Some((parent, p)) = tf.get(cur) else {
            return Ok(None);
        };
        acc = p * acc;
        let v = acc.translation.vector;
        if !(v.x.is_finite() && v.y.is_finite()) {
            return Err(format!("transform chain from '{laser}' overflows"));
        }
        if parent == "base_link" {
            return Ok(Some(acc));
        }
        cur = parent;
    }
    Err(format!("transform chain from '{laser}' loops"))
}

/// Wheel angles from wheel rates (rad/s) by the trapezoidal rule, one sample
/// at a time in stamp order, from 0 at the first sample.
#[derive(Debug, Default)]
pub(crate) struct RateIntegrator {
    prev: Option<WheelSample>,
    left: f64,
    right: f64,
}

impl RateIntegrator {
    /// The angles (rad) at `rate.stamp`; `rate` carries rates in its angle fields.
    pub(crate) fn angles(&mut self, rate: WheelSample) -> WheelSample {
        if let Some(p) = self.prev {
            let dt = rate.stamp - p.stamp;
            self.left += 0.5 * (p.left + rate.left) * dt;
            self.right += 0.5 * (p.right + rate.right) * dt;
        }
        self.prev = Some(rate);
        WheelSample {
            stamp: rate.stamp,
            left: self.left,
            right: self.right,
        }
    }
}

/// `item` as released to a reader: a wheel sample whose values are rates
/// (`rates`) integrated into angles by `integrator` (made on first use).
pub(crate) fn released(
    item: super::source::Item,
    rates: bool,
    integrator: &mut Option<RateIntegrator>,
) -> super::source::Item {
    use super::source::Item;
    match item {
        Item::Wheel(w) if rates => {
            Item::Wheel(integrator.get_or_insert_with(Default::default).angles(w))
        }
        other => other,
    }
}

/// Turns wheel rates (rad/s, stored in the angle fields) into angles (rad)
/// from 0 by the trapezoidal rule.
fn integrate_rates(w: &mut [WheelSample]) {
    let mut integrator = RateIntegrator::default();
    for s in w.iter_mut() {
        *s = integrator.angles(*s);
    }
}

/// The roles an MCAP channel plays (see [`roles_for`]); its messages must be CDR.
pub(crate) fn channel_roles(
    ch: &mcap::Channel<'_>,
    opts: &ReadOptions,
) -> Result<Vec<Role>, String> {
    let schema = ch.schema.as_ref().map(|s| s.name.as_ref()).unwrap_or("");
    roles_for(&ch.topic, schema, &ch.message_encoding, Wire::Cdr, opts)
}

/// The roles a topic of message type `type_name` (`pkg/msg/Type` or ROS 1's
/// `pkg/Type`) plays; a configured topic with an unexpected type, or with an
/// encoding other than `wire`'s, is an error; other topics are ignored.
pub(crate) fn roles_for(
    topic: &str,
    type_name: &str,
    encoding: &str,
    wire: Wire,
    opts: &ReadOptions,
) -> Result<Vec<Role>, String> {
    if opts.all_topics {
        return Ok(vec![Role::Survey]);
    }
    let t = &opts.topics;
    let schema = short_name(type_name);
    let mut roles = Vec::new();
    let mut want = |name: &str, accepted: &[(&str, Role)]| -> Result<(), String> {
        if topic != name {
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
                    "schema '{}' where {} was expected (the --config file's [topics] table \
                     names each stream's topic; `odocal inspect REC` lists the topics and types)",
                    if schema.is_empty() { "(none)" } else { &schema },
                    names.join(" or ")
                ))
            }
        }
    };
    want(&t.scan, &[(LaserScanMsg::TYPE, Role::Scan)])?;
    want(opts.wheel_topic(), &[(opts.wheel_type(), Role::Wheels)]).map_err(|e| {
        format!(
            "{e}: the robot file's [wheels] source = \"{}\" reads the wheels from this topic",
            opts.wheels.source.word()
        )
    })?;
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
    want(&t.tf, &[(TfMessage::TYPE, Role::Tf)])?;
    if !roles.is_empty() && encoding != wire.encoding() {
        return Err(format!(
            "message encoding '{encoding}' where {} was expected",
            wire.encoding()
        ));
    }
    Ok(roles)
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
}
