//! A time-stamped 3D trajectory (`world_from_base` as SE(3)), so TUM and KITTI
//! files are evaluated exactly as evo does; planar trajectories embed into it
//! (z = 0, rotation about z) and project back by yaw.

use crate::geom::{self, Pose2};
use crate::recording::StampedPose;
use crate::traj::Trajectory;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// A rigid 3D transform `parent_from_child` (m, unit quaternion).
pub type Pose3 = Isometry3<f64>;

/// Poses at strictly increasing stamps (s); the two vectors have equal length.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trajectory3 {
    /// Stamps (s), strictly increasing.
    pub stamps: Vec<f64>,
    /// `world_from_base` at each stamp.
    pub poses: Vec<Pose3>,
}

impl Trajectory3 {
    /// Builds from parallel vectors; `None` if lengths differ or stamps do not
    /// strictly increase (NaN included).
    pub fn from_parts(stamps: Vec<f64>, poses: Vec<Pose3>) -> Option<Self> {
        if stamps.len() != poses.len()
            || stamps
                .windows(2)
                .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return None;
        }
        Some(Self { stamps, poses })
    }

    /// Embeds a planar trajectory: z = 0, rotation θ about z.
    pub fn from_2d(t: &Trajectory) -> Self {
        Self {
            stamps: t.stamps.clone(),
            poses: t.poses.iter().map(pose3_from_2d).collect(),
        }
    }

    /// The planar view: x, y and yaw (rotation about z) of each pose.
    pub fn to_2d(&self) -> Trajectory {
        Trajectory {
            stamps: self.stamps.clone(),
            poses: self.poses.iter().map(pose2_from_3d).collect(),
        }
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// True when there are no poses.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// Length (m) of the 3D polyline through the positions.
    pub fn path_length(&self) -> f64 {
        path_length(&self.poses)
    }

    /// True when the orientations carry no information: every rotation is
    /// exactly the identity while the path, taken in steps of at least
    /// 0.1 m, somewhere heads more than 0.5 rad away from +x — a tracker's
    /// positions written with a stand-in quaternion. A robot driving
    /// straight along +x with identity orientation is not flagged (nor, by
    /// this test, one reversing straight along −x).
    pub fn orientation_undefined(&self) -> bool {
        if self
            .poses
            .iter()
            .any(|p| p.rotation != UnitQuaternion::identity())
        {
            return false;
        }
        let mut last = match self.poses.first() {
            Some(p) => p.translation.vector.xy(),
            None => return false,
        };
        for p in &self.poses[1..] {
            let d = p.translation.vector.xy() - last;
            if d.norm() >= 0.1 {
                if d.y.atan2(d.x).abs() > 0.5 {
                    return true;
                }
                last = p.translation.vector.xy();
            }
        }
        false
    }

    /// Index of the first pose holding a NaN or infinite value, if any.
    pub fn first_non_finite(&self) -> Option<usize> {
        (0..self.len()).find(|&i| {
            !self.stamps[i].is_finite()
                || !self.poses[i]
                    .translation
                    .vector
                    .iter()
                    .all(|v| v.is_finite())
                || !self.poses[i].rotation.coords.iter().all(|v| v.is_finite())
        })
    }
}

/// A planar trajectory from time-sorted stamped poses (a recording's odometry
/// or reference), keeping the first of repeated or backward stamps; also
/// returns how many samples were dropped.
pub fn trajectory_from_stamped(samples: &[StampedPose]) -> (Trajectory, usize) {
    let mut t = Trajectory::with_capacity(samples.len());
    let mut dropped = 0;
    for s in samples {
        if !t.push(s.stamp, s.pose) {
            dropped += 1;
        }
    }
    (t, dropped)
}

/// Length (m) of the polyline through the positions of `poses`.
pub fn path_length(poses: &[Pose3]) -> f64 {
    poses
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum()
}

/// A planar pose as SE(3): z = 0, rotation θ about z.
pub fn pose3_from_2d(p: &Pose2) -> Pose3 {
    let [x, y, th] = geom::xyt(p);
    Isometry3::from_parts(
        Translation3::new(x, y, 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), th),
    )
}

/// The planar part of an SE(3) pose: x, y and yaw = atan2(R₁₀, R₀₀).
pub fn pose2_from_3d(p: &Pose3) -> Pose2 {
    let r = p.rotation.to_rotation_matrix();
    let yaw = r[(1, 0)].atan2(r[(0, 0)]);
    geom::pose(p.translation.x, p.translation.y, yaw)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pose;

    #[test]
    fn planar_round_trip_is_exact() {
        let t = Trajectory::from_parts(
            vec![0.0, 1.0, 2.5],
            vec![
                pose(1.0, 2.0, 3.1),
                pose(-1.0, 0.5, -2.0),
                pose(4.0, 4.0, 0.0),
            ],
        )
        .unwrap();
        let back = Trajectory3::from_2d(&t).to_2d();
        for (a, b) in t.poses.iter().zip(&back.poses) {
            let d = geom::between(a, b);
            assert!(d.translation.vector.norm() < 1e-12 && geom::heading(&d).abs() < 1e-12);
        }
        assert!((Trajectory3::from_2d(&t).path_length() - t.path_length()).abs() < 1e-12);
    }
}
