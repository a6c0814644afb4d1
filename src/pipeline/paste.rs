//! What a user pastes after `odocal calibrate`: the `diff_drive_controller`
//! parameters of ros2_control (`DIR/ros2_control.yaml`) and, when the laser
//! mounting was estimated (`--method batch`), a URDF joint and a
//! `static_transform_publisher` line (`DIR/laser_mount.urdf`).
//!
//! ros2_controllers' `diff_drive_controller` computes each wheel's radius as
//! `wheel_radius × left/right_wheel_radius_multiplier` and the separation as
//! `wheel_separation × wheel_separation_multiplier` (its odometry and its
//! inverse kinematics alike). It has one `wheel_radius`: the YAML gives the
//! nominal mean radius and the nominal wheel base with the multipliers that
//! turn them into the calibrated right and left radii and wheel base, so the
//! controller's effective values are the calibrated ones whatever the
//! multipliers were before (paste all five together).

use crate::calib::CalibSummary;
use crate::robot::{DiffDrive, RobotConfig, WheelSourceKind};
use serde::Serialize;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The controller name the YAML is keyed by (rename it to yours).
pub const CONTROLLER: &str = "diff_drive_controller";
/// The file names in the calibration's output directory.
pub const YAML_FILE: &str = "ros2_control.yaml";
/// See [`YAML_FILE`].
pub const URDF_FILE: &str = "laser_mount.urdf";

/// `diff_drive_controller`'s calibration parameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ControllerParams {
    /// The nominal mean wheel radius (m).
    pub wheel_radius: f64,
    /// The nominal wheel base (m).
    pub wheel_separation: f64,
    /// Calibrated left radius / `wheel_radius`.
    pub left_wheel_radius_multiplier: f64,
    /// Calibrated right radius / `wheel_radius`.
    pub right_wheel_radius_multiplier: f64,
    /// Calibrated wheel base / `wheel_separation`.
    pub wheel_separation_multiplier: f64,
    /// The robot file's wheel joints, when the wheels were JointState joints.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub left_wheel_names: Option<Vec<String>>,
    /// See `left_wheel_names`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub right_wheel_names: Option<Vec<String>>,
}

/// The ros2_control parameters and their YAML text.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ros2Control {
    /// The key the YAML puts them under.
    pub controller: String,
    /// The values.
    pub parameters: ControllerParams,
    /// The file's text.
    pub yaml: String,
}

/// The estimated laser mounting as a URDF joint and a static transform.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LaserSnippet {
    /// Parent frame.
    pub parent: String,
    /// Child frame (rename to the scans' frame).
    pub child: String,
    /// x (m), y (m), yaw (rad) with their std.
    pub xyz_yaw: [f64; 3],
    /// Standard deviations of x, y (m) and yaw (rad).
    pub std: [f64; 3],
    /// A URDF `<joint>` element.
    pub urdf: String,
    /// A ROS 2 `static_transform_publisher` command line.
    pub static_transform: String,
}

/// Everything to paste (JSON keys `ros2_control`, `laser_mount`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Paste {
    /// The controller's parameters.
    pub ros2_control: Ros2Control,
    /// The laser mounting, when it was estimated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub laser_mount: Option<LaserSnippet>,
}

/// A calibration summary with what to paste, as `--json` and `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct WithPaste<'a> {
    #[serde(flatten)]
    summary: &'a CalibSummary,
    #[serde(flatten)]
    paste: &'a Paste,
}

impl Paste {
    /// What to paste after the calibration `s` of `robot` (read from `input`).
    pub fn of(s: &CalibSummary, robot: &RobotConfig, input: &str) -> Self {
        Self {
            ros2_control: ros2_control(s, robot, input),
            laser_mount: s.batch.as_ref().map(|b| {
                let l = &b.laser;
                laser(
                    [l.x.value, l.y.value, l.yaw.value],
                    [l.x.std, l.y.std, l.yaw.std],
                    input,
                )
            }),
        }
    }

    /// The summary with these keys added.
    pub fn with<'a>(&'a self, summary: &'a CalibSummary) -> WithPaste<'a> {
        WithPaste {
            summary,
            paste: self,
        }
    }

    /// The files [`Self::write`] writes into `dir` (the URDF only with a
    /// mounting; `batch` says whether there will be one).
    pub fn paths(dir: &Path, batch: bool) -> Vec<PathBuf> {
        let mut v = vec![dir.join(YAML_FILE)];
        if batch {
            v.push(dir.join(URDF_FILE));
        }
        v
    }

    /// Writes the YAML and, with a mounting, the URDF snippet, each atomically.
    pub fn write(&self, dir: &Path) -> Result<(), super::PipelineError> {
        let mut files = vec![(dir.join(YAML_FILE), self.ros2_control.yaml.clone())];
        if let Some(l) = &self.laser_mount {
            let text = format!(
                "<!-- or, without a URDF:\n     {} -->\n{}",
                l.static_transform, l.urdf
            );
            files.push((dir.join(URDF_FILE), text));
        }
        for (path, text) in files {
            crate::io::atomic::write_bytes_atomic(&path, text.as_bytes())
                .map_err(|e| super::PipelineError::write(&path, e))?;
        }
        Ok(())
    }
}

fn params(
    cal: &DiffDrive,
    nominal: &DiffDrive,
    robot: &RobotConfig,
    s: &CalibSummary,
) -> ControllerParams {
    let radius = 0.5 * (nominal.r_right + nominal.r_left);
    let joints = s
        .wheel_source
        .as_ref()
        .is_some_and(|w| w.kind == WheelSourceKind::JointStates);
    ControllerParams {
        wheel_radius: radius,
        wheel_separation: nominal.wheel_base,
        left_wheel_radius_multiplier: cal.r_left / radius,
        right_wheel_radius_multiplier: cal.r_right / radius,
        wheel_separation_multiplier: cal.wheel_base / nominal.wheel_base,
        left_wheel_names: joints.then(|| vec![robot.left_joint.clone()]),
        right_wheel_names: joints.then(|| vec![robot.right_joint.clone()]),
    }
}

fn ros2_control(s: &CalibSummary, robot: &RobotConfig, input: &str) -> Ros2Control {
    let nominal = robot.diff_drive();
    let p = params(&s.final_params, &nominal, robot, s);
    let mut comments = vec![
        format!(
            "diff_drive_controller (ros2_controllers) parameters from `odocal calibrate --method \
             {}` on {input}.",
            s.method
        ),
        format!(
            "Effective values: right radius {:.6} ± {:.6} m, left radius {:.6} ± {:.6} m, wheel \
             separation {:.6} ± {:.6} m",
            s.final_params.r_right,
            s.std.r_right,
            s.final_params.r_left,
            s.std.r_left,
            s.final_params.wheel_base,
            s.std.wheel_base
        ),
        "(wheel_radius × left/right_wheel_radius_multiplier, wheel_separation × \
         wheel_separation_multiplier)."
            .into(),
        "Paste all five values together; rename the top key to your controller's name.".into(),
    ];
    comments.extend(caveats(s));
    Ros2Control {
        controller: CONTROLLER.into(),
        yaml: controller_yaml(&p, &comments),
        parameters: p,
    }
}

/// The ros2_control YAML of `p` under [`CONTROLLER`], after `comments` (one
/// `#` line each; a line break inside one starts a new `#` line, so that no
/// text, e.g. a file name, can leave the comment).
pub fn controller_yaml(p: &ControllerParams, comments: &[String]) -> String {
    let mut y = String::new();
    for c in comments {
        for line in c.replace("\r\n", "\n").split(['\n', '\r']) {
            let _ = writeln!(y, "# {}", yaml_safe(line));
        }
    }
    let _ = writeln!(y, "{CONTROLLER}:\n  ros__parameters:");
    let _ = writeln!(y, "    wheel_radius: {:.6}", p.wheel_radius);
    let _ = writeln!(y, "    wheel_separation: {:.6}", p.wheel_separation);
    let _ = writeln!(
        y,
        "    left_wheel_radius_multiplier: {:.6}",
        p.left_wheel_radius_multiplier
    );
    let _ = writeln!(
        y,
        "    right_wheel_radius_multiplier: {:.6}",
        p.right_wheel_radius_multiplier
    );
    let _ = writeln!(
        y,
        "    wheel_separation_multiplier: {:.6}",
        p.wheel_separation_multiplier
    );
    if let (Some(l), Some(r)) = (&p.left_wheel_names, &p.right_wheel_names) {
        let _ = writeln!(y, "    left_wheel_names: [{}]", yaml_names(l));
        let _ = writeln!(y, "    right_wheel_names: [{}]", yaml_names(r));
    }
    y
}

fn yaml_names(v: &[String]) -> String {
    v.iter()
        .map(|n| yaml_quoted(n))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether YAML 1.2 lets `c` stand in a document as itself, without ending
/// a line (its printable set less the line breaks NEL, LS and PS; YAML 1.2
/// §5.1, §5.4).
fn yaml_plain_char(c: char) -> bool {
    matches!(c, '\t' | '\u{20}'..='\u{7e}' | '\u{a0}'..='\u{d7ff}' | '\u{e000}'..='\u{fffd}')
        && !matches!(c, '\u{2028}' | '\u{2029}')
        || c >= '\u{10000}'
}

/// `c` as a YAML double-quoted escape (`\u`/`\U` + hex).
fn yaml_escape(c: char) -> String {
    match u32::from(c) {
        n @ 0..=0xffff => format!("\\u{n:04x}"),
        n => format!("\\U{n:08x}"),
    }
}

/// `text` with every character a YAML comment cannot hold as itself (a
/// control character, a line break) written as its escape: no text can
/// leave the comment or make the file unreadable.
fn yaml_safe(text: &str) -> String {
    text.chars()
        .map(|c| {
            if yaml_plain_char(c) {
                c.to_string()
            } else {
                yaml_escape(c)
            }
        })
        .collect()
}

/// `text` as a YAML double-quoted scalar that reads back as exactly `text`
/// (written by hand: JSON's quoting, which serde offers, leaves DEL, C1
/// controls and the line breaks LS and PS raw, which YAML refuses or folds).
fn yaml_quoted(text: &str) -> String {
    let mut q = String::with_capacity(text.len() + 2);
    q.push('"');
    for c in text.chars() {
        match c {
            '"' => q.push_str("\\\""),
            '\\' => q.push_str("\\\\"),
            c if yaml_plain_char(c) && c != '\t' => q.push(c),
            c => q.push_str(&yaml_escape(c)),
        }
    }
    q.push('"');
    q
}

/// What the user should know before pasting: weak parameters, a twist source.
fn caveats(s: &CalibSummary) -> Vec<String> {
    let mut v = Vec::new();
    if let Some(o) = &s.observability {
        for (name, p) in &o.parameters {
            if p.weak {
                v.push(format!(
                    "{name} is weakly determined by this recording{}: its std is widened",
                    p.missing
                        .as_deref()
                        .map(|m| format!(" ({m})"))
                        .unwrap_or_default()
                ));
            }
        }
    }
    if s.wheel_source
        .as_ref()
        .is_some_and(|w| w.kind == WheelSourceKind::Odometry)
    {
        v.push(
            "The wheels came from the controller's own odometry twist: the robot file's radii \
             and wheel base were taken to be the controller's effective ones."
                .into(),
        );
    }
    v
}

fn laser(v: [f64; 3], std: [f64; 3], input: &str) -> LaserSnippet {
    let [x, y, yaw] = v.map(|a| a + 0.0);
    let (parent, child) = ("base_link", "laser");
    let urdf = format!(
        "<!-- laser mounting estimated by `odocal calibrate --method batch` on {input}:\n     \
         x {x:.4} ± {:.4} m, y {y:.4} ± {:.4} m, yaw {yaw:.5} ± {:.5} rad. A planar \
         calibration\n     cannot see the height, roll or pitch: set z and keep your roll and \
         pitch. Rename the child link to your laser's frame. -->\n\
         <joint name=\"{child}_joint\" type=\"fixed\">\n  <parent link=\"{parent}\"/>\n  \
         <child link=\"{child}\"/>\n  <origin xyz=\"{x:.6} {y:.6} 0\" rpy=\"0 0 {yaw:.6}\"/>\n\
         </joint>\n",
        std[0], std[1], std[2]
    );
    let static_transform = format!(
        "ros2 run tf2_ros static_transform_publisher --x {x:.6} --y {y:.6} --z 0 --yaw {yaw:.6} \
         --frame-id {parent} --child-frame-id {child}"
    );
    LaserSnippet {
        parent: parent.into(),
        child: child.into(),
        xyz_yaw: [x, y, yaw],
        std,
        urdf,
        static_transform,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names and a comment no YAML quoting of JSON's survives (DEL, a C1
    /// control, the line breaks NEL and LS, a quote, a backslash) read back
    /// exactly by a YAML parser, and the comment stays a comment.
    #[test]
    fn names_and_comments_of_any_text_read_back() {
        let left = "l\u{7f}\u{85}wheel\"\\\t".to_string();
        let right = "r\u{2028}\u{9b}\u{1}joint".to_string();
        let p = ControllerParams {
            wheel_radius: 0.1,
            wheel_separation: 0.5,
            left_wheel_radius_multiplier: 1.0123456,
            right_wheel_radius_multiplier: 0.98,
            wheel_separation_multiplier: 1.05,
            left_wheel_names: Some(vec![left.clone()]),
            right_wheel_names: Some(vec![right.clone()]),
        };
        let note = "on a\u{85}b: x\u{2029}c\r\nd\u{1b}".to_string();
        let yaml = controller_yaml(&p, &[note]);
        let doc: serde_yaml_ng::Value = serde_yaml_ng::from_str(&yaml).expect(&yaml);
        assert_eq!(doc.as_mapping().map(|m| m.len()), Some(1), "{yaml}");
        let params = &doc[CONTROLLER]["ros__parameters"];
        assert_eq!(params["left_wheel_names"][0].as_str(), Some(left.as_str()));
        assert_eq!(
            params["right_wheel_names"][0].as_str(),
            Some(right.as_str())
        );
        assert_eq!(
            params["left_wheel_radius_multiplier"].as_f64(),
            Some(1.012346)
        );
        // The note's two lines are two comment lines, nothing else.
        assert_eq!(yaml.lines().filter(|l| l.starts_with('#')).count(), 2);
    }
}
