//! Which topic each stream would come from, and why: the configured topic
//! when the recording has it with the right type, else the likeliest
//! candidate with the key that would make odocal read it; and what each
//! command would still miss.

use super::mount::LaserFinding;
use super::uses::{is_type, Use, IMU, LASER_SCAN, ODOMETRY, REFERENCE_TYPES};
use crate::io::survey::{Survey, TopicSurvey};
use crate::io::ReadOptions;
use crate::pipeline::Nominal;
use std::collections::BTreeMap;

/// Words in a topic name that mark a reference trajectory rather than the
/// robot's own odometry.
const REFERENCE_WORDS: [&str; 8] = [
    "ground_truth",
    "groundtruth",
    "truth",
    "reference",
    "mocap",
    "vicon",
    "slam",
    "gt",
];

/// The stream of `[topics] key` (configured topic `want`) among topics of `types`.
fn pick(s: &Survey, key: &str, want: &str, types: &[&str], skip: &[&str]) -> Use {
    let wrong = match s.topic(want) {
        Some(t) if is_type(t, types) => {
            return Use::of(t, true, format!("the configured [topics] {key}"));
        }
        Some(t) => format!(
            " ({want} is a {}, not a {})",
            t.type_name,
            types.join(" or ")
        ),
        None => String::new(),
    };
    let candidates: Vec<&TopicSurvey> = types
        .iter()
        .flat_map(|ty| s.of_type(ty))
        .filter(|t| !skip.contains(&t.topic.as_str()))
        .collect();
    let Some(best) = candidates.first() else {
        return Use::none(format!("no {} topic{wrong}", types.join(" or ")));
    };
    let others: Vec<&str> = candidates[1..].iter().map(|t| t.topic.as_str()).collect();
    let why = if others.is_empty() {
        format!("the only {} topic{wrong}", best.type_name)
    } else {
        format!(
            "the {} topic with the most messages{wrong}; also: {}",
            best.type_name,
            others.join(", ")
        )
    };
    let mut u = Use::of(best, false, why);
    u.set.push(format!(
        "[topics] {key} = \"{}\" (--config file)",
        best.topic
    ));
    u
}

/// The stream every command would read, by name.
pub fn uses(s: &Survey, read: &ReadOptions, nominal: &Nominal) -> BTreeMap<&'static str, Use> {
    let mut out = BTreeMap::new();
    if !s.is_bag() {
        return log_uses(s);
    }
    let t = &read.topics;
    let reference = reference(s, read);
    let skip: Vec<&str> = reference.topic.iter().map(String::as_str).collect();
    let odom = pick(s, "odom", &t.odom, &[ODOMETRY], &skip);
    out.insert("scans", pick(s, "scan", &t.scan, &[LASER_SCAN], &[]));
    out.insert("gyro", pick(s, "imu", &t.imu, &[IMU], &[]));
    out.insert(
        "wheels",
        super::choose_wheels::wheels(s, read, nominal, &odom),
    );
    out.insert("odom", odom);
    out.insert("reference", reference);
    out
}

/// The reference trajectory: the configured topic, else a pose topic whose
/// name says it is one (never the robot's own odometry by guess).
fn reference(s: &Survey, read: &ReadOptions) -> Use {
    let key = &read.topics.reference;
    if let Some(t) = s.topic(key).filter(|t| is_type(t, &REFERENCE_TYPES)) {
        return Use::of(t, true, "the configured [topics] reference");
    }
    let named: Vec<&TopicSurvey> = s
        .topics
        .iter()
        .filter(|t| is_type(t, &REFERENCE_TYPES))
        .filter(|t| {
            let n = t.topic.to_lowercase();
            REFERENCE_WORDS.iter().any(|w| n.contains(w))
        })
        .collect();
    match named.first() {
        Some(t) => {
            let mut u = Use::of(t, false, "a pose topic whose name marks a reference");
            u.set.push(format!(
                "[topics] reference = \"{}\" (--config file)",
                t.topic
            ));
            u
        }
        None => {
            let poses: Vec<String> = s
                .topics
                .iter()
                .filter(|t| is_type(t, &REFERENCE_TYPES))
                .map(|t| t.topic.clone())
                .collect();
            let why = if poses.is_empty() {
                format!("no {key} and no pose topic")
            } else {
                format!(
                    "no {key}; pose topics {} may be odometry: name the one that is an \
                     independent reference in [topics] reference",
                    poses.join(", ")
                )
            };
            Use::none(why)
        }
    }
}

/// A CARMEN log's streams: its laser and odometry lines.
fn log_uses(s: &Survey) -> BTreeMap<&'static str, Use> {
    let mut out = BTreeMap::new();
    let line = |i: usize, why: &str| match s.topics.get(i) {
        Some(t) => Use::of(t, true, why),
        None => Use::none("none in the file"),
    };
    let is_log = s.format == crate::io::survey::format_word(crate::io::Format::Text);
    if is_log {
        out.insert("scans", line(0, "the log's laser lines"));
        let odom = s.topics.iter().position(|t| t.topic == "ODOM");
        out.insert(
            "odom",
            odom.map_or(Use::none("no ODOM lines"), |i| {
                line(i, "the log's ODOM lines")
            }),
        );
        out.insert(
            "wheels",
            Use::none("a CARMEN log has no wheel encoders, only the robot's odometry (ODOM)"),
        );
    } else {
        out.insert(
            "wheels",
            line(0, "each tuple's wheel rotations and scan-matching motion"),
        );
    }
    out
}

/// Per command, what it would miss with the settings given, and with the
/// keys of [`Use::set`] applied.
pub fn missing(
    s: &Survey,
    uses: &BTreeMap<&'static str, Use>,
    laser: &LaserFinding,
    nominal: &Nominal,
) -> BTreeMap<&'static str, Vec<String>> {
    let need = |name: &str, min: usize, what: &str| -> Option<String> {
        let u = uses.get(name)?;
        if u.messages < min {
            return Some(format!("{what}: {}", u.why));
        }
        (!u.configured).then(|| format!("{what} on {}: set {}", topic(u), u.set.join(", ")))
    };
    let scans = need("scans", 2, "laser scans (2 or more)");
    let wheels = need("wheels", 2, "wheel encoders (2 or more samples)");
    let mount = laser.missing();
    let kinematics = nominal.file.is_none().then(|| {
        "the nominal wheel radii and wheel base: r_right, r_left, wheel_base in a robot file \
         (--robot ROBOT.toml); no recording states them, and without one the wheelchair's \
         (0.32, 0.32, 0.65 m) are assumed"
            .to_string()
    });
    let trajectory = match (
        need("reference", 2, "a reference"),
        need("odom", 2, "odometry"),
    ) {
        (Some(r), Some(o)) => Some(format!("a trajectory ({r}; {o})")),
        _ => None,
    };
    let odom_or_wheels = match (&wheels, need("odom", 2, "odometry")) {
        (Some(w), Some(o)) => Some(format!("{w}; or {o}")),
        _ => None,
    };
    let list = |items: Vec<&Option<String>>| items.into_iter().flatten().cloned().collect();
    let mut out = BTreeMap::new();
    if s.format == crate::io::survey::format_word(crate::io::Format::CensiTuples) {
        out.insert("calibrate --method batch", list(vec![&kinematics]));
        out.insert("diagnose", list(vec![&kinematics]));
        return out;
    }
    out.insert("icp", list(vec![&scans, &mount]));
    out.insert(
        "calibrate",
        list(vec![&scans, &mount, &wheels, &kinematics]),
    );
    out.insert(
        "calibrate --method batch",
        list(vec![&scans, &wheels, &kinematics]),
    );
    out.insert(
        "diagnose",
        list(vec![&scans, &mount, &odom_or_wheels, &kinematics]),
    );
    out.insert("eval --reference", list(vec![&trajectory]));
    out
}

fn topic(u: &Use) -> &str {
    u.topic.as_deref().unwrap_or("(none)")
}
