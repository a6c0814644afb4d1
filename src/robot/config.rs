//! Nominal robot description, loadable from TOML (`--robot FILE.toml`).

use super::wheels::{WheelSourceKind, WheelsConfig};
use crate::geom::{self, Pose2};
use serde::{Deserialize, Serialize};

/// Where the laser sits on the robot: `base_from_laser` as x, y (m) and yaw (rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaserMount {
    /// Forward offset from the base origin (m).
    pub x: f64,
    /// Leftward offset (m).
    pub y: f64,
    /// Yaw of the laser x axis relative to base x (rad).
    pub yaw: f64,
}

impl Default for LaserMount {
    /// The wheelchair's LMS111: on the back of the chair, facing backwards.
    fn default() -> Self {
        Self {
            x: -0.45,
            y: 0.0,
            yaw: std::f64::consts::PI,
        }
    }
}

impl LaserMount {
    /// The mounting as a pose `base_from_laser`.
    pub fn pose(&self) -> Pose2 {
        geom::pose(self.x, self.y, self.yaw)
    }
}

/// Corrections of a scanner whose recorded beam geometry or ranges are
/// known to be off (the robot file's optional `[scanner]`): applied to
/// every scan before matching ([`crate::scan::LaserScan::corrected`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScannerCorrection {
    /// The true angle between beams (rad, positive), replacing the
    /// recording's; the beam the recording puts at angle 0 stays there.
    /// `None`: the recording's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_increment: Option<f64>,
    /// Added to every valid range (m); a scanner that reads short has a
    /// positive offset. Its validity limits move with it.
    pub range_offset: f64,
}

impl ScannerCorrection {
    /// Whether it changes nothing.
    pub fn is_none(&self) -> bool {
        self.angle_increment.is_none() && self.range_offset == 0.0
    }
}

/// A differential-drive robot's nominal parameters and sensor layout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobotConfig {
    /// Human-readable name.
    pub name: String,
    /// Right wheel radius (m).
    pub r_right: f64,
    /// Left wheel radius (m).
    pub r_left: f64,
    /// Distance between the wheel contact points (m).
    pub wheel_base: f64,
    /// Encoder ticks per wheel revolution (may be fractional after a gear,
    /// e.g. 691.2 × 4 on a Khepera III).
    pub ticks_per_rev: f64,
    /// JointState name of the left wheel joint.
    pub left_joint: String,
    /// JointState name of the right wheel joint.
    pub right_joint: String,
    /// Laser mounting, used when the recording states none (/tf_static, a
    /// CARMEN log's laser pose). `None`: unknown — it is then estimated
    /// (`calibrate --method batch`) or the run stops naming `[laser]`; a
    /// file without a `[laser]` table never inherits the wheelchair's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub laser: Option<LaserMount>,
    /// Where the wheels are reported (`[wheels]`; absent: JointState).
    #[serde(default, skip_serializing_if = "WheelsConfig::is_default")]
    pub wheels: WheelsConfig,
    /// Corrections of the scanner's beam angles and ranges (`[scanner]`;
    /// absent: the recording's are taken as they are).
    #[serde(default, skip_serializing_if = "ScannerCorrection::is_none")]
    pub scanner: ScannerCorrection,
}

impl Default for RobotConfig {
    /// The wheelchair of \[Farina\]: R = 0.32 m, D = 0.65 m, 8800 ticks/rev.
    fn default() -> Self {
        Self {
            name: "wheelchair".into(),
            r_right: 0.32,
            r_left: 0.32,
            wheel_base: 0.65,
            ticks_per_rev: 8800.0,
            left_joint: "left_wheel".into(),
            right_joint: "right_wheel".into(),
            laser: Some(LaserMount::default()),
            wheels: WheelsConfig::default(),
            scanner: ScannerCorrection::default(),
        }
    }
}

/// The physical range of each robot-file number: key, lowest, highest, unit.
/// Wheel radii from 1 mm (micro robots) to 2 m; a wheel base from 1 cm to
/// 10 m; 1 to 10⁸ encoder ticks per revolution; a laser within 10 m of the
/// base origin.
pub const PHYSICAL_BOUNDS: [(&str, f64, f64, &str); 6] = [
    ("r_right", 1e-3, 2.0, " m"),
    ("r_left", 1e-3, 2.0, " m"),
    ("wheel_base", 1e-2, 10.0, " m"),
    ("ticks_per_rev", 1.0, 1e8, ""),
    ("laser.x", -10.0, 10.0, " m"),
    ("laser.y", -10.0, 10.0, " m"),
];

/// A robot file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum RobotConfigError {
    /// Keys without which the file describes no robot.
    #[error(
        "robot config: {} missing; a robot file must state the wheel radii and wheel base \
         (r_right, r_left, wheel_base in m): they are never taken from another robot",
        .0.join(", ")
    )]
    Missing(Vec<&'static str>),
    /// The TOML does not parse or has unknown keys.
    #[error("robot config: {0}")]
    Parse(#[from] toml::de::Error),
    /// A value is out of its physical range.
    #[error("robot config: {0}")]
    Invalid(String),
}

/// The keys a robot file must give: the nominal kinematics.
pub const REQUIRED_KEYS: [&str; 3] = ["r_right", "r_left", "wheel_base"];

impl RobotConfig {
    /// Parses and validates a TOML robot description. The wheel radii and
    /// wheel base are required; other keys default (see [`Self::from_toml_keys`]
    /// for which were given).
    pub fn from_toml(text: &str) -> Result<Self, RobotConfigError> {
        Ok(Self::from_toml_keys(text)?.0)
    }

    /// Like [`Self::from_toml`], also returning the top-level keys the file
    /// gave (`laser` for a `[laser]` table), so that every defaulted value
    /// can be stated as an assumption.
    pub fn from_toml_keys(
        text: &str,
    ) -> Result<(Self, std::collections::BTreeSet<String>), RobotConfigError> {
        let (c, keys) = Self::from_toml_keys_open(text)?;
        if !keys.contains("r_right") {
            return Err(RobotConfigError::Missing(REQUIRED_KEYS.to_vec()));
        }
        Ok((c, keys))
    }

    /// Like [`Self::from_toml_keys`], but a file that states none of the
    /// nominal kinematics is accepted (a robot calibrated from scratch):
    /// its `r_right`, `r_left` and `wheel_base` are then the defaults, which
    /// stand in for nothing: they are never nominal values (the keys returned say they
    /// were not given). A file stating some of the three is refused.
    pub fn from_toml_keys_open(
        text: &str,
    ) -> Result<(Self, std::collections::BTreeSet<String>), RobotConfigError> {
        let table: toml::Table = toml::from_str(text)?;
        let c: Self = toml::from_str(text)?;
        let missing: Vec<&'static str> = REQUIRED_KEYS
            .into_iter()
            .filter(|k| !table.contains_key(*k))
            .collect();
        if !missing.is_empty() && missing.len() < REQUIRED_KEYS.len() {
            return Err(RobotConfigError::Missing(missing));
        }
        if c.wheels.source == WheelSourceKind::Ticks && !table.contains_key("ticks_per_rev") {
            return Err(RobotConfigError::Invalid(
                "[wheels] source = \"ticks\" needs ticks_per_rev (encoder ticks per wheel \
                 revolution): the tick counts mean nothing without it"
                    .into(),
            ));
        }
        c.validate()?;
        Ok((c, table.keys().cloned().collect()))
    }

    /// Checks that every parameter is finite and within `PHYSICAL_BOUNDS`
    /// (a value outside is a typo or a unit slip, e.g. mm for m); the error
    /// names the key, its value and its range.
    pub fn validate(&self) -> Result<(), RobotConfigError> {
        let laser = self.laser.unwrap_or(LaserMount {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
        });
        let values = [
            self.r_right,
            self.r_left,
            self.wheel_base,
            self.ticks_per_rev,
            laser.x,
            laser.y,
        ];
        for ((key, lo, hi, unit), v) in PHYSICAL_BOUNDS.iter().zip(values) {
            if !(v.is_finite() && *lo <= v && v <= *hi) {
                return Err(RobotConfigError::Invalid(format!(
                    "{key} = {v} is outside the physical range [{lo}, {hi}]{unit}"
                )));
            }
        }
        if !laser.yaw.is_finite() {
            return Err(RobotConfigError::Invalid(format!(
                "laser.yaw = {} must be finite (rad)",
                laser.yaw
            )));
        }
        let sc = &self.scanner;
        if let Some(inc) = sc.angle_increment {
            if !(inc.is_finite() && (1e-5..=0.2).contains(&inc)) {
                return Err(RobotConfigError::Invalid(format!(
                    "scanner.angle_increment = {inc} is outside the physical range [1e-5, 0.2] rad"
                )));
            }
        }
        if !(sc.range_offset.is_finite() && sc.range_offset.abs() <= 1.0) {
            return Err(RobotConfigError::Invalid(format!(
                "scanner.range_offset = {} is outside the physical range [-1, 1] m",
                sc.range_offset
            )));
        }
        if self.left_joint == self.right_joint {
            return Err(RobotConfigError::Invalid(
                "left_joint and right_joint must differ".into(),
            ));
        }
        self.wheels.validate().map_err(RobotConfigError::Invalid)
    }

    /// The nominal kinematic parameters.
    pub fn diff_drive(&self) -> super::DiffDrive {
        super::DiffDrive {
            r_right: self.r_right,
            r_left: self.r_left,
            wheel_base: self.wheel_base,
        }
    }

    /// Wheel angle of one encoder tick (rad).
    pub fn rad_per_tick(&self) -> f64 {
        2.0 * std::f64::consts::PI / self.ticks_per_rev
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_round_trips_through_toml() {
        let c = RobotConfig::default();
        let text = toml::to_string(&c).unwrap();
        assert_eq!(RobotConfig::from_toml(&text).unwrap(), c);
    }

    #[test]
    fn scanner_corrections_parse_and_are_bounded() {
        let base = "r_right = 0.02\nr_left = 0.02\nwheel_base = 0.15\n";
        let c = RobotConfig::from_toml(&format!(
            "{base}[scanner]\nangle_increment = 0.00632\nrange_offset = 0.07\n"
        ))
        .unwrap();
        assert_eq!(c.scanner.angle_increment, Some(0.00632));
        assert_eq!(c.scanner.range_offset, 0.07);
        assert!(RobotConfig::from_toml(base).unwrap().scanner.is_none());
        for (bad, key) in [
            ("angle_increment = 0.5", "scanner.angle_increment"),
            ("angle_increment = -0.006", "scanner.angle_increment"),
            ("range_offset = 70", "scanner.range_offset"),
        ] {
            let e = RobotConfig::from_toml(&format!("{base}[scanner]\n{bad}\n"))
                .unwrap_err()
                .to_string();
            assert!(e.contains(key), "{e}");
        }
        assert!(RobotConfig::from_toml(&format!("{base}[scanner]\nscale = 1\n")).is_err());
    }

    #[test]
    fn kinematics_are_required_and_unknown_keys_are_refused() {
        let base = "r_right = 0.05\nr_left = 0.05\nwheel_base = 0.7\n";
        let (c, keys) = RobotConfig::from_toml_keys(&format!("{base}[laser]\nx = 0.1\n")).unwrap();
        assert_eq!(c.wheel_base, 0.7);
        assert_eq!(c.laser.unwrap().x, 0.1);
        assert!(keys.contains("laser") && !keys.contains("ticks_per_rev"));
        // Without [laser] the mounting is unknown, not the wheelchair's.
        assert_eq!(RobotConfig::from_toml(base).unwrap().laser, None);
        for missing in [
            "",
            "wheel_base = 0.7\n",
            "r_right = 0.05\nwheel_base = 0.7\n",
        ] {
            let e = RobotConfig::from_toml(missing).unwrap_err().to_string();
            assert!(e.contains("missing") && e.contains("r_left"), "{e}");
        }
        assert!(RobotConfig::from_toml(&format!("{base}wheelbase = 0.7")).is_err());
        let with = |key: &str, v: &str| {
            let text = format!("{base}ticks_per_rev = 100\n")
                .lines()
                .map(|l| {
                    if l.starts_with(key) {
                        format!("{key} = {v}")
                    } else {
                        l.into()
                    }
                })
                .collect::<Vec<_>>()
                .join("\n");
            RobotConfig::from_toml(&text)
        };
        assert!(with("r_left", "0.3").is_ok());
        assert!(with("r_left", "-0.3").is_err() && with("r_left", "nan").is_err());
        assert!(with("ticks_per_rev", "0").is_err());
    }

    #[test]
    fn a_wheels_table_is_read_and_ticks_need_ticks_per_rev() {
        let base = "r_right = 0.05\nr_left = 0.05\nwheel_base = 0.3\n";
        let c =
            RobotConfig::from_toml(&format!("{base}[wheels]\nsource = \"odometry\"\n")).unwrap();
        assert_eq!(c.wheels.source, WheelSourceKind::Odometry);
        let ticks = "[wheels]\nsource = \"ticks\"\ntopic = \"/ticks\"\n\
                     ticks_type = \"std_msgs/msg/Int64MultiArray\"\n";
        let e = RobotConfig::from_toml(&format!("{base}{ticks}"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("ticks_per_rev"), "{e}");
        let c = RobotConfig::from_toml(&format!("{base}ticks_per_rev = 4096\n{ticks}")).unwrap();
        assert_eq!(c.wheels.ticks_layout().unwrap().wrap_bits, 64);
        let text = toml::to_string(&c).unwrap();
        assert_eq!(RobotConfig::from_toml(&text).unwrap(), c);
        let e = RobotConfig::from_toml(&format!("{base}[wheels]\nticks_type = \"x\"\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("Int32MultiArray"), "{e}");
    }

    #[test]
    fn bundled_robot_files_load() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scans/robots");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap() {
            let text = std::fs::read_to_string(e.unwrap().path()).unwrap();
            RobotConfig::from_toml(&text).unwrap();
            n += 1;
        }
        assert!(n >= 4);
    }
}
