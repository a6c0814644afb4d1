//! Scan preprocessing: valid readings (REP 117, as [`LaserScan::is_valid_range`]
//! decides) within the configured range limits, placed in the robot base frame
//! with `base_from_laser`, plus the surface links between consecutive beams
//! (reference scans) or a thinned copy (source scans).

use crate::geom::{self, Pose2};
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
    ///
    /// `twist` = `(v, ω)` (m/s, rad/s) is the base's velocity during the
    /// sweep: beam `i` is measured `i · time_increment` s after the stamp,
    /// from wherever the base has moved by then, so each point is carried
    /// back into the base frame at the stamp (motion compensation, as every
    /// rotating scanner needs while the robot moves). Without it, or when the
    /// scan states no positive finite `time_increment`, points stay as measured.
    pub fn points(&mut self, scan: &LaserScan, twist: Option<(f64, f64)>, out: &mut ScanPoints) {
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
        let dt_beam = scan.time_increment;
        let twist = twist.filter(|(v, w)| {
            dt_beam.is_finite() && dt_beam > 0.0 && v.is_finite() && w.is_finite()
        });
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
            let mut p = [o.x + r * d[0], o.y + r * d[1]];
            if let Some((v, w)) = twist {
                p = carry_back(p, v, w, i as f64 * dt_beam);
            }
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
    /// keeps all. `kept` gets the index in `src` of every point kept.
    pub fn downsample(
        &mut self,
        src: &[[f64; 2]],
        stride: usize,
        voxel: f64,
        out: &mut Vec<[f64; 2]>,
        kept: &mut Vec<usize>,
    ) {
        out.clear();
        kept.clear();
        if stride <= 1 && voxel <= 0.0 {
            // Nothing thinned (the default): all of `src`, in one copy.
            out.extend_from_slice(src);
            kept.extend(0..src.len());
            return;
        }
        self.cells.clear();
        for (i, p) in src.iter().enumerate().step_by(stride.max(1)) {
            if voxel > 0.0 {
                let key = ((p[0] / voxel).floor() as i64, (p[1] / voxel).floor() as i64);
                if !self.cells.insert(key) {
                    continue;
                }
            }
            out.push(*p);
            kept.push(i);
        }
    }
}

/// Maps point `p`, measured `tau` s after the stamp while the base moves at
/// `(v, w)` on a constant-velocity arc, into the base frame at the stamp.
/// Series for the small sweep angles of real scans (no trigonometry per
/// point), exact formula beyond.
#[inline]
fn carry_back(p: [f64; 2], v: f64, w: f64, tau: f64) -> [f64; 2] {
    let th = w * tau;
    let (s, c, sinc, cosc) = if th.abs() < 0.2 {
        let t2 = th * th;
        let sinc = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0));
        // (1 − cos θ) / θ
        let cosc = th / 2.0 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0)));
        (th * sinc, 1.0 - th * cosc, sinc, cosc)
    } else {
        let inc = geom::arc_increment(v, w, tau);
        let (s, c) = (inc.rotation.sin_angle(), inc.rotation.cos_angle());
        let ds = v * tau;
        (s, c, inc.translation.x / ds, inc.translation.y / ds)
    };
    let ds = v * tau;
    let (tx, ty) = if ds == 0.0 {
        (0.0, 0.0)
    } else {
        (ds * sinc, ds * cosc)
    };
    [c * p[0] - s * p[1] + tx, s * p[0] + c * p[1] + ty]
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
        pre.points(&s, None, &mut out);
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
        pre.points(&s, None, &mut out);
        assert_eq!(out.link, vec![true, false, true, false]);
    }

    #[test]
    fn carrying_back_matches_the_exact_arc() {
        for (v, w, tau) in [
            (1.0, 0.0, 0.03),
            (0.8, 0.6, 0.03),
            (-0.5, -2.5, 0.05),
            (1.0, 10.0, 0.1),
        ] {
            let p = [1.3, -2.1];
            let inc = geom::arc_increment(v, w, tau);
            let want = inc * nalgebra::Point2::new(p[0], p[1]);
            let got = carry_back(p, v, w, tau);
            assert!((got[0] - want.x).abs() < 1e-12 && (got[1] - want.y).abs() < 1e-12);
        }
    }

    #[test]
    fn voxel_downsampling_keeps_one_point_per_cell() {
        let mut pre = Preprocessor::new(Pose2::identity(), 0.0, 30.0, 6.0, 0.5);
        let src: Vec<[f64; 2]> = (0..100).map(|i| [i as f64 * 0.01, 0.0]).collect();
        let (mut out, mut kept) = (Vec::new(), Vec::new());
        pre.downsample(&src, 1, 0.1, &mut out, &mut kept);
        assert_eq!(out.len(), 10);
        assert_eq!(kept[1], 10);
        pre.downsample(&src, 3, 0.0, &mut out, &mut kept);
        assert_eq!(out.len(), 34);
        assert_eq!(kept[1], 3);
        // no thinning at all: every point, each at its own index
        pre.downsample(&src, 1, 0.0, &mut out, &mut kept);
        assert_eq!(out, src);
        assert!(kept.iter().enumerate().all(|(i, &k)| i == k) && kept.len() == 100);
    }
}
