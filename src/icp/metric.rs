//! The point-to-line error of ICP and its Jacobian, shared by the
//! registration (its Gauss–Newton steps) and the covariance (the information
//! at the solution).
//!
//! A source point `p` (in its own frame) is matched to a reference line with
//! unit normal `n` through a point `a`. At the pose `(x, y, θ)`, i.e. rotation
//! `R(θ)` and translation `t = (x, y)`, the error is the signed distance of the
//! moved point from the line, along its normal:
//!
//! `e(x, y, θ) = nᵀ (R(θ) p + t − a)`
//!
//! Any point `a` of the line gives the same distance; the registration
//! measures it from the line's centroid, the covariance from the foot of the
//! correspondence. Its Jacobian with respect to `(x, y, θ)`, with
//! `∂(R p)/∂θ = (−(R p)_y, (R p)_x)`:
//!
//! `J = [n_x, n_y, −n_x (R p)_y + n_y (R p)_x]`
//!
//! The error moves only across the line: a point sliding along a wall
//! changes nothing, which is why a corridor leaves its axis unconstrained.
//!
//! The point-to-point error (`[icp] metric = "point-to-point"`) is the
//! distance `|x − q|` of the moved point from its nearest reference point
//! `q` itself, with the Jacobian `[I | ∂(R p)/∂θ]` of `x − q`. It is the
//! point-to-line error twice over: once along the unit vector `u` from `q`
//! to `x` (residual `|x − q|`) and once across it (residual 0, the same
//! sum of squares in any orthonormal basis). So the registration and the
//! covariance treat a point-to-point correspondence as a line through `q`
//! with normal `u`, plus a second row of normal `u⊥` ([`rows`]); a robust
//! kernel of the distance then weighs both rows alike.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Which error ICP minimises (`[icp] metric`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    /// Distance of the moved point from the nearest reference point's fitted
    /// line \[Censi2008, PL-ICP\].
    #[default]
    PointToLine,
    /// Distance of the moved point from the nearest reference point
    /// \[BeslMcKay1992\].
    PointToPoint,
}

/// The point-to-point error of the moved point `x` against the reference
/// point `q`: the unit vector `u` from `q` to `x` (any unit vector when
/// they coincide) and the distance `|x − q|` (m). As a point-to-line
/// correspondence: the line through `q` with normal `u`, residual `|x − q|`.
pub fn point_to_point(x: [f64; 2], q: [f64; 2]) -> ([f64; 2], f64) {
    let r = [x[0] - q[0], x[1] - q[1]];
    let d = r[0].hypot(r[1]);
    if d > 0.0 {
        ([r[0] / d, r[1] / d], d)
    } else {
        ([1.0, 0.0], 0.0)
    }
}

/// The rows `(normal, residual)` of one correspondence in `metric`, given its
/// normal `n` and residual `e` as the registration stores them (for
/// point-to-point, `u` and `|x − q|` of [`point_to_point`]): point-to-line
/// one row, point-to-point two (the second across `u`, residual 0).
pub fn rows(metric: Metric, n: [f64; 2], e: f64) -> ([([f64; 2], f64); 2], usize) {
    let across = ([-n[1], n[0]], 0.0);
    match metric {
        Metric::PointToLine => ([(n, e), across], 1),
        Metric::PointToPoint => ([(n, e), across], 2),
    }
}

/// A pose `[x, y, θ]` ready to move points: its rotation's sine and cosine
/// (computed once per pose) and its translation.
#[derive(Debug, Clone, Copy)]
pub struct Placement {
    s: f64,
    c: f64,
    t: [f64; 2],
}

/// A source point moved by a [`Placement`].
#[derive(Debug, Clone, Copy)]
pub struct Moved {
    /// `R p`: the point rotated (m).
    pub rp: [f64; 2],
    /// `R p + t`: the point in the reference frame (m).
    pub x: [f64; 2],
}

impl Placement {
    /// The placement of pose `[x, y, θ]` (m, rad).
    pub fn new(pose: [f64; 3]) -> Self {
        let (s, c) = pose[2].sin_cos();
        Self {
            s,
            c,
            t: [pose[0], pose[1]],
        }
    }

    /// `R v`: a vector (a point, a normal) rotated.
    pub fn rotate(&self, v: [f64; 2]) -> [f64; 2] {
        let (s, c) = (self.s, self.c);
        [c * v[0] - s * v[1], s * v[0] + c * v[1]]
    }

    /// `R p + t`: a point moved, with its rotated part.
    pub fn apply(&self, p: [f64; 2]) -> Moved {
        let rp = self.rotate(p);
        Moved {
            rp,
            x: [rp[0] + self.t[0], rp[1] + self.t[1]],
        }
    }
}

/// `∂(R p)/∂θ = (−(R p)_y, (R p)_x)` from the rotated point `rp`.
pub fn rotation_derivative(rp: [f64; 2]) -> [f64; 2] {
    [-rp[1], rp[0]]
}

/// `e = nᵀ (x − a)`: signed distance (m) of the moved point `x` from the line
/// through `a` with unit normal `n`.
pub fn residual(x: [f64; 2], a: [f64; 2], n: [f64; 2]) -> f64 {
    (x[0] - a[0]) * n[0] + (x[1] - a[1]) * n[1]
}

/// `J = [n_x, n_y, nᵀ ∂(R p)/∂θ]`: the error's Jacobian with respect to
/// `(x, y, θ)`, from the rotated point `rp` and the line's unit normal `n`.
pub fn jacobian(rp: [f64; 2], n: [f64; 2]) -> Vector3<f64> {
    let dth = rotation_derivative(rp);
    Vector3::new(n[0], n[1], n[0] * dth[0] + n[1] * dth[1])
}

/// The error `e` of the moved point `m` against the line through `a` with
/// unit normal `n`, and its Jacobian `J` (see the module's equations).
pub fn residual_and_jacobian(m: &Moved, a: [f64; 2], n: [f64; 2]) -> (f64, Vector3<f64>) {
    (residual(m.x, a, n), jacobian(m.rp, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quarter_turn_by_hand() {
        // (1, 0) turned a quarter left is (0, 1), then moved by (1, 2): (1, 3).
        let m = Placement::new([1.0, 2.0, std::f64::consts::FRAC_PI_2]).apply([1.0, 0.0]);
        let close =
            |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12;
        assert!(close(m.rp, [0.0, 1.0]) && close(m.x, [1.0, 3.0]), "{m:?}");
        // 3 m above the line y = 0 (normal (0, 1)) … and 0.5 m right of x = 0.5.
        let (e, j) = residual_and_jacobian(&m, [0.0, 0.0], [0.0, 1.0]);
        assert!((e - 3.0).abs() < 1e-12 && (j - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        let (e, j) = residual_and_jacobian(&m, [0.5, 7.0], [1.0, 0.0]);
        // Turning moves (0, 1) towards −x: ∂e/∂θ = −1.
        assert!((e - 0.5).abs() < 1e-12 && (j - Vector3::new(1.0, 0.0, -1.0)).norm() < 1e-12);
        assert_eq!(rotation_derivative([2.0, 3.0]), [-3.0, 2.0]);
        let r = Placement::new([0.0, 0.0, 0.3]).rotate([0.0, 1.0]);
        assert!(close(r, [-(0.3f64.sin()), 0.3f64.cos()]));
    }

    /// The two rows of a point-to-point correspondence carry the squared
    /// distance and the Gauss–Newton information `Jᵀ J` of `x − q` with
    /// `J = [I | ∂(R p)/∂θ]`, computed here by hand.
    #[test]
    fn point_to_point_rows_are_the_distance_and_its_full_jacobian() {
        let (p, q) = ([2.0, -1.0], [1.0, 0.5]);
        let at = Placement::new([0.3, -0.2, 0.5]);
        let m = at.apply(p);
        let (u, d) = point_to_point(m.x, q);
        let r = [m.x[0] - q[0], m.x[1] - q[1]];
        assert!((d * d - (r[0] * r[0] + r[1] * r[1])).abs() < 1e-12);
        assert!((u[0] * d - r[0]).abs() < 1e-12 && (u[1] * d - r[1]).abs() < 1e-12);
        let (rows2, n) = rows(Metric::PointToPoint, u, d);
        assert_eq!(n, 2);
        let mut h = nalgebra::Matrix3::zeros();
        let mut ss = 0.0;
        for &(nr, e) in &rows2[..n] {
            let j = jacobian(m.rp, nr);
            h += j * j.transpose();
            ss += e * e;
        }
        assert!((ss - d * d).abs() < 1e-12);
        // By hand: ∂(x − q)/∂(x, y, θ) = [[1, 0, −(Rp)_y], [0, 1, (Rp)_x]].
        let (a, b) = (-m.rp[1], m.rp[0]);
        let want = nalgebra::Matrix3::new(1.0, 0.0, a, 0.0, 1.0, b, a, b, a * a + b * b);
        assert!((h - want).norm() < 1e-12, "{h}");
        // Point-to-line keeps one row; coincident points give residual 0.
        assert_eq!(rows(Metric::PointToLine, u, d).1, 1);
        assert_eq!(point_to_point(q, q), ([1.0, 0.0], 0.0));
    }

    #[test]
    fn the_jacobian_is_the_derivative_of_the_residual() {
        let (p, a, n) = ([2.0, -1.0], [1.5, 0.3], [0.6, 0.8]);
        let pose = [0.2, -0.1, 0.4];
        let (e, j) = residual_and_jacobian(&Placement::new(pose).apply(p), a, n);
        for k in 0..3 {
            let h = 1e-6;
            let mut up = pose;
            up[k] += h;
            let eu = residual(Placement::new(up).apply(p).x, a, n);
            assert!(((eu - e) / h - j[k]).abs() < 1e-5, "{k}: {j}");
        }
    }
}
