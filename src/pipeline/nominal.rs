//! The nominal robot of a run and where each of its values came from: the
//! robot file, the recording (the laser mounting), or a default. No value of
//! the wheelchair's is applied to a recording that did not ask for it: the
//! laser mounting is taken from the recording or the robot file, or the run
//! stops naming the key to set.

use super::PipelineError;
use crate::assumptions::{Assumptions, Origin};
use crate::error::InputError;
use crate::geom::{self, Pose2};
use crate::icp::{IcpParams, Prior, PriorChoice};
use crate::io::StreamInfo;
use crate::recording::WheelValues;
use crate::robot::{DiffDrive, LaserMount, RobotConfig, WheelSourceKind};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The assumptions of the wheel model: used by a run only when wheel
/// odometry enters it.
const WHEEL_KEYS: [&str; 6] = [
    "r_right",
    "r_left",
    "wheel_base",
    "ticks_per_rev",
    "left_joint",
    "right_joint",
];

/// The nominal robot, the file it came from and the keys that file gave.
#[derive(Debug, Clone, PartialEq)]
pub struct Nominal {
    /// The values used (the wheelchair's kinematics without a robot file,
    /// but never its laser mounting).
    pub robot: RobotConfig,
    /// The robot file, when one was given.
    pub file: Option<PathBuf>,
    /// The top-level keys the robot file gave.
    pub given: BTreeSet<String>,
}

impl Nominal {
    /// Loads `path`, or, without one, the wheelchair's kinematics with an
    /// unknown laser mounting.
    pub fn load(path: Option<&Path>) -> Result<Self, PipelineError> {
        let Some(path) = path else {
            let robot = RobotConfig {
                laser: None,
                ..RobotConfig::default()
            };
            return Ok(Self {
                robot,
                file: None,
                given: BTreeSet::new(),
            });
        };
        Self::load_with(Some(path), RobotConfig::from_toml_keys)
    }

    /// Like [`Self::load`], but a robot file may state no nominal
    /// kinematics at all ([`Self::kinematics`] is then `None`): for the
    /// online calibration, which starts from a closed-form fit of the first
    /// minutes instead.
    pub fn load_open(path: Option<&Path>) -> Result<Self, PipelineError> {
        match path {
            None => Self::load(None),
            Some(_) => Self::load_with(path, RobotConfig::from_toml_keys_open),
        }
    }

    fn load_with(
        path: Option<&Path>,
        parse: fn(&str) -> Result<(RobotConfig, BTreeSet<String>), crate::robot::RobotConfigError>,
    ) -> Result<Self, PipelineError> {
        let Some(path) = path else {
            return Self::load(None);
        };
        let (text, name) = robot_text(path)?;
        let (robot, given) = parse(&text).map_err(|e| InputError::new(name, e.to_string()))?;
        Ok(Self {
            robot,
            file: Some(path.to_path_buf()),
            given,
        })
    }

    /// The nominal kinematics, `None` when the robot file states none
    /// (loaded by [`Self::load_open`]).
    pub fn kinematics(&self) -> Option<DiffDrive> {
        let unknown = self.file.is_some() && !self.given.contains("r_right");
        (!unknown).then(|| self.robot.diff_drive())
    }

    /// Where `key` of the robot came from.
    fn origin(&self, key: &str) -> Origin {
        if self.given.contains(key) {
            Origin::RobotFile
        } else {
            Origin::Default
        }
    }

    /// The robot's values and the laser mounting `mount`, with their sources.
    pub fn assumptions_with(&self, mount: &Mount) -> Assumptions {
        let mut a = self.assumptions();
        mount.state(&mut a);
        a
    }

    /// The scan matcher's prior for a recording with `info`'s streams:
    /// `[icp] prior` as `given`, except that `auto` without a robot file
    /// takes the recording's own odometry when it has one beside its wheels:
    /// the wheels would be integrated with assumed kinematics (the
    /// wheelchair's), the odometry needs none.
    pub fn prior_choice(&self, given: PriorChoice, info: &StreamInfo) -> PriorChoice {
        match given {
            PriorChoice::Auto if self.file.is_none() && info.wheels >= 2 && info.odom >= 2 => {
                PriorChoice::Odometry
            }
            // No kinematics to integrate the wheels with.
            PriorChoice::Auto if self.kinematics().is_none() => {
                if info.odom >= 2 {
                    PriorChoice::Odometry
                } else {
                    PriorChoice::None
                }
            }
            c => c,
        }
    }

    /// `params` with its prior resolved for a recording with `info`'s
    /// streams (see [`Self::prior_choice`]).
    pub fn icp_params(&self, params: &IcpParams, info: &StreamInfo) -> IcpParams {
        IcpParams {
            prior: self.prior_choice(params.prior, info),
            ..params.clone()
        }
    }

    /// What `odocal icp` used: the laser mounting `mount`, the scanner
    /// corrections, the stream each pair's initial guess came from
    /// (`prior`, chosen from `[icp] prior` = `given` for a recording with
    /// `wheel_samples`) and, only when that is the wheels, the wheel model it
    /// was integrated with. Odometry from the recording or no prior at all
    /// uses no wheel radius or wheel base, so none is stated.
    pub fn icp_assumptions(
        &self,
        mount: &Mount,
        prior: &Prior,
        given: PriorChoice,
        info: &StreamInfo,
    ) -> Assumptions {
        let mut a = self.assumptions_with(mount);
        if matches!(prior, Prior::Wheels(_)) {
            self.drop_unused_wheel_keys(&mut a, info.wheel_values);
        } else {
            a.0.retain(|k, _| !WHEEL_KEYS.contains(&k.as_str()));
        }
        self.state_prior(&mut a, prior, given, info.wheels);
        a
    }

    /// Records the scan matcher's prior in `a` under `prior` (see
    /// [`Self::prior_reason`]), its source: the recording's streams, the
    /// `--config` file's `[icp] prior` (`given`), or the default of none.
    pub fn state_prior(
        &self,
        a: &mut Assumptions,
        prior: &Prior,
        given: PriorChoice,
        wheel_samples: usize,
    ) {
        let (value, why) = self.prior_reason(prior, given, wheel_samples);
        let source = match (given, prior) {
            (PriorChoice::Auto, Prior::None) => Origin::Default,
            (PriorChoice::Auto, _) => Origin::Recording,
            _ => Origin::Config,
        };
        let note = format!("each pair's initial guess and the prior term's centre: {why}");
        a.set("prior", value, source, Some(note));
    }

    /// The word for the scan matcher's `prior` (`wheels`, `odometry`,
    /// `none`) and why it is the one and what it brings in, for a recording
    /// with `wheel_samples` under `[icp] prior` = `given`: what every run
    /// states and `inspect` foretells.
    pub fn prior_reason(
        &self,
        prior: &Prior,
        given: PriorChoice,
        wheel_samples: usize,
    ) -> (&'static str, String) {
        let auto = given == PriorChoice::Auto;
        let why = match prior {
            Prior::Wheels(_) if self.file.is_none() => {
                "wheel odometry, integrated with the wheelchair's r_right, r_left and wheel_base \
                 (no robot file states this robot's: the scans correct a guess somewhat off, a \
                 far-off one fails pairs; --robot ROBOT.toml)"
            }
            Prior::Wheels(_) => {
                "wheel odometry, integrated with the robot file's r_right, r_left and wheel_base"
            }
            Prior::Odom if wheel_samples >= 2 && auto => {
                "the recording's own odometry, preferred to its wheels as no robot file states \
                 their kinematics (--robot ROBOT.toml, or [icp] prior = \"wheels\", takes the \
                 wheels)"
            }
            Prior::Odom => {
                "the recording's own odometry, which takes no wheel radius or wheel base"
            }
            Prior::None if auto => {
                "neither a wheel stream nor odometry ([topics] in a --config file names them): \
                 each pair starts from the previous one's velocity (the first from rest), and no \
                 prior term holds what the scans leave loose"
            }
            Prior::None => {
                "each pair starts from the previous one's velocity (the first from rest), and no \
                 prior term holds what the scans leave loose"
            }
        };
        let value = match prior {
            Prior::Wheels(_) => "wheels",
            Prior::Odom => "odometry",
            Prior::None => "none",
        };
        (value, why.to_string())
    }

    /// Removes from `a` the wheel keys that wheel samples read as `values`
    /// do not use: `ticks_per_rev` unless they are tick counts, the joint
    /// names unless they are JointState's (a twist is an odometry's).
    pub fn drop_unused_wheel_keys(&self, a: &mut Assumptions, values: Option<WheelValues>) {
        if values.is_some_and(|v| v != WheelValues::Ticks) {
            a.0.remove("ticks_per_rev");
        }
        let twist = values == Some(WheelValues::Twist);
        if twist || self.robot.wheels.source != WheelSourceKind::JointStates {
            a.0.remove("left_joint");
            a.0.remove("right_joint");
        }
    }

    /// The robot's values and their sources (the laser mounting is added by
    /// [`Mount::state`] once the recording is known).
    pub fn assumptions(&self) -> Assumptions {
        let r = &self.robot;
        let hint = |k: &str| match (&self.file, self.origin(k)) {
            (None, _) => Some("the wheelchair's; give --robot ROBOT.toml for another robot".into()),
            (Some(f), Origin::Default) => Some(format!("{} does not set `{k}`", f.display())),
            _ => None,
        };
        let mut a = Assumptions::default();
        let unknown = self.kinematics().is_none();
        for (k, v) in [
            ("r_right", r.r_right),
            ("r_left", r.r_left),
            ("wheel_base", r.wheel_base),
            ("ticks_per_rev", r.ticks_per_rev),
        ] {
            if unknown && k != "ticks_per_rev" {
                let note = "the robot file states no nominal value: the filters start from a \
                            closed-form fit of the first minutes (the warm-up), and no estimate \
                            is judged against a nominal one";
                a.set(k, Option::<f64>::None, Origin::RobotFile, Some(note.into()));
                continue;
            }
            a.set(k, v, self.origin(k), hint(k));
        }
        for (k, v) in [
            ("left_joint", &r.left_joint),
            ("right_joint", &r.right_joint),
        ] {
            a.set(k, v, self.origin(k), hint(k));
        }
        if !r.scanner.is_none() {
            let note = "applied to every scan before matching".to_string();
            a.set("scanner", r.scanner, self.origin("scanner"), Some(note));
        }
        a
    }
}

/// The text of a robot file and the name errors give it: the file, or, for a
/// bare name that is no file, one of the robots compiled in from
/// `scans/robots/` (so that `--robot khepera` works from an installed binary).
fn robot_text(path: &Path) -> Result<(String, String), PipelineError> {
    let bare = path.components().count() == 1 && !path.exists();
    if bare {
        let name = path.to_str().unwrap_or_default();
        if let Some(text) = crate::robot::bundled_robot(name) {
            return Ok((text.to_string(), format!("bundled robot {name}")));
        }
        let names: Vec<&str> = crate::robot::BUNDLED_ROBOTS
            .iter()
            .map(|(n, _)| *n)
            .collect();
        return Err(InputError::new(
            path.display().to_string(),
            format!(
                "no such file, and not a bundled robot name ({})",
                names.join(", ")
            ),
        )
        .into());
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::new(path.display().to_string(), format!("cannot read: {e}")))?;
    Ok((text, path.display().to_string()))
}

/// The laser mounting a run uses (`base_from_laser`) and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Mount {
    /// `base_from_laser`.
    pub pose: Pose2,
    /// Its source.
    pub origin: Origin,
    /// What the user may want to know about it.
    pub note: Option<String>,
}

/// What a recording says of the laser mounting.
#[derive(Debug, Clone, Copy)]
pub struct Stated<'a> {
    /// The mounting it states.
    pub pose: Option<Pose2>,
    /// From where.
    pub origin: Option<Origin>,
    /// Why it states none, when it could have.
    pub note: Option<&'a str>,
}

impl<'a> From<&'a crate::io::StreamInfo> for Stated<'a> {
    fn from(i: &'a crate::io::StreamInfo) -> Self {
        Self {
            pose: i.base_from_laser,
            origin: i.mount_origin,
            note: i.mount_note.as_deref(),
        }
    }
}

impl<'a> From<&'a crate::recording::Recording> for Stated<'a> {
    fn from(r: &'a crate::recording::Recording) -> Self {
        Self {
            pose: r.base_from_laser,
            origin: r.mount_origin,
            note: r.mount_note.as_deref(),
        }
    }
}

/// Largest difference between the robot file's mounting and the
/// recording's that is not worth a note (m, rad).
const SAME_MOUNT_M: f64 = 0.005;
const SAME_MOUNT_RAD: f64 = 0.01;

impl Mount {
    /// The mounting for `input`: the recording's when it states one, else
    /// the robot file's `[laser]`; neither → an error naming the key to set.
    pub fn resolve(
        stated: Stated,
        robot: &RobotConfig,
        input: &str,
    ) -> Result<Self, PipelineError> {
        if let Some(pose) = stated.pose {
            let note = robot.laser.and_then(|l| differs(&l, &pose));
            return Ok(Self {
                pose,
                origin: stated.origin.unwrap_or(Origin::TfStatic),
                note,
            });
        }
        match robot.laser {
            Some(l) => Ok(Self {
                pose: l.pose(),
                origin: Origin::RobotFile,
                note: stated
                    .note
                    .map(|n| format!("the recording states none: {n}")),
            }),
            None => Err(unknown(stated.note, input).into()),
        }
    }

    /// Records the mounting in `a` under `laser`.
    pub fn state(&self, a: &mut Assumptions) {
        a.set("laser", self.laser(), self.origin, self.note.clone());
    }

    /// The mounting as the robot file's table (−0 written as 0).
    pub fn laser(&self) -> LaserMount {
        let [x, y, yaw] = geom::xyt(&self.pose).map(|v| v + 0.0);
        LaserMount { x, y, yaw }
    }
}

/// The report's "Assumptions" section: every nominal value, its source and
/// what to know about it.
pub fn report_assumptions(
    r: &mut crate::viz::report::Report,
    a: &Assumptions,
) -> Result<(), PipelineError> {
    if a.is_empty() {
        return Ok(());
    }
    r.heading(2, "Assumptions");
    let rows: Vec<Vec<String>> =
        a.0.iter()
            .map(|(k, v)| {
                let note = v.note.clone().unwrap_or_default();
                vec![
                    format!("`{k}`"),
                    v.value.to_string(),
                    v.source.describe().into(),
                    note,
                ]
            })
            .collect();
    r.table(&["value", "as used", "source", "note"], &rows)
        .map_err(|e| PipelineError::Write {
            path: "report".into(),
            message: e.to_string(),
        })?;
    Ok(())
}

/// A note when the robot file's `[laser]` differs from what the recording states.
fn differs(file: &LaserMount, stated: &Pose2) -> Option<String> {
    let d = geom::between(&file.pose(), stated);
    (d.translation.vector.norm() > SAME_MOUNT_M || d.rotation.angle().abs() > SAME_MOUNT_RAD).then(
        || {
            let [x, y, yaw] = geom::xyt(stated);
            format!(
                "the recording's mounting (x {x:.3} m, y {y:.3} m, yaw {yaw:.3} rad) is used; \
                 the robot file's [laser] (x {:.3}, y {:.3}, yaw {:.3}) differs",
                file.x, file.y, file.yaw
            )
        },
    )
}

/// The error of a run whose laser mounting nobody states.
fn unknown(note: Option<&str>, input: &str) -> InputError {
    let why = note.unwrap_or("the recording states no base_link → laser transform");
    InputError::new(
        input,
        format!(
            "the laser mounting is unknown: {why}, and the robot file gives no [laser] table \
             (without --robot, no mounting is assumed). Set [laser] x, y, yaw (base_from_laser \
             in m, m, rad) in the robot file (--robot ROBOT.toml), or let \
             `odocal calibrate --method batch` estimate it (`odocal inspect {input}` shows the \
             recording's transforms)"
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stated(pose: Option<Pose2>) -> Stated<'static> {
        Stated {
            pose,
            origin: pose.map(|_| Origin::TfStatic),
            note: None,
        }
    }

    #[test]
    fn without_robot_file_no_mounting_is_assumed() {
        let n = Nominal::load(None).unwrap();
        let e = Mount::resolve(stated(None), &n.robot, "x.clf")
            .unwrap_err()
            .to_string();
        assert!(e.contains("x.clf") && e.contains("[laser]"), "{e}");
        let a = n.assumptions();
        assert_eq!(a.source("wheel_base"), Some(Origin::Default));
    }

    #[test]
    fn the_recording_wins_and_a_differing_file_is_noted() {
        let robot = RobotConfig::default();
        let m = Mount::resolve(stated(Some(Pose2::identity())), &robot, "b.mcap").unwrap();
        assert_eq!(m.origin, Origin::TfStatic);
        assert!(m.note.unwrap().contains("differs"));
        let m = Mount::resolve(stated(None), &robot, "b.mcap").unwrap();
        assert_eq!(m.origin, Origin::RobotFile);
        assert_eq!(m.pose, robot.laser.unwrap().pose());
    }
}
