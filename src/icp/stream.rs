//! Scan matching fed sample by sample: the odometry prior is integrated as
//! wheel (or odometry) samples arrive, a scan waits until the prior covers
//! its stamp, and motions leave one by one. [`super::match_recording`] is this
//! matcher fed a whole recording, so a bag streamed from disk and the same
//! data in memory give the same motions.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::collections::VecDeque;

use super::matcher::ScanMatcher;
use super::params::{IcpParams, IcpParamsError};
use crate::geom::{self, Pose2};
use crate::motion::Motion;
use crate::recording::{StampedPose, WheelSample};
use crate::robot::{DiffDrive, WheelIntegrator};
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

/// Where the ICP prior comes from: wheel odometry when the recording has
/// encoders, else the recording's own odometry, else none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Prior {
    /// Wheel odometry integrated with this (nominal) model.
    Wheels(DiffDrive),
    /// The recording's own odometry.
    Odom,
    /// No prior.
    None,
}

impl Prior {
    /// The prior a recording with these many wheel and odometry samples
    /// gets: wheel odometry with `nominal` from two wheel samples on, else the
    /// recording's own odometry from two poses on.
    pub fn choose(wheel_samples: usize, odom_poses: usize, nominal: DiffDrive) -> Self {
        if wheel_samples >= 2 {
            Self::Wheels(nominal)
        } else if odom_poses >= 2 {
            Self::Odom
        } else {
            Self::None
        }
    }
}

/// Scan matching over streamed samples (see the module doc).
pub struct StreamMatcher {
    matcher: ScanMatcher,
    /// Dead reckoning of the wheel samples, for a wheel-odometry prior.
    wheels: Option<WheelIntegrator>,
    /// Whether the recording's own odometry is the prior.
    odom: bool,
    prior: PoseWindow,
    pending: VecDeque<LaserScan>,
    prev: Option<f64>,
}

impl StreamMatcher {
    /// A matcher for a laser at `base_from_laser` with the given prior.
    pub fn new(
        params: &IcpParams,
        base_from_laser: Pose2,
        prior: Prior,
    ) -> Result<Self, IcpParamsError> {
        let mut window = PoseWindow::default();
        if prior == Prior::None {
            window.end();
        }
        Ok(Self {
            matcher: ScanMatcher::new(params.clone(), base_from_laser)?,
            wheels: match prior {
                Prior::Wheels(nominal) => Some(WheelIntegrator::new(nominal, Pose2::identity())),
                Prior::Odom | Prior::None => None,
            },
            odom: prior == Prior::Odom,
            prior: window,
            pending: VecDeque::new(),
            prev: None,
        })
    }

    /// A wheel sample (stamp order); ignored unless the prior is wheel odometry.
    pub fn push_wheel(&mut self, s: &WheelSample) {
        if let Some((t, p)) = self.wheels.as_mut().and_then(|w| w.push(s)) {
            self.prior.push(t, p);
        }
    }

    /// A pose of the recording's own odometry (stamp order); ignored unless
    /// it is the prior.
    pub fn push_odom(&mut self, p: &StampedPose) {
        if self.odom {
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

    /// Matches every scan the prior now covers, handing out the motions.
    pub fn poll(&mut self, out: &mut dyn FnMut(Motion)) {
        while let Some(scan) = self.pending.front() {
            if !self.prior.covers(scan.stamp) {
                break;
            }
            let scan = self.pending.pop_front().expect("front exists");
            let has_prior = self.odom || self.wheels.is_some();
            let prior = match self.prev.filter(|_| has_prior) {
                None => None,
                Some(t0) => self
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
