//! ICP on the Intel Research Lab log (shared real data): bursts of scans a few
//! milliseconds apart must come out flagged, never as confident motions.

use crate::support::shared_data;
use odocal::icp::{match_recording, IcpParams};
use odocal::io::{read_recording, ReadOptions};
use odocal::motion::VelocityObs;

#[test]
fn icp_intel_burst_pairs_are_flagged() {
    let Some(dir) = shared_data("icp_intel_burst_pairs_are_flagged") else {
        return;
    };
    let rec = read_recording(
        &dir.join("slam-benchmark/intel.mcap"),
        &ReadOptions::default(),
    )
    .unwrap();
    let t_start = rec.scans[0].stamp;
    // The burst around t = 2125.6 s after the start, with some context.
    let scans: Vec<_> = rec
        .scans
        .iter()
        .filter(|s| (2120.0..2131.0).contains(&(s.stamp - t_start)))
        .cloned()
        .collect();
    assert!(scans.len() > 20);
    let odom = odocal::traj::Trajectory::from_parts(
        rec.odom.iter().map(|o| o.stamp).collect(),
        rec.odom.iter().map(|o| o.pose).collect(),
    );
    let base_from_laser = rec
        .base_from_laser
        .unwrap_or_else(odocal::geom::Pose2::identity);
    let (motions, stats) = match_recording(
        &scans,
        base_from_laser,
        odom.as_ref(),
        &IcpParams::default(),
    )
    .unwrap();
    let mut burst = 0;
    for m in &motions {
        let dt = m.t1 - m.t0;
        // Scans < 30 ms apart whose match implies an impossible turn or jump.
        if dt < 0.03 && (m.dtheta.abs() > 0.05 || m.dx.hypot(m.dy) > 0.1) {
            burst += 1;
            assert!(
                !m.is_valid(),
                "burst pair at {:.3} s accepted: {m:?}",
                m.t0 - t_start
            );
            assert!(VelocityObs::from_motion(m).is_none());
        }
        if let Some(o) = VelocityObs::from_motion(m) {
            assert!(o.v.abs() < 3.5 && o.w.abs() < 4.5, "{o:?}");
        }
    }
    assert!(burst >= 3, "the burst was not seen ({stats:?})");
    // Most of the stretch still matches.
    assert!(stats.failed_pairs * 2 < stats.pairs, "{stats:?}");
}

/// Every pair of a real log's motions, bit for bit: stamps, motion,
/// covariance, iterations, inliers and failure.
fn same_motions(a: &[odocal::motion::Motion], b: &[odocal::motion::Motion]) -> Result<(), String> {
    if a.len() != b.len() {
        return Err(format!("{} against {} motions", a.len(), b.len()));
    }
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let same = x.t0 == y.t0
            && x.t1 == y.t1
            && x.dx == y.dx
            && x.dy == y.dy
            && x.dtheta == y.dtheta
            && x.cov == y.cov
            && x.iterations == y.iterations
            && x.inliers == y.inliers
            && x.failure == y.failure;
        if !same {
            return Err(format!("pair {k}: {x:?} against {y:?}"));
        }
    }
    Ok(())
}

/// kiddo's k-d tree and the grid answer the same exact nearest-neighbour
/// query, so the whole MIT-CSAIL log (1,987 pairs, 361 beams, the local map
/// of five keyframes) matches to the same motions whichever answers it. The
/// comparison is shown able to fail: one point more in each line fit
/// (`normal_window` 9 instead of 8) changes the motions.
#[test]
fn icp_kd_tree_and_grid_give_the_same_motions_on_a_real_log() {
    use odocal::icp::NeighbourSearch;
    use odocal::pipeline::icp::match_recording as run;
    use odocal::robot::RobotConfig;
    let Some(dir) = shared_data("icp_kd_tree_and_grid_give_the_same_motions_on_a_real_log") else {
        return;
    };
    let rec = read_recording(
        &dir.join("slam-benchmark/mit-csail.mcap"),
        &ReadOptions::default(),
    )
    .unwrap();
    let with = |search: NeighbourSearch, window: usize| {
        let params = IcpParams {
            neighbours: search,
            normal_window: window,
            ..IcpParams::default()
        };
        run(&rec, &RobotConfig::default(), &params).unwrap().motions
    };
    let grid = with(NeighbourSearch::Grid, 8);
    assert!(grid.len() > 1900, "{} pairs", grid.len());
    assert!(grid.iter().filter(|m| m.is_valid()).count() > 1800);
    same_motions(&grid, &with(NeighbourSearch::KdTree, 8)).unwrap();
    // Negative control: a change of the matcher shows.
    assert!(same_motions(&grid, &with(NeighbourSearch::Grid, 9)).is_err());
}
