//! Synthetic measured streams from a known true robot (nominal config plus
//! injected effects) with realistic sensor noise: the ground on which the
//! diagnosis is checked (hidden effect → named, estimated, gain > 0).
//! Not a simulator of scans: ICP is replaced by the true motion plus noise.

use crate::effects::{Departures, Effect};
use crate::geom::{self, Pose2};
use crate::motion::Motion;
use crate::recording::{GyroSample, StampedPose, WheelSample};
use crate::robot::RobotConfig;
use nalgebra::Matrix3;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// What to synthesise.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticSpec {
    /// Recording length (s).
    pub duration: f64,
    /// Scan (ICP motion) rate (Hz).
    pub icp_rate: f64,
    /// Wheel encoder sample rate (Hz).
    pub wheel_rate: f64,
    /// Gyro rate (Hz); 0 = no gyro.
    pub gyro_rate: f64,
    /// ICP σ of the forward and lateral velocity (m/s).
    pub sigma_v: f64,
    /// ICP σ of the turn rate (rad/s).
    pub sigma_w: f64,
    /// Relative spread of the per-pair σ (0.3 = ±30 %, reported faithfully).
    pub sigma_jitter: f64,
    /// Reported ICP σ / true σ (1 = honest covariance).
    pub reported_sigma_factor: f64,
    /// Gyro noise σ (rad/s).
    pub gyro_sigma: f64,
    /// Injected effects (design.md's table).
    pub effects: Vec<Effect>,
    /// Wheel out-of-roundness: radius × (1 + a sin(wheel angle + phase)),
    /// an effect outside the table (0 = none).
    pub out_of_roundness: f64,
}

impl Default for SyntheticSpec {
    fn default() -> Self {
        Self {
            duration: 120.0,
            icp_rate: 25.0,
            wheel_rate: 50.0,
            gyro_rate: 100.0,
            sigma_v: 0.008,
            sigma_w: 0.008,
            sigma_jitter: 0.3,
            reported_sigma_factor: 1.0,
            gyro_sigma: 0.002,
            effects: Vec::new(),
            out_of_roundness: 0.0,
        }
    }
}

/// Synthesised streams (and the true trajectory as reference).
#[derive(Debug, Clone, PartialEq)]
pub struct Synthetic {
    /// Quantised encoder angles (rad).
    pub wheels: Vec<WheelSample>,
    /// ICP-like motions in the base frame with the nominal mount.
    pub motions: Vec<Motion>,
    /// Gyro samples.
    pub gyro: Vec<GyroSample>,
    /// True poses at 10 Hz.
    pub reference: Vec<StampedPose>,
}

/// A smooth random drive: sums of sinusoids with seeded periods and phases;
/// V in about [0.1, 1.2] m/s, |W| up to about 0.7 rad/s.
struct Drive {
    v: [(f64, f64, f64); 3],
    w: [(f64, f64, f64); 3],
}

impl Drive {
    fn new(rng: &mut rand::rngs::StdRng) -> Self {
        let mut c = |a: f64, lo: f64, hi: f64| {
            (
                a,
                rng.random_range(lo..hi),
                rng.random_range(0.0..std::f64::consts::TAU),
            )
        };
        Self {
            v: [c(0.3, 14.0, 25.0), c(0.15, 5.0, 9.0), c(0.08, 2.0, 3.5)],
            w: [c(0.35, 10.0, 20.0), c(0.2, 4.0, 7.0), c(0.1, 1.5, 3.0)],
        }
    }

    fn eval(&self, t: f64) -> (f64, f64) {
        let s = |c: &[(f64, f64, f64); 3]| {
            c.iter()
                .map(|(a, p, ph)| a * (std::f64::consts::TAU * t / p + ph).sin())
                .sum::<f64>()
        };
        (0.65 + s(&self.v), s(&self.w))
    }
}

/// Synthesises the streams of `spec` for the true robot = `nominal` + effects.
pub fn synthesize(nominal: &RobotConfig, spec: &SyntheticSpec, seed: u64) -> Synthetic {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let drive = Drive::new(&mut rng);
    let x = Departures::of(&spec.effects);
    let phase = [
        rng.random_range(0.0..std::f64::consts::TAU),
        rng.random_range(0.0..std::f64::consts::TAU),
    ];
    let truth = TrueMotion::integrate(nominal, spec, &x, &drive, phase);
    let wheels = wheel_samples(nominal, spec, &x, &truth);
    let motions = icp_motions(nominal, spec, &x, &truth, &mut rng);
    let gyro = gyro_samples(spec, &x, &truth, &mut rng);
    let reference = (0..(spec.duration * 10.0) as usize)
        .map(|j| {
            let s = j as f64 / 10.0;
            StampedPose {
                stamp: s,
                pose: truth.pose_at(s),
                has_heading: true,
            }
        })
        .collect();
    Synthetic {
        wheels,
        motions,
        gyro,
        reference,
    }
}

/// The true motion every `h` s from `t_first` (1 s before the recording to
/// 1 s after it): body poses and the wheel angles as the encoders read them
/// (gain included, latency not).
struct TrueMotion {
    t_first: f64,
    h: f64,
    n: usize,
    poses: Vec<Pose2>,
    read: Vec<[f64; 2]>,
}

impl TrueMotion {
    /// Integrates the drive on the true robot (radii at each step's middle,
    /// wheels out of round with phases `phase`).
    fn integrate(
        nominal: &RobotConfig,
        spec: &SyntheticSpec,
        x: &Departures,
        drive: &Drive,
        phase: [f64; 2],
    ) -> Self {
        let (t_first, h) = (-1.0, 0.002);
        let n = ((spec.duration + 2.0) / h) as usize;
        let (mut pose, mut phi, mut phim) = (Pose2::identity(), [0.0f64; 2], [0.0f64; 2]);
        let mut poses = Vec::with_capacity(n + 1);
        let mut read = Vec::with_capacity(n + 1);
        poses.push(pose);
        read.push(phim);
        for i in 0..n {
            let t = t_first + (i as f64 + 0.5) * h;
            let (v, w) = drive.eval(t);
            let [mut rr, mut rl] = x.radii_at([nominal.r_right, nominal.r_left], t);
            rr *= 1.0 + spec.out_of_roundness * (phi[0] + phase[0]).sin();
            rl *= 1.0 + spec.out_of_roundness * (phi[1] + phase[1]).sin();
            let d = x.turning_base(x.wheel_base(nominal.wheel_base), w);
            let om = [(v + w * d / 2.0) / rr, (v - w * d / 2.0) / rl];
            for k in 0..2 {
                phi[k] += om[k] * h;
                phim[k] += x.encoder_rate(om[k]) * h;
            }
            pose *= geom::arc_increment(v, w, h);
            poses.push(pose);
            read.push(phim);
        }
        Self {
            t_first,
            h,
            n,
            poses,
            read,
        }
    }

    /// Sample index and fraction towards the next at time `t` (clamped).
    fn index(&self, t: f64) -> (usize, f64) {
        let f = ((t - self.t_first) / self.h).clamp(0.0, (self.n - 1) as f64);
        let i = f.floor() as usize;
        (i, f - i as f64)
    }

    /// Body pose at `t`.
    fn pose_at(&self, t: f64) -> Pose2 {
        let (i, s) = self.index(t);
        geom::interpolate(&self.poses[i], &self.poses[i + 1], s)
    }

    /// Encoder angles (right, left) at true time `t`.
    fn read_at(&self, t: f64) -> [f64; 2] {
        let (i, f) = self.index(t);
        let (a, b) = (self.read[i], self.read[i + 1]);
        [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
    }
}

/// Quantised encoder angles at the wheel rate, stamped late by the latency.
fn wheel_samples(
    nominal: &RobotConfig,
    spec: &SyntheticSpec,
    x: &Departures,
    truth: &TrueMotion,
) -> Vec<WheelSample> {
    let q = nominal.rad_per_tick();
    let quant = |a: f64| (a / q).floor() * q;
    (0..=(spec.duration * spec.wheel_rate) as usize)
        .map(|j| {
            let s = j as f64 / spec.wheel_rate;
            let [r, l] = truth.read_at(x.encoder_taken(s));
            WheelSample {
                stamp: s,
                left: quant(l),
                right: quant(r),
            }
        })
        .collect()
}

/// ICP-like motions: the true motion seen through the true laser mount,
/// converted with the nominal one, plus noise of jittered σ.
fn icp_motions(
    nominal: &RobotConfig,
    spec: &SyntheticSpec,
    x: &Departures,
    truth: &TrueMotion,
    rng: &mut rand::rngs::StdRng,
) -> Vec<Motion> {
    let mount = nominal.laser.unwrap_or_default();
    let l0 = mount.pose();
    let l1 = x.laser_mount(&mount).pose();
    let e = l1 * l0.inverse();
    let nd = Normal::new(0.0, 1.0).unwrap();
    let n_scans = (spec.duration * spec.icp_rate) as usize;
    (0..n_scans)
        .map(|k| {
            let (t0, t1) = (k as f64 / spec.icp_rate, (k + 1) as f64 / spec.icp_rate);
            let dt = t1 - t0;
            let o = truth.pose_at(t0).inverse() * truth.pose_at(t1);
            let [dx, dy, dth] = geom::xyt(&(e.inverse() * o * e));
            let f = 1.0 + spec.sigma_jitter * rng.random_range(-1.0..1.0);
            let (sv, sw) = (spec.sigma_v * f * dt, spec.sigma_w * f * dt);
            let rep = spec.reported_sigma_factor;
            Motion {
                t0,
                t1,
                dx: dx + sv * nd.sample(rng),
                dy: dy + sv * nd.sample(rng),
                dtheta: dth + sw * nd.sample(rng),
                cov: Matrix3::from_diagonal(&nalgebra::Vector3::new(
                    (rep * sv).powi(2),
                    (rep * sv).powi(2),
                    (rep * sw).powi(2),
                )),
                iterations: 5,
                inliers: 400,
                failure: None,
                split: None,
            }
        })
        .collect()
}

/// Gyro samples (none when the rate is 0): the mean true rate over the
/// sampling period ending at the stamp, biased, plus white noise.
fn gyro_samples(
    spec: &SyntheticSpec,
    x: &Departures,
    truth: &TrueMotion,
    rng: &mut rand::rngs::StdRng,
) -> Vec<GyroSample> {
    if spec.gyro_rate.is_nan() || spec.gyro_rate <= 0.0 {
        return Vec::new();
    }
    let nd = Normal::new(0.0, 1.0).unwrap();
    let dt = 1.0 / spec.gyro_rate;
    (0..(spec.duration * spec.gyro_rate) as usize)
        .map(|j| {
            let s = j as f64 / spec.gyro_rate;
            let dth = geom::heading(&(truth.pose_at(s - dt).inverse() * truth.pose_at(s)));
            GyroSample {
                stamp: s,
                wz: x.gyro_rate(dth / dt) + spec.gyro_sigma * nd.sample(rng),
            }
        })
        .collect()
}
