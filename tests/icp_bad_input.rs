//! Bad input never panics and never yields NaN: empty and all-invalid scans,
//! changing beam counts, zero or negative dt → flagged pairs with a reason.

use odocal::geom::{pose, Pose2};
use odocal::icp::{integrate, match_recording, IcpParams, ScanMatcher};
use odocal::motion::{Motion, PairFailure, VelocityObs};
use odocal::scan::LaserScan;

/// A scan of a 10 m × 6 m room with a pillar, seen from `p` (laser = base).
fn room_scan(stamp: f64, p: Pose2, beams: usize) -> LaserScan {
    let segs = [
        [-4.0, -3.0, 6.0, -3.0],
        [6.0, -3.0, 6.0, 3.0],
        [6.0, 3.0, -4.0, 3.0],
        [-4.0, 3.0, -4.0, -3.0],
        [1.0, 1.0, 1.5, 1.0],
        [1.5, 1.0, 1.5, 1.5],
        [1.5, 1.5, 1.0, 1.5],
        [1.0, 1.5, 1.0, 1.0],
    ];
    let inc = 1.5 * std::f64::consts::PI / (beams - 1) as f64;
    let amin = -0.75 * std::f64::consts::PI;
    let ranges = (0..beams)
        .map(|i| {
            let a = p.rotation.angle() + amin + i as f64 * inc;
            let (d, o) = ([a.cos(), a.sin()], [p.translation.x, p.translation.y]);
            let mut best = f64::INFINITY;
            for s in &segs {
                let e = [s[2] - s[0], s[3] - s[1]];
                let den = d[0] * e[1] - d[1] * e[0];
                if den.abs() < 1e-12 {
                    continue;
                }
                let w = [s[0] - o[0], s[1] - o[1]];
                let t = (w[0] * e[1] - w[1] * e[0]) / den;
                let u = (w[0] * d[1] - w[1] * d[0]) / den;
                if t > 0.0 && (0.0..=1.0).contains(&u) {
                    best = best.min(t);
                }
            }
            best as f32
        })
        .collect();
    LaserScan {
        stamp,
        angle_min: amin,
        angle_increment: inc,
        range_min: 0.1,
        range_max: 20.0,
        ranges,
        ..Default::default()
    }
}

fn no_nan(m: &Motion) {
    assert!(
        [m.t0, m.t1, m.dx, m.dy, m.dtheta]
            .iter()
            .all(|v| v.is_finite()),
        "{m:?}"
    );
    assert!(m.cov.iter().all(|v| v.is_finite()), "{m:?}");
}

#[test]
fn icp_recovers_a_known_motion_on_clean_geometry() {
    let mut m = ScanMatcher::new(IcpParams::default(), Pose2::identity()).unwrap();
    assert!(m
        .push(&room_scan(0.0, pose(0.0, 0.0, 0.0), 541), None)
        .is_none());
    let truth = pose(0.05, -0.02, 0.03);
    let r = m
        .push(&room_scan(0.1, truth, 541), Some(pose(0.0, 0.0, 0.0)))
        .unwrap();
    assert!(r.is_valid(), "{r:?}");
    let recovered = |dx: f64, dy: f64, dtheta: f64| {
        (dx - 0.05).abs() < 1e-3 && (dy + 0.02).abs() < 1e-3 && (dtheta - 0.03).abs() < 1e-4
    };
    assert!(recovered(r.dx, r.dy, r.dtheta), "{r:?}");
    // The negative control: the initial guess it started from fails.
    assert!(!recovered(0.0, 0.0, 0.0));
    assert!(VelocityObs::from_motion(&r).is_some());
}

#[test]
fn icp_flags_empty_invalid_resized_and_mistimed_scans() {
    let good = |t: f64, x: f64| room_scan(t, pose(x, 0.0, 0.0), 541);
    let mut empty = good(0.2, 0.02);
    empty.ranges.clear();
    let mut invalid = good(0.3, 0.03);
    for (i, r) in invalid.ranges.iter_mut().enumerate() {
        *r = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, 50.0][i % 5];
    }
    let resized = room_scan(0.5, pose(0.05, 0.0, 0.0), 361);
    let mut nan_angles = good(0.7, 0.07);
    nan_angles.angle_increment = f64::NAN;
    let scans = vec![
        good(0.0, 0.0),
        good(0.1, 0.01),
        empty,
        invalid,
        good(0.4, 0.04),
        resized,
        good(0.6, 0.06),
        good(0.6, 0.06),   // dt = 0
        good(0.55, 0.055), // dt < 0
        nan_angles,
        good(0.8, 0.08),
        good(0.9, 0.09),
    ];
    let (motions, stats) =
        match_recording(&scans, Pose2::identity(), None, &IcpParams::default()).unwrap();
    assert_eq!(motions.len(), scans.len() - 1);
    for m in &motions {
        no_nan(m);
    }
    let f: Vec<Option<PairFailure>> = motions.iter().map(|m| m.failure).collect();
    use PairFailure::*;
    assert_eq!(
        f,
        vec![
            None,               // 0.0 → 0.1
            Some(TooFewPoints), // empty
            Some(TooFewPoints), // all invalid
            None,               // matched against the last usable scan (0.1)
            Some(Inconsistent), // 361 beams after 541
            Some(Inconsistent), // back to 541
            Some(BadTime),      // dt = 0
            Some(BadTime),      // dt < 0
            Some(TooFewPoints), // NaN beam geometry
            None,               // again against the last usable scan
            None,
        ]
    );
    assert_eq!(stats.failed_pairs, 7);
    for m in motions.iter().filter(|m| !m.is_valid()) {
        assert!(VelocityObs::from_motion(m).is_none());
    }
    // The bridged trajectory is finite and ends near the true position.
    let traj = integrate(&motions);
    let end = traj.poses.last().unwrap();
    assert!(traj
        .poses
        .iter()
        .all(|p| p.translation.vector.iter().all(|v| v.is_finite())));
    assert!((end.translation.x - 0.09).abs() < 0.1, "{end:?}");
}

#[test]
fn icp_invalid_params_are_refused() {
    let p = IcpParams {
        max_iterations: 0,
        ..Default::default()
    };
    assert!(ScanMatcher::new(p.clone(), Pose2::identity()).is_err());
    assert!(match_recording(&[], Pose2::identity(), None, &p).is_err());
    let (m, s) = match_recording(&[], Pose2::identity(), None, &IcpParams::default()).unwrap();
    assert!(m.is_empty() && s.pairs == 0 && s.mean_iterations == 0.0);
    assert!(integrate(&m).is_empty());
}
