//! The calibrated odometry of an online run at the wheels' own rate: each
//! wheel sample integrated with the estimate the filter holds when the
//! sample's time is reached ([`crate::robot::DiffDrive::increment`]), and
//! stamped on the laser's clock (wheel stamp minus the time offset in use).
//! The filter steps over intervals of a second; the robot's odometry does
//! not wait for them.

use std::collections::VecDeque;

use crate::geom::Pose2;
use crate::recording::WheelSample;
use crate::robot::DiffDrive;

/// Wheel samples waiting to be integrated, and the pose so far.
#[derive(Debug, Default)]
pub struct WheelOdometry {
    pending: VecDeque<WheelSample>,
    last: Option<WheelSample>,
    pose: Pose2,
    /// Laser-clock stamp of the last pose given out (s).
    t: Option<f64>,
}

impl WheelOdometry {
    /// A wheel sample (stamp order).
    pub fn push(&mut self, w: WheelSample) {
        self.pending.push_back(w);
    }

    /// Integrates the samples whose laser-clock time (`stamp − offset`) is at
    /// most `until` (s) with `drive`, handing each new pose to `out` (the
    /// first sample gives the identity).
    pub fn advance(
        &mut self,
        until: f64,
        offset: f64,
        drive: &DiffDrive,
        out: &mut dyn FnMut(f64, &Pose2),
    ) {
        while let Some(w) = self.pending.front().copied() {
            if !(w.stamp - offset <= until) {
                break;
            }
            self.pending.pop_front();
            if let Some(prev) = self.last {
                let inc = drive.increment(w.right - prev.right, w.left - prev.left);
                self.pose *= inc;
            }
            self.last = Some(w);
            // Kept increasing when the offset in use moves back.
            let t = self
                .t
                .map_or(w.stamp - offset, |p| (w.stamp - offset).max(p));
            self.t = Some(t);
            out(t, &self.pose);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_each_sample_with_the_estimate_then_on_the_laser_clock() {
        let d = DiffDrive {
            r_right: 0.1,
            r_left: 0.1,
            wheel_base: 0.5,
        };
        let mut o = WheelOdometry::default();
        for i in 0..5 {
            o.push(WheelSample {
                stamp: 10.0 + 0.1 * i as f64,
                left: i as f64,
                right: i as f64,
            });
        }
        let mut got = Vec::new();
        o.advance(9.85, -0.2, &d, &mut |t, p| got.push((t, p.translation.x)));
        // Laser times 10.2, 10.3, …: none by 9.85; then the first two.
        assert!(got.is_empty());
        o.advance(10.35, -0.2, &d, &mut |t, p| got.push((t, p.translation.x)));
        assert_eq!(got.len(), 2);
        assert!((got[0].0 - 10.2).abs() < 1e-12 && got[0].1 == 0.0);
        // One radian of both wheels: 0.1 m straight.
        assert!((got[1].1 - 0.1).abs() < 1e-12);
        // A larger radius for the rest.
        let d2 = DiffDrive {
            r_right: 0.2,
            r_left: 0.2,
            ..d
        };
        o.advance(f64::INFINITY, -0.2, &d2, &mut |t, p| {
            got.push((t, p.translation.x))
        });
        assert_eq!(got.len(), 5);
        assert!((got[4].1 - 0.7).abs() < 1e-12, "{got:?}");
    }
}
