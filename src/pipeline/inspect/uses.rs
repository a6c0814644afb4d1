//! What `odocal inspect` says of each stream: the topic a command would
//! read ([`Use`]), the wheel keys it proposes, and the small judgements the
//! choosing rests on (message types, wheel joint names).

use crate::io::survey::{Detail, TopicSurvey};
use crate::robot::WheelSourceKind;
use serde::Serialize;

/// The message types the streams come as.
pub const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";
/// See [`LASER_SCAN`].
pub const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
/// See [`LASER_SCAN`].
pub const IMU: &str = "sensor_msgs/msg/Imu";
/// See [`LASER_SCAN`].
pub const ODOMETRY: &str = "nav_msgs/msg/Odometry";
/// The types a reference trajectory can come as.
pub const REFERENCE_TYPES: [&str; 3] = [
    ODOMETRY,
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PointStamped",
];

/// The stream a command would read from a topic.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Use {
    /// The topic (a CARMEN log: its record kinds), `None` when there is none.
    pub topic: Option<String>,
    /// Its message type.
    #[serde(rename = "type")]
    pub type_name: Option<String>,
    /// Its messages.
    pub messages: usize,
    /// Whether the settings as given (`--config`, `--robot`) already read it.
    pub configured: bool,
    /// Why this topic, or why none.
    pub why: String,
    /// What to set so that odocal reads it: `KEY = VALUE (FILE)` lines.
    pub set: Vec<String>,
    /// For the wheels: the robot file's wheel keys proposed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wheels: Option<WheelsProposal>,
}

/// The wheel keys of a proposed robot file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WheelsProposal {
    /// `[wheels] source`.
    pub source: WheelSourceKind,
    /// `[wheels] topic` (`None`: the default for the source).
    pub topic: Option<String>,
    /// `left_joint`, `right_joint` (JointState).
    pub joints: Option<[String; 2]>,
    /// `[wheels] ticks_type` (ticks).
    pub ticks_type: Option<String>,
}

impl Use {
    /// No topic, and why.
    pub fn none(why: impl Into<String>) -> Self {
        Self {
            topic: None,
            type_name: None,
            messages: 0,
            configured: false,
            why: why.into(),
            set: Vec::new(),
            wheels: None,
        }
    }

    /// The topic `t`, whether the settings already read it, and why.
    pub fn of(t: &TopicSurvey, configured: bool, why: impl Into<String>) -> Self {
        Self {
            topic: Some(t.topic.clone()),
            type_name: Some(t.type_name.clone()),
            messages: t.count,
            configured,
            why: why.into(),
            set: Vec::new(),
            wheels: None,
        }
    }
}

pub fn is_type(t: &TopicSurvey, types: &[&str]) -> bool {
    let short = crate::io::ros_schema::short_name(&t.type_name);
    types
        .iter()
        .any(|ty| crate::io::ros_schema::short_name(ty) == short)
}

/// The joints that look like the left and right wheels: names with
/// "left"/"right" (or an `l`/`r` word), those that also say "wheel" first.
pub fn guess_joints(names: &[String]) -> Option<[String; 2]> {
    let side = |words: &[&str], short: &str| -> Option<String> {
        let mut c: Vec<&String> = names
            .iter()
            .filter(|n| {
                let l = n.to_lowercase();
                words.iter().any(|w| l.contains(w))
                    || l.split(['_', '-', '/']).any(|part| part == short)
            })
            .collect();
        c.sort_by_key(|n| !n.to_lowercase().contains("wheel"));
        c.first().map(|n| n.to_string())
    };
    let left = side(&["left"], "l")?;
    let right = side(&["right"], "r")?;
    (left != right).then_some([left, right])
}

/// The joints of a JointState topic's first message.
pub fn joints(t: &TopicSurvey) -> Option<(&[String], bool, bool)> {
    match &t.detail {
        Some(Detail::JointState {
            names,
            positions,
            velocities,
        }) => Some((names.as_slice(), *positions, *velocities)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn wheel_joints_are_told_by_side_and_preferred_with_wheel() {
        let g = guess_joints(&names(&[
            "arm",
            "left_caster",
            "wheel_left_joint",
            "wheel_right_joint",
        ]));
        assert_eq!(
            g,
            Some(["wheel_left_joint".into(), "wheel_right_joint".into()])
        );
        let g = guess_joints(&names(&["base_l", "base_r"]));
        assert_eq!(g, Some(["base_l".into(), "base_r".into()]));
        assert_eq!(guess_joints(&names(&["j1", "j2"])), None);
    }
}
