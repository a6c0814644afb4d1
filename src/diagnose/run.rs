//! The diagnosis driver: rows from the measured streams, outliers dropped,
//! a training and a held-out part, forward selection confirmed on the
//! held-out part, then the gain, the structure tests and the verdict.

use super::data::{drop_outliers, gyro_rows, icp_rows, merge_motions, GyroRow, IcpRow, Part};
use super::diagnosis::{Cause, Diagnosis, Verdict};
use super::gain::heldout_gain;
use super::model::Replay;
use super::residuals::{has_structure, stream_stats, structure};
use super::select::{forward, SelectSettings, Selection};
use super::series::series;
use super::stats::StructureTest;
use super::{DiagnoseError, DiagnoseParams, Measured};
use crate::effects::{Departures, EffectKind};
use crate::robot::RobotConfig;
use std::collections::BTreeMap;

/// Runs replay, selection, gain and tests (params already validated).
pub fn run(
    robot: &RobotConfig,
    m: &Measured,
    p: &DiagnoseParams,
) -> Result<Diagnosis, DiagnoseError> {
    let origin = m.origin();
    let replay = Replay::new(robot, m.wheels, origin, p.wheel_smoothing);
    let span = replay
        .span()
        .filter(|s| replay.len() >= 2 && s.1 > s.0)
        .ok_or_else(|| DiagnoseError::TooLittleData("fewer than 2 wheel samples".into()))?;
    let merged = merge_motions(m.motions, p.min_interval);
    let mut icp = icp_rows(&merged, span, p.margin);
    let mut gyro = gyro_rows(m.gyro, span, p.margin, p.gyro_window);
    let outliers = drop_outliers(&replay, &mut icp, &mut gyro, p.outlier_sigma);
    let split = Split::new(&icp, &gyro, span, p.holdout)?;
    let (train, held) = split.parts(&replay, &icp, &gyro);
    let all = Part {
        replay: &replay,
        icp: &icp,
        gyro: &gyro,
    };
    let settings = settings(p, train, &split, origin);
    let (sel, kept, heldout_rejected) = select_confirmed(train, held, settings, p.heldout_margin);
    let model = if kept == 0 {
        &sel.nominal
    } else {
        &sel.steps[kept - 1]
    };
    let nominal = Departures::default();
    let xm = Departures::of(&model.effects);
    // Gain on the held-out part, normalised by the final training scales.
    let scale = model.scale;
    let gain = heldout_gain(
        held,
        m.reference,
        &xm,
        &scale,
        split.time,
        p.trajectory_window,
    );
    // Structure tests on all rows.
    let structure_before = structure(all, &nominal, &sel.nominal.scale, p);
    let structure_after = structure(all, &xm, &scale, p);
    let causes: Vec<Cause> = (0..model.effects.len())
        .map(|i| Cause::of(model, i, sel.delta_bic[i]))
        .collect();
    let all_b = all.physical(&nominal);
    let all_a = all.physical(&xm);
    let train_counts = train.counts();
    Ok(Diagnosis {
        assumptions: Default::default(),
        wheel_source: None,
        verdict: verdict(&causes, &structure_before, p.structure_alpha),
        causes,
        gain,
        remaining_structure: has_structure(&structure_after, p.structure_alpha),
        heldout_rejected,
        candidates: sel.tried,
        structure_before,
        structure_after,
        stats_before: stream_stats(&all_b),
        stats_after: stream_stats(&all_a),
        noise_scale: (0..4)
            .filter(|g| train_counts[*g] > 0)
            .map(|g| (super::data::GROUPS[g].to_string(), scale[g]))
            .collect(),
        rows: split.row_counts(icp.len(), gyro.len(), outliers),
        series: series(&replay, &icp, &gyro, &all_b, &all_a, split.time),
    })
}

/// The held-out part: the rows after `time`, the training part those before.
struct Split {
    /// Start of the held-out part (s).
    time: f64,
    /// Start of the rows (s).
    start: f64,
    /// ICP rows ending before the split.
    icp_train: usize,
    /// Gyro rows ending before the split.
    gyro_train: usize,
    /// First ICP row starting at or after the split.
    icp_held: usize,
    /// First gyro row starting at or after the split.
    gyro_held: usize,
}

impl Split {
    /// Holds out the last `holdout` fraction of the time covered by the ICP
    /// rows and the wheel `span`; refuses too few rows on either side.
    fn new(
        icp: &[IcpRow],
        gyro: &[GyroRow],
        span: (f64, f64),
        holdout: f64,
    ) -> Result<Self, DiagnoseError> {
        if icp.len() < 50 {
            return Err(DiagnoseError::TooLittleData(format!(
                "{} usable ICP motions inside the wheel stream (need ≥ 50)",
                icp.len()
            )));
        }
        let t_end = icp.last().map(|r| r.t1).unwrap_or(span.1).max(span.1);
        let start = icp[0].t0.min(span.0);
        let time = start + (1.0 - holdout) * (t_end - start);
        let split = Self {
            time,
            start,
            icp_train: icp.partition_point(|r| r.t1 <= time),
            gyro_train: gyro.partition_point(|r| r.t1 <= time),
            icp_held: icp.partition_point(|r| r.t0 < time),
            gyro_held: gyro.partition_point(|r| r.t0 < time),
        };
        if split.icp_train < 30 || icp.len() - split.icp_held < 10 {
            return Err(DiagnoseError::TooLittleData(
                "too few ICP motions in the training or held-out part".into(),
            ));
        }
        Ok(split)
    }

    /// The training and the held-out part of the rows.
    fn parts<'a>(
        &self,
        replay: &'a Replay,
        icp: &'a [IcpRow],
        gyro: &'a [GyroRow],
    ) -> (Part<'a>, Part<'a>) {
        let train = Part {
            replay,
            icp: &icp[..self.icp_train],
            gyro: &gyro[..self.gyro_train],
        };
        let held = Part {
            replay,
            icp: &icp[self.icp_held..],
            gyro: &gyro[self.gyro_held..],
        };
        (train, held)
    }

    /// Rows used in each part, and the outliers dropped before the split.
    fn row_counts(&self, icp: usize, gyro: usize, outliers: usize) -> BTreeMap<String, usize> {
        let mut rows = BTreeMap::new();
        rows.insert("icp_train".to_string(), self.icp_train);
        rows.insert("icp_heldout".to_string(), icp - self.icp_held);
        rows.insert("gyro_train".to_string(), self.gyro_train);
        rows.insert("gyro_heldout".to_string(), gyro - self.gyro_held);
        rows.insert("outliers".to_string(), outliers);
        rows
    }
}

/// Selection settings: the candidates the training part can identify (a gyro
/// bias needs at least 20 gyro rows), radius steps inside the training part
/// at least 1 s from its ends.
fn settings(p: &DiagnoseParams, train: Part, split: &Split, origin: f64) -> SelectSettings {
    let usable: Vec<String> = p
        .candidates
        .iter()
        .filter(|c| c.as_str() != EffectKind::GyroBias.name() || train.gyro.len() >= 20)
        .cloned()
        .collect();
    SelectSettings {
        candidates: usable,
        bic_margin: p.bic_margin,
        alpha: p.alpha,
        max_effects: p.max_effects,
        max_iter: p.max_iter,
        step_range: (split.start - origin + 1.0, split.time - origin - 1.0),
        step_min_rows: 30,
    }
}

/// Forward selection on the training part whose every effect the held-out
/// part confirms. An effect the held-out part does not confirm is vetoed and
/// the selection restarts without it, so a spurious first choice (one that
/// fits the training part by accident) cannot hide a real cause behind it.
/// Returns the selection, how many of its effects are kept, and the vetoed.
fn select_confirmed(
    train: Part,
    held: Part,
    settings: SelectSettings,
    margin: f64,
) -> (Selection, usize, Vec<Cause>) {
    let mut usable = settings.candidates.clone();
    let mut rejected: Vec<Cause> = Vec::new();
    loop {
        let sel = forward(train, &usable, &settings);
        let kept = confirmed(held, &sel, margin);
        if kept == sel.steps.len() {
            return (sel, kept, rejected);
        }
        let f = &sel.steps[kept];
        rejected.push(Cause::of(f, kept, sel.delta_bic[kept]));
        let name = f.effects[kept].name();
        usable.retain(|c| c != name);
    }
}

/// How many of the nested models of the selection, in order, each drop the
/// held-out χ² (normalised by the model's noise scales) by at least `margin`.
fn confirmed(held: Part, sel: &Selection, margin: f64) -> usize {
    let sse = |x: &Departures, scale: &[f64; 4]| {
        let mut e: [Vec<f64>; 4] = Default::default();
        held.normalised(x, &mut e);
        (0..4)
            .map(|g| e[g].iter().map(|v| (v / scale[g]).powi(2)).sum::<f64>())
            .sum::<f64>()
    };
    let mut kept = 0;
    for (k, step) in sel.steps.iter().enumerate() {
        let prev = if k == 0 {
            Departures::default()
        } else {
            Departures::of(&sel.steps[k - 1].effects)
        };
        let drop = sse(&prev, &step.scale) - sse(&Departures::of(&step.effects), &step.scale);
        if drop < margin {
            break;
        }
        kept = k + 1;
    }
    kept
}

/// Explained when causes are named; otherwise unexplained when the nominal
/// model's residuals hold structure, no discrepancy when they do not.
fn verdict(
    causes: &[Cause],
    structure_before: &BTreeMap<String, StructureTest>,
    alpha: f64,
) -> Verdict {
    if !causes.is_empty() {
        Verdict::Explained
    } else if has_structure(structure_before, alpha) {
        Verdict::Unexplained
    } else {
        Verdict::NoDiscrepancy
    }
}
