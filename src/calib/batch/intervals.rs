//! Scan-to-scan motions into batch intervals: consecutive valid laser-frame
//! motions are composed until the interval lasts `interval_s` or turns
//! `interval_rad`, so that each interval excites the laser pose; the
//! covariance is composed to first order, Σ' = J₁ Σ J₁ᵀ + J₂ Σ_m J₂ᵀ with
//! the Jacobians of `a ⊕ b` (\[Censi2013\] uses ~1 s tuples for the same end).
//! [`IntervalBuilder`] does it one motion at a time, as they come off the
//! scan matcher; [`aggregate`] is the same over a whole list.

use super::model::{oplus, P3};
use super::{Interval, WheelMotion};
use crate::geom::Pose2;
use crate::motion::{Motion, MIN_SCAN_SHARE};
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

impl LaserMotion {
    /// The laser's own displacement `M⁻¹ ⊕ x ⊕ M` of a base-frame motion
    /// matched with the mounting `M`, where `x` is the scan's own estimate
    /// ([`Motion::scan_measured`]: never the part the matcher's odometry
    /// prior supplied, which would feed the nominal model back into its own
    /// calibration); its covariance is carried by the Jacobian of that map
    /// (the adjoint of `M⁻¹`, by central differences). A failed pair, or one
    /// whose forward motion the scan measured less than [`MIN_SCAN_SHARE`] of
    /// (a corridor's axis), is not valid: it ends an interval.
    pub fn from_motion(m: &Motion, mount: &Pose2) -> Self {
        let (x0, share) = m.scan_measured();
        let f = |x: [f64; 3]| {
            let p = mount.inverse() * crate::geom::pose(x[0], x[1], x[2]) * mount;
            [p.translation.x, p.translation.y, p.rotation.angle()]
        };
        let j = crate::geom::jacobian3(f, x0);
        Self {
            t0: m.t0,
            t1: m.t1,
            s: f(x0),
            cov: j * m.cov * j.transpose(),
            valid: m.failure.is_none() && share >= MIN_SCAN_SHARE,
        }
    }
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

/// Composes consecutive valid motions into intervals of at least `min_s`
/// seconds or `min_rad` of rotation, one motion at a time; a failed match or
/// a gap longer than `max_gap_s` ends the interval, and a shorter remainder
/// is dropped. `min_s = 0` makes every valid motion its own interval.
#[derive(Debug, Clone)]
pub struct IntervalBuilder {
    min_s: f64,
    min_rad: f64,
    max_gap_s: f64,
    cur: Option<(f64, f64, P3, Matrix3<f64>)>,
}

impl IntervalBuilder {
    /// A builder of intervals of `min_s` (s) or `min_rad` (rad).
    pub fn new(min_s: f64, min_rad: f64, max_gap_s: f64) -> Self {
        Self {
            min_s,
            min_rad,
            max_gap_s,
            cur: None,
        }
    }

    /// Adds the next motion (in time order); the interval it completes, if any.
    pub fn push(&mut self, m: &LaserMotion) -> Option<Interval> {
        let joins = self
            .cur
            .is_some_and(|c| m.valid && (m.t0 - c.1).abs() <= self.max_gap_s);
        if !joins {
            self.cur = m.valid.then_some((m.t0, m.t1, m.s, m.cov));
        } else if let Some(c) = self.cur.as_mut() {
            let (s, cov) = compose((c.2, c.3), (m.s, m.cov));
            *c = (c.0, m.t1, s, cov);
        }
        let c = self.cur?;
        if !(c.1 - c.0 >= self.min_s || c.2[2].abs() >= self.min_rad) {
            return None;
        }
        self.cur = None;
        Some(Interval {
            s: [c.2[0], c.2[1], crate::geom::wrap_angle(c.2[2])],
            cov: Some(c.3),
            duration: c.1 - c.0,
            wheels: WheelMotion::Span { t0: c.0, t1: c.1 },
        })
    }
}

/// [`IntervalBuilder`] over a whole list of motions.
pub fn aggregate(
    motions: &[LaserMotion],
    min_s: f64,
    min_rad: f64,
    max_gap_s: f64,
) -> Vec<Interval> {
    let mut b = IntervalBuilder::new(min_s, min_rad, max_gap_s);
    motions.iter().filter_map(|m| b.push(m)).collect()
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
