//! Dead reckoning from wheel angles, and wheel rates from consecutive samples.

use super::DiffDrive;
use crate::geom::Pose2;
use crate::recording::WheelSample;
use crate::traj::Trajectory;

/// Mean wheel rates (rad/s) over the interval between two wheel samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelRate {
    /// Interval start (s).
    pub t0: f64,
    /// Interval end (s).
    pub t1: f64,
    /// Right wheel rate (rad/s).
    pub right: f64,
    /// Left wheel rate (rad/s).
    pub left: f64,
}

/// Wheel rates between consecutive samples. Intervals with dt ≤ 0 (duplicate
/// stamps) are merged into the next one, so no rate is ever inf or NaN.
pub fn wheel_rates(wheels: &[WheelSample]) -> Vec<WheelRate> {
    let mut out = Vec::with_capacity(wheels.len().saturating_sub(1));
    let Some(mut prev) = wheels.first().copied() else {
        return out;
    };
    for s in &wheels[1..] {
        let dt = s.stamp - prev.stamp;
        if !(dt > 0.0) {
            continue;
        }
        out.push(WheelRate {
            t0: prev.stamp,
            t1: s.stamp,
            right: (s.right - prev.right) / dt,
            left: (s.left - prev.left) / dt,
        });
        prev = *s;
    }
    out
}

/// Dead reckoning fed one wheel sample at a time: the pose after each sample
/// whose stamp advances (exact arcs at constant rates between samples).
#[derive(Debug, Clone)]
pub struct WheelIntegrator {
    drive: DiffDrive,
    pose: Pose2,
    prev: Option<WheelSample>,
}

impl WheelIntegrator {
    /// Starts at `start` with the kinematics `drive`.
    pub fn new(drive: DiffDrive, start: Pose2) -> Self {
        Self {
            drive,
            pose: start,
            prev: None,
        }
    }

    /// The pose at `s.stamp` (s) after `s`; `None` when its stamp does not
    /// advance (its motion is then carried by the next sample that does).
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

/// Integrates wheel angles with the given kinematics into a trajectory starting
/// at `start` at the first sample's stamp. Samples with non-increasing stamps
/// are skipped (their motion is carried by the next valid sample).
pub fn wheel_odometry(k: &DiffDrive, wheels: &[WheelSample], start: Pose2) -> Trajectory {
    let mut traj = Trajectory::with_capacity(wheels.len());
    let mut integrator = WheelIntegrator::new(*k, start);
    for s in wheels {
        if let Some((t, p)) = integrator.push(s) {
            traj.push(t, p);
        }
    }
    traj
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom;

    #[test]
    fn constant_rates_trace_a_circle() {
        let k = DiffDrive {
            r_right: 0.32,
            r_left: 0.32,
            wheel_base: 0.65,
        };
        let (v, w) = (0.5, 0.25);
        let (wr, wl) = k.wheel_rates(v, w);
        let period = 2.0 * std::f64::consts::PI / w;
        let n = 1000;
        let wheels: Vec<_> = (0..=n)
            .map(|i| {
                let t = period * i as f64 / n as f64;
                WheelSample {
                    stamp: t,
                    left: wl * t,
                    right: wr * t,
                }
            })
            .collect();
        let traj = wheel_odometry(&k, &wheels, Pose2::identity());
        let end = traj.poses.last().unwrap();
        assert!(end.translation.vector.norm() < 1e-9, "closes the circle");
        let mid = traj.poses[n / 2];
        assert!((mid.translation.y - 2.0 * v / w).abs() < 1e-9);
        assert!((traj.path_length() - v * period).abs() < 1e-3);
        let rates = wheel_rates(&wheels);
        assert!(rates.iter().all(|r| (r.right - wr).abs() < 1e-9));
        assert!((geom::heading(&mid).abs() - std::f64::consts::PI).abs() < 1e-9);
    }

    #[test]
    fn duplicate_stamps_do_not_produce_infinite_rates() {
        let s = |t, a| WheelSample {
            stamp: t,
            left: a,
            right: a,
        };
        let r = wheel_rates(&[
            s(0.0, 0.0),
            s(0.0, 0.0),
            s(1.0, 2.0),
            s(1.0, 2.0),
            s(2.0, 3.0),
        ]);
        assert_eq!(r.len(), 2);
        assert!(r.iter().all(|r| r.left.is_finite()));
        assert_eq!(r[1].left, 1.0);
    }
}
