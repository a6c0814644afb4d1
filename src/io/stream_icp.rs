//! Scan matching fed sample by sample: the odometry prior is integrated as
//! wheel samples arrive, a scan waits until the prior covers its stamp, and
//! motions leave one by one. Numbers are those of `pipeline::icp::run` on the
//! whole recording (same operations in the same order).

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::collections::{BTreeMap, VecDeque};

use crate::geom::{self, Pose2};
use crate::icp::{IcpParams, IcpParamsError, IcpStats, ScanMatcher};
use crate::motion::Motion;
use crate::recording::{StampedPose, WheelSample};
use crate::robot::DiffDrive;
use crate::scan::LaserScan;
use crate::traj::Trajectory;

/// The tail of a growing trajectory: poses from the last one at or before
/// the earliest stamp still to be queried. `pose_at` answers exactly as
/// [`Trajectory::pose_at`] on the whole trajectory once [`covers`](Self::covers).
#[derive(Debug, Default)]
pub struct PoseWindow {
    traj: Trajectory,
    ended: bool,
}

impl PoseWindow {
    /// Appends a pose (non-increasing stamps are dropped, as `Trajectory::push` does).
    pub fn push(&mut self, t: f64, p: Pose2) -> bool {
        self.traj.push(t, p)
    }

    /// No more poses will come.
    pub fn end(&mut self) {
        self.ended = true;
    }

    /// Whether `pose_at(t)` is final: a later pose exists or the stream ended.
    pub fn covers(&self, t: f64) -> bool {
        self.ended || self.traj.stamps.last().is_some_and(|&l| l > t)
    }

    /// Interpolated pose at `t` (s); `None` outside the trajectory.
    pub fn pose_at(&self, t: f64) -> Option<Pose2> {
        self.traj.pose_at(t)
    }

    /// Forgets poses no query at or after `t` needs.
    pub fn forget_before(&mut self, t: f64) {
        let keep = self
            .traj
            .stamps
            .partition_point(|&s| s <= t)
            .saturating_sub(1);
        if keep > 4096 && keep * 2 > self.traj.stamps.len() {
            self.traj.stamps.drain(..keep);
            self.traj.poses.drain(..keep);
        }
    }
}

/// Wheel odometry integrated sample by sample, as `robot::wheel_odometry` does.
#[derive(Debug)]
pub struct WheelIntegrator {
    drive: DiffDrive,
    pose: Pose2,
    prev: Option<WheelSample>,
}

impl WheelIntegrator {
    /// Starts at the identity with the given kinematics.
    pub fn new(drive: DiffDrive) -> Self {
        Self {
            drive,
            pose: Pose2::identity(),
            prev: None,
        }
    }

    /// The pose after `s`, or `None` when its stamp does not advance.
    pub fn push(&mut self, s: &WheelSample) -> Option<(f64, Pose2)> {
        match self.prev {
            None => {
                self.prev = Some(*s);
                Some((s.stamp, self.pose))
            }
            Some(prev) if s.stamp > prev.stamp => {
                self.pose *= self
                    .drive
                    .increment(s.right - prev.right, s.left - prev.left);
                self.prev = Some(*s);
                Some((s.stamp, self.pose))
            }
            Some(_) => None,
        }
    }
}

/// Where the ICP prior comes from (chosen from the stream counts, as
/// `pipeline::icp::odometry_prior` chooses from the recording).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PriorKind {
    /// Wheel odometry with the nominal model.
    Wheels,
    /// The recording's own odometry.
    Odom,
    /// No prior.
    None,
}

/// Counts, iterations and the chained trajectory, kept as motions arrive.
#[derive(Debug, Default)]
pub struct IcpTally {
    pairs: usize,
    failed: usize,
    iters: u64,
    ran: u64,
    failures: BTreeMap<String, usize>,
    pose: Pose2,
    last_t: Option<f64>,
    path_length: f64,
    last_xy: Option<nalgebra::Vector2<f64>>,
}

impl IcpTally {
    /// Counts a motion; returns the trajectory pose it adds (as
    /// `icp::integrate` would), the first call also the start pose.
    pub fn add(&mut self, m: &Motion, out: &mut dyn FnMut(f64, &Pose2)) {
        self.pairs += 1;
        if m.iterations > 0 {
            self.iters += m.iterations as u64;
            self.ran += 1;
        }
        if let Some(f) = m.failure {
            self.failed += 1;
            *self.failures.entry(f.as_str().to_string()).or_default() += 1;
        }
        if self.last_t.is_none() && self.pairs == 1 {
            self.pose = Pose2::identity();
            if m.t0.is_finite() {
                self.emit(m.t0, Pose2::identity(), out);
            }
        }
        if !(m.t1 > m.t0) {
            return;
        }
        let next = self.pose * geom::pose(m.dx, m.dy, m.dtheta);
        if m.t1.is_finite() && self.last_t.is_none_or(|l| m.t1 > l) {
            self.pose = next;
            self.emit(m.t1, next, out);
        }
    }

    fn emit(&mut self, t: f64, p: Pose2, out: &mut dyn FnMut(f64, &Pose2)) {
        let xy = p.translation.vector;
        if let Some(prev) = self.last_xy {
            self.path_length += (xy - prev).norm();
        }
        self.last_xy = Some(xy);
        self.last_t = Some(t);
        out(t, &p);
    }

    /// Length (m) of the chained trajectory so far.
    pub fn path_length(&self) -> f64 {
        self.path_length
    }

    /// The summary `icp::summarise` gives for the same motions.
    pub fn stats(&self, wall_s: f64) -> IcpStats {
        IcpStats {
            pairs: self.pairs,
            failed_pairs: self.failed,
            mean_iterations: if self.ran > 0 {
                self.iters as f64 / self.ran as f64
            } else {
                0.0
            },
            wall_s,
            pairs_per_s: if wall_s > 0.0 {
                self.pairs as f64 / wall_s
            } else {
                0.0
            },
            failures: self.failures.clone(),
        }
    }
}

/// Scan matching over streamed samples.
pub struct StreamIcp {
    matcher: ScanMatcher,
    kind: PriorKind,
    wheels: WheelIntegrator,
    prior: PoseWindow,
    pending: VecDeque<LaserScan>,
    prev: Option<f64>,
}

impl StreamIcp {
    /// A matcher for a laser at `base_from_laser`, with the prior `kind`
    /// (wheel odometry uses `nominal`).
    pub fn new(
        params: &IcpParams,
        base_from_laser: Pose2,
        kind: PriorKind,
        nominal: DiffDrive,
    ) -> Result<Self, IcpParamsError> {
        let mut prior = PoseWindow::default();
        if kind == PriorKind::None {
            prior.end();
        }
        Ok(Self {
            matcher: ScanMatcher::new(params.clone(), base_from_laser)?,
            kind,
            wheels: WheelIntegrator::new(nominal),
            prior,
            pending: VecDeque::new(),
            prev: None,
        })
    }

    /// A wheel sample (stamp order).
    pub fn push_wheel(&mut self, s: &WheelSample) {
        if self.kind == PriorKind::Wheels {
            if let Some((t, p)) = self.wheels.push(s) {
                self.prior.push(t, p);
            }
        }
    }

    /// A pose of the recording's own odometry (stamp order).
    pub fn push_odom(&mut self, p: &StampedPose) {
        if self.kind == PriorKind::Odom {
            self.prior.push(p.stamp, p.pose);
        }
    }

    /// A scan (stamp order); matched once the prior covers it.
    pub fn push_scan(&mut self, s: LaserScan) {
        self.pending.push_back(s);
    }

    /// The prior stream has ended: every pending scan can be matched.
    pub fn end_prior(&mut self) {
        self.prior.end();
    }

    /// Scans waiting for the prior.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Matches every scan the prior now covers, handing out the motions.
    pub fn poll(&mut self, out: &mut dyn FnMut(Motion)) {
        while let Some(scan) = self.pending.front() {
            if !self.prior.covers(scan.stamp) {
                break;
            }
            let scan = self.pending.pop_front().expect("front exists");
            let prior = match (self.kind, self.prev) {
                (PriorKind::None, _) | (_, None) => None,
                (_, Some(t0)) => self
                    .prior
                    .pose_at(t0)
                    .zip(self.prior.pose_at(scan.stamp))
                    .map(|(a, b)| geom::between(&a, &b)),
            };
            if let Some(m) = self.matcher.push(&scan, prior) {
                out(m);
            }
            if self.prev.is_none_or(|t| scan.stamp > t) {
                self.prev = Some(scan.stamp);
            }
            if let Some(t) = self.prev {
                self.prior.forget_before(t);
            }
        }
    }
}
