//! What each scan is matched against: the previous scan, or a local map of
//! recent keyframes; when a matched scan becomes a keyframe, how the map is
//! kept across a few failed scans (bridging them by their prior), and when
//! a scan starts a new map.

use crate::geom::{self, Pose2};
use crate::icp::neighbours::NeighbourSearch;
use crate::icp::preprocess::ScanPoints;
use crate::icp::reference::Reference;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// Failed scans in a row after which the local map is given up for a new
/// one started at the current scan.
const MAP_PATIENCE: usize = 3;

/// The reference's shape and the keyframe policy. Units: m, rad.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LocalMapSettings {
    /// Match against keyframes (true) or the previous scan (false).
    pub local_map: bool,
    /// Keyframes kept.
    pub keyframes: usize,
    /// New keyframe after this much translation (m) …
    pub keyframe_dist: f64,
    /// … or this much rotation (rad).
    pub keyframe_angle: f64,
    /// Fewest valid points a scan needs to serve as reference.
    pub min_points: usize,
    /// Points after the first in one line fit.
    pub normal_window: usize,
    /// Surface length (m) a line fit should span; 0 = always `normal_window`.
    pub normal_length: f64,
    /// What answers the reference's nearest-neighbour queries.
    pub neighbours: NeighbourSearch,
}

impl Default for LocalMapSettings {
    fn default() -> Self {
        Self {
            local_map: true,
            keyframes: 5,
            keyframe_dist: 0.3,
            keyframe_angle: 0.2,
            min_points: 20,
            normal_window: 8,
            normal_length: 0.3,
            neighbours: NeighbourSearch::default(),
        }
    }
}

/// The reference, the current scan's own lines, and the pose of the last
/// scan in the reference frame.
pub struct LocalMap {
    set: LocalMapSettings,
    /// What the next scan is matched against.
    reference: Reference,
    /// The current scan as a reference (lines, tree): its normals serve the
    /// registration, and it becomes the next pair's reference (scan to
    /// scan) or a keyframe.
    own: Reference,
    /// The keyframes: pose, and the scan's points and lines placed in the
    /// map frame by it.
    keyframes: VecDeque<(Pose2, Reference)>,
    /// Pose of the last scan in the reference frame (the reference scan, or
    /// the local map's world frame).
    ref_from_last: Pose2,
    /// Covariance of `ref_from_last` from its registration (local map only).
    last_cov: Matrix3<f64>,
    /// Failed pairs since the last successful match.
    misses: usize,
}

impl LocalMap {
    /// An empty reference.
    pub fn new(set: LocalMapSettings) -> Self {
        Self {
            reference: Reference::new(set.normal_window, set.normal_length)
                .with_search(set.neighbours),
            own: Reference::new(set.normal_window, set.normal_length),
            keyframes: VecDeque::new(),
            ref_from_last: Pose2::identity(),
            last_cov: Matrix3::zeros(),
            misses: 0,
            set,
        }
    }

    /// What the next scan is matched against.
    pub fn reference(&self) -> &Reference {
        &self.reference
    }

    /// The current scan's own lines.
    pub fn own(&self) -> &Reference {
        &self.own
    }

    /// Pose of the last scan in the reference frame.
    pub fn ref_from_last(&self) -> Pose2 {
        self.ref_from_last
    }

    /// Whether failed pairs came since the last successful match: the next
    /// one starts from a pose their prior placed.
    pub fn bridged(&self) -> bool {
        self.misses > 0
    }

    /// Fits the current scan's lines (for its normals); with scan-to-scan
    /// matching also its tree, as it becomes the next reference.
    pub fn set_own(&mut self, cur: &ScanPoints) {
        if self.set.local_map {
            self.own.set_lines(cur);
        } else {
            self.own.set(cur);
        }
    }

    /// Covariance of the motion from the last scan to `ref_from_cur`, whose
    /// registration has covariance `own_cov`: that covariance (scan to scan),
    /// or with the last pose's own propagated through
    /// `motion = inv(W_last) W_cur`, both registered against the map.
    pub fn motion_cov(&self, ref_from_cur: &Pose2, own_cov: &Matrix3<f64>) -> Matrix3<f64> {
        if self.set.local_map {
            let (ja, jb) = geom::between_jacobians(&self.ref_from_last, ref_from_cur);
            ja * self.last_cov * ja.transpose() + jb * own_cov * jb.transpose()
        } else {
            *own_cov
        }
    }

    /// After a successful match: the current scan becomes the reference (scan
    /// to scan) or may become a keyframe (local map).
    pub fn advance(&mut self, cur: &ScanPoints, ref_from_cur: Pose2, cov: Matrix3<f64>) {
        self.misses = 0;
        if !self.set.local_map {
            self.start_reference(cur, Pose2::identity());
            return;
        }
        self.ref_from_last = ref_from_cur;
        self.last_cov = cov;
        let key = self
            .keyframes
            .back()
            .map(|k| geom::between(&k.0, &ref_from_cur));
        let new_key = key.is_none_or(|d| {
            d.translation.vector.norm() > self.set.keyframe_dist
                || geom::heading(&d).abs() > self.set.keyframe_angle
        });
        if new_key {
            if self.keyframes.len() >= self.set.keyframes {
                self.keyframes.pop_front();
            }
            let key = self.own.placed(&ref_from_cur);
            self.keyframes.push_back((ref_from_cur, key));
            self.reference
                .set_many(self.keyframes.iter().map(|(_, s)| s));
        }
    }

    /// After a failed match: the scan is placed by the `prior`. The local map
    /// is kept for the next scans to re-localise against (one odd scan — a
    /// crowd in front of the laser, a mis-stamped sweep — then costs nothing
    /// but its own pair), unless `MAP_PATIENCE` scans in a row failed: then
    /// the current scan alone starts a new map.
    /// `cov` is the failed pair's (as wide as the gates, isotropic in x, y).
    pub fn bridge(&mut self, cur: &ScanPoints, prior: &Pose2, cov: Matrix3<f64>) {
        self.misses += 1;
        let ref_from_cur = self.ref_from_last * prior;
        if self.set.local_map && self.misses <= MAP_PATIENCE && !self.keyframes.is_empty() {
            // Uncertainty of the bridged pose: the last one's plus the
            // prior's (isotropic in x, y, so the same in the map frame).
            self.last_cov += cov;
            self.ref_from_last = ref_from_cur;
        } else {
            self.start_reference(cur, ref_from_cur);
        }
    }

    /// A pair not matched: the scan is placed by `prior`, and starts a new
    /// reference there if it has enough points.
    pub fn skip(&mut self, cur: &ScanPoints, prior: &Pose2) {
        let ref_from_cur = self.ref_from_last * prior;
        if cur.pts.len() >= self.set.min_points {
            self.start_reference(cur, ref_from_cur);
        } else {
            self.ref_from_last = ref_from_cur;
        }
    }

    /// Makes the current scan the only reference, placed at `ref_from_cur`
    /// (local map) or as the new reference frame (scan to scan).
    pub fn start_reference(&mut self, cur: &ScanPoints, ref_from_cur: Pose2) {
        self.last_cov = Matrix3::zeros();
        if cur.pts.len() < self.set.min_points {
            self.reference.set(&ScanPoints::default());
            self.keyframes.clear();
            self.ref_from_last = ref_from_cur;
            return;
        }
        if self.set.local_map {
            self.keyframes.clear();
            let key = self.own.placed(&ref_from_cur);
            self.keyframes.push_back((ref_from_cur, key));
            self.reference
                .set_many(self.keyframes.iter().map(|(_, s)| s));
            self.ref_from_last = ref_from_cur;
        } else {
            // The current scan's lines and tree are already built: swap them in.
            std::mem::swap(&mut self.reference, &mut self.own);
            self.ref_from_last = Pose2::identity();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points 5 cm apart along a wall 2 m ahead, all linked.
    fn wall(n: usize) -> ScanPoints {
        let pts: Vec<[f64; 2]> = (0..n).map(|i| [2.0, 0.05 * i as f64 - 1.0]).collect();
        let range = pts.iter().map(|p| p[0].hypot(p[1])).collect();
        ScanPoints {
            link: vec![true; n],
            pts,
            range,
        }
    }

    fn map_with(local_map: bool) -> (LocalMap, ScanPoints) {
        let set = LocalMapSettings {
            local_map,
            ..Default::default()
        };
        let (mut m, cur) = (LocalMap::new(set), wall(40));
        m.set_own(&cur);
        m.start_reference(&cur, Pose2::identity());
        (m, cur)
    }

    #[test]
    fn keyframes_follow_distance_and_angle_and_the_oldest_goes() {
        let (mut m, cur) = map_with(true);
        let (z, at) = (Matrix3::zeros(), |x: f64, t: f64| geom::pose(x, 0.0, t));
        assert_eq!((m.keyframes.len(), m.reference().len()), (1, 40));
        m.advance(&cur, at(0.1, 0.1), z);
        assert_eq!(m.keyframes.len(), 1);
        (1..=6).for_each(|k| m.advance(&cur, at(0.31 * k as f64, 0.0), z));
        assert_eq!((m.keyframes.len(), m.reference().len()), (5, 200));
        m.advance(&cur, at(1.86, 0.21), z);
        assert_eq!(m.keyframes.back().unwrap().0, at(1.86, 0.21));
    }

    #[test]
    fn failed_scans_are_bridged_until_patience_runs_out() {
        let (mut m, cur) = map_with(true);
        let step = geom::pose(0.1, 0.0, 0.0);
        let cov = Matrix3::identity() * 1e-2;
        for k in 1..=MAP_PATIENCE {
            m.bridge(&cur, &step, cov);
            assert!(m.bridged() && m.keyframes.len() == 1);
            assert_eq!(m.last_cov, cov * k as f64);
        }
        m.bridge(&cur, &step, cov);
        let x = |p: &Pose2| p.translation.vector.x;
        assert!(m.keyframes.len() == 1 && (x(&m.keyframes[0].0) - 0.4).abs() < 1e-12);
        assert_eq!(m.last_cov, Matrix3::zeros());
        m.advance(&cur, geom::pose(0.4, 0.0, 0.0), cov);
        assert!(!m.bridged());
        // A skipped scan without enough points moves the last pose only.
        m.skip(&wall(5), &step);
        assert!(m.keyframes.len() == 1 && (x(&m.ref_from_last()) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn scan_to_scan_makes_each_matched_scan_the_reference() {
        let (mut m, cur) = map_with(false);
        let cov = Matrix3::identity() * 1e-4;
        let to = geom::pose(0.2, 0.1, 0.05);
        assert_eq!(m.motion_cov(&to, &cov), cov);
        m.set_own(&wall(30));
        m.advance(&cur, to, cov);
        assert_eq!(
            (m.reference().len(), m.ref_from_last()),
            (30, Pose2::identity())
        );
        // Against the map from the origin with an exact last pose, the
        // motion's covariance is the registration's.
        let (m, _) = map_with(true);
        assert!((m.motion_cov(&to, &cov) - cov).norm() < 1e-18);
    }
}
