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
        // True wheel angles (rad), for faults that depend on them.
        let (mut ar, mut al) = (0.0, 0.0);
        right.push(r);
        left.push(l);
        for k in 0..drive.steps() {
            let t = (k as f64 + 0.5) * dt;
            let rates = robot.wheel_rates(t, drive.v[k], drive.w[k]);
            let (wr, wl) = robot.faulty_rates(rates, (ar, al), drive.pose_at(t)[0]);
            ar += wr * dt;
            al += wl * dt;
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
/// encoder clock, which runs the `latency` of `robot` behind the laser's.
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
            let (r, l) = robot.wire(track.at(robot.encoder_taken(t)));
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
                wz: robot.departures().gyro_rate(rate) + noise.sample(&mut rng),
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

/// The simulated LMS111 of one run: owns what it needs to cast any scan on
/// demand, so a long recording can be written scan by scan instead of held
/// in memory. Scan `k` depends only on `k` (its own generator), never on
/// which scans were made before it.
#[derive(Clone)]
pub struct LaserSim {
    cfg: LaserConfig,
    world: World,
    drive: Drive,
    robot: TrueRobot,
    seed: u64,
    stamps: Vec<f64>,
}

impl LaserSim {
    /// The laser of a run of `duration` s: one scan per period whose sweep ends within the run.
    pub fn new(
        cfg: &LaserConfig,
        world: World,
        drive: Drive,
        robot: TrueRobot,
        seed: u64,
        duration: f64,
    ) -> Self {
        let sweep = Self::sweep(cfg);
        let stamps = sample_times(cfg.rate_hz, duration, sweep).collect();
        Self {
            cfg: cfg.clone(),
            world,
            drive,
            robot,
            seed,
            stamps,
        }
    }

    /// Time from the first to the last beam of a sweep (s).
    fn sweep(cfg: &LaserConfig) -> f64 {
        let period = 1.0 / cfg.rate_hz;
        let time_inc = period * cfg.resolution_deg / 360.0;
        time_inc * (cfg.beams() - 1) as f64
    }

    /// Stamps of every scan (s), increasing.
    pub fn stamps(&self) -> &[f64] {
        &self.stamps
    }

    /// Number of scans in the run.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// Whether the run is too short for a single scan.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// True laser pose `[x, y, θ unwrapped]` at `t` (s).
    fn laser_pose(&self, t: f64) -> [f64; 3] {
        let [x, y, th] = self.drive.pose_at(t);
        let p = geom::pose(x, y, th) * self.robot.laser.pose();
        // Heading continuous with the body's unwrapped heading.
        [p.translation.x, p.translation.y, th + self.robot.laser.yaw]
    }

    /// Scan `k`: every beam cast from the true laser pose at its own time in
    /// the sweep, with Gaussian range noise; no echo is +inf and too close is
    /// −inf (REP 117).
    pub fn scan(&self, k: usize) -> LaserScan {
        let cfg = &self.cfg;
        let stamp = self.stamps[k];
        let beams = cfg.beams();
        let inc = cfg.resolution_deg.to_radians();
        let angle_min = -((beams - 1) as f64) * inc / 2.0;
        let period = 1.0 / cfg.rate_hz;
        let time_inc = period * cfg.resolution_deg / 360.0;
        let noise = Normal::new(0.0, cfg.noise_sigma).expect("validated sigma");
        let mut rng = stream_rng(self.seed, STREAM_LASER, k as u64);
        let a = self.laser_pose(stamp);
        let b = if cfg.sweep_motion {
            self.laser_pose(stamp + Self::sweep(cfg))
        } else {
            a
        };
        let ranges = (0..beams)
            .map(|i| {
                let f = i as f64 / (beams - 1) as f64;
                let o = Point2::new(a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f);
                let th = a[2] + (b[2] - a[2]) * f + angle_min + i as f64 * inc;
                let e = noise.sample(&mut rng);
                match self.world.cast_ray(o, th, cfg.range_max) {
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
    }

    /// Scans `range`, cast in parallel (the result does not depend on the thread count).
    pub fn scans(&self, range: std::ops::Range<usize>) -> Vec<LaserScan> {
        range.into_par_iter().map(|k| self.scan(k)).collect()
    }

    /// Every scan of the run, in blocks of [`Self::BLOCK`]; `progress` gets the fraction done.
    pub fn all(&self, progress: &mut dyn FnMut(f64)) -> Vec<LaserScan> {
        let n = self.len();
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let start = out.len();
            out.extend(self.scans(start..(start + Self::BLOCK).min(n)));
            progress(out.len() as f64 / n as f64);
        }
        out
    }

    /// Scans cast together: enough to keep every core busy, few enough to stay small (541 beams each).
    pub const BLOCK: usize = 250;
}
