//! Aligning the estimate to the reference before measuring errors: none, the
//! first pose (origin), or a least-squares SE(2)/Sim(2) (x, y and yaw) or
//! SE(3)/Sim(3) (evo's `-a` / `-as`) Umeyama fit of the positions.

use super::sync::Matched;
use super::traj3::Pose3;
use super::umeyama::{umeyama2, umeyama3};
use super::EvalError;
use nalgebra::{Isometry3, Rotation3, Similarity3, Translation3, UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use std::str::FromStr;

/// Which alignment to apply to the estimate (CLI words `none|origin|se2|sim2|se3|sim3`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Alignment {
    /// Compare as given.
    #[default]
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
            "none" => Self::None,
            "origin" => Self::Origin,
            "se2" => Self::Se2,
            "sim2" => Self::Sim2,
            "se3" => Self::Se3,
            "sim3" => Self::Sim3,
            _ => {
                return Err(EvalError::InvalidOption(format!(
                    "alignment '{s}' (expected none|origin|se2|sim2|se3|sim3)"
                )))
            }
        })
    }
}

/// The transform `reference_from_estimate` that best maps the estimate onto the
/// reference under `kind` (identity for `None`).
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
        Alignment::None => Similarity3::identity(),
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
    let mut out = matched.clone();
    out.estimate = matched.estimate.iter().map(|p| apply(&s, p)).collect();
    Ok((out, s))
}
