//! What `odocal calibrate` is asked to do and what it gives, shared by the
//! online filters ([`super::calibrate`]) and the joint batch estimate
//! ([`super::batch`]).

use super::viewer::Viewer;
use super::Common;
use crate::calib::{self, CalibParams, CalibSummary};
use std::path::PathBuf;

/// Which calibrator `odocal calibrate` runs and how (each `None` keeps the
/// configuration file's value).
#[derive(Debug, Clone, Default)]
pub struct CalibratorChoice {
    /// The method.
    pub method: Option<calib::Method>,
    /// The resampling scheme.
    pub resampler: Option<calib::Scheme>,
    /// When to resample.
    pub trigger: Option<calib::Trigger>,
    /// The initial particle count.
    pub particles: Option<usize>,
    /// The seed of every random draw.
    pub seed: Option<u64>,
}

impl CalibratorChoice {
    /// `params` with the choices made here.
    pub fn apply(&self, params: &mut CalibParams) {
        if let Some(m) = self.method {
            params.method = m;
        }
        if let Some(r) = self.resampler {
            params.resampler = r;
        }
        if let Some(t) = self.trigger {
            params.trigger = t;
        }
        if let Some(n) = self.particles {
            params.particles = Some(n);
        }
        if let Some(s) = self.seed {
            params.seed = s;
        }
    }
}

/// What `odocal calibrate` reads: a recording (ICP runs inside), or ICP
/// motions and wheel angles or rates from CSV files.
#[derive(Debug, Clone)]
pub enum CalibSource {
    /// A recording (any format [`crate::io::sniff`] knows).
    Recording(PathBuf),
    /// Motions CSV (as `odocal icp --motions` writes) and wheels CSV.
    Csv {
        /// The motions.
        motions: PathBuf,
        /// Wheel angles `t,left,right` or rates `t0,t1,omega_right,omega_left`.
        wheels: PathBuf,
    },
    /// A stream that never was a file (a robot's live topics), handed to
    /// [`super::calibrate::run_live`] beside the job.
    Live {
        /// Where the stream comes from, in messages and the summary (e.g.
        /// "ROS 2 domain 7").
        name: String,
    },
}

/// What `odocal calibrate` is asked to do.
#[derive(Debug, Clone)]
pub struct CalibrateJob {
    /// The input.
    pub input: CalibSource,
    /// The output directory.
    pub out: PathBuf,
    /// Overrides of the configured calibrator.
    pub choice: CalibratorChoice,
    /// Where to show the run in the Rerun viewer, if anywhere.
    pub viewer: Option<Viewer>,
    /// Configuration and robot files.
    pub common: Common,
    /// Where an online filter starts (`--init`).
    pub init: Start,
}

/// What `odocal calibrate` gives: the summary, and notes on what the Rerun
/// recording left out.
#[derive(Debug, Clone)]
pub struct CalibrateOutcome {
    /// design.md's summary (also in `DIR/summary.json`).
    pub summary: CalibSummary,
    /// What the recording left out, for the user (empty when nothing).
    pub notes: Vec<String>,
    /// What to paste: the ros2_control parameters, the laser mounting
    /// (also in `DIR/`).
    pub paste: super::paste::Paste,
}

/// Where the online filters start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Start {
    /// The robot file's values (and the recording's mounting).
    #[default]
    Nominal,
    /// The joint batch estimate of the same recording.
    Batch,
}

impl std::str::FromStr for Start {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "nominal" => Ok(Start::Nominal),
            "batch" => Ok(Start::Batch),
            _ => Err(format!("unknown start {s:?} (nominal|batch)")),
        }
    }
}
