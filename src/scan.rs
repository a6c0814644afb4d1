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
    /// The scan with a scanner's corrections: `angle_increment` (rad, the
    /// true spacing, its sign taken from the recording's) replaces the
    /// recorded one, scaling `angle_min` so that the beam at angle 0 stays
    /// there (a scanner whose beams span a wider arc than recorded, e.g. the
    /// LEGO robot's 660 beams); `range_offset` (m) is added to every valid
    /// range and to the validity limits, so no reading changes validity.
    pub fn corrected(&self, angle_increment: Option<f64>, range_offset: f64) -> LaserScan {
        let mut out = self.clone();
        if let Some(inc) = angle_increment {
            if self.angle_increment != 0.0 {
                let k = inc / self.angle_increment.abs();
                out.angle_min = self.angle_min * k;
                out.angle_increment = self.angle_increment * k;
            }
        }
        if range_offset != 0.0 {
            for r in out.ranges.iter_mut() {
                if self.is_valid_range(*r) {
                    *r += range_offset as f32;
                }
            }
            out.range_min += range_offset;
            out.range_max += range_offset;
        }
        out
    }

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

    /// Whether the scan's geometry makes physical sense, as a reader checks
    /// it after parsing: at least [`MIN_BEAMS`] beams, finite angles,
    /// `0 ≤ range_min < range_max`, and, when the message states its
    /// `angle_max` (rad), `angle_min + (n − 1)·angle_increment ≈ angle_max`
    /// within [`angle_tolerance`] with the increment's sign pointing from
    /// `angle_min` to `angle_max`. `Err` says what disagrees, with the values.
    pub fn check_geometry(&self, angle_max: Option<f64>) -> Result<(), String> {
        let n = self.ranges.len();
        if n < MIN_BEAMS {
            return Err(format!(
                "LaserScan with {n} beam(s): at least {MIN_BEAMS} are needed to match a scan"
            ));
        }
        if !(self.angle_min.is_finite() && self.angle_increment.is_finite()) {
            return Err(format!(
                "LaserScan angle_min {} or angle_increment {} is not finite",
                self.angle_min, self.angle_increment
            ));
        }
        if self.angle_increment == 0.0 {
            return Err(format!("LaserScan angle_increment is 0 with {n} beams"));
        }
        if !(self.range_min >= 0.0 && self.range_max > self.range_min) {
            return Err(format!(
                "LaserScan range limits make no sense: range_min {} m, range_max {} m \
                 (need 0 ≤ range_min < range_max)",
                self.range_min, self.range_max
            ));
        }
        let Some(angle_max) = angle_max else {
            return Ok(());
        };
        if !angle_max.is_finite() {
            return Err(format!("LaserScan angle_max is {angle_max}"));
        }
        if (angle_max - self.angle_min) * self.angle_increment < 0.0 {
            return Err(format!(
                "LaserScan angle_increment {} rad points away from angle_max: angle_min {} \
                 rad, angle_max {angle_max} rad",
                self.angle_increment, self.angle_min
            ));
        }
        let last = self.beam_angle(n - 1);
        let tol = angle_tolerance(self.angle_increment);
        if (last - angle_max).abs() > tol {
            return Err(format!(
                "LaserScan angles disagree with its {n} ranges: angle_min {} + ({n} − 1)·{} = \
                 {last:.6} rad, but angle_max = {angle_max:.6} rad (tolerance {tol:.6} rad: one \
                 increment, for CARMEN's π/n convention, + 1 mrad)",
                self.angle_min, self.angle_increment
            ));
        }
        Ok(())
    }
}

/// Fewest beams a scan may have: a line fitted through neighbouring beams
/// (the ICP's normals) needs three.
pub const MIN_BEAMS: usize = 3;

/// How far (rad) the last beam's angle may be from a stated `angle_max`:
/// one increment, because logs converted from CARMEN use increment = π/n
/// with the last beam one increment short of +90° while some state +90°,
/// plus 1 mrad for `f32` rounding of the angles.
pub fn angle_tolerance(increment: f64) -> f64 {
    increment.abs() + 1e-3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corrections_keep_the_centre_beam_and_move_valid_ranges_only() {
        let inc = std::f64::consts::TAU / 1024.0;
        let s = LaserScan {
            angle_min: -330.0 * inc,
            angle_increment: inc,
            range_min: 0.02,
            range_max: 5.6,
            ranges: vec![1.0, f32::NAN, f32::INFINITY, 0.01, 5.59, 2.0],
            ..Default::default()
        };
        let c = s.corrected(Some(1.03 * inc), 0.07);
        // Beam 330 stays at angle 0; beam 0 sits 330 true spacings right.
        assert!((c.angle_min + 330.0 * c.angle_increment).abs() < 1e-12);
        assert!((c.beam_angle(0) + 330.0 * 1.03 * inc).abs() < 1e-12);
        assert!((c.ranges[0] - 1.07).abs() < 1e-6 && (c.ranges[5] - 2.07).abs() < 1e-6);
        assert!(c.ranges[1].is_nan() && c.ranges[2] == f32::INFINITY);
        // Validity is unchanged: too close stays too close, the last valid
        // reading near range_max stays valid.
        let valid = |x: &LaserScan| {
            (0..6)
                .map(|i| x.is_valid_range(x.ranges[i]))
                .collect::<Vec<_>>()
        };
        assert_eq!(valid(&c), valid(&s));
        // A scan stated with a negative increment keeps its direction.
        let mirrored = LaserScan {
            angle_min: 330.0 * inc,
            angle_increment: -inc,
            ..s.clone()
        };
        let m = mirrored.corrected(Some(1.03 * inc), 0.0);
        assert!((m.angle_increment + 1.03 * inc).abs() < 1e-15);
        assert_eq!(m.ranges[0], 1.0);
    }

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
