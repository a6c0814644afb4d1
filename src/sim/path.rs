//! A planned path: densely sampled points (m, world frame) with arc length,
//! tangent heading and curvature, plus the speed the chair may drive there.

use super::world::World;
use super::SimError;
use crate::geom::wrap_angle;
use nalgebra::Point2;

/// Spacing (m) of the path samples.
const STEP: f64 = 0.02;

/// A sampled path, open or closed (the last sample then joins the first).
#[derive(Debug, Clone)]
pub struct Path {
    /// Sample positions (m).
    pub points: Vec<Point2<f64>>,
    /// Arc length (m) at each sample.
    pub s: Vec<f64>,
    /// Tangent heading (rad) at each sample.
    pub heading: Vec<f64>,
    /// Signed curvature (1/m, left turns positive) at each sample.
    pub curvature: Vec<f64>,
    /// Speed limit (m/s) at each sample, with braking ahead of curves.
    pub speed: Vec<f64>,
    /// Whether the path loops.
    pub closed: bool,
    /// Total length (m), including the closing stretch of a closed path.
    pub length: f64,
}

impl Path {
    /// A path through `waypoints` with corners rounded by arcs of `radius` (m),
    /// shrunk where the legs are too short. A closed path starts and ends in
    /// the middle of the first leg.
    pub fn rounded(waypoints: &[[f64; 2]], radius: f64, closed: bool) -> Result<Self, SimError> {
        let w: Vec<Point2<f64>> = waypoints.iter().map(|p| Point2::new(p[0], p[1])).collect();
        if w.len() < 2 || w.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(SimError::Scenario(
                "a path needs at least two finite waypoints".into(),
            ));
        }
        if w.windows(2).any(|p| (p[1] - p[0]).norm() < 0.1)
            || (closed && (w[0] - w[w.len() - 1]).norm() < 0.1)
        {
            return Err(SimError::Scenario(
                "consecutive waypoints must be at least 0.1 m apart".into(),
            ));
        }
        // Vertex chain: interior vertices get rounded corners.
        let chain: Vec<Point2<f64>> = if closed {
            let mid = Point2::from((w[0].coords + w[1].coords) / 2.0);
            let mut c = vec![mid];
            c.extend_from_slice(&w[1..]);
            c.push(w[0]);
            c.push(mid);
            c
        } else {
            w
        };
        let mut pts = vec![chain[0]];
        let mut cursor = chain[0];
        for i in 1..chain.len() - 1 {
            let (a, b, c) = (chain[i - 1], chain[i], chain[i + 1]);
            let (u1, u2) = ((b - a).normalize(), (c - b).normalize());
            let turn = wrap_angle(u2.y.atan2(u2.x) - u1.y.atan2(u1.x));
            if turn.abs() < 1e-9 {
                continue;
            }
            let half = (turn.abs() / 2.0).tan();
            let t = (radius * half)
                .min(0.45 * (b - a).norm())
                .min(0.45 * (c - b).norm());
            let r = t / half;
            let t1 = b - u1 * t;
            line(&mut pts, cursor, t1);
            let n1 = nalgebra::Vector2::new(-u1.y, u1.x) * turn.signum();
            let centre = t1 + n1 * r;
            let a0 = (t1 - centre).y.atan2((t1 - centre).x);
            let n = ((r * turn.abs()) / STEP).ceil().max(1.0) as usize;
            for k in 1..=n {
                let a = a0 + turn * k as f64 / n as f64;
                pts.push(centre + nalgebra::Vector2::new(a.cos(), a.sin()) * r);
            }
            cursor = *pts.last().unwrap();
        }
        line(&mut pts, cursor, chain[chain.len() - 1]);
        if closed {
            pts.pop(); // the start sample closes the loop
        }
        Self::from_points(pts, closed)
    }

    /// A path through dense samples (spacing ≲ 0.05 m); heading and curvature
    /// by central differences.
    pub fn from_points(points: Vec<Point2<f64>>, closed: bool) -> Result<Self, SimError> {
        let n = points.len();
        if n < 3 {
            return Err(SimError::Scenario("a path needs at least 3 samples".into()));
        }
        let mut s = vec![0.0; n];
        for i in 1..n {
            s[i] = s[i - 1] + (points[i] - points[i - 1]).norm();
        }
        let length = s[n - 1]
            + if closed {
                (points[0] - points[n - 1]).norm()
            } else {
                0.0
            };
        let idx = |i: isize| -> usize {
            if closed {
                i.rem_euclid(n as isize) as usize
            } else {
                i.clamp(0, n as isize - 1) as usize
            }
        };
        let dir = |i: usize, j: usize| {
            let d = points[j] - points[i];
            d.y.atan2(d.x)
        };
        let raw: Vec<f64> = (0..n as isize)
            .map(|i| dir(idx(i - 1), idx(i + 1)))
            .collect();
        // Unwrap so the heading is continuous along the path.
        let mut heading = raw.clone();
        for i in 1..n {
            heading[i] = heading[i - 1] + wrap_angle(raw[i] - raw[i - 1]);
        }
        let curvature = (0..n as isize)
            .map(|i| {
                let (a, b) = (idx(i - 1), idx(i + 1));
                let ds = (points[idx(i)] - points[a]).norm() + (points[b] - points[idx(i)]).norm();
                if a == b || ds <= 0.0 {
                    0.0
                } else {
                    wrap_angle(raw[b] - raw[a]) / ds
                }
            })
            .collect();
        Ok(Self {
            points,
            s,
            heading,
            curvature,
            speed: vec![0.0; n],
            closed,
            length,
        })
    }

    /// Sets the speed limit: `min(cruise, turn_rate / |κ|)` (m/s), then brakes
    /// ahead of slow stretches at `decel` (m/s²); an open path ends at rest.
    pub fn plan_speed(&mut self, cruise: f64, turn_rate: f64, decel: f64) {
        let n = self.points.len();
        // Curvature over a short window so arcs entered soon already slow us.
        let window = 10;
        for i in 0..n {
            let mut k = 0.0f64;
            for j in 0..=2 * window {
                let idx = if self.closed {
                    (i + j + n - window) % n
                } else {
                    (i + j).saturating_sub(window).min(n - 1)
                };
                k = k.max(self.curvature[idx].abs());
            }
            self.speed[i] = cruise.min(turn_rate / k.max(1e-9));
        }
        if !self.closed {
            self.speed[n - 1] = 0.0;
        }
        let passes = if self.closed { 2 } else { 1 };
        for _ in 0..passes {
            for i in (0..n).rev() {
                let j = i + 1;
                let (next_v, ds) = if j < n {
                    (self.speed[j], self.s[j] - self.s[i])
                } else if self.closed {
                    (self.speed[0], self.length - self.s[i])
                } else {
                    continue;
                };
                self.speed[i] = self.speed[i].min((next_v * next_v + 2.0 * decel * ds).sqrt());
            }
        }
    }

    /// The smallest distance (m) from any sample to a wall.
    pub fn clearance(&self, world: &World) -> f64 {
        self.points
            .iter()
            .step_by(2)
            .map(|p| world.distance(*p))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Appends samples from `a` (exclusive) to `b` (inclusive) every ≤ STEP m.
fn line(pts: &mut Vec<Point2<f64>>, a: Point2<f64>, b: Point2<f64>) {
    let n = ((b - a).norm() / STEP).ceil() as usize;
    for k in 1..=n {
        pts.push(a + (b - a) * (k as f64 / n as f64));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounded_square_has_expected_length_and_curvature() {
        let r = 1.0;
        let p = Path::rounded(
            &[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]],
            r,
            true,
        )
        .unwrap();
        let expected = 40.0 - 4.0 * (2.0 * r) + 4.0 * (std::f64::consts::FRAC_PI_2 * r);
        assert!(
            (p.length - expected).abs() < 1e-3,
            "{} vs {expected}",
            p.length
        );
        let kmax = p.curvature.iter().cloned().fold(0.0, f64::max);
        assert!((kmax - 1.0 / r).abs() < 0.02, "{kmax}");
        assert!(p.curvature.iter().all(|k| *k > -1e-6), "counter-clockwise");
        let total_turn = p.heading[p.heading.len() - 1] - p.heading[0];
        assert!((total_turn - 2.0 * std::f64::consts::PI).abs() < 0.01);
    }

    #[test]
    fn speed_plan_brakes_before_corners_and_stops_at_open_end() {
        let mut p = Path::rounded(&[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]], 1.0, false).unwrap();
        p.plan_speed(0.8, 0.5, 0.4);
        assert_eq!(*p.speed.last().unwrap(), 0.0);
        let at = |x: f64| {
            let i = p.points.iter().position(|q| q.x >= x).unwrap();
            p.speed[i]
        };
        assert!((at(3.0) - 0.8).abs() < 1e-9);
        assert!(at(9.5) <= 0.5 + 1e-9);
        for w in p.speed.windows(2).zip(p.s.windows(2)) {
            let (v, s) = w;
            assert!(v[1] * v[1] - v[0] * v[0] >= -2.0 * 0.4 * (s[1] - s[0]) - 1e-9);
        }
    }
}
