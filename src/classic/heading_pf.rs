//! The operation stage of \[GAHeading\]: a particle filter over the pose (x, y, θ)
//! propagated with calibrated odometry increments and weighted by an absolute
//! heading source (a camera's yaw, an IMU's integrated heading). Its figure of
//! merit is the end-position error as a percentage of the path length.

use super::error::{check_finite, ClassicError};
use crate::geom::{self, Pose2};
use crate::recording::WheelSample;
use crate::robot::DiffDrive;
use crate::traj::Trajectory;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// Filter settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HeadingPfParams {
    /// Number of particles.
    pub particles: usize,
    /// σ of the travelled distance per metre travelled (relative).
    pub sigma_dist_rel: f64,
    /// σ of the heading change per radian turned (relative).
    pub sigma_turn_rel: f64,
    /// σ of the heading change per metre travelled (rad/m).
    pub sigma_turn_per_m: f64,
    /// σ of the heading source (rad).
    pub heading_sigma: f64,
    /// Resample when N_eff < this fraction of the particles.
    pub resample_below: f64,
    /// Random seed.
    pub seed: u64,
}

impl Default for HeadingPfParams {
    /// 500 particles; odometry noise 1 % of distance, 2 % of turn, 0.01 rad/m;
    /// heading source σ = 0.01 rad; resample below N/2.
    fn default() -> Self {
        Self {
            particles: 500,
            sigma_dist_rel: 0.01,
            sigma_turn_rel: 0.02,
            sigma_turn_per_m: 0.01,
            heading_sigma: 0.01,
            resample_below: 0.5,
            seed: 1,
        }
    }
}

/// A heading reading: stamp (s) and absolute yaw (rad, world frame).
pub type HeadingReading = (f64, f64);

/// Runs the filter over a wheel stream from a known start pose; heading
/// readings (sorted by stamp) are applied at the first wheel sample at or
/// after their stamp. Returns the weighted-mean pose at every wheel sample.
pub fn heading_pf(
    model: &DiffDrive,
    wheels: &[WheelSample],
    headings: &[HeadingReading],
    start: &Pose2,
    p: &HeadingPfParams,
) -> Result<Trajectory, ClassicError> {
    const M: &str = "heading pf";
    check_finite(M, "heading", headings.iter().flat_map(|h| [h.0, h.1]))?;
    if p.particles == 0 || p.heading_sigma.is_nan() || p.heading_sigma <= 0.0 {
        return Err(ClassicError::invalid(
            M,
            "need particles > 0 and heading_sigma > 0",
        ));
    }
    let mut rng = StdRng::seed_from_u64(p.seed);
    let n = p.particles;
    let [x0, y0, t0] = geom::xyt(start);
    let mut parts = vec![[x0, y0, t0]; n];
    let mut logw = vec![0.0f64; n];
    let mut out = Trajectory::with_capacity(wheels.len());
    let Some(first) = wheels.first() else {
        return Ok(out);
    };
    out.push(first.stamp, *start);
    let mut prev = *first;
    let mut hi = headings.partition_point(|h| h.0 < first.stamp);
    for s in &wheels[1..] {
        if s.stamp.is_nan() || s.stamp <= prev.stamp {
            continue;
        }
        // Propagate: calibrated odometry increment plus noise ∝ distance and turn.
        let (ds, dth) = model.body_velocity(s.right - prev.right, s.left - prev.left);
        let sd = p.sigma_dist_rel * ds.abs();
        let st = p.sigma_turn_rel * dth.abs() + p.sigma_turn_per_m * ds.abs();
        for q in parts.iter_mut() {
            let a: f64 = rng.sample(StandardNormal);
            let b: f64 = rng.sample(StandardNormal);
            let (d, t) = (ds + sd * a, dth + st * b);
            let mid = q[2] + 0.5 * t;
            q[0] += d * mid.cos();
            q[1] += d * mid.sin();
            q[2] += t;
        }
        // Weight by every heading reading up to this stamp.
        let mut updated = false;
        while hi < headings.len() && headings[hi].0 <= s.stamp {
            let z = headings[hi].1;
            let k = 0.5 / (p.heading_sigma * p.heading_sigma);
            for (q, w) in parts.iter().zip(logw.iter_mut()) {
                let e = geom::wrap_angle(z - q[2]);
                *w -= k * e * e;
            }
            hi += 1;
            updated = true;
        }
        let w = normalised(&logw);
        if updated {
            let neff = 1.0 / w.iter().map(|v| v * v).sum::<f64>();
            if neff < p.resample_below * n as f64 {
                parts = systematic(&parts, &w, &mut rng);
                logw.iter_mut().for_each(|v| *v = 0.0);
            }
        }
        let w = normalised(&logw);
        out.push(s.stamp, mean_pose(&parts, &w));
        prev = *s;
    }
    Ok(out)
}

fn normalised(logw: &[f64]) -> Vec<f64> {
    let m = logw.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut w: Vec<f64> = logw.iter().map(|l| (l - m).exp()).collect();
    let s: f64 = w.iter().sum();
    w.iter_mut().for_each(|v| *v /= s);
    w
}

fn systematic(parts: &[[f64; 3]], w: &[f64], rng: &mut StdRng) -> Vec<[f64; 3]> {
    let n = parts.len();
    let u0 = rng.random_range(0.0..1.0 / n as f64);
    let mut out = Vec::with_capacity(n);
    let (mut c, mut i) = (w[0], 0);
    for j in 0..n {
        let u = u0 + j as f64 / n as f64;
        while u > c && i < n - 1 {
            i += 1;
            c += w[i];
        }
        out.push(parts[i]);
    }
    out
}

fn mean_pose(parts: &[[f64; 3]], w: &[f64]) -> Pose2 {
    let (mut x, mut y, mut c, mut s) = (0.0, 0.0, 0.0, 0.0);
    for (q, wi) in parts.iter().zip(w) {
        x += wi * q[0];
        y += wi * q[1];
        c += wi * q[2].cos();
        s += wi * q[2].sin();
    }
    geom::pose(x, y, s.atan2(c))
}

/// A simulated absolute heading source.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HeadingSourceParams {
    /// Reading rate (Hz).
    pub rate_hz: f64,
    /// White noise σ of each reading (rad).
    pub sigma: f64,
    /// Random-walk drift (rad/√s), as of an integrated IMU heading; 0 for a camera.
    pub drift_per_sqrt_s: f64,
}

impl Default for HeadingSourceParams {
    /// A camera yaw: 10 Hz, σ = 0.01 rad, no drift.
    fn default() -> Self {
        Self {
            rate_hz: 10.0,
            sigma: 0.01,
            drift_per_sqrt_s: 0.0,
        }
    }
}

/// Heading readings of the true trajectory with the source's noise.
pub fn simulate_heading(
    truth: &Trajectory,
    p: &HeadingSourceParams,
    seed: u64,
) -> Vec<HeadingReading> {
    let mut rng = StdRng::seed_from_u64(seed);
    let (Some(&t0), Some(&t1)) = (truth.stamps.first(), truth.stamps.last()) else {
        return Vec::new();
    };
    let dt = 1.0 / p.rate_hz;
    let mut out = Vec::new();
    let mut drift = 0.0;
    let mut t = t0 + dt;
    while t <= t1 {
        if let Some(q) = truth.pose_at(t) {
            let a: f64 = rng.sample(StandardNormal);
            let b: f64 = rng.sample(StandardNormal);
            drift += p.drift_per_sqrt_s * dt.sqrt() * a;
            out.push((t, geom::wrap_angle(geom::heading(&q) + drift + p.sigma * b)));
        }
        t += dt;
    }
    out
}
