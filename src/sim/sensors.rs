//! The sensors that observe the true motion: the LMS111 laser (ray-cast from
//! the true laser pose, beam by beam through the sweep), quantised wheel
//! encoders, the yaw-rate gyro and a LOAM-like reference. Each stream draws
//! its noise from its own seeded generator, so adding a sensor changes no other.

use super::config::{EncoderConfig, GyroConfig, LaserConfig, ReferenceConfig};
use super::drive::{step_at, Drive};
use super::effects::TrueRobot;
use super::tape::{wheel_step, Tape};
use super::world::World;
use super::{stream_rng, STREAM_ENCODER, STREAM_GYRO, STREAM_LASER, STREAM_REFERENCE};
use crate::geom;
use crate::recording::{GyroSample, StampedPose, WheelSample};
use crate::scan::LaserScan;
use nalgebra::Point2;
use rand::rngs::StdRng;
use rand::RngExt;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

/// The sample times of a sensor: `k / rate` (s) for k ≥ 0 while
/// `t + tail ≤ duration`, each computed from its index (none stored).
#[derive(Debug, Clone, Copy)]
pub struct Clock {
    rate: f64,
    len: usize,
}

impl Clock {
    /// The samples at `rate` Hz of a run of `duration` s whose last sample
    /// lasts `tail` s.
    pub fn new(rate: f64, duration: f64, tail: f64) -> Self {
        let n = ((duration - tail) * rate + 1e-9).floor().max(-1.0) as i64;
        Self {
            rate,
            len: (n + 1) as usize,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there is no sample.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Time of sample `k` (s).
    pub fn stamp(&self, k: usize) -> f64 {
        k as f64 / self.rate
    }

    /// Every sample time, in order.
    pub fn times(self) -> impl Iterator<Item = f64> {
        (0..self.len).map(move |k| self.stamp(k))
    }
}

/// Sample times `k / rate` (s) for k ≥ 0 while `t + tail ≤ duration`.
pub(crate) fn sample_times(rate: f64, duration: f64, tail: f64) -> impl Iterator<Item = f64> {
    Clock::new(rate, duration, tail).times()
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
        let mut truth = (0.0, 0.0);
        right.push(r);
        left.push(l);
        for k in 0..drive.steps() {
            let x = drive.pose_at((k as f64 + 0.5) * dt)[0];
            let (dr, dl) = wheel_step(robot, k, dt, (drive.v[k], drive.w[k]), &mut truth, x);
            r += dr;
            l += dl;
            right.push(r);
            left.push(l);
        }
        Self { dt, right, left }
    }

    /// Angles (right, left) at time `t` (s), exact between steps (constant
    /// rates within a step); 0 before the start, the last value after the end.
    pub fn at(&self, t: f64) -> (f64, f64) {
        let (k, a) = step_at(t, self.dt, self.right.len() - 1);
        (
            self.right[k] + (self.right[k + 1] - self.right[k]) * a,
            self.left[k] + (self.left[k + 1] - self.left[k]) * a,
        )
    }
}

/// The wheel encoders: tick size (rad) and each code wheel's unknown phase at power-up.
#[derive(Debug, Clone, Copy)]
struct Encoder {
    q: f64,
    phase: (f64, f64),
}

impl Encoder {
    fn new(ticks_per_rev: f64, seed: u64) -> Self {
        let q = 2.0 * std::f64::consts::PI / ticks_per_rev;
        let mut rng = stream_rng(seed, STREAM_ENCODER, 0);
        let (p_r, p_l): (f64, f64) = (rng.random_range(0.0..q), rng.random_range(0.0..q));
        Self {
            q,
            phase: (p_r, p_l),
        }
    }

    /// The sample stamped `t` (s) of wheels at angles `(right, left)` (rad): whole ticks (as rad).
    fn sample(&self, t: f64, (r, l): (f64, f64)) -> WheelSample {
        let q = self.q;
        let count = |phi: f64, phase: f64| ((phi + phase) / q).floor() - (phase / q).floor();
        WheelSample {
            stamp: t,
            right: count(r, self.phase.0) * q,
            left: count(l, self.phase.1) * q,
        }
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
    let enc = Encoder::new(ticks_per_rev, seed);
    sample_times(cfg.rate_hz, duration, 0.0)
        .map(|t| enc.sample(t, robot.wire(track.at(robot.encoder_taken(t)))))
        .collect()
}

/// The samples of one sensor of a streamed run, one at a time, each from
/// the motion on the sensor's own [`Tape`] and its own random stream.
pub struct SensorStream<S> {
    sensor: S,
    tape: Tape,
    clock: Clock,
    k: usize,
}

/// What a sensor makes of the motion at one sample time.
pub trait Sensor {
    /// What one sample is.
    type Sample;
    /// The span of drive times `[from, to]` (s) the sample stamped `t`
    /// reads: by default the instant `t` alone.
    fn reads(&self, t: f64) -> (f64, f64) {
        (t, t)
    }
    /// The sample stamped `t` (s), from a tape covering [`reads`](Self::reads)`(t)`.
    fn sample(&mut self, t: f64, tape: &Tape) -> Self::Sample;
}

impl<S: Sensor> SensorStream<S> {
    /// The samples of `sensor` at the times of `clock`, reading the motion on `tape`.
    pub fn new(sensor: S, tape: Tape, clock: Clock) -> Self {
        Self {
            sensor,
            tape,
            clock,
            k: 0,
        }
    }

    /// Drive steps the tape holds now (bounded by the span one sample reads).
    pub fn held(&self) -> usize {
        self.tape.held()
    }

    /// The sample times of the whole stream.
    pub fn clock(&self) -> Clock {
        self.clock
    }
}

impl<S: Sensor> Iterator for SensorStream<S> {
    type Item = S::Sample;

    fn next(&mut self) -> Option<S::Sample> {
        if self.k >= self.clock.len() {
            return None;
        }
        let t = self.clock.stamp(self.k);
        self.k += 1;
        let (from, to) = self.sensor.reads(t);
        self.tape.cover(from, to);
        Some(self.sensor.sample(t, &self.tape))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.clock.len() - self.k;
        (n, Some(n))
    }
}

impl<S: Sensor> ExactSizeIterator for SensorStream<S> {}

/// The encoders reading the true wheels, late by the robot's latency.
pub struct Encoders {
    enc: Encoder,
    robot: TrueRobot,
}

impl Encoders {
    /// Encoders of `ticks_per_rev` on the wheels of `robot`; `seed` draws their phases.
    pub fn new(ticks_per_rev: f64, robot: &TrueRobot, seed: u64) -> Self {
        Self {
            enc: Encoder::new(ticks_per_rev, seed),
            robot: robot.clone(),
        }
    }
}

impl Sensor for Encoders {
    type Sample = WheelSample;
    /// The instant the reading was taken, and before it as far as a
    /// latency that grows during the run can take a later reading back.
    fn reads(&self, t: f64) -> (f64, f64) {
        let taken = self.robot.encoder_taken(t);
        (taken - self.robot.delay_margin(), taken)
    }
    fn sample(&mut self, t: f64, tape: &Tape) -> WheelSample {
        let taken = self.robot.encoder_taken(t);
        self.enc.sample(t, self.robot.wire(tape.wheels_at(taken)))
    }
}

/// The gyro: the mean true yaw rate over the preceding sample interval of
/// `h` s plus bias and white noise (rad/s).
pub struct Gyro {
    robot: TrueRobot,
    h: f64,
    noise: Normal<f64>,
    rng: StdRng,
}

impl Gyro {
    /// The gyro of `cfg` on `robot`; `seed` draws its noise.
    pub fn new(cfg: &GyroConfig, robot: &TrueRobot, seed: u64) -> Self {
        Self {
            robot: robot.clone(),
            h: 1.0 / cfg.rate_hz,
            noise: Normal::new(0.0, cfg.noise_sigma).expect("validated sigma"),
            rng: stream_rng(seed, STREAM_GYRO, 0),
        }
    }
}

impl Sensor for Gyro {
    type Sample = GyroSample;
    fn reads(&self, t: f64) -> (f64, f64) {
        (t - self.h, t)
    }
    fn sample(&mut self, t: f64, tape: &Tape) -> GyroSample {
        let h = self.h;
        let rate = (tape.pose_at(t)[2] - tape.pose_at(t - h)[2]) / h;
        GyroSample {
            stamp: t,
            wz: self.robot.departures().gyro_rate(rate) + self.noise.sample(&mut self.rng),
        }
    }
}

/// A LOAM-like \[ZhangSingh2014\] reference: poses `world_from_base` with
/// small white noise (heading included).
pub struct Reference {
    position: Normal<f64>,
    heading: Normal<f64>,
    rng: StdRng,
}

impl Reference {
    /// The reference of `cfg`; `seed` draws its noise.
    pub fn new(cfg: &ReferenceConfig, seed: u64) -> Self {
        Self {
            position: Normal::new(0.0, cfg.position_sigma).expect("validated sigma"),
            heading: Normal::new(0.0, cfg.heading_sigma).expect("validated sigma"),
            rng: stream_rng(seed, STREAM_REFERENCE, 0),
        }
    }
}

impl Sensor for Reference {
    type Sample = StampedPose;
    fn sample(&mut self, t: f64, tape: &Tape) -> StampedPose {
        let [x, y, th] = tape.pose_at(t);
        let rng = &mut self.rng;
        let (ex, ey, eh) = (
            self.position.sample(rng),
            self.position.sample(rng),
            self.heading.sample(rng),
        );
        StampedPose {
            stamp: t,
            pose: geom::pose(x + ex, y + ey, geom::wrap_angle(th + eh)),
            has_heading: true,
        }
    }
}

/// The simulated LMS111 of one run: owns what it needs to cast any scan on
/// demand, so a long recording can be written scan by scan instead of held
/// in memory. Scan `k` depends only on `k` (its own generator), never on
/// which scans were made before it.
#[derive(Clone)]
pub struct LaserSim {
    cfg: LaserConfig,
    world: World,
    tape: Tape,
    robot: TrueRobot,
    seed: u64,
    clock: Clock,
}

impl LaserSim {
    /// The laser of a run of `duration` s: one scan per period whose sweep ends within the run.
    pub fn new(
        cfg: &LaserConfig,
        world: World,
        tape: Tape,
        robot: TrueRobot,
        seed: u64,
        duration: f64,
    ) -> Self {
        Self {
            cfg: cfg.clone(),
            world,
            tape,
            robot,
            seed,
            clock: Clock::new(cfg.rate_hz, duration, Self::sweep(cfg)),
        }
    }

    /// Time from the first to the last beam of a sweep (s).
    fn sweep(cfg: &LaserConfig) -> f64 {
        let period = 1.0 / cfg.rate_hz;
        let time_inc = period * cfg.resolution_deg / 360.0;
        time_inc * (cfg.beams() - 1) as f64
    }

    /// Stamp of scan `k` (s); stamps increase with `k`.
    pub fn stamp(&self, k: usize) -> f64 {
        self.clock.stamp(k)
    }

    /// Number of scans in the run.
    pub fn len(&self) -> usize {
        self.clock.len()
    }

    /// Whether the run is too short for a single scan.
    pub fn is_empty(&self) -> bool {
        self.clock.is_empty()
    }

    /// Drive steps the laser's tape holds now (bounded by one block's span).
    pub fn held(&self) -> usize {
        self.tape.held()
    }

    /// True laser pose `[x, y, θ unwrapped]` at `t` (s), from the mounting
    /// it has then (a knock moves it during the run).
    fn laser_pose(&self, t: f64) -> [f64; 3] {
        let [x, y, th] = self.tape.pose_at(t);
        let mount = self.robot.laser_at(t);
        let p = geom::pose(x, y, th) * mount.pose();
        // Heading continuous with the body's unwrapped heading.
        [p.translation.x, p.translation.y, th + mount.yaw]
    }

    /// Scan `k`: every beam cast from the true laser pose at its own time in
    /// the sweep, with Gaussian range noise; no echo is +inf and too close is
    /// −inf (REP 117). The tape must cover the sweep.
    fn scan(&self, k: usize) -> LaserScan {
        let cfg = &self.cfg;
        let stamp = self.clock.stamp(k);
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

    /// Scans `range`, cast in parallel (the result does not depend on the
    /// thread count). Blocks must come in order: the tape forgets the motion
    /// before the block.
    pub fn scans(&mut self, range: std::ops::Range<usize>) -> Vec<LaserScan> {
        if range.is_empty() {
            return Vec::new();
        }
        let from = self.clock.stamp(range.start);
        let to = self.clock.stamp(range.end - 1) + Self::sweep(&self.cfg);
        self.tape.cover(from, to);
        let this = &*self;
        range.into_par_iter().map(|k| this.scan(k)).collect()
    }

    /// Every scan of the run, in blocks of [`Self::BLOCK`]; `progress` gets the fraction done.
    pub fn all(&mut self, progress: &mut dyn FnMut(f64)) -> Vec<LaserScan> {
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
