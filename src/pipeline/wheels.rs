//! Which stream a run's wheels came from, as its output states it
//! ([`WheelSource`]), and the error of a recording that has none of the
//! stream the robot file names.

use super::{Nominal, PipelineError};
use crate::assumptions::Origin;
use crate::calib::CalibSummary;
use crate::error::InputError;
use crate::io::ReadOptions;
use crate::recording::{WheelSource, WheelValues};
use crate::robot::WheelSourceKind;

/// The wheel source of a run that read `messages` wheel messages carrying
/// `values`, with what the user should know about it.
pub fn describe(
    read: &ReadOptions,
    nominal: &Nominal,
    messages: usize,
    values: Option<WheelValues>,
) -> WheelSource {
    WheelSource {
        kind: read.wheels.source,
        topic: read.wheel_topic().to_string(),
        type_name: read.wheel_type().to_string(),
        values,
        messages,
        source: origin(read, nominal),
        notes: found_notes(read, nominal)
            .into_iter()
            .chain(notes(read, values))
            .collect(),
    }
}

/// States the wheel source in a calibration summary; with the robot's own
/// odometry as the source, also the scales of that odometry.
pub fn state(summary: &mut CalibSummary, source: WheelSource) {
    if source.kind == WheelSourceKind::Odometry {
        summary.odometry_scale = Some(summary.multipliers.odometry_scale());
    }
    summary.wheel_source = Some(source);
}

/// Where the wheel source came from: the robot file's `[wheels]`, the
/// recording (its one wheel stream, [`only_source`]) or the default.
fn origin(read: &ReadOptions, nominal: &Nominal) -> Origin {
    if nominal.given.contains("wheels") {
        Origin::RobotFile
    } else if read.wheels.source != WheelSourceKind::default() {
        Origin::Recording
    } else {
        Origin::Default
    }
}

/// The read options of a recording whose robot file names no `[wheels]`
/// source and that holds no JointState wheels but the robot's own odometry
/// (`nav_msgs/Odometry`, e.g. a diff_drive_controller's): that odometry,
/// its one usable wheel stream, read from its twist. `None` keeps `read`.
pub fn only_source(read: &ReadOptions, nominal: &Nominal, found: Found) -> Option<ReadOptions> {
    let unnamed = !nominal.given.contains("wheels") && read.wheels.is_default();
    (unnamed && found.bag && found.wheels < 2 && found.odom >= 2).then(|| {
        let mut r = read.clone();
        r.wheels.source = WheelSourceKind::Odometry;
        r
    })
}

/// Why the source is the one it is, when the recording chose it.
fn found_notes(read: &ReadOptions, nominal: &Nominal) -> Vec<String> {
    if origin(read, nominal) != Origin::Recording {
        return Vec::new();
    }
    vec![format!(
        "the robot file names no [wheels] source and the recording has no JointState wheels \
         on {}: its one wheel stream, {} on {}, is used (set [wheels] source and topic to \
         choose another)",
        read.topics.joint_states,
        read.wheel_type(),
        read.wheel_topic()
    )]
}

/// How the messages became wheel angles, and what the source cannot show.
fn notes(read: &ReadOptions, values: Option<WheelValues>) -> Vec<String> {
    match read.wheels.source {
        WheelSourceKind::JointStates => match values {
            Some(WheelValues::Velocities) => vec![
                "the JointState messages carry no positions: the joint velocities are \
                 integrated into wheel angles (trapezoidal rule)"
                    .into(),
            ],
            _ => Vec::new(),
        },
        WheelSourceKind::Odometry => odometry_notes(),
        WheelSourceKind::Ticks => ticks_notes(read),
    }
}

/// What a calibration from a controller's twist rests on and cannot see.
fn odometry_notes() -> Vec<String> {
    vec![
        "the twist (V = linear.x, W = angular.z) is turned back into wheel rates with the \
         robot file's r_right, r_left and wheel_base, taken to be the controller's own \
         wheel_radius × right/left_wheel_radius_multiplier and wheel_separation × \
         wheel_separation_multiplier: the multipliers found multiply the ones set now"
            .into(),
        "the multipliers are only as right as that model of the controller: a common scale \
         error of both radii cancels out of them, but a wrong wheel_base or right/left radius \
         ratio mixes the two wheels (the fit's χ² then grows)"
            .into(),
        "not seen: the controller's velocity filtering and the lag of its twist behind the \
         wheels (a rolling mean lags by about half its window); anything between wheel and \
         twist (encoder errors, slip, the controller's own arithmetic) is folded into the \
         radii and wheel base"
            .into(),
        "the twist must be the controller's wheel odometry, not a fused estimate (e.g. with \
         an IMU), whose turn rate is not the wheels'"
            .into(),
    ]
}

fn ticks_notes(read: &ReadOptions) -> Vec<String> {
    let Some(l) = read.wheels.ticks_layout() else {
        return Vec::new();
    };
    vec![
        format!(
            "ticks from data[{}] (left) and data[{}] (right), {}-bit counters unwrapped, {} \
             ticks per wheel revolution (the robot file's ticks_per_rev)",
            l.left_index, l.right_index, l.wrap_bits, read.ticks_per_rev
        ),
        "the tick arrays have no header: each is stamped with the bag's log (receive) time, \
         so the delay between the encoders and the recorder is not seen"
            .into(),
    ]
}

/// What a recording holds besides its wheel messages, for [`require`].
#[derive(Debug, Clone, Copy)]
pub struct Found {
    /// Wheel messages read.
    pub wheels: usize,
    /// Messages of the robot's own odometry.
    pub odom: usize,
    /// Whether the input is a bag (a CARMEN log has no topics).
    pub bag: bool,
}

/// An error naming the robot-file keys when fewer than 2 wheel messages
/// were read; the robot's own odometry is suggested as the source when the
/// bag has it.
pub fn require(
    read: &ReadOptions,
    nominal: &Nominal,
    input: &str,
    found: Found,
) -> Result<(), PipelineError> {
    let Found {
        wheels: messages,
        odom,
        bag,
    } = found;
    if messages >= 2 {
        return Ok(());
    }
    if !bag {
        return Err(InputError::new(
            input,
            "no wheel encoder data to calibrate: a CARMEN log has no wheel topic, only the \
             robot's own odometry poses (ODOM), which `odocal diagnose --measured` replays",
        )
        .into());
    }
    let kind = read.wheels.source;
    let whence = match origin(read, nominal) {
        Origin::RobotFile => "of the robot file",
        _ => "by default: the robot file has no [wheels] table",
    };
    let joints = match kind {
        WheelSourceKind::JointStates => format!(
            " with the joints '{}' and '{}' (left_joint, right_joint)",
            read.left_joint, read.right_joint
        ),
        _ => String::new(),
    };
    let mut message = format!(
        "no wheel encoder data: {messages} {} messages on {}{joints} ([wheels] source = \"{}\" \
         {whence}). Set [wheels] source and topic in the robot file (--robot ROBOT.toml) to \
         where this robot reports its wheels (`odocal inspect {input}` lists the recording's \
         topics and types)",
        read.wheel_type(),
        read.wheel_topic(),
        kind.word()
    );
    if odom >= 2 && kind != WheelSourceKind::Odometry {
        message.push_str(&format!(
            "; the recording has {odom} nav_msgs/msg/Odometry messages on {}: [wheels] \
             source = \"odometry\" calibrates that odometry from its twist",
            read.topics.odom
        ));
    }
    Err(InputError::new(input, message)
        .topic(read.wheel_topic())
        .into())
}
