//! Scan matching with a wrong odometry prior: an odometry that freezes while
//! the robot drives on and then catches up in one jump (as the MIT-CSAIL
//! log's does for about a second at a time), on simulated LMS111 scans with
//! known truth.

use crate::icp_sim::{base_from_laser, corridor_drive, lms111_scans};
use odocal::geom::{self, Pose2};
use odocal::icp::{integrate, match_recording, IcpParams};
use odocal::traj::Trajectory;

/// The truth as odometry, except that from `t0` for `len` s the reading
/// stays at the pose it had at `t0`; afterwards it is the truth again (the
/// whole missed motion arrives in the first pair after the freeze).
fn frozen_odometry(truth: &Trajectory, t0: f64, len: f64) -> Trajectory {
    let held = truth.pose_at(t0).unwrap();
    let mut out = Trajectory::default();
    for (&t, p) in truth.stamps.iter().zip(&truth.poses) {
        let p: Pose2 = if t >= t0 && t < t0 + len { held } else { *p };
        out.push(t, p);
    }
    out
}

/// Largest position error (m) of the chained estimate against the truth,
/// both starting at the first stamp, over the stamps in `[a, b]`.
fn max_position_error(est: &Trajectory, truth: &Trajectory, a: f64, b: f64) -> f64 {
    let origin = truth.poses[0];
    est.stamps
        .iter()
        .zip(&est.poses)
        .filter(|(t, _)| **t >= a && **t <= b)
        .map(|(&t, p)| {
            let want = geom::between(&origin, &truth.pose_at(t).unwrap());
            (p.translation.vector - want.translation.vector).norm()
        })
        .fold(0.0, f64::max)
}

#[test]
fn icp_frozen_odometry_is_not_followed() {
    // 10 Hz scans, ~1 m/s: a 1 s freeze misses ~1 m of motion.
    let truth = corridor_drive(16.0, 10.0);
    let scans = lms111_scans(&truth, 11);
    let (f0, flen) = (106.0, 1.0);
    let odom = frozen_odometry(&truth, f0, flen);
    let run = |params: &IcpParams| {
        let (motions, _) = match_recording(&scans, base_from_laser(), Some(&odom), params).unwrap();
        let est = integrate(&motions);
        let window = max_position_error(&est, &truth, f0 - 0.5, f0 + flen + 1.0);
        let end = max_position_error(&est, &truth, 115.0, 116.0);
        (window, end, motions)
    };
    let (window, end, motions) = run(&IcpParams::default());
    // Without the freeze detection (deceleration limits out of reach), for
    // comparison: the frozen prior holds the corridor's loose axis.
    let (w_off, e_off, _) = run(&IcpParams {
        max_accel: 1e6,
        max_angular_accel: 1e6,
        ..Default::default()
    });
    eprintln!(
        "frozen odometry: max position error around the freeze {window:.4} m, at the end {end:.4} m; \
         without the detection {w_off:.4} m, {e_off:.4} m"
    );
    // Every pair across the freeze and the jump is a valid scan match.
    let flagged = motions
        .iter()
        .filter(|m| m.t1 > f0 - 0.1 && m.t0 < f0 + flen + 0.1 && !m.is_valid())
        .count();
    assert_eq!(flagged, 0, "pairs flagged across the freeze");
    assert!(window < 0.03, "error around the freeze {window} m");
    assert!(
        w_off > 10.0 * window,
        "the freeze is no test: {w_off} m without"
    );
    assert!(end < 0.05, "error at the end {end} m");
}
