//! ICP on simulated LMS111 scans with known truth: accuracy per pair and per
//! metre, covariance consistency (NEES), unbiased scale and heading, local map
//! against scan to scan.

use nalgebra::{Point2, Vector3};
use odocal::geom::{self, pose, Pose2};
use odocal::icp::{integrate, match_recording, IcpParams};
use odocal::motion::Motion;
use odocal::scan::LaserScan;
use odocal::sim::worlds;
use odocal::traj::Trajectory;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// The wheelchair's LMS111 (on the back, facing backwards).
pub fn base_from_laser() -> Pose2 {
    pose(-0.45, 0.0, std::f64::consts::PI)
}

/// A drive around the corridor loop's centre line (rounded corners, radius
/// 1 m) at a speed varying between 0.6 and 1.4 m/s, sampled at `hz`.
pub fn corridor_drive(duration: f64, hz: f64) -> Trajectory {
    // Centre-line rectangle (1.25, 1.25)–(28.75, 18.75), counter-clockwise.
    let (x0, y0, x1, y1, rc) = (1.25, 1.25, 28.75, 18.75, 1.0);
    let legs = [
        ([x0 + rc, y0], 0.0, x1 - x0 - 2.0 * rc),
        (
            [x1, y0 + rc],
            std::f64::consts::FRAC_PI_2,
            y1 - y0 - 2.0 * rc,
        ),
        ([x1 - rc, y1], std::f64::consts::PI, x1 - x0 - 2.0 * rc),
        (
            [x0, y1 - rc],
            -std::f64::consts::FRAC_PI_2,
            y1 - y0 - 2.0 * rc,
        ),
    ];
    let arc = std::f64::consts::FRAC_PI_2 * rc;
    let lap: f64 = legs.iter().map(|l| l.2 + arc).sum();
    let at = |s: f64| -> Pose2 {
        let mut s = s % lap;
        for (start, h, len) in legs {
            if s <= len {
                return pose(start[0] + s * h.cos(), start[1] + s * h.sin(), h);
            }
            s -= len;
            if s <= arc {
                let end = [start[0] + len * h.cos(), start[1] + len * h.sin()];
                let a = s / rc;
                let c = [end[0] - rc * h.sin(), end[1] + rc * h.cos()];
                let ang = h - std::f64::consts::FRAC_PI_2 + a;
                return pose(c[0] + rc * ang.cos(), c[1] + rc * ang.sin(), h + a);
            }
            s -= arc;
        }
        unreachable!()
    };
    let mut t = Trajectory::default();
    let n = (duration * hz) as usize;
    let dt = 1.0 / hz;
    let mut s = 0.0;
    for i in 0..=n {
        let time = i as f64 * dt;
        t.push(100.0 + time, at(s));
        s += (1.0 + 0.4 * (0.3 * time).sin()) * dt;
    }
    t
}

/// LMS111 scans (541 beams over 270°, 0.5–20 m, σ = 12 mm) along `truth`.
pub fn lms111_scans(truth: &Trajectory, seed: u64) -> Vec<LaserScan> {
    let world = worlds::builtin("corridor-loop").unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.012).unwrap();
    let inc = 0.5f64.to_radians();
    let amin = -135f64.to_radians();
    let mut buf = vec![0.0; 541];
    truth
        .stamps
        .iter()
        .zip(&truth.poses)
        .map(|(&t, p)| {
            let l = p * base_from_laser();
            let o = Point2::new(l.translation.x, l.translation.y);
            world.cast_fan(o, geom::heading(&l) + amin, inc, 20.0, &mut buf);
            LaserScan {
                stamp: t,
                angle_min: amin,
                angle_increment: inc,
                scan_time: 0.04,
                range_min: 0.5,
                range_max: 20.0,
                ranges: buf
                    .iter()
                    .map(|&r| {
                        if r.is_finite() {
                            (r + noise.sample(&mut rng)) as f32
                        } else {
                            f32::INFINITY
                        }
                    })
                    .collect(),
                ..Default::default()
            }
        })
        .collect()
}

/// Wheel odometry with a 2 % scale error, a −3 % heading error and noise:
/// the prior must not leak into the ICP estimate.
pub fn biased_odometry(truth: &Trajectory, seed: u64) -> Trajectory {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut out = Trajectory::default();
    let mut p = Pose2::identity();
    out.push(truth.stamps[0], p);
    for i in 1..truth.len() {
        let [dx, dy, dt] = geom::xyt(&geom::between(&truth.poses[i - 1], &truth.poses[i]));
        let n = rng.random_range(-0.002..0.002);
        p *= pose(dx * 1.02 + n, dy * 1.02, dt * 0.97 + n);
        out.push(truth.stamps[i], p);
    }
    out
}

/// Per-pair errors against truth.
pub struct PairErrors {
    /// Normalised estimation error squared of each valid pair.
    pub nees: Vec<f64>,
    /// Translation error (m) of each valid pair.
    pub trans: Vec<f64>,
    /// Rotation error (rad) of each valid pair.
    pub rot: Vec<f64>,
}

pub fn pair_errors(motions: &[Motion], truth: &Trajectory) -> PairErrors {
    let mut e = PairErrors {
        nees: vec![],
        trans: vec![],
        rot: vec![],
    };
    for m in motions.iter().filter(|m| m.is_valid()) {
        let d = geom::between(&truth.pose_at(m.t0).unwrap(), &truth.pose_at(m.t1).unwrap());
        let [tx, ty, tt] = geom::xyt(&d);
        let r = Vector3::new(m.dx - tx, m.dy - ty, geom::wrap_angle(m.dtheta - tt));
        e.nees
            .push((r.transpose() * m.cov.try_inverse().unwrap() * r)[(0, 0)]);
        e.trans.push(r.xy().norm());
        e.rot.push(r.z.abs());
    }
    e
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn icp_sim_corridor_is_accurate_unbiased_and_consistent() {
    let truth = corridor_drive(40.0, 25.0);
    let scans = lms111_scans(&truth, 1);
    let odom = biased_odometry(&truth, 2);
    let params = IcpParams::default();
    let (motions, stats) =
        match_recording(&scans, base_from_laser(), Some(&odom), &params).unwrap();
    assert_eq!(stats.pairs, scans.len() - 1);
    assert!(stats.failed_pairs * 50 <= stats.pairs, "{stats:?}");
    let est = integrate(&motions);
    let e = pair_errors(&motions, &truth);
    let true_len = truth.path_length();
    let len_err = est.path_length() / true_len - 1.0;
    let truth_dth: f64 = motions
        .iter()
        .map(|m| {
            geom::heading(&geom::between(
                &truth.pose_at(m.t0).unwrap(),
                &truth.pose_at(m.t1).unwrap(),
            ))
        })
        .sum();
    let est_dth: f64 = motions.iter().map(|m| m.dtheta).sum();
    let end = geom::between(
        truth.poses.last().unwrap(),
        &(truth.poses[0] * est.poses.last().unwrap()),
    );
    eprintln!(
        "pairs {} failed {} iters {:.2}; per pair: trans {:.2} mm, rot {:.4} deg; \
         per metre: end error {:.3} m over {:.1} m ({:.3} %); path length {:+.4} %; \
         heading sum {:+.4} deg over {:.1} deg; mean NEES {:.2}",
        stats.pairs,
        stats.failed_pairs,
        stats.mean_iterations,
        1e3 * mean(&e.trans),
        mean(&e.rot).to_degrees(),
        end.translation.vector.norm(),
        true_len,
        100.0 * end.translation.vector.norm() / true_len,
        100.0 * len_err,
        (est_dth - truth_dth).to_degrees(),
        truth_dth.to_degrees(),
        mean(&e.nees)
    );
    assert!(
        len_err.abs() < 1e-3,
        "path length off by {:.3} %",
        100.0 * len_err
    );
    // Unbiased heading: the mean signed error of the heading increments is
    // within 3 standard errors of zero.
    let signed: Vec<f64> = motions
        .iter()
        .filter(|m| m.is_valid())
        .map(|m| {
            let d = geom::between(&truth.pose_at(m.t0).unwrap(), &truth.pose_at(m.t1).unwrap());
            geom::wrap_angle(m.dtheta - geom::heading(&d))
        })
        .collect();
    let mu = mean(&signed);
    let se = (signed.iter().map(|e| (e - mu).powi(2)).sum::<f64>() / (signed.len() as f64 - 1.0))
        .sqrt()
        / (signed.len() as f64).sqrt();
    eprintln!("heading increment error {mu:.3e} ± {se:.3e} rad (mean ± s.e.)");
    assert!(
        mu.abs() < 3.0 * se,
        "heading increments biased: {mu} ± {se} rad"
    );
    assert!(mean(&e.trans) < 0.005);
    let nees = mean(&e.nees);
    assert!((2.0..4.5).contains(&nees), "mean NEES {nees}");
}
