//! One call for the command line: associate, align, measure APE/RPE, the
//! papers' figures and the relation metric, and return what `odocal eval
//! --json` prints (design.md's `eval` keys) plus per-pose data for plots.

use super::align::{align, Alignment};
use super::ape::{ape, Ape};
use super::relations::{relations, Relation, RelationStats};
use super::rpe::{rpe, Rpe, RpeDelta};
use super::stats::Stats;
use super::sync::{sync, Matched, SyncOptions};
use super::traj3::{path_length, Trajectory3};
use super::EvalError;
use nalgebra::Similarity3;
use serde::{Deserialize, Serialize};

/// Options of an evaluation (all with evo's defaults).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EvalOptions {
    /// Time association.
    pub sync: SyncOptions,
    /// Alignment of the estimate to the reference.
    pub align: Alignment,
    /// RPE step.
    pub rpe_delta: RpeDelta,
}

/// The figures against a reference trajectory (JSON keys of design.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrajectoryMetrics {
    /// Pose pairs associated by time.
    pub matched: usize,
    /// APE translation (m).
    pub ape: Stats,
    /// APE rotation angle (deg).
    pub ape_rot_deg: Stats,
    /// RPE translation (m).
    pub rpe: Stats,
    /// RPE rotation angle (deg).
    pub rpe_rot_deg: Stats,
    /// Seed 000's RMSE x,y (m) after alignment.
    pub rmse_xy: f64,
    /// Seed 000's RMSE θ (rad) after alignment.
    pub rmse_theta: f64,
    /// Final position error over reference path length, in % (seed 002's path
    /// error); null when the reference does not move.
    pub drift_percent: Option<f64>,
    /// Distance (m) between the last matched estimate and reference positions.
    pub final_error: f64,
    /// Length (m) of the matched reference path.
    pub path_length: f64,
}

/// Everything `odocal eval` reports. With a reference the trajectory keys are
/// present at top level; with relations, `relations`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalReport {
    /// Figures against the reference trajectory, flattened into the top level.
    #[serde(flatten)]
    pub trajectory: Option<TrajectoryMetrics>,
    /// Relation metric (Kümmerle et al. 2009).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relations: Option<RelationStats>,
    /// Per-pose data for plots; not part of the JSON summary.
    #[serde(skip)]
    pub detail: Option<EvalDetail>,
}

/// Per-pose data behind the figures, for plots.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalDetail {
    /// Matched pairs with the estimate aligned.
    #[serde(skip)]
    pub matched: Matched,
    /// `reference_from_estimate` used for alignment.
    pub transform: Similarity3<f64>,
    /// Full APE with per-pair errors (same order as `matched`).
    pub ape: Ape,
    /// Full RPE with its pairs and per-pair errors.
    pub rpe: Rpe,
}

/// Evaluates `estimate` against a reference trajectory and/or reference
/// relations (at least one). Relations use the planar view of the estimate.
pub fn evaluate(
    estimate: &Trajectory3,
    reference: Option<&Trajectory3>,
    rels: Option<&[Relation]>,
    opts: &EvalOptions,
) -> Result<EvalReport, EvalError> {
    if reference.is_none() && rels.is_none() {
        return Err(EvalError::InvalidOption(
            "nothing to evaluate against: give a reference trajectory or relations".into(),
        ));
    }
    let (trajectory, detail) = match reference {
        Some(r) => {
            let (m, d) = against_reference(estimate, r, opts)?;
            (Some(m), Some(d))
        }
        None => (None, None),
    };
    let relations = match rels {
        Some(rs) => {
            if let Some(index) = estimate.first_non_finite() {
                return Err(EvalError::NonFinite {
                    what: "estimate",
                    index,
                });
            }
            Some(relations(&estimate.to_2d(), rs)?)
        }
        None => None,
    };
    Ok(EvalReport {
        trajectory,
        relations,
        detail,
    })
}

/// Sync → align → APE, RPE, RMSE x,y/θ, drift and final error.
pub fn against_reference(
    estimate: &Trajectory3,
    reference: &Trajectory3,
    opts: &EvalOptions,
) -> Result<(TrajectoryMetrics, EvalDetail), EvalError> {
    let matched = sync(reference, estimate, &opts.sync)?;
    let (aligned, transform) = align(&matched, opts.align)?;
    let a = ape(&aligned)?;
    let r = rpe(&aligned, &opts.rpe_delta)?;
    let last = aligned.len() - 1;
    let final_error = (aligned.estimate[last].translation.vector
        - aligned.reference[last].translation.vector)
        .norm();
    let path = path_length(&aligned.reference);
    let metrics = TrajectoryMetrics {
        matched: aligned.len(),
        ape: a.trans,
        ape_rot_deg: a.rot_deg,
        rpe: r.trans,
        rpe_rot_deg: r.rot_deg,
        rmse_xy: a.rmse_xy,
        rmse_theta: a.rmse_theta,
        drift_percent: (path > 0.0).then(|| 100.0 * final_error / path),
        final_error,
        path_length: path,
    };
    Ok((
        metrics,
        EvalDetail {
            matched: aligned,
            transform,
            ape: a,
            rpe: r,
        },
    ))
}
