//! Scan-to-scan motions into batch intervals: consecutive valid laser-frame
//! motions are composed until the interval lasts `interval_s` or turns
//! `interval_rad`, so that each interval excites the laser pose; the
//! covariance is composed to first order, Σ' = J₁ Σ J₁ᵀ + J₂ Σ_m J₂ᵀ with
//! the Jacobians of `a ⊕ b` (\[Censi2013\] uses ~1 s tuples for the same end).

use super::model::{oplus, P3};
use super::{Interval, WheelMotion};
use nalgebra::Matrix3;

/// One scan-to-scan motion of the laser in its own frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserMotion {
    /// Start and end (s, laser clock).
    pub t0: f64,
    /// End (s).
    pub t1: f64,
    /// Displacement `[x, y, θ]` (m, m, rad) in the laser frame at `t0`.
    pub s: P3,
    /// Its covariance.
    pub cov: Matrix3<f64>,
    /// Whether the match is trustworthy.
    pub valid: bool,
}

/// `a ⊕ b` with the first-order covariance of the composition.
fn compose(a: (P3, Matrix3<f64>), b: (P3, Matrix3<f64>)) -> (P3, Matrix3<f64>) {
    let (s, c) = a.0[2].sin_cos();
    let (x, y) = (b.0[0], b.0[1]);
    let j1 = Matrix3::new(
        1.0,
        0.0,
        -s * x - c * y,
        0.0,
        1.0,
        c * x - s * y,
        0.0,
        0.0,
        1.0,
    );
    let j2 = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    (
        oplus(a.0, b.0),
        j1 * a.1 * j1.transpose() + j2 * b.1 * j2.transpose(),
    )
}

/// Intervals of at least `min_s` seconds or `min_rad` of rotation, made of
/// consecutive valid motions without gaps (a failed match or a gap longer
/// than `max_gap_s` ends the interval; a shorter remainder is dropped).
pub fn aggregate(
    motions: &[LaserMotion],
    min_s: f64,
    min_rad: f64,
    max_gap_s: f64,
) -> Vec<Interval> {
    let mut out = Vec::new();
    let mut cur: Option<(f64, f64, P3, Matrix3<f64>)> = None;
    for m in motions {
        let joins = cur.is_some_and(|c| m.valid && (m.t0 - c.1).abs() <= max_gap_s);
        if !joins {
            cur = m.valid.then_some((m.t0, m.t1, m.s, m.cov));
        } else if let Some(c) = cur.as_mut() {
            let (s, cov) = compose((c.2, c.3), (m.s, m.cov));
            *c = (c.0, m.t1, s, cov);
        }
        if let Some(c) = cur {
            if c.1 - c.0 >= min_s || c.2[2].abs() >= min_rad {
                out.push(Interval {
                    s: [c.2[0], c.2[1], crate::geom::wrap_angle(c.2[2])],
                    cov: Some(c.3),
                    duration: c.1 - c.0,
                    wheels: WheelMotion::Span { t0: c.0, t1: c.1 },
                });
                cur = None;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn composition_and_its_covariance_match_nalgebra_and_sampling() {
        // Two motions: the composed mean against nalgebra's isometries.
        let a = (
            [0.1, 0.02, 0.3],
            Matrix3::from_diagonal(&[1e-4, 2e-4, 1e-3].into()),
        );
        let b = (
            [0.2, -0.05, -0.1],
            Matrix3::from_diagonal(&[3e-4, 1e-4, 2e-3].into()),
        );
        let (s, c) = compose(a, b);
        let na = crate::geom::pose(0.1, 0.02, 0.3) * crate::geom::pose(0.2, -0.05, -0.1);
        assert!((na.translation.x - s[0]).abs() < 1e-12 && (na.translation.y - s[1]).abs() < 1e-12);
        // Variance of y by hand: σ²_ya + (cos θ_a)²σ²_xb·… written out for
        // the y row: ∂y/∂θ_a = x_b cos θ_a − y_b sin θ_a.
        let (sn, cs) = 0.3f64.sin_cos();
        let dy_dth = 0.2 * cs + 0.05 * sn;
        let want = 2e-4 + dy_dth * dy_dth * 1e-3 + sn * sn * 3e-4 + cs * cs * 1e-4;
        assert!((c[(1, 1)] - want).abs() < 1e-15, "{} vs {want}", c[(1, 1)]);
    }

    #[test]
    fn intervals_break_at_failures_and_reach_the_duration() {
        let m = |t0: f64, valid: bool| LaserMotion {
            t0,
            t1: t0 + 0.1,
            s: [0.05, 0.0, 0.01],
            cov: Matrix3::identity() * 1e-6,
            valid,
        };
        let ms: Vec<LaserMotion> = (0..20).map(|i| m(i as f64 * 0.1, i != 7)).collect();
        let iv = aggregate(&ms, 0.5, 1.0, 0.05);
        // 0–6 → one of 0.5 s (0–4), 5–6 dropped at the failure; 8–19 → two.
        assert_eq!(iv.len(), 3, "{iv:?}");
        assert!(iv.iter().all(|i| (i.duration - 0.5).abs() < 1e-9));
        assert!((iv[0].s[0] - 0.25).abs() < 1e-3);
    }
}
