//! A 2D laser scan as ROS `sensor_msgs/LaserScan` defines it, and its conversion
//! to Cartesian points. Invalid ranges (REP 117: NaN, ±inf, or outside
//! [range_min, range_max]) never become points.

use nalgebra::Point2;

/// One laser scan in the laser frame (beam angle 0 = laser x axis, CCW positive).
#[derive(Debug, Clone, PartialEq)]
pub struct LaserScan {
    /// Acquisition time of the first beam (s).
    pub stamp: f64,
    /// Angle of the first beam (rad).
    pub angle_min: f64,
    /// Angle between consecutive beams (rad, may be negative).
    pub angle_increment: f64,
    /// Time between beams (s), 0 when unknown.
    pub time_increment: f64,
    /// Time between scans (s), 0 when unknown.
    pub scan_time: f64,
    /// Smallest valid range (m).
    pub range_min: f64,
    /// Largest valid range (m).
    pub range_max: f64,
    /// Measured ranges (m), one per beam.
    pub ranges: Vec<f32>,
}

impl Default for LaserScan {
    fn default() -> Self {
        Self {
            stamp: 0.0,
            angle_min: 0.0,
            angle_increment: 0.0,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.0,
            range_max: f64::INFINITY,
            ranges: Vec::new(),
        }
    }
}

impl LaserScan {
    /// Angle (rad) of beam `i` in the laser frame.
    pub fn beam_angle(&self, i: usize) -> f64 {
        self.angle_min + i as f64 * self.angle_increment
    }

    /// Whether a range reading is a real echo (REP 117).
    pub fn is_valid_range(&self, r: f32) -> bool {
        let r = r as f64;
        r.is_finite() && r >= self.range_min && r <= self.range_max
    }

    /// Number of valid readings.
    pub fn valid_count(&self) -> usize {
        self.ranges
            .iter()
            .filter(|&&r| self.is_valid_range(r))
            .count()
    }

    /// Valid readings as points (m) in the laser frame, in beam order.
    pub fn points(&self) -> Vec<Point2<f64>> {
        let mut out = Vec::with_capacity(self.ranges.len());
        self.points_into(&mut out);
        out
    }

    /// Like [`points`](Self::points) but reusing `out` (cleared first).
    pub fn points_into(&self, out: &mut Vec<Point2<f64>>) {
        out.clear();
        if !self.angle_min.is_finite() || !self.angle_increment.is_finite() {
            return;
        }
        for (i, &r) in self.ranges.iter().enumerate() {
            if self.is_valid_range(r) {
                let a = self.beam_angle(i);
                let r = r as f64;
                out.push(Point2::new(r * a.cos(), r * a.sin()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_ranges_never_become_points() {
        let s = LaserScan {
            angle_min: -1.0,
            angle_increment: 0.5,
            range_min: 0.5,
            range_max: 20.0,
            ranges: vec![
                1.0,
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                0.2,
                25.0,
                2.0,
            ],
            ..Default::default()
        };
        let p = s.points();
        assert_eq!(p.len(), 2);
        assert_eq!(s.valid_count(), 2);
        assert!((p[0].x - (-1.0f64).cos()).abs() < 1e-12);
        assert!((p[1].y - 2.0 * (2.0f64).sin()).abs() < 1e-9);
    }

    #[test]
    fn nan_geometry_gives_no_points() {
        let s = LaserScan {
            angle_increment: f64::NAN,
            range_max: 10.0,
            ranges: vec![1.0; 10],
            ..Default::default()
        };
        assert!(s.points().is_empty());
    }
}
