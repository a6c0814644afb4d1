//! The vocabulary of a change named during a run: its settings
//! (`[calib.change.naming]`, with the laser-mounting watch's), the
//! candidates tried and the change named. Plain data, below both the
//! calibration (whose settings and summary carry it) and the diagnosis
//! (which names the change: `diagnose::onset`, `diagnose::mount`).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Name given when no candidate beats "nothing changed" by the margin.
pub const UNDETERMINED: &str = "undetermined";

/// A change named against a converged baseline.
pub const CONVERGED: &str = "converged";
/// A change named against a baseline that had not converged.
pub const UNCONVERGED: &str = "unconverged";

/// The calibration filter's change detector.
pub const FILTER: &str = "filter";
/// The laser-mounting watch (`diagnose::mount`).
pub const MOUNT: &str = "laser_mount";

/// Settings of the naming of a change (`[calib.change.naming]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OnsetParams {
    /// Whether the changes are named after the run.
    pub enabled: bool,
    /// Window length before the firing (s); the onset is searched in it.
    /// 15 s: a detector fed intervals whose σ is the scans' own (weak along
    /// a corridor) fires up to about 11 s after a radius step, and the
    /// window must reach back over the step. (20 s reaches, on a 60 s run,
    /// back before the filters start, and the step is then mis-sized.)
    pub before_s: f64,
    /// Window length after the firing (s).
    pub after_s: f64,
    /// Minimum BIC improvement over "nothing changed" to name an effect.
    pub bic_margin: f64,
    /// Minimum ICP rows on each side of the onset.
    pub min_rows: usize,
    /// Width (s) of the wheel-angle smoothing before replay.
    pub wheel_smoothing: f64,
    /// Gyro averaging window (s).
    pub gyro_window: f64,
    /// Time kept free at both ends of the wheel window (s), bounding latency.
    pub margin: f64,
    /// Levenberg–Marquardt iterations per fit.
    pub max_iter: usize,
    /// The watch for a laser moved on the robot, whose firings are named
    /// like the filter's (`diagnose::mount`).
    pub mount: MountParams,
    /// A baseline whose radius std is above this fraction of the radius has
    /// not converged: a radius step named against it names no wheel.
    pub converged_rel_std: f64,
}

impl Default for OnsetParams {
    fn default() -> Self {
        Self {
            enabled: true,
            before_s: 15.0,
            after_s: 10.0,
            bic_margin: 10.0,
            min_rows: 25,
            wheel_smoothing: 0.1,
            gyro_window: 0.1,
            margin: 0.25,
            max_iter: 30,
            mount: Default::default(),
            converged_rel_std: 0.005,
        }
    }
}

impl OnsetParams {
    /// Checks ranges; the message names the bad field.
    pub fn validate(&self) -> Result<(), String> {
        for (k, v) in [
            ("before_s", self.before_s),
            ("after_s", self.after_s),
            ("bic_margin", self.bic_margin),
            ("gyro_window", self.gyro_window),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("change.naming.{k} must be > 0, got {v}"));
            }
        }
        for (k, v) in [
            ("wheel_smoothing", self.wheel_smoothing),
            ("margin", self.margin),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("change.naming.{k} must be ≥ 0 s, got {v}"));
            }
        }
        if !(self.converged_rel_std.is_finite() && self.converged_rel_std > 0.0) {
            return Err(format!(
                "change.naming.converged_rel_std must be > 0, got {}",
                self.converged_rel_std
            ));
        }
        if self.max_iter == 0 || self.min_rows == 0 {
            return Err("change.naming.max_iter and min_rows must be ≥ 1".into());
        }
        self.mount.validate()
    }
}

/// One candidate tried at a firing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OnsetCandidate {
    /// Effect name.
    pub effect: String,
    /// Its own onset: the split before the firing that it explains best
    /// (s, the recording's clock).
    pub onset_s: f64,
    /// The onsets (s) it explains within 3.84 (χ²₁, 95 %) of the best: an
    /// effect that does not show for a while leaves a wide interval.
    pub onset_interval_s: [f64; 2],
    /// BIC of "nothing changed" minus BIC with this change (positive = better).
    pub delta_bic: f64,
    /// BIC with the effect there all window long minus BIC with it
    /// changing at the onset (positive = it changed rather than stood).
    pub changed_delta_bic: f64,
    /// Whether it may be named: identifiable and physical.
    pub admissible: bool,
}

/// What changed at one firing of the change detector.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedChange {
    /// When the detector fired (s, the recording's clock).
    pub time_s: f64,
    /// Which detector fired: [`FILTER`] (the calibration filter's, on the
    /// radii and wheel base) or [`MOUNT`] (the laser-mounting watch).
    pub detector: &'static str,
    /// When the change began by the window's fit (s, the recording's clock).
    pub onset_s: f64,
    /// The onsets (s) the named effect explains within 3.84 of the best
    /// (95 % likelihood interval of the linearised split search).
    pub onset_interval_s: [f64; 2],
    /// The effect that changed, or `undetermined`.
    pub effect: String,
    /// Its main parameter (`right`/`left` for a radius step: the wheel whose
    /// size is the more significant; empty when undetermined).
    pub parameter: String,
    /// The parameter's change (units of the effect table: m, s, s/rad, rad).
    pub estimate: f64,
    /// Its standard error (same unit).
    pub stderr: f64,
    /// BIC of "nothing changed" minus BIC with the change (0 when undetermined).
    pub delta_bic: f64,
    /// When undetermined: an effect that explains the window beyond the
    /// margin but was there before its onset as well (a standing departure
    /// of the baseline, not a change at this firing); empty otherwise.
    pub standing: String,
    /// Every fitted parameter of the named effect.
    pub parameters: BTreeMap<String, f64>,
    /// Every candidate and how it fared.
    pub candidates: Vec<OnsetCandidate>,
    /// ICP rows in the window before and after the onset.
    pub rows: [usize; 2],
    /// Later firings of the detector on this same change (s): the effect
    /// named in their windows is this one, begun before this firing.
    pub refired_s: Vec<f64>,
    /// For a firing that continues an earlier one: that firing's time (s);
    /// it is then reported once, under the earlier firing.
    #[serde(skip)]
    pub continues: Option<f64>,
    /// Whether the filter's estimate the change is named against (at the
    /// start of the window) had converged: `converged`, or `unconverged`
    /// (its radius std above `converged_rel_std` of the radius, or no
    /// estimate yet: the robot file's values). Against an unconverged
    /// baseline a radius step names no wheel: which wheel changed cannot
    /// be told from a baseline that is itself that far off.
    pub baseline: String,
    /// The larger radius std of the baseline over its radius (`null` when
    /// the baseline is the robot file's values).
    pub baseline_rel_std: Option<f64>,
}

impl NamedChange {
    /// A firing whose window holds too few rows to name anything.
    pub fn undetermined(time_s: f64) -> Self {
        Self {
            time_s,
            detector: FILTER,
            onset_s: f64::NAN,
            onset_interval_s: [f64::NAN; 2],
            effect: UNDETERMINED.into(),
            parameter: String::new(),
            estimate: f64::NAN,
            stderr: f64::NAN,
            delta_bic: 0.0,
            standing: String::new(),
            parameters: BTreeMap::new(),
            candidates: Vec::new(),
            rows: [0, 0],
            refired_s: Vec::new(),
            continues: None,
            baseline: CONVERGED.into(),
            baseline_rel_std: None,
        }
    }
}

/// Settings of the laser-mounting watch (`[calib.change.naming.mount]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MountParams {
    /// Whether the watch runs.
    pub enabled: bool,
    /// Block length (s).
    pub block_s: f64,
    /// Probability that one block beyond the threshold is chance (sets the
    /// χ²₁ threshold; a firing needs two blocks in a row).
    pub false_alarm: f64,
    /// Smallest change of the lean that fires (rad).
    pub min_turn_rad: f64,
    /// Shortest reference (s of blocks) before a block is tested.
    pub min_reference_s: f64,
    /// Fewest scan-matching rows in a tested block.
    pub min_rows: usize,
}

impl Default for MountParams {
    fn default() -> Self {
        Self {
            enabled: true,
            block_s: 5.0,
            false_alarm: 1e-6,
            min_turn_rad: 0.01,
            min_reference_s: 10.0,
            min_rows: 20,
        }
    }
}

impl MountParams {
    /// Checks ranges; the message names the bad field.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.block_s.is_finite() && self.block_s > 0.0) {
            return Err("change.naming.mount.block_s must be > 0 s".into());
        }
        if !(self.false_alarm > 0.0 && self.false_alarm < 1.0) {
            return Err("change.naming.mount.false_alarm must be in (0, 1)".into());
        }
        for (k, v) in [
            ("min_reference_s", self.min_reference_s),
            ("min_turn_rad", self.min_turn_rad),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("change.naming.mount.{k} must be ≥ 0, got {v}"));
            }
        }
        if self.min_rows < 3 {
            return Err("change.naming.mount.min_rows must be ≥ 3".into());
        }
        Ok(())
    }
}
