//! Where each nominal value a run used came from: the recording (`tf_static`,
//! `tf`, a log's own laser pose), the robot file, an estimate, or a default.
//! Every command that uses a nominal value states it, so that no number rests
//! on an assumption the user cannot see (design.md's `assumptions` key).

use serde::Serialize;
use std::collections::BTreeMap;

/// The source of one nominal value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// The recording's static transforms (`/tf_static`).
    TfStatic,
    /// The recording's dynamic transforms (`/tf`).
    Tf,
    /// The log itself (a CARMEN laser line's laser pose against its odometry
    /// pose).
    Log,
    /// What streams the recording holds (e.g. which one gives the scan
    /// matcher its initial guesses).
    Recording,
    /// The robot file (`--robot`).
    RobotFile,
    /// Estimated from the data by this run.
    Estimated,
    /// The configuration file (`--config`).
    Config,
    /// A built-in default, not stated by the user or the data.
    Default,
}

impl Origin {
    /// The JSON name (`tf_static`, `robot_file`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            Origin::TfStatic => "tf_static",
            Origin::Tf => "tf",
            Origin::Log => "log",
            Origin::Recording => "recording",
            Origin::RobotFile => "robot_file",
            Origin::Estimated => "estimated",
            Origin::Config => "config",
            Origin::Default => "default",
        }
    }

    /// Words for the human output.
    pub fn describe(self) -> &'static str {
        match self {
            Origin::TfStatic => "the recording's /tf_static",
            Origin::Tf => "the recording's /tf",
            Origin::Log => "the log's laser pose",
            Origin::Recording => "the recording's streams",
            Origin::RobotFile => "the robot file",
            Origin::Estimated => "estimated from the data",
            Origin::Config => "the --config file",
            Origin::Default => "default",
        }
    }
}

/// One nominal value, where it came from and, when useful, why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Assumption {
    /// The value as used (a number in SI units, a name, or a small object).
    pub value: serde_json::Value,
    /// Where it came from.
    pub source: Origin,
    /// What the user may want to know (e.g. what to set to change it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// Every nominal value of a run, by name (`r_right`, `laser`, …).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Assumptions(pub BTreeMap<String, Assumption>);

impl Assumptions {
    /// Records `name`'s value and source.
    pub fn set(&mut self, name: &str, value: impl Serialize, source: Origin, note: Option<String>) {
        let value = serde_json::to_value(value).unwrap_or(serde_json::Value::Null);
        self.0.insert(
            name.to_string(),
            Assumption {
                value,
                source,
                note,
            },
        );
    }

    /// Whether nothing is recorded.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The source of `name`, when recorded.
    pub fn source(&self, name: &str) -> Option<Origin> {
        self.0.get(name).map(|a| a.source)
    }

    /// One line per value, for the human output: `name = value (source)`.
    pub fn lines(&self) -> Vec<String> {
        self.0
            .iter()
            .map(|(name, a)| {
                let note = a
                    .note
                    .as_deref()
                    .map(|n| format!("; {n}"))
                    .unwrap_or_default();
                format!("{name} = {} ({}{note})", a.value, a.source.describe())
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn serialises_by_name_with_snake_case_sources() {
        let mut a = Assumptions::default();
        a.set("wheel_base", 0.65, Origin::RobotFile, None);
        a.set(
            "laser",
            [0.1, 0.0, 0.0],
            Origin::TfStatic,
            Some("frame laser".into()),
        );
        let j = serde_json::to_value(&a).unwrap();
        assert_eq!(j["wheel_base"]["source"], "robot_file");
        assert_eq!(j["laser"]["source"], "tf_static");
        assert_eq!(j["laser"]["note"], "frame laser");
        assert!(j["wheel_base"].get("note").is_none());
        assert_eq!(a.lines().len(), 2);
    }
}
