//! Whole recordings: match every consecutive pair, summarise, and chain the
//! motions into a trajectory. Each is the incremental form fed a whole list:
//! [`match_recording`] drives a [`StreamMatcher`], [`summarise`] and
//! [`integrate`] a [`Tally`].

// `!(x > y)` is deliberate: it is also true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::params::{IcpParams, IcpParamsError};
use super::stream::{Prior, StreamMatcher};
use super::time_offset::TimeOffsetFit;
use crate::geom::{self, Pose2};
use crate::motion::Motion;
use crate::recording::StampedPose;
use crate::scan::LaserScan;
use crate::traj::Trajectory;
use serde::Serialize;
use std::collections::BTreeMap;

/// Summary of a run (the `odocal icp --json` keys).
#[derive(Debug, Clone, Default, Serialize)]
pub struct IcpStats {
    /// Scan pairs matched (scans − 1).
    pub pairs: usize,
    /// Pairs flagged as failed.
    pub failed_pairs: usize,
    /// Mean iterations over the pairs that ran the matcher.
    pub mean_iterations: f64,
    /// Wall-clock time of the matching (s).
    pub wall_s: f64,
    /// Pairs per second of wall-clock time.
    pub pairs_per_s: f64,
    /// Failed pairs by reason (`PairFailure::as_str`).
    pub failures: BTreeMap<String, usize>,
    /// The offset of the prior's clock at which its turns fit the matched
    /// ones best, beside the one in use (absent without a prior or with too
    /// few matched pairs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior_time_offset: Option<TimeOffsetFit>,
    /// The prior's distances and turns over the matched ones (absent
    /// without a prior or with too little motion the scans measured).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior_scale: Option<super::PriorScale>,
}

/// Matches consecutive scans (time order as given). When `odom_prior` covers
/// both stamps of a pair, its increment `inv(odom(t0)) ⊕ odom(t1)` is the
/// initial guess; otherwise the matcher's constant-velocity guess is used.
pub fn match_recording(
    scans: &[LaserScan],
    base_from_laser: Pose2,
    odom_prior: Option<&Trajectory>,
    params: &IcpParams,
) -> Result<(Vec<Motion>, IcpStats), IcpParamsError> {
    let start = std::time::Instant::now();
    let prior = match odom_prior {
        Some(_) => Prior::Odom,
        None => Prior::None,
    };
    let mut matcher = StreamMatcher::new(params, base_from_laser, prior)?;
    for (t, p) in odom_prior
        .iter()
        .flat_map(|o| o.stamps.iter().zip(&o.poses))
    {
        matcher.push_odom(&StampedPose {
            stamp: *t,
            pose: *p,
            has_heading: true,
        });
    }
    matcher.end_prior();
    let mut motions = Vec::with_capacity(scans.len().saturating_sub(1));
    for scan in scans {
        matcher.push_scan(scan.clone());
        matcher.poll(&mut |m| motions.push(m));
    }
    let wall_s = start.elapsed().as_secs_f64();
    let stats = IcpStats {
        prior_time_offset: matcher.time_offset_fit(),
        prior_scale: matcher.prior_scale(),
        ..summarise(&motions, wall_s)
    };
    Ok((motions, stats))
}

/// Counts pairs, failures (by reason) and iterations of a list of motions.
pub fn summarise(motions: &[Motion], wall_s: f64) -> IcpStats {
    let mut tally = Tally::default();
    for m in motions {
        tally.add(m, &mut |_, _| {});
    }
    tally.stats(wall_s)
}

/// Chains motions into `world_from_base` poses starting at the identity at
/// the first motion's `t0` (see [`Tally::add`]).
pub fn integrate(motions: &[Motion]) -> Trajectory {
    let mut traj = Trajectory::with_capacity(motions.len() + 1);
    let mut tally = Tally::default();
    for m in motions {
        tally.add(m, &mut |t, p| {
            traj.push(t, *p);
        });
    }
    traj
}

/// Counts, iterations and the chained trajectory, kept as motions arrive:
/// [`summarise`] and [`integrate`] are this tally fed a whole list.
#[derive(Debug, Default)]
pub struct Tally {
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

impl Tally {
    /// Counts a motion and hands `out` the trajectory poses it adds: the
    /// first motion also the start (identity at its `t0`). Failed pairs are
    /// chained by the motion they carry (the matcher sets it to the prior);
    /// a pair whose `t1` does not increase (bad time) adds no pose.
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

    /// The summary of the motions so far; `wall_s` is the matching time (s).
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
            prior_time_offset: None,
            prior_scale: None,
        }
    }
}
