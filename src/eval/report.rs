//! One call for the command line: associate, align, measure APE/RPE, the
//! papers' figures and the relation metric, and return what `odocal eval
//! --json` prints (design.md's `eval` keys) plus per-pose data for plots.

use super::align::{align, apply_all, origin_by_heading, resolve, Alignment, HEADING_DISTANCE};
use super::ape::{ape, Ape};
use super::relations::{relations, Relation, RelationStats};
use super::rpe::{rpe, rpe_positions, Rpe, RpeDelta};
use super::stats::Stats;
use super::sync::{resample, sync, Matched, SyncOptions};
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
    /// The reference has positions only (e.g. PointStamped): rotation figures
    /// are null, the RPE is evo's point distance, `auto` alignment is an SE(2)
    /// fit, `origin` takes the heading of the reference's first metre, and the
    /// reference is resampled at the estimate's stamps unless told otherwise.
    pub position_only: bool,
}

/// How the estimate was aligned, and why (JSON `alignment`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlignmentUsed {
    /// `none`, `origin`, `origin-heading` (first position, heading of the
    /// reference's first metre), `se2`, `sim2`, `se3` or `sim3`.
    pub kind: String,
    /// Why this alignment.
    pub reason: String,
    /// The scale the alignment applied to the estimate (1 for rigid ones):
    /// with `sim2`/`sim3`, the reference's metric against the estimate's.
    #[serde(default = "unit")]
    pub scale: f64,
}

fn unit() -> f64 {
    1.0
}

/// How poses were paired by time, and why (JSON `pairing`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairingUsed {
    /// `nearest` (evo's nearest stamp within `max_diff`), `interpolated`
    /// (evo's interpolation within `max_diff`) or `resampled` (the reference
    /// interpolated at every estimate stamp inside its span).
    pub method: String,
    /// Why this pairing, with its tolerance.
    pub reason: String,
}

/// The figures against a reference trajectory (JSON keys of design.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrajectoryMetrics {
    /// Pose pairs associated by time.
    pub matched: usize,
    /// Pose pairs associated by time (= `matched`).
    pub paired: usize,
    /// Poses that could have been paired: those of the trajectory driving the
    /// search (the one with fewer poses) for nearest pairing, the estimate's
    /// when resampling.
    pub of: usize,
    /// How the pairs were formed.
    pub pairing: PairingUsed,
    /// How the estimate was aligned.
    pub alignment: AlignmentUsed,
    /// Why no rotation figure is given (absent when they are).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_omitted: Option<String>,
    /// APE translation (m).
    pub ape: Stats,
    /// APE rotation angle (deg); null for a position-only reference.
    pub ape_rot_deg: Option<Stats>,
    /// RPE translation (m).
    pub rpe: Stats,
    /// RPE rotation angle (deg); null for a position-only reference.
    pub rpe_rot_deg: Option<Stats>,
    /// The RMSE x,y (m) of [Farina, Table II] after alignment.
    pub rmse_xy: f64,
    /// The RMSE θ (rad) of [Farina, Table II] after alignment; null for a position-only reference.
    pub rmse_theta: Option<f64>,
    /// Final position error over reference path length, in % (the path
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
    /// Relation metric \[Kummerle2009\].
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
    let (matched, of, pairing) = pair(reference, estimate, opts)?;
    let (aligned, transform, alignment) = align_as_asked(&matched, opts)?;
    let a = ape(&aligned)?;
    let r = if opts.position_only {
        rpe_positions(&aligned, &opts.rpe_delta)?
    } else {
        rpe(&aligned, &opts.rpe_delta)?
    };
    let rot = !opts.position_only;
    let last = aligned.len() - 1;
    let final_error = (aligned.estimate[last].translation.vector
        - aligned.reference[last].translation.vector)
        .norm();
    let path = path_length(&aligned.reference);
    let metrics = TrajectoryMetrics {
        matched: aligned.len(),
        paired: aligned.len(),
        of,
        pairing,
        alignment,
        rotation_omitted: opts.position_only.then(|| {
            "the reference has positions only (no orientation): no rotation error is defined"
                .to_string()
        }),
        ape: a.trans,
        ape_rot_deg: rot.then_some(a.rot_deg),
        rpe: r.trans,
        rpe_rot_deg: r.rot_deg,
        rmse_xy: a.rmse_xy,
        rmse_theta: rot.then_some(a.rmse_theta),
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

/// Pairs by time: the reference resampled at the estimate's stamps when
/// asked, or by default for a position-only reference; else evo's nearest
/// stamp (or its interpolation) within `max_diff`. Returns the pairs, the
/// poses that could have paired, and how.
fn pair(
    reference: &Trajectory3,
    estimate: &Trajectory3,
    opts: &EvalOptions,
) -> Result<(Matched, usize, PairingUsed), EvalError> {
    let s = &opts.sync;
    // evo's interpolation, when asked for, is kept for a position-only reference too.
    if s.resample.unwrap_or(opts.position_only && !s.interpolate) {
        let why = match s.resample {
            Some(_) => "asked for",
            None => "the reference has positions only, as a tracker sampled on its own clock",
        };
        let (m, of) = resample(reference, estimate, s)?;
        let reason = format!(
            "{why}: the reference interpolated at every estimate stamp inside its span \
             (reference gaps up to {} s bridged)",
            s.max_gap
        );
        return Ok((
            m,
            of,
            PairingUsed {
                method: "resampled".into(),
                reason,
            },
        ));
    }
    let m = sync(reference, estimate, s)?;
    let of = reference.len().min(estimate.len());
    let (method, what) = if s.interpolate {
        (
            "interpolated",
            "the denser trajectory interpolated at the sparser's stamps",
        )
    } else {
        ("nearest", "nearest stamps")
    };
    let reason = format!("{what} within {} s (evo's association)", s.max_diff);
    Ok((
        m,
        of,
        PairingUsed {
            method: method.into(),
            reason,
        },
    ))
}

/// Aligns the pairs as `opts.align` asks (`auto` resolved by
/// [`resolve`]; `origin` against a position-only reference by
/// [`origin_by_heading`]).
fn align_as_asked(
    matched: &Matched,
    opts: &EvalOptions,
) -> Result<(Matched, Similarity3<f64>, AlignmentUsed), EvalError> {
    let kind = resolve(opts.align, opts.position_only);
    let reason = match (opts.align, opts.position_only) {
        (Alignment::Auto, true) => {
            "auto: the reference has positions only, in its own frame and \
             without a first orientation; a least-squares SE(2) fit of the positions (Umeyama 1991)"
                .to_string()
        }
        (Alignment::Auto, false) => {
            "auto: the reference has orientations; compared as given (evo's default)".into()
        }
        (Alignment::Origin, true) => format!(
            "origin asked for; the reference has positions only, so the estimate starts on its \
             first position, turned to the heading of the reference's first {HEADING_DISTANCE:.1} m"
        ),
        (k, _) => format!("{} asked for", k.as_str()),
    };
    if kind == Alignment::Origin && opts.position_only {
        let s = origin_by_heading(&matched.reference, &matched.estimate, HEADING_DISTANCE)?;
        let used = AlignmentUsed {
            kind: "origin-heading".into(),
            reason,
            scale: s.scaling(),
        };
        return Ok((apply_all(matched, &s), s, used));
    }
    let (aligned, s) = align(matched, kind)?;
    let used = AlignmentUsed {
        kind: kind.as_str().into(),
        reason,
        scale: s.scaling(),
    };
    Ok((aligned, s, used))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pose;
    use crate::traj::Trajectory;

    #[test]
    fn json_has_design_keys() {
        let mut t = Trajectory::default();
        for i in 0..50 {
            let a = i as f64 * 0.1;
            t.push(a, pose(3.0 * a.cos(), 2.0 * a.sin(), a));
        }
        let reference = Trajectory3::from_2d(&t);
        let mut e2 = t.clone();
        for p in &mut e2.poses {
            p.translation.x += 0.1;
        }
        let estimate = Trajectory3::from_2d(&e2);
        let rels = [Relation {
            t1: 0.0,
            t2: 2.0,
            delta: crate::geom::between(&t.poses[0], &t.poses[20]),
        }];
        let r = evaluate(
            &estimate,
            Some(&reference),
            Some(&rels),
            &EvalOptions::default(),
        )
        .unwrap();
        let v = serde_json::to_value(&r).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        for k in [
            "matched",
            "ape",
            "ape_rot_deg",
            "rpe",
            "rpe_rot_deg",
            "relations",
            "drift_percent",
            "final_error",
        ] {
            assert!(keys.contains(&k), "missing {k} in {keys:?}");
        }
        for k in ["rmse", "mean", "median", "std", "min", "max"] {
            assert!(v["ape"][k].is_f64() && v["rpe_rot_deg"][k].is_f64(), "{k}");
        }
        for k in [
            "count",
            "trans_mean",
            "trans_std",
            "rot_mean_deg",
            "rot_std_deg",
        ] {
            assert!(
                !v["relations"][k].is_null() && !v["relations"]["local"][k].is_null(),
                "{k}"
            );
        }
        assert_eq!(v["matched"], 50);
        assert!((v["ape"]["mean"].as_f64().unwrap() - 0.1).abs() < 1e-12);
        assert!((v["final_error"].as_f64().unwrap() - 0.1).abs() < 1e-12);
        assert_eq!(
            (v["paired"].as_u64(), v["of"].as_u64()),
            (Some(50), Some(50))
        );
        assert_eq!(v["alignment"]["kind"], "none");
        assert_eq!(v["pairing"]["method"], "nearest");
        assert!(v.get("rotation_omitted").is_none());
        // Position-only reference: rotation figures are null, translation stays
        // (resampled at the same stamps, the pairs are the same).
        let po = EvalOptions {
            position_only: true,
            align: Alignment::None,
            ..Default::default()
        };
        let p = evaluate(&estimate, Some(&reference), None, &po).unwrap();
        let pv = serde_json::to_value(&p).unwrap();
        assert!(pv["ape_rot_deg"].is_null() && pv["rpe_rot_deg"].is_null());
        assert!(pv["rmse_theta"].is_null() && pv["rotation_omitted"].is_string());
        assert_eq!(pv["pairing"]["method"], "resampled");
        assert_eq!(pv["ape"], v["ape"]);
        // auto: an SE(2) fit, which absorbs the 0.1 m offset.
        let auto = EvalOptions {
            position_only: true,
            ..Default::default()
        };
        let a = evaluate(&estimate, Some(&reference), None, &auto).unwrap();
        let av = serde_json::to_value(&a).unwrap();
        assert_eq!(av["alignment"]["kind"], "se2");
        assert!(av["ape"]["max"].as_f64().unwrap() < 1e-9);
        // Pure translation offset: point distances agree exactly.
        assert!(pv["rpe"]["max"].as_f64().unwrap() < 1e-12);
        // Only relations: no trajectory keys.
        let r = evaluate(&estimate, None, Some(&rels), &EvalOptions::default()).unwrap();
        let v = serde_json::to_value(&r).unwrap();
        assert!(v.get("ape").is_none() && v["relations"]["count"] == 1);
    }
}
