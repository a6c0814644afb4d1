//! Virtual wheel angles from a robot's own integrated odometry (classic
//! CARMEN logs carry `ODOM x y θ`, not encoder ticks): the wheel angles that a
//! differential drive with the nominal radii and wheel base would have turned
//! to produce exactly that odometry. Replaying them with the nominal model
//! reproduces the logged odometry, so every effect the diagnosis then finds
//! is an error of the robot's odometry against scan matching.

use crate::geom;
use crate::recording::{StampedPose, WheelSample};
use crate::robot::RobotConfig;

/// Cumulative wheel angles (rad) at the odometry stamps: each increment
/// between consecutive poses is taken as one arc (length s, turn Δθ), so
/// Δφ_R = (s + D Δθ / 2) / R_R and Δφ_L = (s − D Δθ / 2) / R_L with the
/// robot's nominal R_R, R_L, D (m). Poses with non-finite values or a stamp
/// not after the previous kept one are skipped.
pub fn wheels_from_odometry(odom: &[StampedPose], robot: &RobotConfig) -> Vec<WheelSample> {
    let mut out: Vec<WheelSample> = Vec::with_capacity(odom.len());
    let mut prev: Option<&StampedPose> = None;
    let half = 0.5 * robot.wheel_base;
    for p in odom {
        let [x, y, th] = geom::xyt(&p.pose);
        if !(p.stamp.is_finite() && x.is_finite() && y.is_finite() && th.is_finite()) {
            continue;
        }
        let Some(q) = prev else {
            out.push(WheelSample {
                stamp: p.stamp,
                left: 0.0,
                right: 0.0,
            });
            prev = Some(p);
            continue;
        };
        if p.stamp <= q.stamp {
            continue;
        }
        let (s, dth) = geom::arc_of_increment(&geom::between(&q.pose, &p.pose));
        let last = *out.last().expect("first sample pushed above");
        out.push(WheelSample {
            stamp: p.stamp,
            right: last.right + (s + half * dth) / robot.r_right,
            left: last.left + (s - half * dth) / robot.r_left,
        });
        prev = Some(p);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::wheel_odometry;

    #[test]
    fn nominal_odometry_of_virtual_wheels_is_the_logged_odometry() {
        let robot = RobotConfig::default();
        let mut pose = geom::pose(1.0, -2.0, 0.3);
        let mut odom = Vec::new();
        for k in 0..200 {
            let t = k as f64 * 0.1;
            odom.push(StampedPose {
                stamp: t,
                pose,
                has_heading: true,
            });
            let (v, w) = (0.5 + 0.3 * (0.1 * t).sin(), 0.4 * (0.07 * t).cos());
            pose *= geom::arc_increment(v, w, 0.1);
        }
        // A repeated stamp is skipped, not turned into an infinite rate.
        odom.insert(
            50,
            StampedPose {
                stamp: odom[49].stamp,
                ..odom[49]
            },
        );
        let wheels = wheels_from_odometry(&odom, &robot);
        assert_eq!(wheels.len(), 200);
        let traj = wheel_odometry(&robot.diff_drive(), &wheels, odom[0].pose);
        let last = traj.poses.last().unwrap();
        let want = odom.last().unwrap().pose;
        let e = geom::between(&want, last);
        assert!(e.translation.vector.norm() < 1e-9, "{e:?}");
        assert!(geom::heading(&e).abs() < 1e-9);
    }
}
