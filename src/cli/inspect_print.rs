//! `odocal inspect`'s human-readable answer.

use super::print::out;
use odocal::io::survey::{Detail, TopicSurvey};
use odocal::pipeline::inspect::Inspection;

pub fn inspection(i: &Inspection) {
    match i.span_s {
        Some([a, b, d]) => out!(
            "{}: {}, {d:.3} s (receive times {a:.3} to {b:.3})",
            i.file,
            i.format
        ),
        None => out!("{}: {}, empty", i.file, i.format),
    }
    out!("");
    out!(
        "{:<28} {:<34} {:>7} {:>8} {:>5} {:>12}  what",
        "topic",
        "type",
        "count",
        "rate Hz",
        "gaps",
        "longest gap"
    );
    for t in &i.topics {
        topic_line(t);
    }
    if !i.transforms.is_empty() {
        out!("");
        out!("transforms (first of each pair):");
        for e in &i.transforms {
            out!(
                "  {} → {} on {} ×{}: x {:.4} y {:.4} z {:.4} m, yaw {:.4} rad",
                e.parent,
                e.child,
                e.topic,
                e.count,
                e.xyz[0],
                e.xyz[1],
                e.xyz[2],
                e.yaw
            );
        }
    }
    out!("");
    match (i.laser.base_from_laser, i.laser.source) {
        (Some([x, y, yaw]), Some(src)) => out!(
            "laser mounting ({src}): x {x:.4} m, y {y:.4} m, yaw {yaw:.4} rad — {}",
            i.laser.note
        ),
        _ => out!("laser mounting: unknown — {}", i.laser.note),
    }
    out!("");
    out!("what odocal would read:");
    for (name, u) in &i.uses {
        let topic = u.topic.as_deref().unwrap_or("—");
        out!("  {name:<10} {topic}: {}", u.why);
        for s in &u.set {
            out!("  {:<10}   set {s}", "");
        }
    }
    let p = &i.prior;
    out!(
        "  {:<10} {}: each scan pair's initial guess in icp and calibrate; {}",
        "prior",
        p.stream.unwrap_or("—"),
        p.why
    );
    out!("");
    out!("what each command misses:");
    for (cmd, m) in &i.missing {
        if m.is_empty() {
            out!("  {cmd:<26} nothing");
        }
        for (k, line) in m.iter().enumerate() {
            out!("  {:<26} {line}", if k == 0 { *cmd } else { "" });
        }
    }
    if let Some(c) = &i.config_toml {
        out!("");
        out!("--config file for these topics:");
        for l in c.lines() {
            out!("  {l}");
        }
    }
    out!("");
    match &i.wrote_robot {
        Some(f) => out!("proposed robot file, written to {f}:"),
        None => out!("proposed robot file (--write-robot FILE writes it):"),
    }
    for l in i.robot_toml.lines() {
        out!("  {l}");
    }
}

fn topic_line(t: &TopicSurvey) {
    let rate = t.rate_hz.map_or("—".into(), |r| format!("{r:.2}"));
    let gap = t
        .longest_gap_s
        .map_or("—".into(), |[g, _]| format!("{g:.3} s"));
    let what = match &t.detail {
        Some(Detail::Scan {
            frame,
            beams,
            fov_rad,
            range_max,
        }) => format!(
            "{}{beams} beams over {:.1}°, range_max {range_max:.2} m",
            if frame.is_empty() {
                String::new()
            } else {
                format!("frame '{frame}', ")
            },
            fov_rad.to_degrees()
        ),
        Some(Detail::JointState {
            names,
            positions,
            velocities,
        }) => format!(
            "joints {names:?}{}{}",
            if *positions { ", positions" } else { "" },
            if *velocities { ", velocities" } else { "" }
        ),
        Some(Detail::Odometry {
            frame,
            child_frame,
            twist_moves,
            pose_moves,
        }) => format!(
            "{frame} → {child_frame}, twist {}, pose {}",
            if *twist_moves { "moves" } else { "zero" },
            if *pose_moves { "moves" } else { "still" }
        ),
        Some(Detail::Frame { frame }) => format!("frame '{frame}'"),
        None => String::new(),
    };
    out!(
        "{:<28} {:<34} {:>7} {:>8} {:>5} {:>12}  {what}",
        t.topic,
        t.type_name,
        t.count,
        rate,
        t.gaps,
        gap
    );
}
