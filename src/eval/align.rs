//! Aligning the estimate to the reference before measuring errors: none, the
//! first pose (origin), or a least-squares SE(2)/Sim(2) (x, y and yaw) or
//! SE(3)/Sim(3) (evo's `-a` / `-as`) Umeyama fit of the positions.
//!
//! A reference with positions only (an overhead tracker, GPS) has no first
//! orientation to align by: `origin` then puts the first positions together
//! and turns the estimate so that its chord over the reference's first
//! [`HEADING_DISTANCE`] m points the reference's way ([`origin_by_heading`]);
//! `auto` (the default) is evo's `none` for a full reference and an SE(2) fit
//! for a position-only one, whose frame is the tracker's, not the odometry's.

use super::sync::Matched;
use super::traj3::Pose3;
use super::umeyama::{umeyama2, umeyama3};
use super::EvalError;
use nalgebra::{Isometry3, Rotation3, Similarity3, Translation3, UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use std::str::FromStr;

/// Path length (m) of the reference over which `origin` alignment against a
/// position-only reference measures the initial heading: long enough that
/// the tracker's millimetre noise turns the chord by well under a degree,
/// short enough that odometry has not drifted yet.
pub const HEADING_DISTANCE: f64 = 1.0;

/// Which alignment to apply to the estimate (CLI words `auto|none|origin|se2|sim2|se3|sim3`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Alignment {
    /// `None` for a reference with orientations (evo's default), `Se2` for a
    /// position-only reference (see [`resolve`]).
    #[default]
    Auto,
    /// Compare as given.
    None,
    /// Move the estimate so its first pose equals the reference's first pose.
    Origin,
    /// Rigid planar fit (x, y, rotation about z).
    Se2,
    /// Planar fit with scale.
    Sim2,
    /// Rigid 3D fit (evo `-a`).
    Se3,
    /// 3D fit with scale (evo `-as`).
    Sim3,
}

impl FromStr for Alignment {
    type Err = EvalError;
    fn from_str(s: &str) -> Result<Self, EvalError> {
        Ok(match s {
            "auto" => Self::Auto,
            "none" => Self::None,
            "origin" => Self::Origin,
            "se2" => Self::Se2,
            "sim2" => Self::Sim2,
            "se3" => Self::Se3,
            "sim3" => Self::Sim3,
            _ => {
                return Err(EvalError::InvalidOption(format!(
                    "alignment '{s}' (expected auto|none|origin|se2|sim2|se3|sim3)"
                )))
            }
        })
    }
}

impl Alignment {
    /// The CLI word.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::None => "none",
            Self::Origin => "origin",
            Self::Se2 => "se2",
            Self::Sim2 => "sim2",
            Self::Se3 => "se3",
            Self::Sim3 => "sim3",
        }
    }
}

/// The alignment `auto` stands for: `None` (evo's default) against a
/// reference with orientations, `Se2` against one with positions only, whose
/// frame (the tracker's) is not the estimate's; other kinds are kept.
pub fn resolve(kind: Alignment, position_only: bool) -> Alignment {
    match (kind, position_only) {
        (Alignment::Auto, true) => Alignment::Se2,
        (Alignment::Auto, false) => Alignment::None,
        (k, _) => k,
    }
}

/// Origin alignment without the reference's orientation:
/// `reference_from_estimate` that puts the first estimate position on the
/// first reference position and turns the estimate about z so that its chord
/// from the first pair to the first pair at least `distance` m along the
/// reference path points the same way as the reference's chord. When the
/// reference never travels that far, its farthest pair is used if it is at
/// least a tenth of `distance` away; otherwise an error.
pub fn origin_by_heading(
    reference: &[Pose3],
    estimate: &[Pose3],
    distance: f64,
) -> Result<Similarity3<f64>, EvalError> {
    let (Some(r0), Some(e0)) = (reference.first(), estimate.first()) else {
        return Err(EvalError::DegenerateAlignment("no pose to align".into()));
    };
    let p = |q: &Pose3| q.translation.vector.xy();
    let mut along = 0.0;
    let mut k = reference.len() - 1;
    for i in 1..reference.len() {
        along += (p(&reference[i]) - p(&reference[i - 1])).norm();
        if along >= distance {
            k = i;
            break;
        }
    }
    let (dr, de) = (p(&reference[k]) - p(r0), p(&estimate[k]) - p(e0));
    if dr.norm() < 0.1 * distance || de.norm() < 0.1 * distance {
        return Err(EvalError::DegenerateAlignment(format!(
            "the reference has positions only and it or the estimate moves less than {} m \
             from its start: no initial heading to align by (use se2 or none)",
            0.1 * distance
        )));
    }
    let theta = dr.y.atan2(dr.x) - de.y.atan2(de.x);
    let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta);
    let t = r0.translation.vector - rot * e0.translation.vector;
    Ok(Similarity3::from_parts(Translation3::from(t), rot, 1.0))
}

/// The transform `reference_from_estimate` that best maps the estimate onto the
/// reference under `kind` (identity for `None`; `Auto` must be [`resolve`]d
/// first and is taken as `None`).
pub fn alignment_transform(
    reference: &[Pose3],
    estimate: &[Pose3],
    kind: Alignment,
) -> Result<Similarity3<f64>, EvalError> {
    let pos = |p: &[Pose3]| {
        p.iter()
            .map(|q| q.translation.vector)
            .collect::<Vec<Vector3<f64>>>()
    };
    let pos2 = |p: &[Pose3]| {
        p.iter()
            .map(|q| q.translation.vector.xy())
            .collect::<Vec<Vector2<f64>>>()
    };
    Ok(match kind {
        Alignment::None | Alignment::Auto => Similarity3::identity(),
        Alignment::Origin => {
            let (r0, e0) = match (reference.first(), estimate.first()) {
                (Some(r), Some(e)) => (r, e),
                _ => return Err(EvalError::DegenerateAlignment("no pose to align".into())),
            };
            let iso = r0 * e0.inverse();
            Similarity3::from_isometry(iso, 1.0)
        }
        Alignment::Se3 | Alignment::Sim3 => {
            let (r, t, c) = umeyama3(&pos(estimate), &pos(reference), kind == Alignment::Sim3)?;
            let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
            Similarity3::from_parts(Translation3::from(t), rot, c)
        }
        Alignment::Se2 | Alignment::Sim2 => {
            let (theta, t, c) =
                umeyama2(&pos2(estimate), &pos2(reference), kind == Alignment::Sim2)?;
            let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta);
            Similarity3::from_parts(Translation3::new(t.x, t.y, 0.0), rot, c)
        }
    })
}

/// Applies a similarity to a pose as evo does: scale the translation, then
/// transform (`R_a R_p`, `s R_a t_p + t_a`); rotations stay orthonormal.
pub fn apply(s: &Similarity3<f64>, p: &Pose3) -> Pose3 {
    let a = &s.isometry;
    let t = a.rotation * (p.translation.vector * s.scaling()) + a.translation.vector;
    Isometry3::from_parts(Translation3::from(t), a.rotation * p.rotation)
}

/// The matched pairs with the estimate aligned to the reference, and the
/// transform used (`reference_from_estimate`).
pub fn align(matched: &Matched, kind: Alignment) -> Result<(Matched, Similarity3<f64>), EvalError> {
    let s = alignment_transform(&matched.reference, &matched.estimate, kind)?;
    Ok((apply_all(matched, &s), s))
}

/// The matched pairs with `s` (`reference_from_estimate`) applied to the estimate.
pub fn apply_all(matched: &Matched, s: &Similarity3<f64>) -> Matched {
    let mut out = matched.clone();
    out.estimate = matched.estimate.iter().map(|p| apply(s, p)).collect();
    out
}
