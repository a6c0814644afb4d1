//! The laser mounting as the commands would find it: the scans' frame walked
//! up the transforms of `[topics] tf_static` (else the first of each frame on
//! `[topics] tf`, as the readers take them) to `base_link`; else a CARMEN
//! log's laser pose; else the robot file's `[laser]`; else unknown, with
//! what the tree has instead.

use super::uses::Use;
use crate::geom::{self, Pose2};
use crate::io::survey::{Detail, Survey, TfEdge};
use crate::io::TopicConfig;
use crate::pipeline::Nominal;
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};

/// The frame odocal takes for the robot's base.
pub const BASE_FRAME: &str = "base_link";

/// The laser frame and its mounting.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LaserFinding {
    /// The scans' `header.frame_id`.
    pub frame: Option<String>,
    /// `base_from_laser` as x (m), y (m), yaw (rad).
    pub base_from_laser: Option<[f64; 3]>,
    /// The laser's height above `base_link` (m), from the transforms; not
    /// used by odocal (2D), given for the URDF.
    pub z_m: Option<f64>,
    /// Where it came from: `tf_static`, `tf`, `log`, `robot_file`; `None`: unknown.
    pub source: Option<&'static str>,
    /// The frames from `base_link` down to the laser.
    pub chain: Vec<String>,
    /// What to know, or what is missing.
    pub note: String,
}

impl LaserFinding {
    /// What a command that needs the mounting misses, if anything.
    pub fn missing(&self) -> Option<String> {
        self.base_from_laser.is_none().then(|| {
            format!(
                "the laser mounting: {}; set [laser] x, y, yaw (base_from_laser, m, m, rad) in \
                 the robot file, or let `odocal calibrate --method batch` estimate it",
                self.note
            )
        })
    }
}

/// Finds the mounting of the scans `uses["scans"]` names.
pub fn find(
    s: &Survey,
    uses: &BTreeMap<&'static str, Use>,
    nominal: &Nominal,
    topics: &TopicConfig,
) -> LaserFinding {
    let mut f = LaserFinding {
        frame: None,
        base_from_laser: None,
        z_m: None,
        source: None,
        chain: Vec::new(),
        note: String::new(),
    };
    if let Some(m) = s.log_mount {
        f.base_from_laser = Some(m.map(|v| v + 0.0));
        f.source = Some("log");
        f.note = "the log's laser lines state the laser pose against the odometry pose".into();
        return f;
    }
    f.frame = uses
        .get("scans")
        .and_then(|u| u.topic.as_deref())
        .and_then(|t| s.topic(t))
        .and_then(|t| match &t.detail {
            Some(Detail::Scan { frame, .. }) => Some(frame.clone()),
            _ => None,
        });
    if let Some(frame) = f.frame.clone() {
        from_transforms(s, &frame, topics, &mut f);
    }
    if f.base_from_laser.is_none() {
        let why = unknown_why(s, f.frame.as_deref(), &s.log_mount_note);
        match nominal.robot.laser {
            Some(l) => {
                f.base_from_laser = Some([l.x, l.y, l.yaw]);
                f.source = Some("robot_file");
                f.note = format!("the robot file's [laser]; the recording states none: {why}");
            }
            None => f.note = why,
        }
    }
    f
}

/// Walks `frame` up the static transforms, else up the first dynamic ones.
fn from_transforms(s: &Survey, frame: &str, topics: &TopicConfig, f: &mut LaserFinding) {
    let on = |t: &str| -> Vec<&TfEdge> { s.transforms.iter().filter(|e| e.topic == t).collect() };
    let (statics, dynamics) = (on(&topics.tf_static), on(&topics.tf));
    for (edges, source) in [(statics, "tf_static"), (dynamics, "tf")] {
        if let Some((pose, z, chain)) = walk(&edges, frame) {
            f.base_from_laser = Some(geom::xyt(&pose).map(|v| v + 0.0));
            f.z_m = Some(z);
            f.source = Some(source);
            f.note = format!("{} from {}", chain.join(" → "), edges_topic(&edges));
            f.chain = chain;
            return;
        }
    }
}

fn edges_topic(edges: &[&TfEdge]) -> String {
    let mut t: Vec<&str> = edges.iter().map(|e| e.topic.as_str()).collect();
    t.sort_unstable();
    t.dedup();
    t.join(", ")
}

/// `base_link_from_frame`, the height and the chain from `base_link`, or
/// `None` when the edges do not lead from `frame` to `base_link`.
fn walk(edges: &[&TfEdge], frame: &str) -> Option<(Pose2, f64, Vec<String>)> {
    let parent: HashMap<&str, &TfEdge> = edges.iter().map(|e| (e.child.as_str(), *e)).collect();
    let mut acc = Pose2::identity();
    let mut z = 0.0;
    let mut chain = vec![frame.to_string()];
    let mut cur = frame;
    for _ in 0..32 {
        if cur == BASE_FRAME {
            chain.reverse();
            return Some((acc, z, chain));
        }
        let e = parent.get(cur)?;
        acc = geom::pose(e.xyz[0], e.xyz[1], e.yaw) * acc;
        z += e.xyz[2];
        cur = e.parent.as_str();
        chain.push(cur.to_string());
    }
    None
}

/// Why no mounting was found: the frames the tree has, a base frame by
/// another name.
fn unknown_why(s: &Survey, frame: Option<&str>, log_note: &Option<String>) -> String {
    if let Some(n) = log_note {
        return n.clone();
    }
    let Some(frame) = frame else {
        return "no laser scans, so no laser frame".into();
    };
    let mut frames: Vec<&str> = s
        .transforms
        .iter()
        .flat_map(|e| [e.parent.as_str(), e.child.as_str()])
        .collect();
    frames.sort_unstable();
    frames.dedup();
    if frames.is_empty() {
        return format!("the scans are in frame '{frame}' and the recording has no transforms");
    }
    let base = if frames.contains(&BASE_FRAME) {
        String::new()
    } else {
        let like: Vec<&str> = frames
            .iter()
            .copied()
            .filter(|f| f.contains("base") || f.contains("footprint"))
            .collect();
        format!(
            "; there is no '{BASE_FRAME}' frame, odocal's robot base{}",
            if like.is_empty() {
                String::new()
            } else {
                format!(" (frames like it: {})", like.join(", "))
            }
        )
    };
    format!(
        "the scans are in frame '{frame}', which the transforms do not link to {BASE_FRAME} \
         (frames: {}){base}",
        frames.join(", ")
    )
}
