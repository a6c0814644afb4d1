//! Which effect changed at an instant: when an online filter's change
//! detector fires, the diagnosis' candidate models are fitted on a window of
//! the streams around the firing and compared with "nothing changed" by BIC.
//!
//! The baseline is the filter's estimate at the window's start (radii and
//! wheel base; the nominal laser mount, no latency): before the change the
//! filter had that model, and the window's first part checks it. The onset
//! is the split time that best explains the residuals by a radius step (the
//! diagnosis' own search, [`search_step_time`]), restricted to the part of
//! the window before the firing (a detector fires after the change). Each
//! candidate acts from the onset on: a radius step (right and left sizes
//! fitted separately), a wheel-base change, a turn-slip change, a latency
//! change, a laser mounting change. Rows before the onset keep the baseline
//! under every model, so a candidate is fitted ([`fit`]) on the rows after
//! the onset and its BIC counts the rows before with the baseline's
//! residuals: BIC = Σ_g n_g ln((RSS_before,g + RSS_after,g)/n_g) + k ln N
//! ([`super::fit::bic`], σ scale per stream profiled out). A candidate is
//! named when it is identifiable, physical ([`physical`]) and lowers BIC by
//! more than `bic_margin`; the best such is reported, or `undetermined`.

use super::data::{gyro_rows, icp_rows, GyroRow, IcpRow, Part};
use super::fit::{bic, fit, Fit};
use super::free::{dof, free_names, zero_effect};
use super::model::Replay;
use super::select::{physical, search_step_time, SelectSettings};
use super::Measured;
use crate::effects::{Departures, Effect};
use crate::recording::WheelSample;
use crate::robot::RobotConfig;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Name given when no candidate beats "nothing changed" by the margin.
pub const UNDETERMINED: &str = "undetermined";

/// Effects that can change at an instant, tried at every firing.
pub const CANDIDATES: [&str; 5] = [
    "radius_step",
    "wheel_base_scale",
    "turn_slip",
    "latency",
    "laser_offset",
];

/// Settings of the naming of a change (`[calib.change.naming]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OnsetParams {
    /// Whether the changes are named after the run.
    pub enabled: bool,
    /// Window length before the firing (s); the onset is searched in it.
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
}

impl Default for OnsetParams {
    fn default() -> Self {
        Self {
            enabled: true,
            before_s: 10.0,
            after_s: 10.0,
            bic_margin: 10.0,
            min_rows: 25,
            wheel_smoothing: 0.1,
            gyro_window: 0.1,
            margin: 0.25,
            max_iter: 30,
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
        if self.max_iter == 0 || self.min_rows == 0 {
            return Err("change.naming.max_iter and min_rows must be ≥ 1".into());
        }
        Ok(())
    }
}

/// One candidate tried at a firing.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OnsetCandidate {
    /// Effect name.
    pub effect: String,
    /// BIC of "nothing changed" minus BIC with this change (positive = better).
    pub delta_bic: f64,
    /// Whether it may be named: identifiable and physical.
    pub admissible: bool,
}

/// What changed at one firing of the change detector.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NamedChange {
    /// When the detector fired (s, the recording's clock).
    pub time_s: f64,
    /// When the change began by the window's fit (s, the recording's clock).
    pub onset_s: f64,
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
    /// Every fitted parameter of the named effect.
    pub parameters: BTreeMap<String, f64>,
    /// Every candidate and how it fared.
    pub candidates: Vec<OnsetCandidate>,
    /// ICP rows in the window before and after the onset.
    pub rows: [usize; 2],
}

impl NamedChange {
    /// A firing whose window holds too few rows to name anything.
    pub fn undetermined(time_s: f64) -> Self {
        Self {
            time_s,
            onset_s: f64::NAN,
            effect: UNDETERMINED.into(),
            parameter: String::new(),
            estimate: f64::NAN,
            stderr: f64::NAN,
            delta_bic: 0.0,
            parameters: BTreeMap::new(),
            candidates: Vec::new(),
            rows: [0, 0],
        }
    }
}

/// Names what changed around `fired_at` (s) against `baseline` (the model
/// the filter had before). `None` when the window holds too few rows.
pub fn name_change(
    baseline: &RobotConfig,
    measured: &Measured,
    fired_at: f64,
    p: &OnsetParams,
) -> Option<NamedChange> {
    let (a, b) = (fired_at - p.before_s, fired_at + p.after_s);
    let origin = measured.origin();
    let wheels: Vec<WheelSample> = measured
        .wheels
        .iter()
        .filter(|w| w.stamp >= a - p.margin && w.stamp <= b + p.margin)
        .copied()
        .collect();
    let replay = Replay::new(baseline, &wheels, origin, p.wheel_smoothing);
    let span = replay.span()?;
    let icp = icp_rows(measured.motions, span, p.margin);
    let gyro = gyro_rows(measured.gyro, span, p.margin, p.gyro_window);
    let all = Part {
        replay: &replay,
        icp: &icp,
        gyro: &gyro,
    };
    let nothing = fit(all, &[], [1.0; 4], p.max_iter, 1);
    let settings = SelectSettings {
        candidates: Vec::new(),
        bic_margin: p.bic_margin,
        alpha: 1.0,
        max_effects: 1,
        max_iter: p.max_iter,
        step_range: (a - origin, fired_at - origin),
        step_min_rows: p.min_rows,
        max_steps: 1,
    };
    let onset = search_step_time(all, &nothing, &settings).map_or(fired_at, |t| t + origin);
    let split = Split::at(&icp, &gyro, onset);
    if split.icp[0].len() < p.min_rows || split.icp[1].len() < p.min_rows {
        return None;
    }
    let scored: Vec<(OnsetCandidate, Fit)> = CANDIDATES
        .iter()
        .filter_map(|name| {
            let e = match zero_effect(name)? {
                Effect::RadiusStep { .. } => Effect::RadiusStep {
                    time: onset - origin,
                    right: 0.0,
                    left: 0.0,
                },
                e => e,
            };
            Some(split.score(&replay, e, &nothing, p))
        })
        .collect();
    Some(report(fired_at, onset, &split, scored, p.bic_margin))
}

/// The window's rows before and after the onset (by interval midpoint).
struct Split {
    icp: [Vec<IcpRow>; 2],
    gyro: [Vec<GyroRow>; 2],
}

impl Split {
    fn at(icp: &[IcpRow], gyro: &[GyroRow], onset: f64) -> Self {
        let after = |t0: f64, t1: f64| 0.5 * (t0 + t1) >= onset;
        let (i1, i0): (Vec<IcpRow>, Vec<IcpRow>) = icp.iter().partition(|r| after(r.t0, r.t1));
        let (g1, g0): (Vec<GyroRow>, Vec<GyroRow>) = gyro.iter().partition(|r| after(r.t0, r.t1));
        Self {
            icp: [i0, i1],
            gyro: [g0, g1],
        }
    }

    fn part<'a>(&'a self, replay: &'a Replay, k: usize) -> Part<'a> {
        Part {
            replay,
            icp: &self.icp[k],
            gyro: &self.gyro[k],
        }
    }

    /// The candidate `e` fitted on the rows after the onset, its BIC over
    /// the whole window (baseline before the onset) against `nothing`'s.
    fn score(
        &self,
        replay: &Replay,
        e: Effect,
        nothing: &Fit,
        p: &OnsetParams,
    ) -> (OnsetCandidate, Fit) {
        let before = self.part(replay, 0);
        let after = self.part(replay, 1);
        let f = fit(after, &[e], nothing.scale, p.max_iter, 2);
        let rb = before.rss(&Departures::default());
        let rss: [f64; 4] = std::array::from_fn(|g| rb[g] + f.rss[g]);
        let (cb, ca) = (before.counts(), after.counts());
        let counts: [usize; 4] = std::array::from_fn(|g| cb[g] + ca[g]);
        let with = bic(&rss, &counts, dof(&f.effects));
        let cand = OnsetCandidate {
            effect: e.name().to_string(),
            delta_bic: nothing.bic - with,
            admissible: f.identifiable && f.effects.iter().all(physical),
        };
        (cand, f)
    }
}

/// The best admissible candidate beyond the margin, or `undetermined`.
fn report(
    fired_at: f64,
    onset: f64,
    split: &Split,
    scored: Vec<(OnsetCandidate, Fit)>,
    margin: f64,
) -> NamedChange {
    let best = scored
        .iter()
        .filter(|(c, _)| c.admissible && c.delta_bic > margin)
        .max_by(|x, y| x.0.delta_bic.total_cmp(&y.0.delta_bic));
    let mut out = NamedChange {
        onset_s: onset,
        candidates: scored.iter().map(|(c, _)| c.clone()).collect(),
        rows: [split.icp[0].len(), split.icp[1].len()],
        ..NamedChange::undetermined(fired_at)
    };
    if let Some((c, f)) = best {
        let e = &f.effects[0];
        let names = free_names(e);
        let values = super::free::free_params(e);
        let se = &f.stderr[0];
        // The most significant free parameter is the one reported.
        let k = (0..names.len())
            .max_by(|&i, &j| {
                (values[i] / se[i])
                    .abs()
                    .total_cmp(&(values[j] / se[j]).abs())
            })
            .unwrap_or(0);
        out.effect = c.effect.clone();
        out.parameter = names.get(k).map_or(String::new(), |s| s.to_string());
        out.estimate = values.get(k).copied().unwrap_or(f64::NAN);
        out.stderr = se.get(k).copied().unwrap_or(f64::NAN);
        out.delta_bic = c.delta_bic;
        out.parameters = names
            .iter()
            .zip(&values)
            .map(|(n, v)| (n.to_string(), *v))
            .collect();
    }
    out
}
