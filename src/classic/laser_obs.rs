//! What the filters of \[Farina\] measure on a simulated run: scan-matching-like body
//! velocities with a per-pair σ (the noise level of odocal's ICP on the
//! LMS111) and a gyro, derived from the true motion. The classic runs carry
//! only wheels and truth; these streams let the Adaptive-PF and the DKF
//! calibrate on exactly the same runs.

use super::drive::SimRun;
use crate::calib::{steps, CalibStep};
use crate::geom;
use crate::motion::VelocityObs;
use crate::recording::GyroSample;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// Noise of the simulated laser velocities and gyro.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaserObsParams {
    /// σ of the scan-matched translation per scan pair (m), before the factor.
    pub sigma_dx: f64,
    /// σ of the scan-matched rotation per pair (rad), before the factor.
    pub sigma_dtheta: f64,
    /// Per-pair σ factor drawn uniformly in this range (ICP's adaptive σ).
    pub sigma_factor: [f64; 2],
    /// σ of one gyro sample (rad/s).
    pub gyro_sigma: f64,
}

impl Default for LaserObsParams {
    /// The levels of `calib::synth`: 1 mm and 0.2 mrad per pair × [0.5, 2], gyro 3 mrad/s.
    fn default() -> Self {
        Self {
            sigma_dx: 1e-3,
            sigma_dtheta: 2e-4,
            sigma_factor: [0.5, 2.0],
            gyro_sigma: 3e-3,
        }
    }
}

/// One velocity observation per wheel interval (a scan pair at the wheel
/// rate) and one gyro sample at each interval's middle, from the run's true
/// poses with the given noise. Same seed, same streams.
pub fn laser_streams(
    run: &SimRun,
    p: &LaserObsParams,
    seed: u64,
) -> (Vec<VelocityObs>, Vec<GyroSample>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut normal = || -> f64 { rng.sample(StandardNormal) };
    let t = &run.truth;
    let mut obs = Vec::with_capacity(t.len());
    let mut gyro = Vec::with_capacity(t.len());
    for i in 1..t.len() {
        let (t0, t1) = (t.stamps[i - 1], t.stamps[i]);
        let dt = t1 - t0;
        if dt.is_nan() || dt <= 0.0 {
            continue;
        }
        let (ds, dth) = geom::arc_of_increment(&geom::between(&t.poses[i - 1], &t.poses[i]));
        let u = (normal().tanh() + 1.0) * 0.5;
        let f = p.sigma_factor[0] + (p.sigma_factor[1] - p.sigma_factor[0]) * u;
        let (sv, sw) = (f * p.sigma_dx / dt, f * p.sigma_dtheta / dt);
        obs.push(VelocityObs {
            t0,
            t1,
            v: ds / dt + sv * normal(),
            w: dth / dt + sw * normal(),
            sigma_v: sv,
            sigma_w: sw,
        });
        gyro.push(GyroSample {
            stamp: 0.5 * (t0 + t1),
            wz: dth / dt + p.gyro_sigma * normal(),
        });
    }
    (obs, gyro)
}

/// The calibration steps of several runs played one after the other: each
/// run's stamps are shifted to start where the previous one ended, and no
/// step spans two runs (run `i` draws its noise from `seed + i`).
pub fn chained_steps(runs: &[&SimRun], p: &LaserObsParams, seed: u64) -> Vec<CalibStep> {
    chained_steps_from(runs, p, seed, 0.0)
}

/// [`chained_steps`] starting at time `offset` (s).
pub fn chained_steps_from(
    runs: &[&SimRun],
    p: &LaserObsParams,
    seed: u64,
    offset: f64,
) -> Vec<CalibStep> {
    let mut out = Vec::new();
    let mut offset = offset;
    for (i, run) in runs.iter().enumerate() {
        let (obs, gyro) = laser_streams(run, p, seed.wrapping_add(i as u64));
        let first = run.wheels.first().map_or(0.0, |w| w.stamp);
        let shift = offset - first;
        let mut st = steps(&obs, &run.wheels, &gyro, p.gyro_sigma);
        for s in &mut st {
            s.t0 += shift;
            s.t1 += shift;
        }
        offset = st.last().map_or(offset, |s| s.t1);
        out.extend(st);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classic::{drive_segments, square_segments, DriveParams, Turn};
    use crate::robot::DiffDrive;

    #[test]
    fn velocities_scatter_around_the_truth_by_their_sigma() {
        let k = DiffDrive {
            r_right: 0.32,
            r_left: 0.32,
            wheel_base: 0.65,
        };
        let run = drive_segments(
            &k,
            &k,
            &square_segments(3.0, Turn::Cw),
            &DriveParams::default(),
            1,
        );
        let (obs, gyro) = laser_streams(&run, &LaserObsParams::default(), 2);
        assert_eq!(obs.len(), run.truth.len() - 1);
        assert_eq!(gyro.len(), obs.len());
        // Straights at 0.4 m/s: normalised variance of v around 0.4 is ≈ 1.
        let z: Vec<f64> = obs
            .iter()
            .filter(|o| o.w.abs() < 0.05)
            .map(|o| ((o.v - 0.4) / o.sigma_v).powi(2))
            .collect();
        let m = z.iter().sum::<f64>() / z.len() as f64;
        assert!(
            z.len() > 100 && (m - 1.0).abs() < 0.25,
            "{m} over {}",
            z.len()
        );
        // Chaining two runs shifts the second one and never goes back in time.
        let st = chained_steps(&[&run, &run], &LaserObsParams::default(), 3);
        assert!(st.windows(2).all(|w| w[1].t0 >= w[0].t1 - 1e-9));
        let end = run.wheels.last().unwrap().stamp;
        assert!((st.last().unwrap().t1 - 2.0 * end).abs() < 1e-6);
    }
}
