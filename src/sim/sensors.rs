//! The sensors that observe the true motion: the LMS111 laser (ray-cast from
//! the true laser pose, beam by beam through the sweep), quantised wheel
//! encoders, the yaw-rate gyro and a LOAM-like reference. Each stream draws
//! its noise from its own seeded generator, so adding a sensor changes no other.

use super::config::{EncoderConfig, GyroConfig, LaserConfig, ReferenceConfig};
use super::drive::Drive;
use super::effects::TrueRobot;
use super::world::World;
use super::{stream_rng, STREAM_ENCODER, STREAM_GYRO, STREAM_LASER, STREAM_REFERENCE};
use crate::geom;
use crate::recording::{GyroSample, StampedPose, WheelSample};
use crate::scan::LaserScan;
use nalgebra::Point2;
use rand::RngExt;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

/// Sample times `k / rate` (s) for k ≥ 0 while `t + tail ≤ duration`.
pub(crate) fn sample_times(rate: f64, duration: f64, tail: f64) -> impl Iterator<Item = f64> {
    let n = ((duration - tail) * rate + 1e-9).floor().max(-1.0) as i64;
    (0..=n).map(move |k| k as f64 / rate)
}

/// Measured wheel angles (rad, right and left) at every integration step
/// boundary: the true wheel rates that realise the commands, as the encoders
/// read them (encoder gain included).
#[derive(Debug, Clone)]
pub struct WheelTrack {
    /// Step length (s).
    pub dt: f64,
    /// Right wheel angle (rad) at `k dt`.
    pub right: Vec<f64>,
    /// Left wheel angle (rad) at `k dt`.
    pub left: Vec<f64>,
}

impl WheelTrack {
    /// Integrates the true wheel rates of `robot` executing `drive`.
    pub fn new(drive: &Drive, robot: &TrueRobot) -> Self {
        let dt = drive.dt;
        let mut right = Vec::with_capacity(drive.steps() + 1);
        let mut left = Vec::with_capacity(drive.steps() + 1);
        let (mut r, mut l) = (0.0, 0.0);
        right.push(r);
        left.push(l);
        for k in 0..drive.steps() {
            let t = (k as f64 + 0.5) * dt;
            let (wr, wl) = robot.wheel_rates(t, drive.v[k], drive.w[k]);
            r += robot.measured_rate(wr) * dt;
            l += robot.measured_rate(wl) * dt;
            right.push(r);
            left.push(l);
        }
        Self { dt, right, left }
    }

    /// Angles (right, left) at time `t` (s), exact between steps (constant
    /// rates within a step); 0 before the start, the last value after the end.
    pub fn at(&self, t: f64) -> (f64, f64) {
        let n = self.right.len() - 1;
        let f = (t / self.dt).clamp(0.0, n as f64);
        let k = (f.floor() as usize).min(n.saturating_sub(1));
        let a = f - k as f64;
        (
            self.right[k] + (self.right[k + 1] - self.right[k]) * a,
            self.left[k] + (self.left[k + 1] - self.left[k]) * a,
        )
    }
}

/// JointState-like wheel samples: whole encoder ticks (as rad), stamped on the
/// encoder clock, which runs `robot.latency` s behind the laser's.
pub fn encoder_samples(
    cfg: &EncoderConfig,
    ticks_per_rev: f64,
    track: &WheelTrack,
    robot: &TrueRobot,
    seed: u64,
    duration: f64,
) -> Vec<WheelSample> {
    let q = 2.0 * std::f64::consts::PI / ticks_per_rev;
    // Unknown phase of each code wheel at power-up.
    let mut rng = stream_rng(seed, STREAM_ENCODER, 0);
    let (p_r, p_l): (f64, f64) = (rng.random_range(0.0..q), rng.random_range(0.0..q));
    let count = |phi: f64, phase: f64| ((phi + phase) / q).floor() - (phase / q).floor();
    sample_times(cfg.rate_hz, duration, 0.0)
        .map(|t| {
            let (r, l) = track.at(t - robot.latency);
            WheelSample {
                stamp: t,
                right: count(r, p_r) * q,
                left: count(l, p_l) * q,
            }
        })
        .collect()
}

/// Gyro yaw rates: the mean true rate over the preceding sample interval plus
/// bias and white noise (rad/s).
pub fn gyro_samples(
    cfg: &GyroConfig,
    drive: &Drive,
    robot: &TrueRobot,
    seed: u64,
    duration: f64,
) -> Vec<GyroSample> {
    let mut rng = stream_rng(seed, STREAM_GYRO, 0);
    let noise = Normal::new(0.0, cfg.noise_sigma).expect("validated sigma");
    let h = 1.0 / cfg.rate_hz;
    sample_times(cfg.rate_hz, duration, 0.0)
        .map(|t| {
            let rate = (drive.pose_at(t)[2] - drive.pose_at(t - h)[2]) / h;
            GyroSample {
                stamp: t,
                wz: rate + robot.gyro_bias + noise.sample(&mut rng),
            }
        })
        .collect()
}

/// Reference poses `world_from_base` with small white noise, like a LOAM
/// trajectory (heading included).
pub fn reference_poses(
    cfg: &ReferenceConfig,
    drive: &Drive,
    seed: u64,
    duration: f64,
) -> Vec<StampedPose> {
    let mut rng = stream_rng(seed, STREAM_REFERENCE, 0);
    let np = Normal::new(0.0, cfg.position_sigma).expect("validated sigma");
    let nh = Normal::new(0.0, cfg.heading_sigma).expect("validated sigma");
    sample_times(cfg.rate_hz, duration, 0.0)
        .map(|t| {
            let [x, y, th] = drive.pose_at(t);
            let (ex, ey, eh) = (
                np.sample(&mut rng),
                np.sample(&mut rng),
                nh.sample(&mut rng),
            );
            StampedPose {
                stamp: t,
                pose: geom::pose(x + ex, y + ey, geom::wrap_angle(th + eh)),
                has_heading: true,
            }
        })
        .collect()
}

/// Laser scans at `cfg.rate_hz`, each beam cast from the true laser pose at
/// its own time in the sweep (LMS111: one turn per scan period), with
/// Gaussian range noise; no echo is +inf and too close is −inf (REP 117).
/// Scans run in parallel with one generator per scan, so the result does not
/// depend on the thread count. `progress` gets the fraction done.
pub fn laser_scans(
    cfg: &LaserConfig,
    world: &World,
    drive: &Drive,
    robot: &TrueRobot,
    seed: u64,
    duration: f64,
    progress: &mut dyn FnMut(f64),
) -> Vec<LaserScan> {
    let beams = cfg.beams();
    let inc = cfg.resolution_deg.to_radians();
    let angle_min = -((beams - 1) as f64) * inc / 2.0;
    let period = 1.0 / cfg.rate_hz;
    let time_inc = period * cfg.resolution_deg / 360.0;
    let sweep = time_inc * (beams - 1) as f64;
    let mount = robot.laser.pose();
    let noise = Normal::new(0.0, cfg.noise_sigma).expect("validated sigma");
    let laser_pose = |t: f64| {
        let [x, y, th] = drive.pose_at(t);
        let p = geom::pose(x, y, th) * mount;
        // Heading continuous with the body's unwrapped heading.
        [p.translation.x, p.translation.y, th + robot.laser.yaw]
    };
    let one = |k: usize, stamp: f64| {
        let mut rng = stream_rng(seed, STREAM_LASER, k as u64);
        let a = laser_pose(stamp);
        let b = if cfg.sweep_motion {
            laser_pose(stamp + sweep)
        } else {
            a
        };
        let ranges = (0..beams)
            .map(|i| {
                let f = i as f64 / (beams - 1) as f64;
                let o = Point2::new(a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f);
                let th = a[2] + (b[2] - a[2]) * f + angle_min + i as f64 * inc;
                let e = noise.sample(&mut rng);
                match world.cast_ray(o, th, cfg.range_max) {
                    None => f32::INFINITY,
                    Some(r) if r < cfg.range_min => f32::NEG_INFINITY,
                    Some(r) if r + e > cfg.range_max => f32::INFINITY,
                    Some(r) => (r + e) as f32,
                }
            })
            .collect();
        LaserScan {
            stamp,
            angle_min,
            angle_increment: inc,
            time_increment: time_inc,
            scan_time: period,
            range_min: cfg.range_min,
            range_max: cfg.range_max,
            ranges,
        }
    };
    let stamps: Vec<f64> = sample_times(cfg.rate_hz, duration, sweep).collect();
    let mut out = Vec::with_capacity(stamps.len());
    for chunk in (0..stamps.len()).collect::<Vec<_>>().chunks(250) {
        let part: Vec<LaserScan> = chunk.par_iter().map(|&k| one(k, stamps[k])).collect();
        out.extend(part);
        progress(out.len() as f64 / stamps.len() as f64);
    }
    out
}
