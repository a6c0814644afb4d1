//! A time-stamped 2D trajectory: poses `world_from_base` at increasing times (s).

use crate::geom::{self, Pose2};

/// Poses at strictly increasing stamps (s). The two vectors always have equal length.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trajectory {
    /// Stamps in seconds, strictly increasing.
    pub stamps: Vec<f64>,
    /// `world_from_base` at each stamp.
    pub poses: Vec<Pose2>,
}

impl Trajectory {
    /// An empty trajectory with room for `n` poses.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            stamps: Vec::with_capacity(n),
            poses: Vec::with_capacity(n),
        }
    }

    /// Builds from parallel vectors; `None` if lengths differ or stamps do not increase.
    pub fn from_parts(stamps: Vec<f64>, poses: Vec<Pose2>) -> Option<Self> {
        if stamps.len() != poses.len() || stamps.windows(2).any(|w| !(w[1] > w[0])) {
            return None;
        }
        Some(Self { stamps, poses })
    }

    /// Appends a pose; a stamp that does not increase is rejected (returns false).
    pub fn push(&mut self, t: f64, p: Pose2) -> bool {
        if !t.is_finite() || self.stamps.last().is_some_and(|&l| t <= l) {
            return false;
        }
        self.stamps.push(t);
        self.poses.push(p);
        true
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// True when there are no poses.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// Time span (s) from first to last stamp; 0 for fewer than two poses.
    pub fn duration(&self) -> f64 {
        match (self.stamps.first(), self.stamps.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }

    /// Length (m) of the polyline through the positions.
    pub fn path_length(&self) -> f64 {
        self.poses
            .windows(2)
            .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
            .sum()
    }

    /// Pose at time `t` by interpolation between the neighbouring stamps;
    /// `None` outside [first, last] stamp.
    pub fn pose_at(&self, t: f64) -> Option<Pose2> {
        let n = self.stamps.len();
        if n == 0 || !(t >= self.stamps[0] && t <= self.stamps[n - 1]) {
            return None;
        }
        let i = self.stamps.partition_point(|&s| s <= t);
        if i == 0 {
            return Some(self.poses[0]);
        }
        if i >= n {
            return Some(self.poses[n - 1]);
        }
        let (t0, t1) = (self.stamps[i - 1], self.stamps[i]);
        let s = (t - t0) / (t1 - t0);
        Some(geom::interpolate(&self.poses[i - 1], &self.poses[i], s))
    }

    /// The same trajectory re-expressed so that its first pose is the identity.
    pub fn relative_to_start(&self) -> Self {
        match self.poses.first() {
            None => self.clone(),
            Some(p0) => {
                let inv = p0.inverse();
                Self {
                    stamps: self.stamps.clone(),
                    poses: self.poses.iter().map(|p| inv * p).collect(),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pose;

    #[test]
    fn push_rejects_non_increasing_stamps() {
        let mut t = Trajectory::default();
        assert!(t.push(1.0, pose(0.0, 0.0, 0.0)));
        assert!(!t.push(1.0, pose(1.0, 0.0, 0.0)));
        assert!(!t.push(0.5, pose(1.0, 0.0, 0.0)));
        assert!(!t.push(f64::NAN, pose(1.0, 0.0, 0.0)));
        assert!(t.push(2.0, pose(3.0, 4.0, 0.0)));
        assert_eq!(t.len(), 2);
        assert!((t.path_length() - 5.0).abs() < 1e-12);
    }

    #[test]
    fn pose_at_interpolates_and_refuses_outside() {
        let t = Trajectory::from_parts(
            vec![0.0, 1.0, 3.0],
            vec![
                pose(0.0, 0.0, 0.0),
                pose(1.0, 0.0, 0.2),
                pose(1.0, 2.0, 0.6),
            ],
        )
        .unwrap();
        let p = t.pose_at(2.0).unwrap();
        assert!((p.translation.y - 1.0).abs() < 1e-12);
        assert!((geom::heading(&p) - 0.4).abs() < 1e-12);
        assert_eq!(t.pose_at(3.0).unwrap(), t.poses[2]);
        assert!(t.pose_at(-0.1).is_none());
        assert!(t.pose_at(3.1).is_none());
    }
}
