//! The result of a diagnosis: the verdict, the named causes with their
//! estimates, the held-out gain, the structure tests and the residual series.

use super::fit::Fit;
use super::gain::Gain;
use super::select::{named, CandidateScore};
use super::series::ResidualSeries;
use super::stats::{SeriesStats, StructureTest};
use serde::Serialize;
use std::collections::BTreeMap;

/// What the diagnosis concludes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Named causes explain the discrepancy and nothing is left.
    Explained,
    /// Named causes explain part of it; `remaining` says what is left.
    PartlyExplained,
    /// The nominal model agrees with the measurements within their noise.
    NoDiscrepancy,
    /// The residuals hold structure that no candidate explains.
    Unexplained,
}

/// One named cause with its estimate (design.md JSON keys).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cause {
    /// Effect name (design.md's table).
    pub effect: String,
    /// Estimated parameters (units of the effect table).
    pub parameters: BTreeMap<String, f64>,
    /// Their standard errors (a radius step's time has none: grid-searched).
    pub stderr: BTreeMap<String, f64>,
    /// BIC improvement when the effect entered the model.
    pub delta_bic: f64,
}

impl Cause {
    /// Effect `i` of a fit as a cause that entered with `delta_bic`.
    pub fn of(f: &Fit, i: usize, delta_bic: f64) -> Self {
        let (parameters, stderr) = named(f, i);
        Self {
            effect: f.effects[i].name().to_string(),
            parameters,
            stderr,
            delta_bic,
        }
    }
}

/// A fault outside the effect table, named by its own name (never dressed
/// as a table effect), with what shows it and how to fix it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fault {
    /// Its name (`swapped_wheels`, `mirrored_wheels`, `wheel_out_of_round`,
    /// `floor_slip`, `varying_latency`, `gyro_scale`, `tyre_load_transfer`).
    pub name: String,
    /// Its estimated size, with units in the keys' docs of each fault.
    pub parameters: BTreeMap<String, f64>,
    /// What in the data shows it.
    pub evidence: String,
    /// What to do about it.
    pub fix: String,
}

/// Structure left in one stream's residuals after the extension.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Remaining {
    /// The stream (`icp_v`, `icp_lateral`, `icp_w`, `gyro`).
    pub stream: String,
    /// The kind of structure: `bias`, `trend`, `speed-dependent`,
    /// `turn-dependent`, `periodic in wheel angle`.
    pub structure: String,
    /// Its size in the stream's unit (per unit of the regressor).
    pub size: f64,
    /// The unit of `size`.
    pub unit: String,
    /// p-value of the test that found it.
    pub p_value: f64,
    /// Whose it is: [`ROBOT`] (a departure no effect of the table explains)
    /// or [`SCAN_MATCHING`] (the scan matcher's own error accounts for it;
    /// it does not count against the verdict).
    pub source: String,
    /// Why it is the scan matcher's, in words (absent for the robot's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// `remaining[].source` of a structure left unexplained by the robot model.
pub const ROBOT: &str = "robot";
/// `remaining[].source` of a structure the scan matcher's own error accounts for.
pub const SCAN_MATCHING: &str = "scan_matching";

impl Remaining {
    /// Whether it counts against the robot model (not the instrument's).
    pub fn is_robot(&self) -> bool {
        self.source == ROBOT
    }
}

/// The whole diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosis {
    /// `explained`, `no-discrepancy` or `unexplained`.
    pub verdict: Verdict,
    /// Named causes (empty unless explained), from the final joint fit.
    pub causes: Vec<Cause>,
    /// Faults outside the effect table, under their own names.
    pub faults: Vec<Fault>,
    /// What the extension leaves (empty for `explained`).
    pub remaining: Vec<Remaining>,
    /// Held-out gain of the extension.
    pub gain: Gain,
    /// Whether structure remains after the extension (explained verdicts).
    pub remaining_structure: bool,
    /// Effects the training data selected but the held-out part did not
    /// confirm (the held-out χ² dropped by less than the margin).
    pub heldout_rejected: Vec<Cause>,
    /// Every candidate tried in every selection round.
    pub candidates: Vec<CandidateScore>,
    /// Structure tests per stream on binned residuals, nominal model.
    pub structure_before: BTreeMap<String, StructureTest>,
    /// Same, extended model.
    pub structure_after: BTreeMap<String, StructureTest>,
    /// Residual statistics per stream (physical units), nominal model, all rows.
    pub stats_before: BTreeMap<String, SeriesStats>,
    /// Same, extended model.
    pub stats_after: BTreeMap<String, SeriesStats>,
    /// Noise scale per stream fitted on the training part (σ_actual / σ_given).
    pub noise_scale: BTreeMap<String, f64>,
    /// Rows used: training, held-out, rejected as outliers.
    pub rows: BTreeMap<String, usize>,
    /// Where every nominal value came from (set by the command that ran).
    #[serde(skip_serializing_if = "crate::assumptions::Assumptions::is_empty")]
    pub assumptions: crate::assumptions::Assumptions,
    /// Which stream the wheels came from (set by the command that ran).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wheel_source: Option<crate::recording::WheelSource>,
    /// Residual series for plots (not in the JSON summary).
    #[serde(skip)]
    pub series: ResidualSeries,
}
