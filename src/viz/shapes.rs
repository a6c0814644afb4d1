//! Shapes the viewer draws from plain numbers: a covariance's ellipse as a
//! closed polygon, and which prefixes of a trajectory to log so that it
//! grows along the time line in bounded size.

use crate::geom::Pose2;

/// The outline (`n` points, closed: the first point repeated at the end) of
/// the `sigmas`-σ ellipse of the 2×2 covariance `cov` (m², in the frame of
/// `at`), magnified by `scale`, placed at `at` in the world. The semi-axes
/// are `sigmas · scale · √λ` along the eigenvectors of `cov`; a covariance
/// that is not positive semidefinite or not finite gives `None`.
pub fn ellipse(
    at: &Pose2,
    cov: [[f64; 2]; 2],
    sigmas: f64,
    scale: f64,
    n: usize,
) -> Option<Vec<[f64; 2]>> {
    let [[a, b], [b2, c]] = cov;
    let b = 0.5 * (b + b2);
    if ![a, b, c].iter().all(|v| v.is_finite()) {
        return None;
    }
    // Eigenvalues of the symmetric matrix [[a, b], [b, c]].
    let mean = 0.5 * (a + c);
    let diff = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let (l1, l2) = (mean + diff, mean - diff);
    if l2 < -1e-12 * l1.abs().max(1e-30) {
        return None;
    }
    let angle = 0.5 * (2.0 * b).atan2(a - c);
    let (r1, r2) = (
        sigmas * scale * l1.max(0.0).sqrt(),
        sigmas * scale * l2.max(0.0).sqrt(),
    );
    let n = n.max(4);
    let pts = (0..=n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * (k % n) as f64 / n as f64;
            let local = nalgebra::Point2::new(
                r1 * t.cos() * angle.cos() - r2 * t.sin() * angle.sin(),
                r1 * t.cos() * angle.sin() + r2 * t.sin() * angle.cos(),
            );
            let w = at * local;
            [w.x, w.y]
        })
        .collect();
    Some(pts)
}

/// The pose indices after which a trajectory of `len` poses is logged as
/// grown so far: at most `steps`, evenly spread, always the last.
pub fn growth_steps(len: usize, steps: usize) -> Vec<usize> {
    if len == 0 || steps == 0 {
        return Vec::new();
    }
    let steps = steps.min(len);
    let mut v: Vec<usize> = (1..=steps).map(|k| (k * len).div_ceil(steps) - 1).collect();
    v.dedup();
    v
}

/// Indices of at most `max` (≥ 2) of the first `upto + 1` poses: every k-th
/// and always the last, so a grown line ends where the robot is.
pub fn thin_prefix(upto: usize, max: usize) -> Vec<usize> {
    let n = upto + 1;
    let max = max.max(2);
    let stride = n.div_ceil(max - 1).max(1);
    let mut v: Vec<usize> = (0..n).step_by(stride).collect();
    if v.last() != Some(&upto) {
        v.push(upto);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pose;

    #[test]
    fn ellipse_axes_follow_the_eigenvectors() {
        // σx = 2 mm, σy = 1 mm, robot at (1, 2) turned 90°: the long axis
        // points along world y.
        let cov = [[4e-6, 0.0], [0.0, 1e-6]];
        let e = ellipse(
            &pose(1.0, 2.0, std::f64::consts::FRAC_PI_2),
            cov,
            1.0,
            100.0,
            8,
        )
        .unwrap();
        assert_eq!(e.len(), 9);
        assert_eq!(e[0], e[8]);
        let far = e.iter().map(|p| (p[1] - 2.0).abs()).fold(0.0, f64::max);
        let wide = e.iter().map(|p| (p[0] - 1.0).abs()).fold(0.0, f64::max);
        assert!((far - 0.2).abs() < 1e-9, "{far}");
        assert!((wide - 0.1).abs() < 1e-9, "{wide}");
        // A correlated covariance: the long axis at 45°.
        let e = ellipse(&Pose2::identity(), [[2.0, 1.0], [1.0, 2.0]], 1.0, 1.0, 360).unwrap();
        let r45 = e
            .iter()
            .map(|p| p[0] * p[0] + p[1] * p[1])
            .fold(0.0, f64::max);
        assert!((r45 - 3.0).abs() < 1e-3, "{r45}");
        assert!(ellipse(&Pose2::identity(), [[1.0, 2.0], [2.0, 1.0]], 1.0, 1.0, 8).is_none());
    }

    #[test]
    fn growth_reaches_the_last_pose_in_bounded_steps() {
        assert_eq!(growth_steps(5, 10), vec![0, 1, 2, 3, 4]);
        let g = growth_steps(1000, 7);
        assert_eq!(g.len(), 7);
        assert_eq!(*g.last().unwrap(), 999);
        assert!(g.windows(2).all(|w| w[0] < w[1]));
        let t = thin_prefix(999, 10);
        assert!(t.len() <= 11 && t[0] == 0 && *t.last().unwrap() == 999);
        assert_eq!(thin_prefix(2, 10), vec![0, 1, 2]);
    }
}
