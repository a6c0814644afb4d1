//! A run into a [`Logger`] (design.md's Rerun entities) as it goes, in memory
//! that does not grow with the recording: scans at their ICP pose, ICP
//! quality, estimates, particle clouds, the four trajectories (reference, raw
//! odometry, calibrated, ICP), each put on the reference at its start. It is
//! an observer of the one driver, with two concessions to long runs, both reported by
//! [`StreamRecorder::notes`]: trajectories are drawn through at most
//! [`RecorderOptions::max_polyline`] poses each, and when a run has more
//! filter steps than [`RecorderOptions::max_clouds`], the particle cloud is
//! logged at every k-th step only. The logger may bound more (the Rerun
//! logger's trail of scan-matching ellipses); [`StreamRecorder::finish`]
//! returns its notes too.

use std::collections::VecDeque;

use super::observe::RunObserver;
use crate::calib::{CloudView, Estimate};
use crate::geom::Pose2;
use crate::io::{Item, StreamInfo};
use crate::motion::Motion;
use crate::recording::WheelSample;
use crate::robot::DiffDrive;
use crate::scan::LaserScan;
use crate::traj::Trajectory;
use crate::viz::{CalibEstimate, Logger, Stamp, TrajectoryKind, VizError};
use nalgebra::Point2;

/// Scans between two particle clouds logged on a live stream (no end to
/// spread `max_clouds` over).
const LIVE_CLOUD_EVERY: usize = 10;

/// `world_from_estimate` that puts the estimate's first pose on the reference.
pub fn anchor(est: &Trajectory, reference: Option<&Trajectory>) -> Pose2 {
    match (est.stamps.first(), est.poses.first(), reference) {
        (Some(&t0), Some(p0), Some(r)) => r
            .pose_at(t0)
            .or_else(|| r.poses.first().copied())
            .map(|w| w * p0.inverse())
            .unwrap_or_else(Pose2::identity),
        _ => Pose2::identity(),
    }
}

/// The estimate's poses placed in the world by `world_from_est`.
pub fn in_world(est: &Trajectory, world_from_est: &Pose2) -> Vec<Pose2> {
    est.poses.iter().map(|p| world_from_est * p).collect()
}

/// Limits that keep a long run's recording bounded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecorderOptions {
    /// Most particle clouds logged per run (then every k-th step's).
    pub max_clouds: usize,
    /// Most poses per logged trajectory (then every k-th pose, and the last).
    pub max_polyline: usize,
}

impl Default for RecorderOptions {
    fn default() -> Self {
        Self {
            max_clouds: 20_000,
            max_polyline: 20_000,
        }
    }
}

/// A trajectory kept as every `stride`-th pose; the stride doubles whenever
/// the kept poses reach the cap, so memory stays bounded.
#[derive(Debug, Clone)]
pub struct Polyline {
    traj: Trajectory,
    stride: usize,
    seen: usize,
    last: Option<(f64, Pose2)>,
    cap: usize,
}

impl Polyline {
    /// An empty polyline of at most `cap` (≥ 2) kept poses.
    pub fn new(cap: usize) -> Self {
        Self {
            traj: Trajectory::default(),
            stride: 1,
            seen: 0,
            last: None,
            cap: cap.max(2),
        }
    }

    /// Adds the pose at `t` (s); stamps that do not increase are ignored.
    pub fn push(&mut self, t: f64, p: Pose2) {
        if !t.is_finite() || self.last.is_some_and(|(l, _)| t <= l) {
            return;
        }
        if self.seen.is_multiple_of(self.stride)
            && self.traj.push(t, p)
            && self.traj.len() >= self.cap
        {
            let mut thin = Trajectory::with_capacity(self.cap / 2 + 1);
            for i in (0..self.traj.len()).step_by(2) {
                thin.push(self.traj.stamps[i], self.traj.poses[i]);
            }
            self.traj = thin;
            self.stride *= 2;
        }
        self.seen += 1;
        self.last = Some((t, p));
    }

    /// The kept poses plus the last one pushed.
    pub fn finish(mut self) -> Trajectory {
        if let Some((t, p)) = self.last {
            self.traj.push(t, p);
        }
        self.traj
    }

    /// Whether poses were left out.
    pub fn decimated(&self) -> bool {
        self.stride > 1
    }

    /// The first pose pushed.
    fn first(&self) -> Option<(f64, Pose2)> {
        Some((*self.traj.stamps.first()?, *self.traj.poses.first()?))
    }
}

/// Logs a streamed calibration run (see the module doc). Timelines: `scan`
/// counts the scans read, `time` is seconds since the first sample read.
pub struct StreamRecorder<'a> {
    logger: &'a mut dyn Logger,
    opts: RecorderOptions,
    nominal: DiffDrive,
    base_from_laser: Pose2,
    error: Option<VizError>,
    t_start: Option<f64>,
    /// Every k-th step's cloud is logged.
    cloud_every: usize,
    steps: usize,
    motions: i64,
    /// Scans read but not yet placed at an ICP pose: (index, scan).
    pending: VecDeque<(i64, LaserScan)>,
    scans_read: i64,
    /// Stamps of scans that no filter step has passed yet, and how many have.
    unpassed: VecDeque<f64>,
    passed: i64,
    /// The first reference poses, to anchor the trajectories' starts.
    early_reference: Trajectory,
    icp_anchor: Option<Pose2>,
    prev_icp: Option<(f64, Pose2)>,
    last_icp: Option<(f64, Pose2)>,
    icp: Polyline,
    reference: Polyline,
    raw: Polyline,
    raw_pose: Pose2,
    last_wheel: Option<WheelSample>,
    /// Every filter step's sensor time (s) and scan index, for
    /// [`Self::changes`]: 16 bytes a step (1.2 MB for 2 h at 10 Hz); the
    /// firings are named after the run has passed their windows, the
    /// mounting watch's dated back, and reach the recording at its end.
    step_stamps: Vec<(f64, i64)>,
    calibrated: Polyline,
    pts: Vec<Point2<f64>>,
    /// Scan-match covariances (2×2, m²) waiting for their matched pose:
    /// (stamp of the row, t1).
    covariances: VecDeque<(Stamp, f64, [[f64; 2]; 2])>,
}

/// Most scans kept waiting for their ICP pose (a few are, normally).
const MAX_PENDING: usize = 2048;

/// How long after a trajectory's start the recorder waits for the reference
/// to cover it, and how much of the reference it keeps for anchoring (s).
const ANCHOR_WINDOW_S: f64 = 30.0;

impl<'a> StreamRecorder<'a> {
    /// A recorder logging into `logger`; `nominal` integrates the raw wheel
    /// odometry and `base_from_laser` places the scans unless the bag states it.
    pub fn new(
        logger: &'a mut dyn Logger,
        opts: RecorderOptions,
        nominal: DiffDrive,
        base_from_laser: Pose2,
    ) -> Self {
        Self {
            logger,
            opts,
            nominal,
            base_from_laser,
            error: None,
            t_start: None,
            cloud_every: 1,
            steps: 0,
            motions: 0,
            pending: VecDeque::new(),
            scans_read: 0,
            unpassed: VecDeque::new(),
            passed: 0,
            early_reference: Trajectory::default(),
            icp_anchor: None,
            prev_icp: None,
            last_icp: None,
            icp: Polyline::new(opts.max_polyline),
            reference: Polyline::new(opts.max_polyline),
            raw: Polyline::new(opts.max_polyline),
            raw_pose: Pose2::identity(),
            last_wheel: None,
            step_stamps: Vec::new(),
            calibrated: Polyline::new(opts.max_polyline),
            pts: Vec::new(),
            covariances: VecDeque::new(),
        }
    }

    /// Every k-th filter step's particle cloud is logged (1: every step).
    pub fn cloud_every(&self) -> usize {
        self.cloud_every
    }

    /// What the recording leaves out, for the user (empty when nothing).
    pub fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if self.cloud_every > 1 {
            notes.push(format!(
                "the recording shows the particle cloud of one filter step in {} ({} steps)",
                self.cloud_every, self.steps
            ));
        }
        let thin: Vec<&str> = [
            ("ICP", &self.icp),
            ("reference", &self.reference),
            ("raw odometry", &self.raw),
            ("calibrated", &self.calibrated),
        ]
        .iter()
        .filter(|(_, p)| p.decimated())
        .map(|(n, _)| *n)
        .collect();
        if !thin.is_empty() {
            notes.push(format!(
                "the {} trajectories are drawn through at most {} poses each",
                thin.join(", "),
                self.opts.max_polyline
            ));
        }
        notes
    }

    fn keep(&mut self, r: Result<(), VizError>) {
        if let (Err(e), None) = (r, &self.error) {
            self.error = Some(e);
        }
    }

    fn time(&self, t: f64) -> f64 {
        t - self.t_start.unwrap_or(0.0)
    }

    /// `world_from_odom` putting a trajectory whose first pose is `p0` at
    /// `t0` on the reference (as the in-memory recording does). `None` while
    /// the reference may still cover `t0` (the stream is before `now`).
    fn anchor_at(&self, t0: f64, p0: &Pose2, now: Option<f64>) -> Option<Pose2> {
        let r = &self.early_reference;
        let covered = r.len() >= 2 && r.stamps.last().is_some_and(|&t| t >= t0);
        let waited = now.is_none_or(|n| n > t0 + ANCHOR_WINDOW_S);
        if !covered && !waited {
            return None;
        }
        let mut est = Trajectory::default();
        est.push(t0, *p0);
        let reference = (r.len() >= 2).then_some(r);
        Some(anchor(&est, reference))
    }

    /// Logs the scans waiting for a pose up to `t` (s), at the ICP pose
    /// interpolated to their stamps; scans before the first pose have none
    /// and are not drawn (as in the in-memory recording).
    fn place_scans(&mut self, t: f64) {
        let (Some(w), Some((t1, p1))) = (self.icp_anchor, self.last_icp) else {
            return;
        };
        let t0 = self.icp.first().map_or(t1, |f| f.0);
        while self.pending.front().is_some_and(|(_, s)| s.stamp <= t) {
            let (i, scan) = self.pending.pop_front().expect("checked");
            if scan.stamp < t0 {
                continue;
            }
            let pose = match self.prev_icp {
                Some((ta, pa)) if scan.stamp < t1 && t1 > ta => {
                    crate::geom::interpolate(&pa, &p1, (scan.stamp - ta) / (t1 - ta))
                }
                _ => p1,
            };
            scan.points_into(&mut self.pts);
            let at = Stamp::new(i, self.time(scan.stamp));
            let r = self
                .logger
                .scan(at, &(w * pose), &self.base_from_laser, &self.pts);
            self.keep(r);
        }
    }

    /// Logs the scan-match covariances whose matched pose (at their t1) is
    /// known, as ellipses at that pose in the world.
    fn place_covariances(&mut self) {
        let (Some(w), Some((tl, pl))) = (self.icp_anchor, self.last_icp) else {
            return;
        };
        while self.covariances.front().is_some_and(|c| c.1 <= tl) {
            let (at, t1, cov) = self.covariances.pop_front().expect("checked");
            let pose = match self.prev_icp {
                Some((tp, pp)) if tp == t1 => pp,
                _ => pl,
            };
            let r = self.logger.icp_covariance(at, &(w * pose), cov);
            self.keep(r);
        }
    }

    /// A trajectory's stamps on the `time` timeline.
    fn times(&self, traj: &Trajectory) -> Vec<f64> {
        traj.stamps.iter().map(|&t| self.time(t)).collect()
    }

    /// Logs `texts` (what changed) at their firings' times (s): each at the
    /// first filter step at or after it, the step that fired for the
    /// filter's detector (none after the last step).
    pub fn changes(&mut self, texts: &[(f64, String)]) {
        for (t, text) in texts {
            let i = self.step_stamps.partition_point(|s| s.0 < *t);
            let Some(&(ts, scan)) = self.step_stamps.get(i) else {
                continue;
            };
            let r = self.logger.change(Stamp::new(scan, self.time(ts)), text);
            self.keep(r);
        }
    }

    /// Logs the trajectories and finishes the recording. Returns the notes
    /// on what was left out, or the first logging error of the run.
    pub fn finish(mut self) -> Result<Vec<String>, VizError> {
        if self.icp_anchor.is_none() {
            if let Some((t0, p0)) = self.icp.first() {
                self.icp_anchor = self.anchor_at(t0, &p0, None);
                if let Some((t, _)) = self.last_icp {
                    self.place_scans(t);
                }
            }
        }
        let notes = self.notes();
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let reference = std::mem::replace(&mut self.reference, Polyline::new(2)).finish();
        if reference.len() >= 2 {
            let times = self.times(&reference);
            self.logger
                .trajectory(TrajectoryKind::Reference, &times, &reference.poses)?;
        }
        let lines = [
            (
                TrajectoryKind::RawOdometry,
                std::mem::replace(&mut self.raw, Polyline::new(2)),
            ),
            (
                TrajectoryKind::Calibrated,
                std::mem::replace(&mut self.calibrated, Polyline::new(2)),
            ),
            (
                TrajectoryKind::Icp,
                std::mem::replace(&mut self.icp, Polyline::new(2)),
            ),
        ];
        for (kind, line) in lines {
            let traj = line.finish();
            let (Some(&t0), Some(p0)) = (traj.stamps.first(), traj.poses.first()) else {
                continue;
            };
            let w = self.anchor_at(t0, p0, None).unwrap_or_else(Pose2::identity);
            let times = self.times(&traj);
            self.logger.trajectory(kind, &times, &in_world(&traj, &w))?;
        }
        self.logger.finish()?;
        let mut notes = notes;
        notes.extend(self.logger.notes());
        Ok(notes)
    }
}

impl RunObserver for StreamRecorder<'_> {
    fn start(&mut self, info: &StreamInfo) {
        if let Some(b) = info.base_from_laser {
            self.base_from_laser = b;
        }
        // About one filter step per scan pair.
        // A live stream has no count: one cloud every few scans.
        self.cloud_every = if info.scans == usize::MAX {
            LIVE_CLOUD_EVERY
        } else {
            info.scans.div_ceil(self.opts.max_clouds.max(1)).max(1)
        };
    }

    fn item(&mut self, item: &Item) {
        let t = item.stamp();
        if self.t_start.is_none() {
            self.t_start = Some(t);
        }
        match item {
            Item::Scan(s) => {
                self.pending.push_back((self.scans_read, s.clone()));
                // Scans ICP never places (stamps that do not advance) are let go.
                if self.pending.len() > MAX_PENDING {
                    self.pending.pop_front();
                }
                self.unpassed.push_back(s.stamp);
                self.scans_read += 1;
            }
            Item::Wheel(w) => {
                match self.last_wheel {
                    None => self.raw.push(w.stamp, self.raw_pose),
                    Some(prev) if w.stamp > prev.stamp => {
                        self.raw_pose *= self
                            .nominal
                            .increment(w.right - prev.right, w.left - prev.left);
                        self.raw.push(w.stamp, self.raw_pose);
                    }
                    Some(_) => return,
                }
                self.last_wheel = Some(*w);
            }
            Item::Reference(p) => {
                self.reference.push(p.stamp, p.pose);
                let first = self.early_reference.stamps.first().copied();
                if first.is_none_or(|f| p.stamp - f <= ANCHOR_WINDOW_S) {
                    self.early_reference.push(p.stamp, p.pose);
                }
            }
            Item::Gyro(_) | Item::Odom(_) => {}
        }
        // A reference that never covers the ICP start must not hold the scans back.
        if self.icp_anchor.is_none() {
            if let Some((t0, p0)) = self.icp.first() {
                self.icp_anchor = self.anchor_at(t0, &p0, Some(t));
                if let Some((tl, _)) = self.last_icp {
                    self.place_scans(tl);
                }
            }
        }
    }

    fn icp_pose(&mut self, t: f64, pose: &Pose2) {
        if self.last_icp.is_some_and(|(l, _)| t <= l) {
            return;
        }
        self.prev_icp = self.last_icp;
        self.last_icp = Some((t, *pose));
        self.icp.push(t, *pose);
        if self.icp_anchor.is_none() {
            let (t0, p0) = self.icp.first().expect("pushed above");
            self.icp_anchor = self.anchor_at(t0, &p0, Some(t));
        }
        self.place_scans(t);
        self.place_covariances();
    }

    fn motion(&mut self, m: &Motion) {
        // One motion per consecutive scan pair: pair k−1 → k is logged on scan k's row.
        self.motions += 1;
        let at = Stamp::new(self.motions, self.time(m.t1));
        let r = self.logger.icp(at, m.iterations, m.cov.trace());
        self.keep(r);
        let c = &m.cov;
        let cov = [[c[(0, 0)], c[(0, 1)]], [c[(1, 0)], c[(1, 1)]]];
        let drawable = crate::viz::shapes::ellipse(&Pose2::identity(), cov, 1.0, 1.0, 4).is_some();
        if m.failure.is_none() && drawable && self.covariances.len() < MAX_PENDING {
            self.covariances.push_back((at, m.t1, cov));
        }
        self.place_covariances();
    }

    fn step(&mut self, e: &Estimate, cloud: Option<CloudView<'_>>) {
        while self.unpassed.front().is_some_and(|&s| s <= e.t) {
            self.unpassed.pop_front();
            self.passed += 1;
        }
        let at = Stamp::new(self.passed, self.time(e.t));
        if let Some(c) = cloud.filter(|_| self.steps.is_multiple_of(self.cloud_every)) {
            let r = self.logger.particles(at, c.r_right, c.r_left, c.weights);
            self.keep(r);
        }
        let est = CalibEstimate {
            params: [e.r_right, e.r_left, e.wheel_base],
            std: [e.std_r_right, e.std_r_left, e.std_wheel_base],
            particles: e.particles,
            process_sigma: e.process_sigma,
        };
        let r = self.logger.estimate(at, &est);
        self.keep(r);
        self.step_stamps.push((e.t, self.passed));
        self.steps += 1;
    }

    fn calibrated_pose(&mut self, t: f64, pose: &Pose2) {
        self.calibrated.push(t, *pose);
    }
}
