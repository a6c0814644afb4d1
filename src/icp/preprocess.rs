//! Scan preprocessing: valid readings (REP 117, as [`LaserScan::is_valid_range`]
//! decides) within the configured range limits, placed in the robot base frame
//! with `base_from_laser`, plus the surface links between consecutive beams
//! (reference scans) or a thinned copy (source scans).

use crate::geom::Pose2;
use crate::scan::LaserScan;
use std::collections::HashSet;

/// Points of one scan in the base frame, in beam order, with the beam layout
/// they came from.
#[derive(Debug, Clone, Default)]
pub struct ScanPoints {
    /// Points (m) in the base frame.
    pub pts: Vec<[f64; 2]>,
    /// `link[j]`: points `j` and `j + 1` are consecutive beams on one surface,
    /// so the segment between them approximates that surface.
    pub link: Vec<bool>,
    /// Range (m) of each point from the laser.
    pub range: Vec<f64>,
}

/// Turns scans into base-frame points, caching the beam directions of the
/// last beam layout (so no trigonometry per scan in steady state).
#[derive(Debug, Clone)]
pub struct Preprocessor {
    base_from_laser: Pose2,
    min_range: f64,
    max_range: f64,
    gap_factor: f64,
    max_gap: f64,
    layout: (f64, f64, usize),
    dirs: Vec<[f64; 2]>,
    cells: HashSet<(i64, i64)>,
}

impl Preprocessor {
    /// A preprocessor for a laser mounted at `base_from_laser`, keeping ranges
    /// in [`min_range`, `max_range`] (m) and linking neighbours closer than
    /// `min(max_gap, gap_factor · range · beam spacing)`.
    pub fn new(
        base_from_laser: Pose2,
        min_range: f64,
        max_range: f64,
        gap_factor: f64,
        max_gap: f64,
    ) -> Self {
        Self {
            base_from_laser,
            min_range,
            max_range,
            gap_factor,
            max_gap,
            layout: (f64::NAN, f64::NAN, 0),
            dirs: Vec::new(),
            cells: HashSet::new(),
        }
    }

    /// Fills `out` with the scan's usable points. A scan with non-finite beam
    /// geometry yields no points.
    pub fn points(&mut self, scan: &LaserScan, out: &mut ScanPoints) {
        out.pts.clear();
        out.link.clear();
        out.range.clear();
        if !scan.angle_min.is_finite() || !scan.angle_increment.is_finite() {
            return;
        }
        let layout = (scan.angle_min, scan.angle_increment, scan.ranges.len());
        if layout != self.layout {
            let rot = self.base_from_laser.rotation;
            self.dirs.clear();
            self.dirs.extend((0..layout.2).map(|i| {
                let d = rot
                    * nalgebra::Vector2::new(scan.beam_angle(i).cos(), scan.beam_angle(i).sin());
                [d.x, d.y]
            }));
            self.layout = layout;
        }
        let o = self.base_from_laser.translation.vector;
        let spacing = scan.angle_increment.abs();
        let mut last: Option<(usize, f64)> = None;
        for (i, &r) in scan.ranges.iter().enumerate() {
            if !scan.is_valid_range(r) {
                continue;
            }
            let r = r as f64;
            if r < self.min_range || r > self.max_range {
                continue;
            }
            let d = self.dirs[i];
            let p = [o.x + r * d[0], o.y + r * d[1]];
            if let Some((li, lr)) = last {
                let q = out.pts[out.pts.len() - 1];
                let gap = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                let allowed =
                    (self.gap_factor * r.max(lr) * spacing * (i - li) as f64).min(self.max_gap);
                let n = out.link.len();
                out.link[n - 1] = i - li <= 2 && gap <= allowed;
            }
            out.pts.push(p);
            out.link.push(false);
            out.range.push(r);
            last = Some((i, r));
        }
    }

    /// Thins `src` into `out`: every `stride`-th point, then at most one point
    /// per `voxel` × `voxel` cell (first come, in beam order); `voxel = 0`
    /// keeps all.
    pub fn downsample(
        &mut self,
        src: &[[f64; 2]],
        stride: usize,
        voxel: f64,
        out: &mut Vec<[f64; 2]>,
    ) {
        out.clear();
        self.cells.clear();
        for p in src.iter().step_by(stride.max(1)) {
            if voxel > 0.0 {
                let key = ((p[0] / voxel).floor() as i64, (p[1] / voxel).floor() as i64);
                if !self.cells.insert(key) {
                    continue;
                }
            }
            out.push(*p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::pose;

    fn scan(ranges: Vec<f32>) -> LaserScan {
        LaserScan {
            angle_min: -0.1,
            angle_increment: 0.01,
            range_min: 0.5,
            range_max: 20.0,
            ranges,
            ..Default::default()
        }
    }

    #[test]
    fn invalid_readings_are_dropped_and_points_land_in_base_frame() {
        let mut pre =
            Preprocessor::new(pose(-0.45, 0.0, std::f64::consts::PI), 0.0, 10.0, 6.0, 0.5);
        let s = scan(vec![
            2.0,
            f32::NAN,
            2.0,
            f32::INFINITY,
            0.2,
            15.0,
            2.0,
            2.01,
        ]);
        let mut out = ScanPoints::default();
        pre.points(&s, &mut out);
        assert_eq!(out.pts.len(), 4);
        // beam 0 at −0.1 rad in a laser facing backwards, 0.45 m behind the axle
        let a: f64 = -0.1;
        assert!((out.pts[0][0] - (-0.45 - 2.0 * a.cos())).abs() < 1e-12);
        assert!((out.pts[0][1] - (-2.0 * a.sin())).abs() < 1e-12);
        // beams 0 and 2 are two spacings apart on one arc: linked; 2 → 6 is not.
        assert_eq!(out.link, vec![true, false, true, false]);
    }

    #[test]
    fn a_range_jump_breaks_the_surface_link() {
        let mut pre = Preprocessor::new(Pose2::identity(), 0.0, 30.0, 6.0, 0.5);
        let s = scan(vec![2.0, 2.0, 5.0, 5.0]);
        let mut out = ScanPoints::default();
        pre.points(&s, &mut out);
        assert_eq!(out.link, vec![true, false, true, false]);
    }

    #[test]
    fn voxel_downsampling_keeps_one_point_per_cell() {
        let mut pre = Preprocessor::new(Pose2::identity(), 0.0, 30.0, 6.0, 0.5);
        let src: Vec<[f64; 2]> = (0..100).map(|i| [i as f64 * 0.01, 0.0]).collect();
        let mut out = Vec::new();
        pre.downsample(&src, 1, 0.1, &mut out);
        assert_eq!(out.len(), 10);
        pre.downsample(&src, 3, 0.0, &mut out);
        assert_eq!(out.len(), 34);
    }
}
