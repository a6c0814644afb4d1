//! A synthetic differential-drive run with known truth, for tests and the
//! Monte Carlo experiments: a smooth (v, w) profile, wheel angles from the
//! true parameters (quantised like an 8800-tick encoder), ICP-like velocity
//! observations with per-pair σ, and a gyro.

use crate::geom::{self, Pose2};
use crate::motion::VelocityObs;
use crate::recording::{GyroSample, WheelSample};
use crate::robot::DiffDrive;
use crate::traj::Trajectory;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// A jump of the true radii at a moment (a new user boards).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadiusStep {
    /// When (s from the start).
    pub time: f64,
    /// Change of the right radius (m).
    pub right: f64,
    /// Change of the left radius (m).
    pub left: f64,
}

/// Settings of the synthetic run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SynthParams {
    /// Duration (s).
    pub duration: f64,
    /// Velocity observation (scan pair) rate (Hz); should divide 1000.
    pub obs_rate: f64,
    /// Gyro rate (Hz); should divide 1000.
    pub gyro_rate: f64,
    /// Wheel encoder sampling rate (Hz); should divide 1000.
    pub wheel_rate: f64,
    /// Encoder ticks per wheel revolution (0 = no quantisation).
    pub ticks_per_rev: u32,
    /// σ of the ICP translation per scan pair (m), before the per-pair factor.
    pub sigma_dx: f64,
    /// σ of the ICP rotation per scan pair (rad), before the per-pair factor.
    pub sigma_dtheta: f64,
    /// Per-pair σ factor drawn uniformly in this range (ICP's adaptive σ).
    pub sigma_factor: [f64; 2],
    /// σ of one gyro sample (rad/s).
    pub gyro_sigma: f64,
    /// Mean forward speed (m/s).
    pub speed: f64,
    /// Turn-rate amplitude (rad/s).
    pub turn: f64,
    /// Optional jump of the true radii.
    pub radius_step: Option<RadiusStep>,
    /// From this time on (s) the robot drives straight (turn rate 0), e.g. a
    /// corridor where the wheel base is unobservable; `None` = turns all along.
    pub straight_from: Option<f64>,
}

impl Default for SynthParams {
    fn default() -> Self {
        Self {
            duration: 60.0,
            obs_rate: 50.0,
            gyro_rate: 100.0,
            wheel_rate: 100.0,
            ticks_per_rev: 8800,
            sigma_dx: 1e-3,
            sigma_dtheta: 2e-4,
            sigma_factor: [0.5, 2.0],
            gyro_sigma: 3e-3,
            speed: 0.8,
            turn: 0.5,
            radius_step: None,
            straight_from: None,
        }
    }
}

/// The generated streams and the truth behind them.
#[derive(Debug, Clone)]
pub struct SynthData {
    /// True parameters at the start.
    pub truth: DiffDrive,
    /// The radius jump, if any.
    pub radius_step: Option<RadiusStep>,
    /// Wheel angles (rad), quantised.
    pub wheels: Vec<WheelSample>,
    /// Gyro samples (rad/s).
    pub gyro: Vec<GyroSample>,
    /// ICP-like velocity observations, one per scan pair.
    pub obs: Vec<VelocityObs>,
    /// True poses at the wheel stamps (identity at t = 0).
    pub reference: Trajectory,
    /// Cumulative integrals of the true v (m) and w (rad) every millisecond.
    cum: Vec<(f64, f64)>,
}

const H: f64 = 1e-3;

impl SynthData {
    /// True parameters at time `t` (s).
    pub fn truth_at(&self, t: f64) -> DiffDrive {
        let mut k = self.truth;
        if let Some(s) = self.radius_step {
            if t >= s.time {
                k.r_right += s.right;
                k.r_left += s.left;
            }
        }
        k
    }

    /// True mean (V, W) over `[t0, t1]` (m/s, rad/s).
    pub fn mean_velocity(&self, t0: f64, t1: f64) -> (f64, f64) {
        let at = |t: f64| {
            let x = (t / H).clamp(0.0, (self.cum.len() - 1) as f64);
            let i = (x.floor() as usize).min(self.cum.len() - 2);
            let f = x - i as f64;
            let (a, b) = (self.cum[i], self.cum[i + 1]);
            (a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f)
        };
        let (a, b) = (at(t0), at(t1));
        let dt = t1 - t0;
        ((b.0 - a.0) / dt, (b.1 - a.1) / dt)
    }
}

/// Draws true parameters: radii uniform in the [0.305, 0.335] m of \[Farina\], wheel
/// base uniform in [0.60, 0.70] m.
pub fn draw_truth(seed: u64) -> DiffDrive {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x7275_7468);
    DiffDrive {
        r_right: rng.random_range(0.305..0.335),
        r_left: rng.random_range(0.305..0.335),
        wheel_base: rng.random_range(0.60..0.70),
    }
}

/// Generates a run with the given truth; same seed, same data.
pub fn generate(p: &SynthParams, truth: DiffDrive, seed: u64) -> SynthData {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut u = |lo: f64, hi: f64| rng.random_range(lo..hi);
    // Smooth profile: a speed that ramps up from rest and breathes, a turn
    // rate made of two sines, so both wheels vary independently.
    let (tv, phv) = (u(12.0, 20.0), u(0.0, 6.3));
    let (t1, ph1, t2, ph2) = (u(8.0, 14.0), u(0.0, 6.3), u(3.0, 6.0), u(0.0, 6.3));
    let (speed, turn) = (p.speed, p.turn);
    let straight = p.straight_from.unwrap_or(f64::INFINITY);
    let tau = std::f64::consts::TAU;
    let profile = move |t: f64| {
        let ramp = 1.0 - (-t / 1.5).exp();
        let v = speed * ramp * (1.0 + 0.4 * (tau * t / tv + phv).sin());
        let w = ramp * turn * (0.7 * (tau * t / t1 + ph1).sin() + 0.5 * (tau * t / t2 + ph2).sin());
        (v, if t < straight { w } else { 0.0 })
    };
    let n = (p.duration / H).round() as usize;
    let every = |rate: f64| ((1.0 / (rate * H)).round() as usize).max(1);
    let (wheel_every, gyro_every, obs_every) =
        (every(p.wheel_rate), every(p.gyro_rate), every(p.obs_rate));
    let tick = if p.ticks_per_rev > 0 {
        tau / p.ticks_per_rev as f64
    } else {
        0.0
    };
    let quant = |a: f64| {
        if tick > 0.0 {
            (a / tick).floor() * tick
        } else {
            a
        }
    };
    let mut data = SynthData {
        truth,
        radius_step: p.radius_step,
        wheels: Vec::with_capacity(n / wheel_every + 1),
        gyro: Vec::with_capacity(n / gyro_every + 1),
        obs: Vec::with_capacity(n / obs_every + 1),
        reference: Trajectory::with_capacity(n / wheel_every + 1),
        cum: Vec::with_capacity(n + 1),
    };
    let (mut pr, mut pl) = (0.0f64, 0.0f64);
    let mut pose = Pose2::identity();
    let (mut iv, mut iw) = (0.0f64, 0.0f64);
    let mut last_obs = (0.0, 0.0, 0.0);
    let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
    for i in 0..=n {
        let t = i as f64 * H;
        if i > 0 {
            let tm = t - 0.5 * H;
            let (v, w) = profile(tm);
            let k = data.truth_at(tm);
            let (wr, wl) = k.wheel_rates(v, w);
            pr += wr * H;
            pl += wl * H;
            pose *= geom::arc_increment(v, w, H);
            iv += v * H;
            iw += w * H;
        }
        data.cum.push((iv, iw));
        if i % wheel_every == 0 {
            data.wheels.push(WheelSample {
                stamp: t,
                left: quant(pl),
                right: quant(pr),
            });
            data.reference.push(t, pose);
        }
        if i % gyro_every == 0 {
            let w = profile(t).1;
            data.gyro.push(GyroSample {
                stamp: t,
                wz: w + p.gyro_sigma * normal(),
            });
        }
        if i % obs_every == 0 {
            let (t0, v0, w0) = last_obs;
            if i > 0 {
                let dt = t - t0;
                let f = p.sigma_factor[0]
                    + (p.sigma_factor[1] - p.sigma_factor[0]) * 0.5 * (1.0 + normal().tanh());
                let (sv, sw) = (f * p.sigma_dx / dt, f * p.sigma_dtheta / dt);
                data.obs.push(VelocityObs {
                    t0,
                    t1: t,
                    v: (iv - v0) / dt + sv * normal(),
                    w: (iw - w0) / dt + sw * normal(),
                    sigma_v: sv,
                    sigma_w: sw,
                });
            }
            last_obs = (t, iv, iw);
        }
    }
    data
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wheels_follow_the_true_kinematics() {
        let truth = draw_truth(3);
        let d = generate(&SynthParams::default(), truth, 3);
        assert_eq!(d.wheels.len(), 6001);
        assert_eq!(d.obs.len(), 3000);
        assert_eq!(d.gyro.len(), 6001);
        // Odometry with the true parameters reproduces the reference (only
        // quantisation separates them).
        let odo = crate::robot::wheel_odometry(&truth, &d.wheels, Pose2::identity());
        let (a, b) = (odo.poses.last().unwrap(), d.reference.poses.last().unwrap());
        assert!((a.translation.vector - b.translation.vector).norm() < 0.05);
        let (v, _) = d.mean_velocity(10.0, 11.0);
        assert!(v > 0.2 && v < 1.2);
        // Observations scatter around the truth by their own σ.
        let z: f64 = d
            .obs
            .iter()
            .map(|o| ((o.v - d.mean_velocity(o.t0, o.t1).0) / o.sigma_v).powi(2))
            .sum::<f64>()
            / d.obs.len() as f64;
        assert!((z - 1.0).abs() < 0.1, "normalised variance {z}");
    }
}
