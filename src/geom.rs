//! SE(2) poses on nalgebra's `Isometry2<f64>`: build, compose, invert, relate,
//! interpolate and wrap angles. Frames are named `parent_from_child` where it
//! matters (a pose maps child-frame points into the parent frame). Units: m, rad.

pub mod cells;

use nalgebra::{Isometry2, Point2, Vector2};
use std::f64::consts::PI;

/// A rigid 2D transform (rotation + translation), `parent_from_child`.
pub type Pose2 = Isometry2<f64>;

/// Wraps an angle into (−π, π] (rad).
pub fn wrap_angle(a: f64) -> f64 {
    if !a.is_finite() {
        return a;
    }
    let mut r = a % (2.0 * PI);
    if r <= -PI {
        r += 2.0 * PI;
    } else if r > PI {
        r -= 2.0 * PI;
    }
    r
}

/// Pose from x (m), y (m) and heading θ (rad).
pub fn pose(x: f64, y: f64, theta: f64) -> Pose2 {
    Isometry2::new(Vector2::new(x, y), theta)
}

/// `[x, y, θ]` of a pose, θ wrapped into (−π, π].
pub fn xyt(p: &Pose2) -> [f64; 3] {
    [
        p.translation.x,
        p.translation.y,
        wrap_angle(p.rotation.angle()),
    ]
}

/// Heading θ (rad) of a pose in (−π, π].
pub fn heading(p: &Pose2) -> f64 {
    p.rotation.angle()
}

/// `a ⊕ b`: apply `b` in the frame of `a` (`world_from_a * a_from_b`).
pub fn compose(a: &Pose2, b: &Pose2) -> Pose2 {
    a * b
}

/// The inverse transform (`child_from_parent`).
pub fn inverse(a: &Pose2) -> Pose2 {
    a.inverse()
}

/// The Jacobian of a map of planar pose vectors `[x, y, θ]` at `x`, by
/// central differences of step 1e-6 (what a covariance is carried through a
/// frame change with, to first order).
pub fn jacobian3(f: impl Fn([f64; 3]) -> [f64; 3], x: [f64; 3]) -> nalgebra::Matrix3<f64> {
    let mut j = nalgebra::Matrix3::zeros();
    for k in 0..3 {
        let (mut a, mut b) = (x, x);
        a[k] += 1e-6;
        b[k] -= 1e-6;
        let (fa, fb) = (f(a), f(b));
        for r in 0..3 {
            j[(r, k)] = (fa[r] - fb[r]) / 2e-6;
        }
    }
    j
}

/// Relative motion `inv(a) ⊕ b`: pose `b` expressed in the frame of `a`.
/// This is the relation convention of \[Kummerle2009\] (`delta = inv(x_t1) * x_t2`).
pub fn between(a: &Pose2, b: &Pose2) -> Pose2 {
    a.inv_mul(b)
}

/// Jacobians of `m = inv(a) ⊕ b` (as x, y, θ) with respect to the (x, y, θ)
/// of `a` and of `b`, all in the common parent frame.
pub fn between_jacobians(a: &Pose2, b: &Pose2) -> (nalgebra::Matrix3<f64>, nalgebra::Matrix3<f64>) {
    let (s, c) = heading(a).sin_cos();
    let m = between(a, b).translation.vector;
    let jb = nalgebra::Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
    let ja = nalgebra::Matrix3::new(-c, -s, m.y, s, -c, -m.x, 0.0, 0.0, -1.0);
    (ja, jb)
}

/// Interpolates between two poses at fraction `s` (0 → `a`, 1 → `b`): linear in
/// translation, shortest-arc in heading. `s` outside [0, 1] extrapolates.
pub fn interpolate(a: &Pose2, b: &Pose2, s: f64) -> Pose2 {
    let ta = a.translation.vector;
    let tb = b.translation.vector;
    let t = ta + (tb - ta) * s;
    let dth = wrap_angle(heading(b) - heading(a));
    pose(t.x, t.y, heading(a) + dth * s)
}

/// Exact pose increment of a body moving at constant forward speed `v` (m/s)
/// and turn rate `w` (rad/s) for `dt` seconds (arc, not Euler step).
pub fn arc_increment(v: f64, w: f64, dt: f64) -> Pose2 {
    let dth = w * dt;
    let ds = v * dt;
    // sin(x)/x and (1−cos x)/x with series near 0 for accuracy.
    let (a, b) = if dth.abs() < 1e-6 {
        (1.0 - dth * dth / 6.0, dth / 2.0 - dth * dth * dth / 24.0)
    } else {
        (dth.sin() / dth, (1.0 - dth.cos()) / dth)
    };
    pose(ds * a, ds * b, dth)
}

/// Inverse of [`arc_increment`]: the constant (v·dt, w·dt) that produce a given
/// increment, i.e. the arc length (m, signed) and heading change (rad).
pub fn arc_of_increment(d: &Pose2) -> (f64, f64) {
    let [dx, dy, dth] = xyt(d);
    let chord = (dx * dx + dy * dy).sqrt();
    let sign = if dx < 0.0 { -1.0 } else { 1.0 };
    let factor = if dth.abs() < 1e-6 {
        1.0 + dth * dth / 24.0
    } else {
        (dth / 2.0) / (dth / 2.0).sin()
    };
    (sign * chord * factor, dth)
}

/// Maps a point from the child frame into the parent frame of `p`.
pub fn transform_point(p: &Pose2, q: &Point2<f64>) -> Point2<f64> {
    p * q
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn between_jacobians_match_central_differences() {
        let p = random_poses(20, 7);
        for w in p.windows(2) {
            let (ja, jb) = between_jacobians(&w[0], &w[1]);
            let [a, b] = [xyt(&w[0]), xyt(&w[1])];
            let m = |x: [f64; 3], y: [f64; 3]| {
                xyt(&between(&pose(x[0], x[1], x[2]), &pose(y[0], y[1], y[2])))
            };
            let na = jacobian3(|x| m(x, b), a);
            let nb = jacobian3(|y| m(a, y), b);
            assert!(
                (ja - na).norm() < 1e-6 && (jb - nb).norm() < 1e-6,
                "{ja} {na} {jb} {nb}"
            );
        }
    }

    fn random_poses(n: usize, seed: u64) -> Vec<Pose2> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                pose(
                    rng.random_range(-50.0..50.0),
                    rng.random_range(-50.0..50.0),
                    rng.random_range(-PI..PI),
                )
            })
            .collect()
    }

    fn close(a: &Pose2, b: &Pose2, tol: f64) -> bool {
        let d = between(a, b);
        d.translation.vector.norm() < tol && heading(&d).abs() < tol
    }

    #[test]
    fn group_laws_hold_over_many_random_poses() {
        let ps = random_poses(300, 7);
        assert!(ps.len() >= 300, "law suite needs examples");
        let id = Pose2::identity();
        for w in ps.windows(3) {
            let (a, b, c) = (&w[0], &w[1], &w[2]);
            assert!(close(
                &compose(&compose(a, b), c),
                &compose(a, &compose(b, c)),
                1e-9
            ));
            assert!(close(&compose(a, &inverse(a)), &id, 1e-9));
            assert!(close(&compose(&inverse(a), a), &id, 1e-9));
            assert!(close(&compose(a, &between(a, b)), b, 1e-9));
            assert!(close(&inverse(&inverse(a)), a, 1e-12));
            let [x, y, t] = xyt(a);
            assert!(close(&pose(x, y, t), a, 1e-12));
            assert!(close(&interpolate(a, b, 0.0), a, 1e-9));
            assert!(close(&interpolate(a, b, 1.0), b, 1e-9));
        }
    }

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        for k in -20..=20 {
            let a = 0.3 + k as f64 * 2.0 * PI;
            assert!((wrap_angle(a) - 0.3).abs() < 1e-9);
        }
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-12);
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-9);
        assert!(wrap_angle(f64::NAN).is_nan());
    }

    #[test]
    fn interpolation_takes_the_short_way_round() {
        let a = pose(0.0, 0.0, 3.0);
        let b = pose(2.0, 0.0, -3.0);
        let m = interpolate(&a, &b, 0.5);
        assert!((m.translation.x - 1.0).abs() < 1e-12);
        assert!((wrap_angle(heading(&m) - PI)).abs() < 1e-9);
    }

    #[test]
    fn arc_increment_round_trips_and_matches_euler_for_small_steps() {
        let mut rng = StdRng::seed_from_u64(3);
        for _ in 0..500 {
            let v = rng.random_range(-1.5..1.5);
            let w = rng.random_range(-2.0..2.0);
            let dt = rng.random_range(0.001..1.0);
            let d = arc_increment(v, w, dt);
            let (ds, dth) = arc_of_increment(&d);
            assert!((ds - v * dt).abs() < 1e-9, "{ds} vs {}", v * dt);
            assert!((dth - w * dt).abs() < 1e-12);
            // Many small Euler steps converge to the arc.
            let n = 2000;
            let mut p = Pose2::identity();
            for _ in 0..n {
                let h = heading(&p);
                let s = dt / n as f64;
                p = pose(
                    p.translation.x + v * s * h.cos(),
                    p.translation.y + v * s * h.sin(),
                    h + w * s,
                );
            }
            assert!(close(&p, &d, 1e-3 * (1.0 + v.abs())));
        }
    }
}
