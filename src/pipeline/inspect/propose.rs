//! The robot file and `[topics]` table `odocal inspect` proposes: what the
//! recording states filled in, what it cannot state left as commented keys
//! with what to put there (a robot file without `r_right`, `r_left` and
//! `wheel_base` is refused when loaded, naming them).

use super::mount::LaserFinding;
use super::uses::Use;
use crate::io::survey::Survey;
use crate::pipeline::Nominal;
use crate::robot::WheelSourceKind;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

fn quoted(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// The proposed robot file (TOML with comments).
pub fn robot_toml(
    s: &Survey,
    uses: &BTreeMap<&'static str, Use>,
    laser: &LaserFinding,
    nominal: &Nominal,
    input: &Path,
) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# Robot file proposed by `odocal inspect {}` ({}); check every value.",
        input.display(),
        s.format
    );
    let name = match &nominal.file {
        Some(_) => nominal.robot.name.clone(),
        None => input
            .file_stem()
            .map_or("robot".into(), |n| n.to_string_lossy().into_owned()),
    };
    let _ = writeln!(t, "name = {}", quoted(&name));
    kinematics(&mut t, nominal, uses);
    wheels(&mut t, nominal, uses);
    laser_table(&mut t, laser);
    t
}

fn kinematics(t: &mut String, nominal: &Nominal, uses: &BTreeMap<&'static str, Use>) {
    let r = &nominal.robot;
    if let Some(f) = &nominal.file {
        let _ = writeln!(t, "# Kinematics from {}:", f.display());
        let _ = writeln!(t, "r_right = {}", r.r_right);
        let _ = writeln!(t, "r_left = {}", r.r_left);
        let _ = writeln!(t, "wheel_base = {}", r.wheel_base);
    } else {
        let twist = uses
            .get("wheels")
            .and_then(|u| u.wheels.as_ref())
            .is_some_and(|w| w.source == WheelSourceKind::Odometry);
        let _ = writeln!(
            t,
            "# No recording states the wheel radii and wheel base: measure them and remove the #.{}",
            if twist {
                "\n# With the odometry twist as the wheels, give the controller's configured\n\
                 # values: r_right = wheel_radius × right_wheel_radius_multiplier,\n\
                 # r_left = wheel_radius × left_wheel_radius_multiplier,\n\
                 # wheel_base = wheel_separation × wheel_separation_multiplier."
            } else {
                ""
            }
        );
        let _ = writeln!(t, "# r_right = 0.0     # m, right wheel radius");
        let _ = writeln!(t, "# r_left = 0.0      # m, left wheel radius");
        let _ = writeln!(
            t,
            "# wheel_base = 0.0  # m, between the wheels' contact points"
        );
    }
    if nominal.given.contains("ticks_per_rev") {
        let _ = writeln!(t, "ticks_per_rev = {}", r.ticks_per_rev);
    }
}

fn wheels(t: &mut String, nominal: &Nominal, uses: &BTreeMap<&'static str, Use>) {
    let w = uses.get("wheels").and_then(|u| u.wheels.as_ref());
    let Some(w) = w else {
        let _ = writeln!(
            t,
            "# No wheel stream found: set [wheels] source and topic (see `odocal inspect`'s \
             \"wheels\" line)."
        );
        return;
    };
    if let Some([l, r]) = &w.joints {
        let _ = writeln!(t, "left_joint = {}", quoted(l));
        let _ = writeln!(t, "right_joint = {}", quoted(r));
    }
    if w.source == WheelSourceKind::Ticks && !nominal.given.contains("ticks_per_rev") {
        let _ = writeln!(
            t,
            "# ticks_per_rev = 0   # encoder ticks per wheel revolution: required for ticks"
        );
    }
    if w.source == WheelSourceKind::JointStates && w.topic.is_none() {
        return;
    }
    let _ = writeln!(t, "\n[wheels]");
    let _ = writeln!(t, "source = {}", quoted(w.source.word()));
    if let Some(topic) = &w.topic {
        let _ = writeln!(t, "topic = {}", quoted(topic));
    }
    if let Some(ty) = &w.ticks_type {
        let _ = writeln!(t, "ticks_type = {}", quoted(ty));
        let _ = writeln!(
            t,
            "left_index = 0    # which data[] element is the left counter: check\n\
             right_index = 1\n\
             # ticks_wrap_bits = 16   # when the counters are narrower than the array's elements"
        );
    }
}

fn laser_table(t: &mut String, laser: &LaserFinding) {
    match (laser.source, laser.base_from_laser) {
        (Some("robot_file"), Some([x, y, yaw])) => {
            let _ = writeln!(t, "\n[laser]  # base_from_laser, from the robot file given");
            let _ = writeln!(t, "x = {x}\ny = {y}\nyaw = {yaw}");
        }
        (Some(src), Some([x, y, yaw])) => {
            let _ = writeln!(
                t,
                "\n# No [laser] needed: the recording states the mounting ({src}: x {x:.4} m, \
                 y {y:.4} m, yaw {yaw:.4} rad),\n# which every command reads from it."
            );
        }
        _ => {
            let _ = writeln!(
                t,
                "\n# The laser mounting is unknown: {}.\n# Measure it and remove the #, or run \
                 `odocal calibrate --method batch`, which estimates it.\n# [laser]\n# x = 0.0     \
                 # m, forward of the base origin\n# y = 0.0     # m, to the left\n# yaw = 0.0   \
                 # rad, of the laser's x axis",
                laser.note
            );
        }
    }
}

/// The `--config` `[topics]` table naming the topics chosen that are not
/// the configured ones; `None` when there are none.
pub fn config_toml(uses: &BTreeMap<&'static str, Use>) -> Option<String> {
    let keys = [
        ("scans", "scan"),
        ("gyro", "imu"),
        ("odom", "odom"),
        ("reference", "reference"),
    ];
    let mut lines = Vec::new();
    for (stream, key) in keys {
        let Some(u) = uses.get(stream) else { continue };
        if let (false, Some(topic)) = (u.configured, &u.topic) {
            lines.push(format!("{key} = {}", quoted(topic)));
        }
    }
    (!lines.is_empty()).then(|| format!("[topics]\n{}\n", lines.join("\n")))
}
