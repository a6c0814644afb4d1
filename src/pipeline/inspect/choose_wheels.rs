//! Where the wheels would come from: the robot file's `[wheels]` source when
//! the recording has it, else JointState wheel joints, else the robot's own
//! odometry twist, else integer tick arrays, in that order of preference
//! (encoders before a controller's arithmetic).

use super::uses::{guess_joints, is_type, joints, Use, WheelsProposal, JOINT_STATE, ODOMETRY};
use crate::io::survey::{Detail, Survey, TopicSurvey};
use crate::io::ReadOptions;
use crate::pipeline::Nominal;
use crate::robot::WheelSourceKind;

/// Integer array types a robot may publish tick counters as.
const TICK_TYPES: [&str; 6] = [
    "std_msgs/msg/Int16MultiArray",
    "std_msgs/msg/UInt16MultiArray",
    "std_msgs/msg/Int32MultiArray",
    "std_msgs/msg/UInt32MultiArray",
    "std_msgs/msg/Int64MultiArray",
    "std_msgs/msg/UInt64MultiArray",
];

/// The wheel stream; `odom` is the robot's odometry chosen for `[topics] odom`.
pub fn wheels(s: &Survey, read: &ReadOptions, nominal: &Nominal, odom: &Use) -> Use {
    if let Some(u) = configured(s, read, nominal) {
        return u;
    }
    let j = s.of_type(JOINT_STATE);
    if let Some(u) = j.iter().find_map(|t| from_joints(t, read)) {
        return u;
    }
    let moving = |t: &&TopicSurvey| {
        matches!(
            t.detail,
            Some(Detail::Odometry {
                twist_moves: true,
                ..
            })
        )
    };
    let twist = odom
        .topic
        .as_deref()
        .and_then(|o| s.topic(o))
        .filter(moving)
        .or_else(|| s.of_type(ODOMETRY).into_iter().find(moving));
    if let Some(t) = twist {
        return from_twist(t, read, !j.is_empty());
    }
    let ticks = TICK_TYPES.iter().flat_map(|ty| s.of_type(ty)).next();
    if let Some(t) = ticks {
        return from_ticks(t);
    }
    let had = if j.is_empty() {
        String::new()
    } else {
        let names: Vec<String> = j
            .iter()
            .filter_map(|t| joints(t))
            .map(|(n, ..)| format!("{n:?}"))
            .collect();
        format!(
            " (JointState joints {} name no left and right wheel)",
            names.join(", ")
        )
    };
    Use::none(format!(
        "no wheel stream: no JointState with wheel joints, no Odometry whose twist moves, no \
         integer tick array{had}"
    ))
}

/// The robot file's source, when the recording has it as configured.
fn configured(s: &Survey, read: &ReadOptions, nominal: &Nominal) -> Option<Use> {
    let topic = read.wheel_topic();
    let t = s
        .topic(topic)
        .filter(|t| is_type(t, &[read.wheel_type()]))?;
    let from = if nominal.given.contains("wheels") {
        "the robot file's [wheels]"
    } else {
        "the default wheel source"
    };
    let why = match read.wheels.source {
        WheelSourceKind::JointStates => {
            let (names, pos, vel) = joints(t)?;
            let has = |j: &str| names.iter().any(|n| n == j);
            if !(has(&read.left_joint) && has(&read.right_joint)) {
                return None;
            }
            format!(
                "{from}: joints '{}' and '{}' ({})",
                read.left_joint,
                read.right_joint,
                values(pos, vel)
            )
        }
        WheelSourceKind::Odometry => match t.detail {
            Some(Detail::Odometry {
                twist_moves: true, ..
            }) => format!("{from}: the odometry's twist"),
            _ => return None,
        },
        WheelSourceKind::Ticks => format!("{from}: tick counters"),
    };
    let mut u = Use::of(t, true, why);
    u.wheels = Some(WheelsProposal {
        source: read.wheels.source,
        topic: read.wheels.topic.clone(),
        joints: (read.wheels.source == WheelSourceKind::JointStates)
            .then(|| [read.left_joint.clone(), read.right_joint.clone()]),
        ticks_type: read
            .wheels
            .ticks_layout()
            .map(|l| l.ticks_type.type_name().to_string()),
    });
    Some(u)
}

fn values(pos: bool, vel: bool) -> &'static str {
    match (pos, vel) {
        (true, true) => "positions and velocities; positions are used",
        (true, false) => "positions",
        (false, true) => "velocities only, integrated into angles",
        (false, false) => "neither positions nor velocities for every joint",
    }
}

/// A JointState topic whose joints name a left and a right wheel.
fn from_joints(t: &TopicSurvey, read: &ReadOptions) -> Option<Use> {
    let (names, pos, vel) = joints(t)?;
    if !(pos || vel) {
        return None;
    }
    let [l, r] = guess_joints(names)?;
    let mut u = Use::of(
        t,
        false,
        format!(
            "JointState joints {names:?}: '{l}' and '{r}' are taken for the left and right \
             wheel by their names ({}); check that they are the driven wheels",
            values(pos, vel)
        ),
    );
    if l != read.left_joint || r != read.right_joint {
        u.set.push(format!("left_joint = \"{l}\" (robot file)"));
        u.set.push(format!("right_joint = \"{r}\" (robot file)"));
    }
    if t.topic != read.wheel_topic() || read.wheels.source != WheelSourceKind::JointStates {
        u.set
            .push("[wheels] source = \"joint_states\" (robot file)".to_string());
        u.set
            .push(format!("[wheels] topic = \"{}\" (robot file)", t.topic));
    }
    u.wheels = Some(WheelsProposal {
        source: WheelSourceKind::JointStates,
        topic: (t.topic != read.topics.joint_states).then(|| t.topic.clone()),
        joints: Some([l, r]),
        ticks_type: None,
    });
    Some(u)
}

/// The robot's own odometry twist as the wheels.
fn from_twist(t: &TopicSurvey, read: &ReadOptions, had_joints: bool) -> Use {
    let why = format!(
        "{}the robot's own odometry: its twist is turned back into wheel rates with the \
         robot file's r_right, r_left, wheel_base, which must then be the controller's \
         configured wheel_radius × its radius multipliers and wheel_separation × \
         wheel_separation_multiplier",
        if had_joints {
            "no JointState names a left and a right wheel; "
        } else {
            "no JointState; "
        }
    );
    let mut u = Use::of(t, false, why);
    u.set
        .push("[wheels] source = \"odometry\" (robot file)".to_string());
    let topic = (t.topic != read.topics.odom).then(|| t.topic.clone());
    if let Some(tp) = &topic {
        u.set
            .push(format!("[wheels] topic = \"{tp}\" (robot file)"));
    }
    u.wheels = Some(WheelsProposal {
        source: WheelSourceKind::Odometry,
        topic,
        joints: None,
        ticks_type: None,
    });
    u
}

/// An integer array topic as encoder tick counters.
fn from_ticks(t: &TopicSurvey) -> Use {
    let mut u = Use::of(
        t,
        false,
        "an integer array, read as encoder tick counters: which element is the left \
         counter, and the counters' width, cannot be told from the bag (left_index, \
         right_index, ticks_wrap_bits), and ticks_per_rev must be given",
    );
    u.set
        .push("[wheels] source = \"ticks\" (robot file)".to_string());
    u.set
        .push(format!("[wheels] topic = \"{}\" (robot file)", t.topic));
    u.set.push(format!(
        "[wheels] ticks_type = \"{}\" (robot file)",
        t.type_name
    ));
    u.set
        .push("ticks_per_rev = <ticks per wheel revolution> (robot file)".to_string());
    u.wheels = Some(WheelsProposal {
        source: WheelSourceKind::Ticks,
        topic: Some(t.topic.clone()),
        joints: None,
        ticks_type: Some(t.type_name.clone()),
    });
    u
}
