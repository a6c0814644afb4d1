//! The odometry a robot runs on while it calibrates online: the wheels
//! dead-reckoned over consecutive windows, each with the estimate in effect
//! at the window's start, against the reference's motion over the same
//! window.
//!
//! The online odometry of a calibration run integrates each step with the
//! estimate *after* that step; a filter whose parameters jitter to fit each
//! step's measured turn rate then scores well with wrong parameters. Here
//! the parameters are frozen at each window's start, as a robot's odometry
//! uses them until the next update it trusts, so that a figure cannot be
//! won by re-fitting each step.

use crate::geom::{self, Pose2};
use crate::robot::DiffDrive;
use serde::Serialize;

/// One stretch of wheel rotation: from `t0` to `t1` (s), the right and left
/// wheel turned by `d_right`, `d_left` (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelIncrement {
    /// Start (s).
    pub t0: f64,
    /// End (s).
    pub t1: f64,
    /// Right wheel rotation (rad).
    pub d_right: f64,
    /// Left wheel rotation (rad).
    pub d_left: f64,
}

/// The windowed odometry error (JSON `windowed`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WindowedError {
    /// Window length (s).
    pub window_s: f64,
    /// Windows scored.
    pub windows: usize,
    /// RMSE (m) of the position at every increment's end, each relative to
    /// its window's start, against the reference's.
    pub rmse_m: f64,
    /// RMSE (m) of the position at each window's end.
    pub end_rmse_m: f64,
}

/// The windowed error of `increments` (sorted by time) under `estimates`
/// (`(t, kinematics in effect from t on)`, sorted by `t`) against
/// `reference` (a pose at a time, `None` where it has none), in windows of
/// `window_s` from the first estimate on: a window starts at the first
/// increment at or after the previous one's end and holds the increments
/// that end within `window_s` of its start; a last window the data do not
/// fill is left out, and so is one whose start the reference cannot place.
/// `None` when no window could be scored.
pub fn windowed_error(
    increments: &[WheelIncrement],
    estimates: &[(f64, DiffDrive)],
    reference: &dyn Fn(f64) -> Option<Pose2>,
    window_s: f64,
) -> Option<WindowedError> {
    let first = estimates.first()?.0;
    if !(window_s > 0.0) {
        return None;
    }
    let (mut sum, mut n, mut end_sum, mut windows) = (0.0, 0usize, 0.0, 0usize);
    let mut i = increments.partition_point(|s| s.t0 < first);
    while i < increments.len() {
        let t_start = increments[i].t0;
        let t_end = t_start + window_s + 1e-9;
        let end = increments[i..].partition_point(|s| s.t1 <= t_end) + i;
        // A window is whole when the data go on past it (or end with it).
        let whole = end < increments.len() || increments[end - 1].t1 >= t_end - 2e-9;
        if end == i || !whole {
            break;
        }
        if let (Some(k), Some(origin)) = (estimate_at(estimates, t_start), reference(t_start)) {
            if let Some((s, m, last)) = window(&increments[i..end], &k, &origin, reference) {
                sum += s;
                n += m;
                end_sum += last;
                windows += 1;
            }
        }
        i = end;
    }
    (windows > 0).then(|| WindowedError {
        window_s,
        windows,
        rmse_m: (sum / n as f64).sqrt(),
        end_rmse_m: (end_sum / windows as f64).sqrt(),
    })
}

/// The estimate in effect at `t`: the last one at or before it.
fn estimate_at(estimates: &[(f64, DiffDrive)], t: f64) -> Option<DiffDrive> {
    let i = estimates.partition_point(|(s, _)| *s <= t);
    (i > 0).then(|| estimates[i - 1].1)
}

/// One window dead-reckoned with `k` from the identity: the sum of squared
/// position errors against the reference relative to `origin`, their
/// count, and the last one; `None` when the reference covers none of it.
fn window(
    incs: &[WheelIncrement],
    k: &DiffDrive,
    origin: &Pose2,
    reference: &dyn Fn(f64) -> Option<Pose2>,
) -> Option<(f64, usize, f64)> {
    let mut pose = Pose2::identity();
    let (mut sum, mut n, mut last) = (0.0, 0usize, None);
    for s in incs {
        pose *= k.increment(s.d_right, s.d_left);
        if let Some(q) = reference(s.t1) {
            let truth = geom::between(origin, &q);
            let e2 = (pose.translation.vector - truth.translation.vector).norm_squared();
            sum += e2;
            n += 1;
            last = Some(e2);
        }
    }
    last.map(|l| (sum, n, l))
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: DiffDrive = DiffDrive {
        r_right: 0.1,
        r_left: 0.1,
        wheel_base: 0.5,
    };

    /// Straight at 1 m/s (10 rad/s on 0.1 m wheels) in 0.1 s increments.
    fn straight(seconds: usize) -> Vec<WheelIncrement> {
        (0..seconds * 10)
            .map(|i| WheelIncrement {
                t0: i as f64 * 0.1,
                t1: (i + 1) as f64 * 0.1,
                d_right: 1.0,
                d_left: 1.0,
            })
            .collect()
    }

    fn truth(t: f64) -> Option<Pose2> {
        Some(geom::pose(t, 0.0, 0.0))
    }

    #[test]
    fn the_true_parameters_score_zero() {
        let e = windowed_error(&straight(30), &[(0.0, K)], &truth, 10.0).unwrap();
        assert_eq!(e.windows, 3);
        assert!(e.rmse_m < 1e-12 && e.end_rmse_m < 1e-12, "{e:?}");
    }

    #[test]
    fn each_window_uses_the_estimate_at_its_start_not_later_ones() {
        // 2 % too large radii until 10 s, exact from 10 s on: the first
        // window drifts 2 % of its 10 m (0.2 m at its end), the others none.
        // An estimate that arrives mid-window does not change that window.
        let big = DiffDrive {
            r_right: 0.102,
            r_left: 0.102,
            ..K
        };
        let est = [(0.0, big), (10.0, K), (25.0, big)];
        let e = windowed_error(&straight(30), &est, &truth, 10.0).unwrap();
        assert_eq!(e.windows, 3);
        // End errors 0.2, 0, 0 m: RMSE 0.2/√3.
        assert!((e.end_rmse_m - 0.2 / 3f64.sqrt()).abs() < 1e-9, "{e:?}");
        // Per increment in the first window 0.002·k m for k = 1…100.
        let s: f64 = (1..=100).map(|k| (0.002 * k as f64).powi(2)).sum();
        assert!((e.rmse_m - (s / 300.0).sqrt()).abs() < 1e-9, "{e:?}");
    }

    #[test]
    fn windows_start_at_the_first_estimate_and_need_a_reference() {
        let est = [(5.0, K)];
        let e = windowed_error(&straight(30), &est, &truth, 10.0).unwrap();
        // 5–15 and 15–25 s; 25–30 s is not a whole window.
        assert_eq!(e.windows, 2);
        assert!(windowed_error(&straight(30), &[], &truth, 10.0).is_none());
        assert!(windowed_error(&straight(30), &est, &|_| None, 10.0).is_none());
        assert!(windowed_error(&straight(30), &est, &truth, 0.0).is_none());
    }
}
