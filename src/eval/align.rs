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

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn pose(x: f64, y: f64, z: f64, yaw: f64) -> Pose3 {
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
        )
    }

    fn near(a: &Pose3, b: &Pose3, tol: f64) -> bool {
        (a.translation.vector - b.translation.vector).norm() < tol
            && a.rotation.angle_to(&b.rotation) < tol
    }

    #[test]
    fn words_and_auto() {
        for k in [
            Alignment::Auto,
            Alignment::None,
            Alignment::Origin,
            Alignment::Se2,
            Alignment::Sim2,
            Alignment::Se3,
            Alignment::Sim3,
        ] {
            assert_eq!(k.as_str().parse::<Alignment>().unwrap(), k);
        }
        assert!("se4".parse::<Alignment>().is_err());
        assert_eq!(resolve(Alignment::Auto, true), Alignment::Se2);
        assert_eq!(resolve(Alignment::Auto, false), Alignment::None);
        assert_eq!(resolve(Alignment::Sim3, true), Alignment::Sim3);
        let s = alignment_transform(
            &[pose(1.0, 2.0, 0.0, 0.3)],
            &[pose(0.0, 0.0, 0.0, 0.0)],
            Alignment::Auto,
        )
        .unwrap();
        assert!(near(
            &apply(&s, &pose(4.0, 5.0, 6.0, 0.7)),
            &pose(4.0, 5.0, 6.0, 0.7),
            1e-12
        ));
    }

    #[test]
    fn apply_scales_the_translation_then_moves_it_as_evo_does() {
        // Scale 2, a quarter turn about z, then 1 m along x: (1, 0, 0) → (2,
        // 0, 0) → (0, 2, 0) → (1, 2, 0); the heading turns by the quarter.
        let s = Similarity3::from_parts(
            Translation3::new(1.0, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), FRAC_PI_2),
            2.0,
        );
        let got = apply(&s, &pose(1.0, 0.0, 0.0, 0.1));
        assert!(
            near(&got, &pose(1.0, 2.0, 0.0, 0.1 + FRAC_PI_2), 1e-12),
            "{got:?}"
        );
    }

    #[test]
    fn origin_puts_the_first_poses_together() {
        let reference = [pose(1.0, 2.0, 0.5, 0.3), pose(2.0, 2.0, 0.5, 0.3)];
        let estimate = [pose(-1.0, 0.0, 0.0, -0.2), pose(0.0, 1.0, 0.0, 0.0)];
        let s = alignment_transform(&reference, &estimate, Alignment::Origin).unwrap();
        assert!(near(&apply(&s, &estimate[0]), &reference[0], 1e-12));
        assert!(alignment_transform(&[], &estimate, Alignment::Origin).is_err());
    }

    #[test]
    fn origin_by_heading_turns_the_chord_onto_the_references() {
        // The reference runs north from the origin, the estimate east from
        // (5, 5), both 0.6 m a step: the chord to the first pair 1 m along
        // (index 2) turns the estimate a quarter to the left onto it.
        let reference: Vec<Pose3> = (0..4)
            .map(|i| pose(0.0, 0.6 * i as f64, 0.0, 0.0))
            .collect();
        let estimate: Vec<Pose3> = (0..4)
            .map(|i| pose(5.0 + 0.6 * i as f64, 5.0, 0.0, 0.0))
            .collect();
        let s = origin_by_heading(&reference, &estimate, 1.0).unwrap();
        for (r, e) in reference.iter().zip(&estimate) {
            let got = apply(&s, e).translation.vector;
            assert!(
                (got - r.translation.vector).norm() < 1e-12,
                "{got:?} vs {r:?}"
            );
        }
        assert!((s.isometry.rotation.angle() - FRAC_PI_2).abs() < 1e-12);
        // A reference that never moves 0.1 m has no heading to align by; one
        // that moves less than the distance but more than a tenth of it uses
        // its farthest pair.
        let still = vec![pose(0.0, 0.0, 0.0, 0.0); 4];
        assert!(origin_by_heading(&still, &estimate, 1.0).is_err());
        assert!(origin_by_heading(&reference[..1], &estimate[..1], 1.0).is_err());
        let short = &reference[..2];
        let s = origin_by_heading(short, &estimate[..2], 1.0).unwrap();
        assert!((s.isometry.rotation.angle() - FRAC_PI_2).abs() < 1e-12);
        assert!(origin_by_heading(short, &estimate[..2], 7.0).is_err());
    }

    #[test]
    fn least_squares_fits_recover_a_known_similarity() {
        // The estimate is the reference seen from a frame turned 0.4 rad,
        // shifted and (for the Sim fits) shrunk by 1/1.1: each fit maps it
        // back exactly; the rigid fits keep scale 1.
        let truth = Similarity3::from_parts(
            Translation3::new(0.7, -1.2, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.4),
            1.1,
        );
        let reference: Vec<Pose3> = [
            (0.0, 0.0, 0.0),
            (3.0, 0.5, 0.2),
            (4.0, 4.0, -0.1),
            (-1.0, 3.0, 0.3),
            (1.0, -2.0, 0.0),
        ]
        .iter()
        .map(|&(x, y, z)| pose(x, y, z, 0.1 * x))
        .collect();
        let inverse = truth.inverse();
        let estimate: Vec<Pose3> = reference.iter().map(|p| apply(&inverse, p)).collect();
        for kind in [Alignment::Sim2, Alignment::Sim3] {
            let s = alignment_transform(&reference, &estimate, kind).unwrap();
            assert!(
                (s.scaling() - 1.1).abs() < 1e-9,
                "{kind:?}: {}",
                s.scaling()
            );
            for (r, e) in reference.iter().zip(&estimate) {
                assert!(near(&apply(&s, e), r, 1e-9), "{kind:?}");
            }
        }
        for kind in [Alignment::Se2, Alignment::Se3] {
            let s = alignment_transform(&reference, &estimate, kind).unwrap();
            assert_eq!(s.scaling(), 1.0, "{kind:?}");
            assert!((s.isometry.rotation.angle() - 0.4).abs() < 1e-9, "{kind:?}");
        }
        let (aligned, s) = align(
            &Matched {
                ref_stamps: vec![0.0; 5],
                est_stamps: vec![0.0; 5],
                reference: reference.clone(),
                estimate: estimate.clone(),
            },
            Alignment::Sim2,
        )
        .unwrap();
        assert!((s.scaling() - 1.1).abs() < 1e-9);
        assert!(near(&aligned.estimate[2], &reference[2], 1e-9));
        assert!(near(&aligned.reference[2], &reference[2], 0.0 + 1e-15));
    }

    #[test]
    fn origin_by_heading_uses_the_chord_at_the_heading_distance_along_a_bent_path() {
        // The reference goes 0.6 m east then 0.6 m north (1.2 m along at
        // index 2, the first pair at least 1 m along), then 1.4 m north. The
        // estimate is the reference turned a quarter left and shifted by (5,
        // 5) at indices 0 and 2 only: index 1 is off by 0.3 m and index 3 has
        // drifted. Its chord to index 2, (−0.6, 0.6), turned a quarter right
        // is the reference's, (0.6, 0.6): the alignment is a quarter turn
        // right that puts estimate 0 on (2, −1) and estimate 2 on (2.6, −0.4);
        // estimate 1, (0.3, 0.6) from estimate 0, lands at (2.6, −1.3).
        let reference = [
            pose(2.0, -1.0, 0.0, 0.0),
            pose(2.6, -1.0, 0.0, 0.0),
            pose(2.6, -0.4, 0.0, 0.0),
            pose(2.6, 1.0, 0.0, 0.0),
        ];
        let estimate = [
            pose(6.0, 7.0, 0.0, 0.0),
            pose(6.3, 7.6, 0.0, 0.0),
            pose(5.4, 7.6, 0.0, 0.0),
            pose(4.5, 7.0, 0.0, 0.0),
        ];
        let s = origin_by_heading(&reference, &estimate, 1.0).unwrap();
        let at = |i: usize| apply(&s, &estimate[i]).translation.vector;
        for (i, want) in [(0, (2.0, -1.0)), (1, (2.6, -1.3)), (2, (2.6, -0.4))] {
            let got = at(i);
            assert!(
                (got - Vector3::new(want.0, want.1, 0.0)).norm() < 1e-12,
                "{i}: {got:?}"
            );
        }
        let heading = s.isometry.rotation.euler_angles().2;
        assert!((heading + FRAC_PI_2).abs() < 1e-12, "{heading}");
    }

    #[test]
    fn origin_by_heading_accepts_a_tenth_of_the_distance_and_refuses_less() {
        // Distance 10 m: a reference and an estimate that each move exactly
        // 1 m (a tenth) give a heading, here a quarter turn right.
        let reference = [pose(0.0, 0.0, 0.0, 0.0), pose(1.0, 0.0, 0.0, 0.0)];
        let estimate = [pose(3.0, 3.0, 0.0, 0.0), pose(3.0, 4.0, 0.0, 0.0)];
        let s = origin_by_heading(&reference, &estimate, 10.0).unwrap();
        let got = apply(&s, &estimate[1]).translation.vector;
        assert!(
            (got - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12,
            "{got:?}"
        );
        // Either one moving 0.5 m while the other moves 2 m: refused.
        let half = [pose(0.0, 0.0, 0.0, 0.0), pose(0.5, 0.0, 0.0, 0.0)];
        let two = [pose(3.0, 3.0, 0.0, 0.0), pose(3.0, 5.0, 0.0, 0.0)];
        assert!(origin_by_heading(&half, &two, 10.0).is_err());
        assert!(origin_by_heading(&two, &half, 10.0).is_err());
    }
}
