//! Reads a ROS 2 bag in MCAP (CDR messages, chunks plain or zstd/lz4) into a
//! [`Recording`]. Message types are recognised by schema name; topics come from
//! [`TopicConfig`]. Every problem is an [`InputError`] naming the file, the
//! topic and the message index (0-based, counted per topic).

use std::collections::HashMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::mcap_streams::{Role, State};
use super::ros_msgs::{
    ImuMsg, JointStateMsg, LaserScanMsg, OdometryMsg, PointStampedMsg, PoseStampedMsg, RosMsg,
    TfMessage,
};
use super::ros_schema::short_name;
use crate::error::InputError;
use crate::recording::Recording;
use crate::robot::RobotConfig;

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
    super::mcap_guard::check_file(bytes, false)
        .map_err(|m| InputError::new(file, m).at("after 0 messages"))?;
    let mut stream = mcap::read::RawMessageStream::new(bytes).map_err(|e| mcap_err(e, 0))?;
    let mut st = State::new(file, opts);
    let mut total = 0usize;
    // Per channel: topic, roles, messages seen so far.
    let mut channels: HashMap<u16, (String, Vec<Role>, usize)> = HashMap::new();
    while let Some(msg) = stream.next() {
        let msg = msg.map_err(|e| mcap_err(e, total))?;
        total += 1;
        let id = msg.header.channel_id;
        let (topic, rs, count) = match channels.entry(id) {
            std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::hash_map::Entry::Vacant(e) => {
                let ch = stream.get_channel(id).ok_or_else(|| {
                    InputError::new(file, format!("message refers to unknown channel {id}"))
                        .at(format!("after {total} messages"))
                })?;
                let r = channel_roles(&ch, opts)
                    .map_err(|m| InputError::new(file, m).topic(&ch.topic))?;
                e.insert((ch.topic.clone(), r, 0))
            }
        };
        let i = *count;
        *count += 1;
        for role in rs {
            st.handle(*role, &msg.data, msg.header.log_time)
                .map_err(|m| {
                    InputError::new(file, m)
                        .topic(topic.as_str())
                        .at(format!("message {i}"))
                })?;
        }
    }
    st.finish()
}

/// The error for a file without a valid footer: names the last message that
/// could still be read (topic and per-topic index), so the cut can be found.
fn truncated(bytes: &[u8], file: &str, e: mcap::McapError) -> InputError {
    // Only the complete records of the cut file are read.
    let lenient = super::mcap_guard::check_file(bytes, true)
        .map_err(|_| mcap::McapError::UnexpectedEof)
        .and_then(|end| {
            mcap::read::RawMessageStream::new_with_options(
                &bytes[..end],
                mcap::read::Options::IgnoreEndMagic.into(),
            )
        });
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

/// The roles a channel plays; a configured topic with an unexpected schema is
/// an error, other topics are ignored.
pub(crate) fn channel_roles(
    ch: &mcap::Channel<'_>,
    opts: &ReadOptions,
) -> Result<Vec<Role>, String> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn topic_config_reads_partial_toml() {
        let t: TopicConfig = toml::from_str("reference = \"/reference\"").unwrap();
        assert_eq!(t.reference, "/reference");
        assert_eq!(t.scan, "/scan");
        assert!(toml::from_str::<TopicConfig>("bogus = 1").is_err());
    }
}
