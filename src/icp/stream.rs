//! Scan matching fed sample by sample: the odometry prior is integrated as
//! wheel (or odometry) samples arrive, a scan waits until the prior covers
//! its stamp, and motions leave one by one. [`super::match_recording`] is this
//! matcher fed a whole recording, so a bag streamed from disk and the same
//! data in memory give the same motions.

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::collections::VecDeque;

use super::matcher::ScanMatcher;
use super::params::{IcpParams, IcpParamsError, PriorChoice};
use super::prior_scale::{PriorScale, ScaleCheck};
use super::time_offset::{offsets, OffsetCheck, TimeOffsetFit, OFFSET_SPAN_S};
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
    /// Heading (rad) of each pose, unwrapped along the window.
    headings: Vec<f64>,
    ended: bool,
}

impl PoseWindow {
    /// Appends a pose (non-increasing stamps are dropped, as `Trajectory::push` does).
    pub fn push(&mut self, t: f64, p: Pose2) -> bool {
        let pushed = self.traj.push(t, p);
        if pushed {
            let h = geom::heading(&p);
            self.headings.push(match self.headings.last() {
                Some(&prev) => prev + geom::wrap_angle(h - prev),
                None => h,
            });
        }
        pushed
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

    /// The heading (rad, unwrapped along the window) at each of the
    /// increasing stamps `times`, interpolated as `pose_at` interpolates
    /// (one search, then a walk); `false` (and `out` incomplete) when one
    /// lies outside the trajectory.
    pub fn headings_at(&self, times: impl Iterator<Item = f64>, out: &mut Vec<f64>) -> bool {
        out.clear();
        let (stamps, headings) = (&self.traj.stamps, &self.headings);
        let (Some(&first), Some(&last)) = (stamps.first(), stamps.last()) else {
            return false;
        };
        let mut i = None;
        for t in times {
            if !(t >= first && t <= last) {
                return false;
            }
            // First stamp above t (at least 1: t ≥ first).
            let mut k = *i.get_or_insert_with(|| stamps.partition_point(|&s| s <= t));
            while k < stamps.len() && stamps[k] <= t {
                k += 1;
            }
            i = Some(k);
            let h0 = headings[k - 1];
            if k == stamps.len() {
                out.push(h0);
                continue;
            }
            let f = (t - stamps[k - 1]) / (stamps[k] - stamps[k - 1]);
            out.push(h0 + f * (headings[k] - h0));
        }
        true
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
            self.headings.drain(..keep);
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
    /// The prior `choice` gives a recording with these many wheel and
    /// odometry samples: `auto` takes wheel odometry with `nominal` from two
    /// wheel samples on, else the recording's own odometry from two poses
    /// on, else none; a named stream must have two samples, else the error
    /// says what the recording lacks.
    pub fn choose(
        choice: PriorChoice,
        wheel_samples: usize,
        odom_poses: usize,
        nominal: DiffDrive,
    ) -> Result<Self, String> {
        let lacks = |what: &str, n: usize| {
            format!(
                "[icp] prior = \"{}\" needs {what}, and the recording has {n} sample(s) of it \
                 (`odocal inspect` lists its streams; \"auto\" takes what there is)",
                choice.as_str()
            )
        };
        match choice {
            PriorChoice::Auto if wheel_samples >= 2 => Ok(Self::Wheels(nominal)),
            PriorChoice::Auto if odom_poses >= 2 => Ok(Self::Odom),
            PriorChoice::Auto | PriorChoice::None => Ok(Self::None),
            PriorChoice::Wheels if wheel_samples >= 2 => Ok(Self::Wheels(nominal)),
            PriorChoice::Wheels => Err(lacks("a wheel stream", wheel_samples)),
            PriorChoice::Odometry if odom_poses >= 2 => Ok(Self::Odom),
            PriorChoice::Odometry => Err(lacks("an odometry stream", odom_poses)),
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
    /// Offset (s) of the prior's clock (`IcpParams::time_offset`).
    offset: f64,
    /// How the prior's turns fit the matched ones at other offsets.
    check: OffsetCheck,
    /// Scratch of the clock check.
    headings: Headings,
    /// How the prior's distances and turns compare with the matched ones.
    scale: ScaleCheck,
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
            offset: params.time_offset,
            check: OffsetCheck::new(params.time_offset),
            headings: Default::default(),
            scale: ScaleCheck::default(),
        })
    }

    /// The prior's distances and turns against the matched ones (see
    /// `prior_scale`); `None` without a prior or with too little motion.
    pub fn prior_scale(&self) -> Option<PriorScale> {
        self.scale.result()
    }

    /// The offset of the prior's clock at which its turns fit the matched
    /// ones best, beside the one in use (see `time_offset`); `None` without
    /// a prior or with too few matched pairs.
    pub fn time_offset_fit(&self) -> Option<TimeOffsetFit> {
        self.check.result()
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

    /// Matches every scan the prior now covers (on the prior's clock, and
    /// as far beyond as the clock check reads it), handing out the motions.
    /// The prior of a pair is the odometry's motion over its stamps plus
    /// `time_offset`.
    pub fn poll(&mut self, out: &mut dyn FnMut(Motion)) {
        while let Some(scan) = self.pending.front() {
            if !self.prior.covers(scan.stamp + self.offset + OFFSET_SPAN_S) {
                break;
            }
            let scan = self.pending.pop_front().expect("front exists");
            let has_prior = self.odom || self.wheels.is_some();
            let d = self.offset;
            let prior = match self.prev.filter(|_| has_prior) {
                None => None,
                Some(t0) => self
                    .prior
                    .pose_at(t0 + d)
                    .zip(self.prior.pose_at(scan.stamp + d))
                    .map(|(a, b)| geom::between(&a, &b)),
            };
            if let Some(m) = self.matcher.push(&scan, prior) {
                if has_prior {
                    self.check_clock(&m);
                    self.check_scale(&m, prior);
                }
                out(m);
            }
            if self.prev.is_none_or(|t| scan.stamp > t) {
                self.prev = Some(scan.stamp);
            }
            if let Some(t) = self.prev {
                self.prior.forget_before(t + d - OFFSET_SPAN_S);
            }
        }
    }

    /// Adds a matched pair whose scans measured it to the scale check,
    /// against the `prior` increment the pair started from.
    fn check_scale(&mut self, m: &Motion, prior: Option<Pose2>) {
        let (Some(p), Some(split)) = (prior, m.split.as_ref()) else {
            return;
        };
        if m.is_valid() {
            let matched = [m.dx, m.dy, m.dtheta];
            self.scale.add(geom::xyt(&p), matched, split.scan_share);
        }
    }

    /// Adds a matched pair to the clock check: the prior's heading
    /// increment over the pair at each offset tried against the matched one.
    /// The headings at a pair's end serve as the next pair's start.
    fn check_clock(&mut self, m: &Motion) {
        if !m.is_valid() {
            return;
        }
        let at = |t: f64| offsets(self.offset).map(move |d| t + d);
        let Headings {
            t1,
            start,
            end,
            diff,
        } = &mut self.headings;
        let start_ok = if *t1 == Some(m.t0) {
            std::mem::swap(start, end);
            true
        } else {
            self.prior.headings_at(at(m.t0), start)
        };
        let end_ok = self.prior.headings_at(at(m.t1), end);
        *t1 = end_ok.then_some(m.t1);
        if !(start_ok && end_ok) {
            return;
        }
        diff.clear();
        diff.extend(end.iter().zip(start.iter()).map(|(b, a)| b - a));
        self.check.add(diff, m.dtheta);
    }
}

/// Scratch of the clock check: the prior's headings at the offsets tried
/// around a pair's start and end stamps, and their differences.
#[derive(Debug, Default)]
struct Headings {
    /// The end stamp `end` was read at (s), if it was read whole.
    t1: Option<f64>,
    start: Vec<f64>,
    end: Vec<f64>,
    diff: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The walked headings are `pose_at`'s (to the wrap), at any increasing
    /// stamps inside the trajectory, and refused outside it.
    #[test]
    fn headings_at_interpolate_as_pose_at() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let mut w = PoseWindow::default();
        let (mut t, mut th) = (0.0, 0.0);
        for _ in 0..200 {
            t += rng.random_range(0.005..0.05);
            th += rng.random_range(-0.4..0.4);
            w.push(t, geom::pose(t, 0.0, th));
        }
        let first = w.traj.stamps[0];
        let times: Vec<f64> = (0..300)
            .map(|k| first + k as f64 * (t - first) / 299.0)
            .collect();
        let mut out = Vec::new();
        assert!(w.headings_at(times.iter().copied(), &mut out));
        for (&s, h) in times.iter().zip(&out) {
            let want = geom::heading(&w.pose_at(s).unwrap());
            assert!(
                geom::wrap_angle(h - want).abs() < 1e-9,
                "{s}: {h} vs {want}"
            );
        }
        assert!(!w.headings_at([first - 0.01, first].into_iter(), &mut out));
        assert!(!w.headings_at([t, t + 0.01].into_iter(), &mut out));
    }
}
