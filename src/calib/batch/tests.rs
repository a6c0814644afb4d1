//! Synthetic intervals from known parameters, simulated with nalgebra's
//! isometries and `geom::arc_increment` (not the module's own model), with
//! seeded Gaussian noise on the laser displacements.

use super::*;
use crate::calib::CheckParams;
use crate::geom::{self, Pose2};
use crate::robot::DiffDrive;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};

/// The robot's motion over one sub-step, written out apart from the
/// model's `arc`: distance and turn from the wheels, then the exact arc
/// (the unit tests of `solve` and `closed_form` build their intervals with it).
pub(super) fn arc_by_hand(dl: f64, dr: f64, rr: f64, rl: f64, b: f64) -> nalgebra::Isometry2<f64> {
    let (ds, dth) = (0.5 * (rr * dr + rl * dl), (rr * dr - rl * dl) / b);
    let (x, y) = if dth.abs() < 1e-12 {
        (ds, 0.0)
    } else {
        (ds / dth * dth.sin(), ds / dth * (1.0 - dth.cos()))
    };
    nalgebra::Isometry2::new(nalgebra::Vector2::new(x, y), dth)
}

/// Left and right wheel increments (rad) of drives every way: straight,
/// curved both ways, spinning, reversing (the unit tests of `solve` and
/// `closed_form` build intervals from them).
pub(super) const DRIVES: [(f64, f64); 7] = [
    (2.0, 2.5),
    (3.0, 1.0),
    (-1.0, 1.5),
    (1.2, -0.8),
    (4.0, 4.2),
    (0.5, 2.5),
    (2.2, 0.3),
];

const TRUE_R: f64 = 0.101;
const TRUE_L: f64 = 0.0985;
const TRUE_B: f64 = 0.52;
const TRUE_LASER: [f64; 3] = [0.31, -0.12, 0.4];
const SIGMA: [f64; 3] = [2e-3, 1e-3, 3e-3];

fn nominal() -> DiffDrive {
    DiffDrive {
        r_right: 0.1,
        r_left: 0.1,
        wheel_base: 0.5,
    }
}

/// The laser displacement of a robot motion: `ℓ⁻¹ · o · ℓ`.
fn laser_of(o: &Pose2) -> [f64; 3] {
    let l = geom::pose(TRUE_LASER[0], TRUE_LASER[1], TRUE_LASER[2]);
    geom::xyt(&(l.inverse() * o * l))
}

/// Speed and turn rate of the k-th interval: straight runs, curves both
/// ways, turns in place and reversing.
fn command(k: usize, rng: &mut Xoshiro256PlusPlus) -> (f64, f64) {
    match k % 4 {
        0 => (rng.random_range(0.2..0.5), 0.0),
        1 => (rng.random_range(-0.2..0.5), rng.random_range(-1.0..1.0)),
        2 => (0.0, rng.random_range(-1.2..1.2)),
        _ => (rng.random_range(0.1..0.4), rng.random_range(-0.6..0.6)),
    }
}

/// `n` intervals of five 0.1 s sub-steps; `cov`: give the true covariance,
/// else none (to be estimated); `turn`: whether the robot ever turns.
fn intervals(seed: u64, n: usize, cov: bool, turn: bool) -> Problem {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let normal = gauss;
    let c = nalgebra::Matrix3::from_diagonal(&SIGMA.map(|s| s * s).into());
    let intervals = (0..n)
        .map(|k| {
            let (v, w) = command(k, &mut rng);
            let w = if turn { w } else { 0.0 };
            let mut o = Pose2::identity();
            let mut steps = Vec::new();
            for _ in 0..5 {
                let (v, w) = (
                    v + 0.05 * normal(&mut rng),
                    w + 0.1 * normal(&mut rng) * f64::from(u8::from(turn)),
                );
                o *= geom::arc_increment(v, w, 0.1);
                steps.push([
                    (v - w * TRUE_B / 2.0) * 0.1 / TRUE_L,
                    (v + w * TRUE_B / 2.0) * 0.1 / TRUE_R,
                ]);
            }
            let s = laser_of(&o);
            let s = [0, 1, 2].map(|i| s[i] + SIGMA[i] * normal(&mut rng));
            Interval {
                s,
                cov: cov.then_some(c),
                duration: 0.5,
                wheels: WheelMotion::Steps(steps),
            }
        })
        .collect();
    Problem {
        intervals,
        track: None,
    }
}

fn gauss(r: &mut Xoshiro256PlusPlus) -> f64 {
    StandardNormal.sample(r)
}

fn truth() -> [f64; 6] {
    [
        TRUE_R,
        TRUE_L,
        TRUE_B,
        TRUE_LASER[0],
        TRUE_LASER[1],
        TRUE_LASER[2],
    ]
}

fn values(e: &BatchEstimate) -> [(f64, f64); 6] {
    let v = |x: Valued| (x.value, x.std);
    [
        v(e.r_right),
        v(e.r_left),
        v(e.wheel_base),
        v(e.laser.x),
        v(e.laser.y),
        v(e.laser.yaw),
    ]
}

#[test]
fn recovers_known_parameters_within_their_std() {
    let e = estimate(
        &intervals(1, 400, true, true),
        &nominal(),
        &BatchParams::default(),
        &CheckParams::default(),
    )
    .unwrap();
    for ((name, (v, s)), t) in NAMES.iter().zip(values(&e)).zip(truth()) {
        assert!((v - t).abs() < 4.0 * s, "{name}: {v} vs {t} (std {s})");
        assert!(s > 0.0 && s < 0.05 * t.abs().max(0.1), "{name}: std {s}");
    }
    assert!(e.time_offset.is_none());
    assert!(e.observability.values().all(|o| o.observable));
    assert_eq!(e.correlation.names.len(), 6);
}

#[test]
fn reported_std_is_honest_over_seeds() {
    // (estimate − truth)/std over 20 seeds × 6 parameters: mean square ≈ 1
    // (χ²₁₂₀/120 lies in [0.72, 1.32] with 98 % probability).
    let mut z2 = Vec::new();
    let p = BatchParams {
        outlier_iterations: 0,
        ..Default::default()
    };
    for seed in 0..20 {
        let e = estimate(
            &intervals(100 + seed, 200, true, true),
            &nominal(),
            &p,
            &CheckParams::default(),
        )
        .unwrap();
        for ((v, s), t) in values(&e).into_iter().zip(truth()) {
            z2.push(((v - t) / s).powi(2));
        }
    }
    let m = z2.iter().sum::<f64>() / z2.len() as f64;
    assert!((0.72..1.32).contains(&m), "mean z² {m}");
}

#[test]
fn estimates_the_noise_when_no_covariance_is_given() {
    let e = estimate(
        &intervals(7, 400, false, true),
        &nominal(),
        &BatchParams::default(),
        &CheckParams::default(),
    )
    .unwrap();
    for ((name, (v, s)), t) in NAMES.iter().zip(values(&e)).zip(truth()) {
        assert!((v - t).abs() < 4.0 * s, "{name}: {v} vs {t} (std {s})");
    }
    let n = e.noise_sigma.unwrap();
    // Outlier rounds trim the tails: the σ's come out somewhat under truth.
    for i in 0..3 {
        assert!(n[i] > 0.7 * SIGMA[i] && n[i] < 1.1 * SIGMA[i], "{n:?}");
    }
    assert!(e.dropped > 0);
}

#[test]
fn a_robot_that_never_turns_is_refused() {
    let err = estimate(
        &intervals(3, 200, true, false),
        &nominal(),
        &BatchParams::default(),
        &CheckParams::default(),
    )
    .unwrap_err();
    assert!(matches!(err, BatchError::Unobservable(_)), "{err}");
    assert!(err.to_string().contains("turn"), "{err}");
}

#[test]
fn swapped_wheels_are_refused() {
    let mut pb = intervals(4, 200, true, true);
    for iv in &mut pb.intervals {
        if let WheelMotion::Steps(s) = &mut iv.wheels {
            s.iter_mut().for_each(|x| x.swap(0, 1));
        }
    }
    let err = estimate(
        &pb,
        &nominal(),
        &BatchParams::default(),
        &CheckParams::default(),
    )
    .unwrap_err();
    assert!(matches!(err, BatchError::Implausible(_)), "{err}");
    assert!(
        err.to_string().contains("Swap left_joint and right_joint"),
        "{err}"
    );
    // One encoder counting backwards is named as such.
    let mut pb = intervals(4, 200, true, true);
    for iv in &mut pb.intervals {
        if let WheelMotion::Steps(s) = &mut iv.wheels {
            s.iter_mut().for_each(|x| x[0] = -x[0]);
        }
    }
    let err = estimate(
        &pb,
        &nominal(),
        &BatchParams::default(),
        &CheckParams::default(),
    )
    .unwrap_err();
    assert!(
        err.to_string().contains("left encoder counts backwards"),
        "{err}"
    );
}

/// A continuous drive (speed and turn rate as sums of sines) sampled by
/// wheel encoders at 50 Hz whose stamps are `delay` s late, and laser
/// displacements over 0.6 s intervals on the laser clock.
fn drive_with_delay(seed: u64, delay: f64) -> Problem {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let vw = |t: f64| {
        (
            0.3 + 0.25 * (0.7 * t).sin() + 0.1 * (2.3 * t).sin(),
            0.8 * (0.45 * t).sin() + 0.5 * (1.7 * t + 1.0).sin(),
        )
    };
    let dt = 1e-3;
    let (mut pose, mut left, mut right) = (Pose2::identity(), 0.0, 0.0);
    let mut poses = Vec::new();
    let mut track = WheelTrack::default();
    for i in 0..=60_000 {
        let t = i as f64 * dt;
        if i % 20 == 0 {
            track.t.push(t + delay);
            track.left.push(left);
            track.right.push(right);
        }
        if i % 600 == 0 {
            poses.push((t, pose));
        }
        // Midpoint rates over the millisecond.
        let (v, w) = vw(t + 0.5 * dt);
        pose *= geom::arc_increment(v, w, dt);
        left += (v - w * TRUE_B / 2.0) * dt / TRUE_L;
        right += (v + w * TRUE_B / 2.0) * dt / TRUE_R;
    }
    let c = nalgebra::Matrix3::from_diagonal(&SIGMA.map(|s| s * s).into());
    let intervals = poses
        .windows(2)
        .map(|w| {
            let s = laser_of(&(w[0].1.inverse() * w[1].1));
            let s = [0, 1, 2].map(|i| s[i] + SIGMA[i] * gauss(&mut rng));
            Interval {
                s,
                cov: Some(c),
                duration: w[1].0 - w[0].0,
                wheels: WheelMotion::Span {
                    t0: w[0].0,
                    t1: w[1].0,
                },
            }
        })
        .collect();
    Problem {
        intervals,
        track: Some(track),
    }
}

#[test]
fn recovers_the_time_offset_of_late_wheels() {
    let delay = 0.013;
    let e = estimate(
        &drive_with_delay(5, delay),
        &nominal(),
        &BatchParams::default(),
        &CheckParams::default(),
    )
    .unwrap();
    let d = e.time_offset.unwrap();
    assert!(
        (d.value - delay).abs() < 4.0 * d.std && d.std < 0.005,
        "{d:?}"
    );
    for ((name, (v, s)), t) in NAMES.iter().zip(values(&e)).zip(truth()) {
        assert!((v - t).abs() < 4.0 * s, "{name}: {v} vs {t} (std {s})");
    }
    assert_eq!(e.correlation.names.len(), 7);
}
