//! Whole recordings: match every consecutive pair, summarise, and chain the
//! motions into a trajectory.

use super::matcher::ScanMatcher;
use super::params::{IcpParams, IcpParamsError};
use crate::geom::{self, Pose2};
use crate::motion::Motion;
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
    let mut matcher = ScanMatcher::new(params.clone(), base_from_laser)?;
    let mut motions = Vec::with_capacity(scans.len().saturating_sub(1));
    let mut prev: Option<f64> = None;
    for scan in scans {
        let prior = match (odom_prior, prev) {
            (Some(odom), Some(t0)) => odom
                .pose_at(t0)
                .zip(odom.pose_at(scan.stamp))
                .map(|(a, b)| geom::between(&a, &b)),
            _ => None,
        };
        if let Some(m) = matcher.push(scan, prior) {
            motions.push(m);
        }
        if prev.is_none_or(|t| scan.stamp > t) {
            prev = Some(scan.stamp);
        }
    }
    let wall_s = start.elapsed().as_secs_f64();
    Ok((motions.clone(), summarise(&motions, wall_s)))
}

/// Counts pairs, failures (by reason) and iterations of a list of motions.
pub fn summarise(motions: &[Motion], wall_s: f64) -> IcpStats {
    let mut s = IcpStats {
        pairs: motions.len(),
        wall_s,
        ..Default::default()
    };
    let (mut iters, mut ran) = (0u64, 0u64);
    for m in motions {
        if m.iterations > 0 {
            iters += m.iterations as u64;
            ran += 1;
        }
        if let Some(f) = m.failure {
            s.failed_pairs += 1;
            *s.failures.entry(f.as_str().to_string()).or_default() += 1;
        }
    }
    s.mean_iterations = if ran > 0 {
        iters as f64 / ran as f64
    } else {
        0.0
    };
    s.pairs_per_s = if wall_s > 0.0 {
        s.pairs as f64 / wall_s
    } else {
        0.0
    };
    s
}

/// Chains motions into `world_from_base` poses starting at the identity at
/// the first motion's `t0`. Failed pairs are bridged by the motion they carry,
/// which the matcher sets to the prior (odometry increment, else constant
/// velocity, else no motion). Pairs whose `t1` does not increase (bad time) add
/// no pose.
pub fn integrate(motions: &[Motion]) -> Trajectory {
    let mut traj = Trajectory::with_capacity(motions.len() + 1);
    let Some(first) = motions.first() else {
        return traj;
    };
    let mut pose = Pose2::identity();
    traj.push(first.t0, pose);
    for m in motions {
        if !(m.t1 > m.t0) {
            continue;
        }
        let next = pose * geom::pose(m.dx, m.dy, m.dtheta);
        if traj.push(m.t1, next) {
            pose = next;
        }
    }
    traj
}
