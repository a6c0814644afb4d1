//! A robot that drives a planned path by its own odometry: the wheel commands
//! come from the robot's (possibly wrong) model, the ground truth from the true
//! kinematics plus wheel slip. This is how a real UMBmark or calibration run
//! goes, so the true path is distorted exactly as on a real robot.

use crate::geom::Pose2;
use crate::recording::WheelSample;
use crate::robot::DiffDrive;
use crate::traj::Trajectory;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// One piece of a planned path, in the robot's own (odometry) frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Segment {
    /// Straight ahead by `length` (m, negative = backwards).
    Straight {
        /// Distance (m).
        length: f64,
    },
    /// Turn in place by `angle` (rad, positive = counter-clockwise).
    Turn {
        /// Heading change (rad).
        angle: f64,
    },
    /// Constant-curvature arc of `length` (m) turning by `angle` (rad).
    Arc {
        /// Arc length (m).
        length: f64,
        /// Heading change (rad).
        angle: f64,
    },
}

impl Segment {
    /// Path length (m) and heading change (rad) of the segment.
    pub fn motion(&self) -> (f64, f64) {
        match *self {
            Segment::Straight { length } => (length, 0.0),
            Segment::Turn { angle } => (0.0, angle),
            Segment::Arc { length, angle } => (length, angle),
        }
    }
}

/// Direction of the square's turns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Turn {
    /// Clockwise: right turns (negative heading changes, REP 103).
    Cw,
    /// Counter-clockwise: left turns.
    Ccw,
}

/// How the robot drives and how the world disturbs it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DriveParams {
    /// Forward speed (m/s).
    pub speed: f64,
    /// Turn rate for in-place turns (rad/s).
    pub turn_rate: f64,
    /// Wheel sample rate (Hz).
    pub rate_hz: f64,
    /// Relative wheel slip: each wheel's ground travel in a step is its
    /// commanded travel times (1 + N(0, slip_sigma²)); the non-systematic error.
    pub slip_sigma: f64,
    /// Encoder resolution (ticks per wheel revolution) the recorded angles are
    /// quantised to; 0 = no quantisation.
    pub ticks_per_rev: f64,
}

impl Default for DriveParams {
    /// 0.4 m/s, 0.5 rad/s, 20 Hz, no slip, no quantisation.
    fn default() -> Self {
        Self {
            speed: 0.4,
            turn_rate: 0.5,
            rate_hz: 20.0,
            slip_sigma: 0.0,
            ticks_per_rev: 0.0,
        }
    }
}

/// A simulated run: what the encoders recorded and where the robot really was.
#[derive(Debug, Clone, PartialEq)]
pub struct SimRun {
    /// Recorded wheel angles (rad), starting at 0 at t = 0.
    pub wheels: Vec<WheelSample>,
    /// True `world_from_base` at the same stamps, starting at the identity.
    pub truth: Trajectory,
    /// Stamp (s) at which each planned segment ended (empty when unknown).
    pub segment_ends: Vec<f64>,
}

/// The UMBmark square of side `side` (m): four legs, each followed by a 90°
/// turn in `dir`, ending where and how it started (by odometry).
pub fn square_segments(side: f64, dir: Turn) -> Vec<Segment> {
    let a = match dir {
        Turn::Cw => -std::f64::consts::FRAC_PI_2,
        Turn::Ccw => std::f64::consts::FRAC_PI_2,
    };
    (0..4)
        .flat_map(|_| {
            [
                Segment::Straight { length: side },
                Segment::Turn { angle: a },
            ]
        })
        .collect()
}

/// A random irregular path of total length `length` (m) made of straights
/// (1–5 m) and arcs (radius ≥ 1.5 m, 20°–100°), as a tricycle AGV can follow.
pub fn irregular_path(length: f64, seed: u64) -> Vec<Segment> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut out = Vec::new();
    let mut left = length;
    while left > 1e-9 {
        let seg = if out.len() % 2 == 0 {
            Segment::Straight {
                length: rng.random_range(1.0..5.0f64).min(left),
            }
        } else {
            let angle = rng.random_range(20f64.to_radians()..100f64.to_radians())
                * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            let radius = rng.random_range(1.5..4.0);
            let l = (angle.abs() * radius).min(left);
            Segment::Arc {
                length: l,
                angle: angle * l / (angle.abs() * radius),
            }
        };
        left -= seg.motion().0;
        out.push(seg);
    }
    out
}

/// Drives `segments` as planned by the robot's `model` (it stops each segment
/// when its odometry says the segment is done) while the world moves it by the
/// `truth` kinematics with slip. Deterministic for a given `seed`.
pub fn drive_segments(
    model: &DiffDrive,
    truth: &DiffDrive,
    segments: &[Segment],
    p: &DriveParams,
    seed: u64,
) -> SimRun {
    let mut rng = StdRng::seed_from_u64(seed);
    let dt = 1.0 / p.rate_hz;
    let quant = |a: f64| {
        if p.ticks_per_rev > 0.0 {
            let tick = 2.0 * std::f64::consts::PI / p.ticks_per_rev;
            (a / tick).round() * tick
        } else {
            a
        }
    };
    let (mut t, mut phi_r, mut phi_l) = (0.0, 0.0, 0.0);
    let mut pose = Pose2::identity();
    let mut wheels = vec![WheelSample {
        stamp: 0.0,
        left: 0.0,
        right: 0.0,
    }];
    let mut traj = Trajectory::with_capacity(1024);
    let mut segment_ends = Vec::with_capacity(segments.len());
    traj.push(0.0, pose);
    for seg in segments {
        let (ds, dth) = seg.motion();
        // Wheel angles the model needs for this body motion (inverse kinematics).
        let (wr, wl) = model.wheel_rates(ds, dth);
        let duration = (ds.abs() / p.speed).max(dth.abs() / p.turn_rate);
        let n = ((duration * p.rate_hz).ceil() as usize).max(1);
        let (sr, sl) = (wr / n as f64, wl / n as f64);
        for _ in 0..n {
            let (er, el) = if p.slip_sigma > 0.0 {
                let a: f64 = rng.sample(StandardNormal);
                let b: f64 = rng.sample(StandardNormal);
                (1.0 + p.slip_sigma * a, 1.0 + p.slip_sigma * b)
            } else {
                (1.0, 1.0)
            };
            pose *= truth.increment(sr * er, sl * el);
            phi_r += sr;
            phi_l += sl;
            t += dt;
            wheels.push(WheelSample {
                stamp: t,
                left: quant(phi_l),
                right: quant(phi_r),
            });
            traj.push(t, pose);
        }
        segment_ends.push(t);
    }
    SimRun {
        wheels,
        truth: traj,
        segment_ends,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::wheel_odometry;

    #[test]
    fn perfect_robot_closes_the_square_and_odometry_agrees() {
        let k = DiffDrive {
            r_right: 0.32,
            r_left: 0.32,
            wheel_base: 0.65,
        };
        for dir in [Turn::Cw, Turn::Ccw] {
            let run = drive_segments(
                &k,
                &k,
                &square_segments(4.0, dir),
                &DriveParams::default(),
                1,
            );
            let end = run.truth.poses.last().unwrap();
            assert!(end.translation.vector.norm() < 1e-9);
            let odo = wheel_odometry(&k, &run.wheels, Pose2::identity());
            assert!((odo.path_length() - 16.0).abs() < 1e-6);
        }
    }

    #[test]
    fn irregular_path_has_the_requested_length() {
        let segs = irregular_path(47.0, 3);
        let l: f64 = segs.iter().map(|s| s.motion().0).sum();
        assert!((l - 47.0).abs() < 1e-9);
        assert_ne!(segs, irregular_path(47.0, 4));
    }
}
