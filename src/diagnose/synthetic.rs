//! Synthetic measured streams from a known true robot (nominal config plus
//! injected effects) with realistic sensor noise: the ground on which the
//! diagnosis is checked (hidden effect → named, estimated, gain > 0).
//! Not a simulator of scans: ICP is replaced by the true motion plus noise.

use super::model::Extension;
use crate::effects::Effect;
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
    let x = Extension::from_effects(&spec.effects);
    let h = 0.002;
    let t_first = -1.0;
    let n = ((spec.duration + 2.0) / h) as usize;
    let phase = [
        rng.random_range(0.0..std::f64::consts::TAU),
        rng.random_range(0.0..std::f64::consts::TAU),
    ];
    let (mut pose, mut phi, mut phim) = (Pose2::identity(), [0.0f64; 2], [0.0f64; 2]);
    let mut poses = Vec::with_capacity(n + 1);
    let mut meas = Vec::with_capacity(n + 1);
    poses.push(pose);
    meas.push(phim);
    for i in 0..n {
        let t = t_first + (i as f64 + 0.5) * h;
        let (v, w) = drive.eval(t);
        let mut rr = nominal.r_right * (1.0 + x.scale[0]) + x.drift[0] * t / 3600.0;
        let mut rl = nominal.r_left * (1.0 + x.scale[1]) + x.drift[1] * t / 3600.0;
        if let Some((ts, sr, sl)) = x.step {
            if t >= ts {
                rr += sr;
                rl += sl;
            }
        }
        rr *= 1.0 + spec.out_of_roundness * (phi[0] + phase[0]).sin();
        rl *= 1.0 + spec.out_of_roundness * (phi[1] + phase[1]).sin();
        let d = nominal.wheel_base * (1.0 + x.base_scale) * (1.0 + x.slip * w.abs());
        let om = [(v + w * d / 2.0) / rr, (v - w * d / 2.0) / rl];
        for k in 0..2 {
            phi[k] += om[k] * h;
            phim[k] += om[k] * (1.0 + x.enc_k * om[k].abs()) * h;
        }
        pose *= geom::arc_increment(v, w, h);
        poses.push(pose);
        meas.push(phim);
    }
    let idx = |t: f64| -> (usize, f64) {
        let f = ((t - t_first) / h).clamp(0.0, (n - 1) as f64);
        let i = f.floor() as usize;
        (i, f - i as f64)
    };
    let pose_at = |t: f64| {
        let (i, s) = idx(t);
        geom::interpolate(&poses[i], &poses[i + 1], s)
    };
    let q = nominal.rad_per_tick();
    let quant = |a: f64| (a / q).floor() * q;
    let wheels: Vec<WheelSample> = (0..=(spec.duration * spec.wheel_rate) as usize)
        .map(|j| {
            let s = j as f64 / spec.wheel_rate;
            let (i, f) = idx(s - x.delay);
            let r = meas[i][0] + f * (meas[i + 1][0] - meas[i][0]);
            let l = meas[i][1] + f * (meas[i + 1][1] - meas[i][1]);
            WheelSample {
                stamp: s,
                left: quant(l),
                right: quant(r),
            }
        })
        .collect();
    let m = &nominal.laser;
    let l0 = geom::pose(m.x, m.y, m.yaw);
    let l1 = geom::pose(m.x + x.laser[0], m.y + x.laser[1], m.yaw + x.laser[2]);
    let e = l1 * l0.inverse();
    let nd = Normal::new(0.0, 1.0).unwrap();
    let n_scans = (spec.duration * spec.icp_rate) as usize;
    let motions: Vec<Motion> = (0..n_scans)
        .map(|k| {
            let (t0, t1) = (k as f64 / spec.icp_rate, (k + 1) as f64 / spec.icp_rate);
            let dt = t1 - t0;
            let o = pose_at(t0).inverse() * pose_at(t1);
            let [dx, dy, dth] = geom::xyt(&(e.inverse() * o * e));
            let f = 1.0 + spec.sigma_jitter * rng.random_range(-1.0..1.0);
            let (sv, sw) = (spec.sigma_v * f * dt, spec.sigma_w * f * dt);
            let rep = spec.reported_sigma_factor;
            Motion {
                t0,
                t1,
                dx: dx + sv * nd.sample(&mut rng),
                dy: dy + sv * nd.sample(&mut rng),
                dtheta: dth + sw * nd.sample(&mut rng),
                cov: Matrix3::from_diagonal(&nalgebra::Vector3::new(
                    (rep * sv).powi(2),
                    (rep * sv).powi(2),
                    (rep * sw).powi(2),
                )),
                iterations: 5,
                inliers: 400,
                failure: None,
            }
        })
        .collect();
    let gyro = if spec.gyro_rate > 0.0 {
        (0..(spec.duration * spec.gyro_rate) as usize)
            .map(|j| {
                let s = j as f64 / spec.gyro_rate;
                // Mean true rate over the sampling period ending at the stamp.
                let dt = 1.0 / spec.gyro_rate;
                let dth = geom::heading(&(pose_at(s - dt).inverse() * pose_at(s)));
                GyroSample {
                    stamp: s,
                    wz: dth / dt + x.gyro_bias + spec.gyro_sigma * nd.sample(&mut rng),
                }
            })
            .collect()
    } else {
        Vec::new()
    };
    let reference = (0..(spec.duration * 10.0) as usize)
        .map(|j| {
            let s = j as f64 / 10.0;
            StampedPose {
                stamp: s,
                pose: pose_at(s),
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
