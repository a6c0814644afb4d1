//! What a scan is matched against: points in a fixed frame with their surface
//! links, a local line fitted through every point's surface neighbourhood, and
//! a nearest-neighbour index (`neighbours`: kiddo's k-d tree or the grid);
//! all built once per reference (never per iteration).
//!
//! Why fitted lines rather than the polyline through the raw points: range
//! noise turns the polyline into a zigzag whose segments tilt by
//! ~σ√2 / spacing (12 mm over the 2–4 cm between LMS111 beams: 0.3–0.6 rad).
//! Source points then slide along that zigzag, and the optimum is pulled
//! towards the reference's sampling: on simulated LMS111 scans the motion
//! came out ~2 % short in translation and rotation, almost entirely from the
//! reference noise. A line fitted through `2k + 1` linked neighbours averages
//! the noise out of both its position and its direction.

use super::metric;
use super::neighbours::{NeighbourIndex, NeighbourSearch};
use super::preprocess::ScanPoints;

/// The local surface of one reference point.
#[derive(Debug, Clone, Copy, Default)]
struct Line {
    /// Centroid of the fitted neighbourhood (m).
    c: [f64; 2],
    /// Unit normal of the fitted line.
    n: [f64; 2],
    /// Unit tangent, oriented along increasing beam index.
    t: [f64; 2],
    /// Whether the surface continues before / after this point.
    before: bool,
    after: bool,
    /// Whether a usable line was fitted.
    ok: bool,
    /// Whether a line was fitted at all (`ok` also needs its scatter within
    /// the reference's limit).
    fitted: bool,
    /// Whether its score counts towards the reference's typical scatter
    /// (windows of at least 3 points).
    scored: bool,
    /// Mean squared distance of the fitted points from the line (m²).
    score: f64,
    /// Spread of the fitted points along the line, `Σ (tᵀ (p − c))²` (m²):
    /// with the scatter across it, the variance of the line's direction.
    spread: f64,
}

impl Line {
    /// The line moved by the rotation (`c`, `s` = cos, sin) and translation
    /// `t`.
    fn moved(&self, c: f64, s: f64, t: [f64; 2]) -> Self {
        let rot = |v: [f64; 2]| [c * v[0] - s * v[1], s * v[0] + c * v[1]];
        let rc = rot(self.c);
        Self {
            c: [rc[0] + t[0], rc[1] + t[1]],
            n: rot(self.n),
            t: rot(self.t),
            ..*self
        }
    }
}

/// Lines scattering more than this factor times the scan's median mean
/// squared fit distance are not used.
const SCATTER_LIMIT: f64 = 9.0;
/// Floor of the typical fit scatter (m), for noise-free scans.
const MIN_SCATTER: f64 = 1e-3;

/// A reference point set with its local lines and nearest-neighbour index.
#[derive(Default)]
pub struct Reference {
    pts: Vec<[f64; 2]>,
    link: Vec<bool>,
    lines: Vec<Line>,
    /// Nearest-neighbour index over `pts` (empty until built).
    index: NeighbourIndex,
    /// Most points after the first in one line fit.
    window: usize,
    /// Surface length (m) a line fit should span; 0 = always `window`.
    length: f64,
    /// Mean squared fit distances of the lines as [`total_key`]s (scratch
    /// for the median: integer comparisons).
    scatter: Vec<i64>,
    /// Their median (m²), at least `MIN_SCATTER²`: the typical scatter of a
    /// point across its surface.
    typical: f64,
    /// Prefix sums of x, y, x², xy, y² along one surface (scratch).
    prefix: Vec<[f64; 5]>,
    /// Score and fit of every window along one surface (scratch).
    windows: Vec<(f64, Fit)>,
}

/// The closest point of the reference surface to a query.
#[derive(Debug, Clone, Copy)]
pub struct Closest {
    /// Foot of the query on the local surface line (m).
    pub target: [f64; 2],
    /// Unit normal of the surface there.
    pub normal: [f64; 2],
    /// Signed distance of the query from the line along `normal` (m).
    pub residual: f64,
    /// Distance (m) from the query to the nearest reference point.
    pub vertex_dist: f64,
    /// Index of the nearest reference point (whose line this is; its
    /// direction's variance is [`Reference::tilt_variance`]).
    pub index: usize,
}

impl Reference {
    /// An empty reference whose line fits use windows of `window + 1`
    /// consecutive linked points (`window` at least 1), fewer (down to 3
    /// points) where that many would span more than `length` m of surface
    /// (`length` = 0: always `window + 1`).
    pub fn new(window: usize, length: f64) -> Self {
        Self {
            window: window.max(1),
            length: if length.is_finite() {
                length.max(0.0)
            } else {
                0.0
            },
            ..Default::default()
        }
    }

    /// The same, its nearest-neighbour queries answered by `search`
    /// (default: kiddo's k-d tree).
    pub fn with_search(mut self, search: NeighbourSearch) -> Self {
        self.index = NeighbourIndex::new(search);
        self
    }

    /// Number of reference points.
    pub fn len(&self) -> usize {
        self.pts.len()
    }

    /// Reference point `j` (m).
    pub fn point(&self, j: usize) -> [f64; 2] {
        self.pts[j]
    }

    /// Unit normal of the local surface line at point `j`, if one was fitted.
    pub fn normal(&self, j: usize) -> Option<[f64; 2]> {
        self.lines.get(j).filter(|l| l.ok).map(|l| l.n)
    }

    /// True when there is nothing to match against.
    pub fn is_empty(&self) -> bool {
        self.pts.is_empty() || self.index.is_empty()
    }

    /// Replaces the content with `scan`'s points and rebuilds lines and search index.
    pub fn set(&mut self, scan: &ScanPoints) {
        self.set_lines(scan);
        self.rebuild_index();
    }

    /// Replaces the content with `scan`'s points and fits their lines, but
    /// builds no search index (for [`normal`](Self::normal) only).
    pub fn set_lines(&mut self, scan: &ScanPoints) {
        self.pts.clear();
        self.link.clear();
        self.pts.extend_from_slice(&scan.pts);
        self.link.extend_from_slice(&scan.link);
        self.fit_lines();
        self.drop_index();
    }

    /// Forgets the search index, keeping its buffers for the next one.
    fn drop_index(&mut self) {
        self.index.clear();
    }

    /// Replaces the content with several references whose lines are
    /// fitted and placed in one frame (a local map's keyframes, each from
    /// [`placed`](Self::placed)); links never cross from one set to the
    /// next. The scatter limit is applied over all of them, as a fit of the
    /// whole would.
    pub fn set_many<'a>(&mut self, sets: impl Iterator<Item = &'a Reference>) {
        self.pts.clear();
        self.link.clear();
        self.lines.clear();
        for r in sets {
            self.pts.extend_from_slice(&r.pts);
            self.link.extend_from_slice(&r.link);
            if let Some(l) = self.link.last_mut() {
                *l = false;
            }
            self.lines.extend_from_slice(&r.lines);
        }
        self.scatter.clear();
        let scored = self.lines.iter().filter(|l| l.scored);
        let scored = scored.map(|l| total_key(l.score));
        self.scatter.extend(scored);
        self.limit_scatter();
        self.rebuild_index();
    }

    /// A copy of the points, links and lines only (no search index, no
    /// scratch), mapped by the pose `frame_from_set`: a keyframe for
    /// [`set_many`](Self::set_many). The lines are moved rather than fitted
    /// again (a fit is invariant under the move), once per keyframe rather
    /// than at every map it is part of.
    pub fn placed(&self, frame_from_set: &crate::geom::Pose2) -> Self {
        let pose = frame_from_set;
        let (c, sn) = (pose.rotation.cos_angle(), pose.rotation.sin_angle());
        let t = pose.translation.vector;
        Self {
            pts: self
                .pts
                .iter()
                .map(|p| [c * p[0] - sn * p[1] + t.x, sn * p[0] + c * p[1] + t.y])
                .collect(),
            link: self.link.clone(),
            lines: self
                .lines
                .iter()
                .map(|l| l.moved(c, sn, [t.x, t.y]))
                .collect(),
            window: self.window,
            length: self.length,
            ..Default::default()
        }
    }

    fn rebuild_index(&mut self) {
        self.index.build(&self.pts);
    }

    /// Fits a line through each point's surface neighbourhood: of all the
    /// windows of `window + 1` consecutive linked points that contain the
    /// point, the one whose points lie closest to a line. Near a corner that
    /// is a window on the point's own wall (a centred window would round the
    /// corner off and pull every point near it by centimetres). Lines whose
    /// scatter is far above the scan's typical scatter (clutter, short faces
    /// between two corners) are dropped.
    fn fit_lines(&mut self) {
        let n = self.pts.len();
        let k = self.window;
        self.lines.clear();
        self.lines.reserve(n);
        self.scatter.clear();
        let mut start = 0;
        while start < n {
            let mut end = start;
            while end + 1 < n && self.link[end] {
                end += 1;
            }
            if end == start {
                self.lines.push(Line::default());
            } else {
                let m = self.window_of(start, end, k);
                self.fit_windows(start, end, m);
                self.surface_lines(start, end, m);
            }
            start = end + 1;
        }
        self.limit_scatter();
    }

    /// Appends the lines of the surface `start..=end` (at least two points)
    /// from its window fits (`fit_windows` with `m`): each point's the best
    /// of the windows containing it, the first of the smallest score. The
    /// windows containing point `j` start at `max(j − m, start)` ..=
    /// `min(j, end − m)`, both bounds moving up with `j`: the best is kept
    /// while it stays in range and compared with each window that enters
    /// (a sliding minimum), and a line is made once per best window.
    fn surface_lines(&mut self, start: usize, end: usize, m: usize) {
        let windows = &self.windows;
        let (pa, pb) = (self.pts[start], self.pts[end]);
        let scored = m >= 2;
        // Scores are never NaN from finite points; if one is, the plain
        // search below is what a scan of each range would give.
        let plain = windows.iter().any(|w| w.0.is_nan());
        let last = end - start - m;
        let (mut hi, mut best) = (0, 0);
        // The line of window `made` (none yet).
        let (mut made, mut line) = (usize::MAX, Line::default());
        let len = end - start;
        for j in 0..=len {
            let (first, end_first) = (j.saturating_sub(m), j.min(last));
            if plain || best < first {
                best = first;
                for a in first + 1..end_first + 1 {
                    if windows[a].0 < windows[best].0 {
                        best = a;
                    }
                }
            } else {
                for a in hi + 1..end_first + 1 {
                    if windows[a].0 < windows[best].0 {
                        best = a;
                    }
                }
            }
            hi = end_first;
            if best != made {
                line = window_line(&windows[best], pa, pb, scored);
                made = best;
            }
            line.before = j > 0;
            line.after = j < len;
            self.lines.push(line);
            if scored {
                self.scatter.push(total_key(line.score));
            }
        }
    }

    /// Marks usable the fitted lines whose scatter is within
    /// `SCATTER_LIMIT` times the median of `self.scatter` (the scored
    /// lines' scores).
    fn limit_scatter(&mut self) {
        self.typical = MIN_SCATTER * MIN_SCATTER;
        if self.scatter.is_empty() {
            for l in &mut self.lines {
                l.ok = l.fitted;
            }
            return;
        }
        let mid = self.scatter.len() / 2;
        let typical = from_total_key(*self.scatter.select_nth_unstable(mid).1);
        self.typical = typical.max(self.typical);
        let limit = SCATTER_LIMIT * self.typical;
        for l in &mut self.lines {
            l.ok = l.fitted && l.score <= limit;
        }
    }

    /// Points after the first in the line fits of the surface `start..=end`:
    /// `k`, or fewer so that a window spans about `length` m at the
    /// surface's mean point spacing (sparse beams at long range or on 1°
    /// scanners would otherwise fit lines across corners and curves), at
    /// least 2, at most the surface.
    fn window_of(&self, start: usize, end: usize, k: usize) -> usize {
        let m = k.min(end - start);
        if self.length <= 0.0 || end == start {
            return m;
        }
        let arc: f64 = self.pts[start..=end]
            .windows(2)
            .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
            .sum();
        let spacing = arc / (end - start) as f64;
        let fit = (self.length / spacing).round();
        if fit.is_finite() && fit < m as f64 {
            (fit as usize).max(2).min(m)
        } else {
            m
        }
    }

    /// Fits every window of `m + 1` consecutive points of the surface
    /// `start..=end` from prefix sums (O(1) per window, whatever `m`), into
    /// `self.windows[a - start]`, with its score (mean squared distance from
    /// the line, m²).
    fn fit_windows(&mut self, start: usize, end: usize, m: usize) {
        let o = self.pts[start];
        self.prefix.clear();
        let mut acc = [0.0; 5];
        self.prefix.push(acc);
        self.prefix.extend(self.pts[start..=end].iter().map(|p| {
            let (x, y) = (p[0] - o[0], p[1] - o[1]);
            acc = [
                acc[0] + x,
                acc[1] + y,
                acc[2] + x * x,
                acc[3] + x * y,
                acc[4] + y * y,
            ];
            acc
        }));
        self.windows.clear();
        let n = (m + 1) as f64;
        // Window `a` is the difference of prefix sums `a + m + 1` and `a`.
        let ends = self.prefix.iter().zip(&self.prefix[m + 1..]);
        self.windows.extend(ends.map(|(lo, hi)| {
            let d: [f64; 5] = std::array::from_fn(|i| hi[i] - lo[i]);
            let (cx, cy) = (d[0] / n, d[1] / n);
            let sxx = (d[2] - n * cx * cx).max(0.0);
            let sxy = d[3] - n * cx * cy;
            let syy = (d[4] - n * cy * cy).max(0.0);
            let ss = 0.5 * (sxx + syy - ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt());
            let f = Fit {
                c: [o[0] + cx, o[1] + cy],
                sxx,
                sxy,
                syy,
                ss: ss.max(0.0),
            };
            let score = if m >= 2 { f.ss / (m - 1) as f64 } else { 0.0 };
            (score, f)
        }));
    }

    /// The closest point to `q` on the reference surface: the nearest
    /// reference point's fitted line (or a linked neighbour's), and the foot
    /// of `q` on it. `None` when the reference is empty, the nearest point is
    /// isolated, or `q` lies beyond the open end of a surface: such points
    /// move with the viewpoint (sampling, occlusion edges) and would pull the
    /// estimate towards zero motion.
    #[cfg(test)]
    pub fn closest(&self, q: [f64; 2]) -> Option<Closest> {
        let (j, d2) = self.nearest(q, f64::INFINITY)?;
        self.correspondence(q, j, d2)
    }

    /// Index and squared distance (m²) of the reference point nearest to `q`
    /// among those closer than `max_dist` m (index search); `None` when there is
    /// none.
    pub fn nearest(&self, q: [f64; 2], max_dist: f64) -> Option<(usize, f64)> {
        self.index.nearest(q, max_dist)
    }

    /// Same as [`nearest`](Self::nearest) when the nearest point is known to
    /// be near index `hint` (the previous iteration's): walks along the
    /// linked surface to the locally nearest point, no index search. Only
    /// valid while the query moves little between calls.
    #[inline]
    pub fn walk(&self, q: [f64; 2], hint: usize) -> Option<(usize, f64)> {
        if hint >= self.pts.len() {
            return self.nearest(q, f64::INFINITY);
        }
        let d2 = |j: usize| (self.pts[j][0] - q[0]).powi(2) + (self.pts[j][1] - q[1]).powi(2);
        let (mut j, mut best) = (hint, d2(hint));
        loop {
            // Each distance once: the one compared is the next `best`.
            if j > 0 && self.link[j - 1] {
                let d = d2(j - 1);
                if d < best {
                    (j, best) = (j - 1, d);
                    continue;
                }
            }
            if j + 1 < self.pts.len() && self.link[j] {
                let d = d2(j + 1);
                if d < best {
                    (j, best) = (j + 1, d);
                    continue;
                }
            }
            return Some((j, best));
        }
    }

    /// The foot of `q` on the line of reference point `j` (the correspondence
    /// held fixed once a registration has settled); `None` as for
    /// [`closest`](Self::closest).
    pub fn on_line(&self, q: [f64; 2], j: usize) -> Option<Closest> {
        let a = self.pts.get(j)?;
        self.line_foot(q, j, (a[0] - q[0]).powi(2) + (a[1] - q[1]).powi(2))
    }

    /// The correspondence of `q` given its nearest reference point `j` at
    /// squared distance `d2` (m²): the foot on `j`'s fitted line. Always the
    /// nearest point's line, never the best-fitting of several: picking the
    /// line with the smallest residual would make every pose look good and
    /// hold the estimate at its initial guess (measured: 9 % of a biased
    /// prior's error survived). Corners are handled by the fit itself, which
    /// keeps each point's line on its own wall.
    pub fn correspondence(&self, q: [f64; 2], j: usize, d2: f64) -> Option<Closest> {
        // Beyond the open end at the nearest point: no correspondence at all.
        let l = self.lines.get(j)?;
        let a = self.pts[j];
        let s = (q[0] - a[0]) * l.t[0] + (q[1] - a[1]) * l.t[1];
        if (s < 0.0 && !l.before) || (s > 0.0 && !l.after) {
            return None;
        }
        self.line_foot(q, j, d2)
    }

    /// Foot of `q` on point `j`'s line, `None` without a usable line.
    fn line_foot(&self, q: [f64; 2], j: usize, d2: f64) -> Option<Closest> {
        let l = self.lines.get(j)?;
        if !l.ok {
            return None;
        }
        let e = metric::residual(q, l.c, l.n);
        Some(Closest {
            target: [q[0] - e * l.n[0], q[1] - e * l.n[1]],
            normal: l.n,
            residual: e,
            vertex_dist: d2.sqrt(),
            index: j,
        })
    }

    /// Variance (rad²) of the direction of line `l`: the scatter across it
    /// (its own, at least the reference's typical one — the straightest
    /// window was chosen for a small scatter) over the spread of its points
    /// along it, as for the slope of a least-squares line. Range noise alone
    /// tilts a line fitted over a few centimetres of wall by tenths of a
    /// radian: information along a wall that is only this noise is not
    /// measured (see `covariance`). At most 1 rad². Asked for by index
    /// (a [`Closest::index`]) and only where needed: the registration's
    /// iterations use none of it, only the covariance at the end.
    pub fn tilt_variance(&self, j: usize) -> f64 {
        let Some(l) = self.lines.get(j) else {
            return 1.0;
        };
        let across = l.score.max(self.typical);
        if l.spread > 0.0 {
            (across / l.spread).min(1.0)
        } else {
            1.0
        }
    }
}

/// `x` as an integer ordered as `f64::total_cmp` orders floats (the same
/// bit flip it applies to both sides of each comparison, done once).
fn total_key(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    b ^ ((((b >> 63) as u64) >> 1) as i64)
}

/// The float of a [`total_key`] (the flip is its own inverse).
fn from_total_key(k: i64) -> f64 {
    f64::from_bits(total_key(f64::from_bits(k as u64)) as u64)
}

/// A total-least-squares line through some points.
#[derive(Debug, Clone, Copy, Default)]
struct Fit {
    /// Centroid (m).
    c: [f64; 2],
    /// Scatter matrix entries Σdx², Σdx·dy, Σdy² about the centroid (m²).
    sxx: f64,
    sxy: f64,
    syy: f64,
    /// Sum of squared distances from the line (m²): the scatter matrix's
    /// smaller eigenvalue.
    ss: f64,
}

impl Fit {
    /// Unit direction of the line: the eigenvector of the larger eigenvalue
    /// (no trigonometry).
    fn direction(&self) -> [f64; 2] {
        let big = self.sxx + self.syy - self.ss;
        let (u, v) = if self.sxx >= self.syy {
            (big - self.syy, self.sxy)
        } else {
            (self.sxy, big - self.sxx)
        };
        let len = (u * u + v * v).sqrt();
        if len > 0.0 {
            [u / len, v / len]
        } else {
            [1.0, 0.0]
        }
    }
}

/// The line of a window fit `(score, fit)` on the surface from `pa` to
/// `pb`, its tangent oriented from `pa` towards `pb` (without its
/// `before`/`after` links).
fn window_line(w: &(f64, Fit), pa: [f64; 2], pb: [f64; 2], scored: bool) -> Line {
    let (score, f) = *w;
    let mut t = f.direction();
    if (pb[0] - pa[0]) * t[0] + (pb[1] - pa[1]) * t[1] < 0.0 {
        t = [-t[0], -t[1]];
    }
    Line {
        c: f.c,
        n: [-t[1], t[0]],
        t,
        before: false,
        after: false,
        ok: true,
        fitted: true,
        scored,
        score,
        spread: (f.sxx + f.syy - f.ss).max(0.0),
    }
}

/// Direct two-pass fit: the reference the prefix-sum fits are checked against.
#[cfg(test)]
fn fit(pts: &[[f64; 2]]) -> Fit {
    let m = pts.len() as f64;
    let o = pts[0];
    let (mut cx, mut cy) = (0.0, 0.0);
    for p in pts {
        cx += p[0] - o[0];
        cy += p[1] - o[1];
    }
    let (cx, cy) = (cx / m, cy / m);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (dx, dy) = (p[0] - o[0] - cx, p[1] - o[1] - cy);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let ss = 0.5 * (sxx + syy - ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt());
    Fit {
        c: [o[0] + cx, o[1] + cy],
        sxx,
        sxy,
        syy,
        ss: ss.max(0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefix_sum_window_fits_equal_direct_fits() {
        // A noisy wall 12 m away: the prefix sums must not lose the mm-scale
        // scatter to cancellation.
        let pts: Vec<[f64; 2]> = (0..40)
            .map(|i| {
                let e = 0.01 * ((i * 7919) % 13) as f64 / 13.0 - 0.005;
                [12.0 + e, -3.0 + 0.05 * i as f64]
            })
            .collect();
        let mut r = Reference::new(4, 0.0);
        r.pts = pts.clone();
        r.link = vec![true; pts.len()];
        r.fit_windows(3, 30, 4);
        assert_eq!(r.windows.len(), 30 - 3 - 4 + 1);
        for (a, (score, f)) in r.windows.iter().enumerate() {
            let g = fit(&pts[3 + a..=3 + a + 4]);
            assert!((f.c[0] - g.c[0]).abs() < 1e-12 && (f.c[1] - g.c[1]).abs() < 1e-12);
            assert!(
                (f.ss - g.ss).abs() < 1e-12 * (1.0 + g.sxx + g.syy),
                "{} {}",
                f.ss,
                g.ss
            );
            assert!((score - g.ss / 3.0).abs() < 1e-11);
        }
    }

    #[test]
    fn each_point_gets_the_first_straightest_window_containing_it() {
        // Three walls with two corners and a gap, ±5 mm pseudo-random noise:
        // every point's line must be that of the window a scan over all the
        // windows containing it picks (direct fits, first of the smallest
        // scatter), whatever the window size.
        let mut pts = Vec::new();
        let mut link = Vec::new();
        for i in 0..90 {
            let mut h = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            h = (h ^ (h >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            let e = 0.01 * ((h ^ (h >> 32)) % 10_007) as f64 / 10_007.0 - 0.005;
            let s = 0.03 * i as f64;
            let p = match i {
                0..=29 => [s, 2.0 + e],
                30..=59 => [0.9 + e, 2.0 - (s - 0.9)],
                _ => [0.9 + (s - 1.8), 1.1 + e],
            };
            pts.push(p);
            link.push(i + 1 < 90 && i != 44);
        }
        let sp = ScanPoints {
            range: vec![1.0; pts.len()],
            pts: pts.clone(),
            link,
        };
        for k in [1, 2, 3, 6, 10] {
            let mut r = Reference::new(k, 0.0);
            r.set_lines(&sp);
            for (start, end) in [(0, 44), (45, 89)] {
                let m = k.min(end - start);
                for j in start..=end {
                    let windows = j.saturating_sub(m).max(start)..=j.min(end - m);
                    let mut best = None;
                    for a in windows {
                        // Two-point windows all fit exactly: the first wins.
                        let score = if m >= 2 { fit(&pts[a..=a + m]).ss } else { 0.0 };
                        if best.is_none_or(|(_, b)| score < b) {
                            best = Some((a, score));
                        }
                    }
                    let g = fit(&pts[best.unwrap().0..=best.unwrap().0 + m]);
                    let l = &r.lines[j];
                    assert!(l.fitted && l.before == (j > start) && l.after == (j < end));
                    assert!(
                        (l.c[0] - g.c[0]).abs() < 1e-9 && (l.c[1] - g.c[1]).abs() < 1e-9,
                        "k {k} point {j}: {:?} vs {:?}",
                        l.c,
                        g.c
                    );
                    assert!((l.n[0] * g.direction()[0] + l.n[1] * g.direction()[1]).abs() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn total_keys_order_as_total_cmp_and_map_back() {
        let xs = [
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            0.0,
            -0.0,
            1e-300,
            -1e-300,
            f64::MIN_POSITIVE / 2.0,
            2.5e-5,
            3.0,
            -3.0,
            f64::MAX,
        ];
        for a in xs {
            assert_eq!(from_total_key(total_key(a)).to_bits(), a.to_bits());
            for b in xs {
                assert_eq!(total_key(a).cmp(&total_key(b)), a.total_cmp(&b), "{a} {b}");
            }
        }
    }

    #[test]
    fn closest_point_lies_on_the_fitted_line() {
        let sp = ScanPoints {
            pts: vec![[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [5.0, 5.0]],
            link: vec![true, true, false, false],
            range: vec![1.0; 4],
        };
        let mut r = Reference::new(2, 0.0);
        r.set(&sp);
        let c = r.closest([0.3, 0.2]).unwrap();
        assert!((c.target[0] - 0.3).abs() < 1e-12 && c.target[1].abs() < 1e-12);
        assert!(c.normal[1].abs() > 0.999);
        assert!((c.residual.abs() - 0.2).abs() < 1e-12);
        // isolated samples and open ends give no correspondence
        assert!(r.closest([5.2, 5.1]).is_none());
        assert!(r.closest([-0.2, 0.1]).is_none());
        assert!(r.closest([1.2, 0.1]).is_none());
        // the walk from a hint finds the same point as the index
        let (j, d2) = r.walk([0.9, 0.1], 0).unwrap();
        assert_eq!((j, d2), r.nearest([0.9, 0.1], 1.0).unwrap());
        let w = r.correspondence([0.9, 0.1], j, d2).unwrap();
        assert!((w.target[0] - 0.9).abs() < 1e-12);
    }

    #[test]
    fn the_fitted_line_averages_range_noise() {
        // A wall y = 1 sampled every 2 cm with ±1 cm alternating noise: the
        // raw polyline tilts by 45°, the 7-point fit stays nearly level.
        let pts: Vec<[f64; 2]> = (0..50)
            .map(|i| [i as f64 * 0.02, 1.0 + if i % 2 == 0 { 0.01 } else { -0.01 }])
            .collect();
        let n = pts.len();
        let sp = ScanPoints {
            link: (0..n).map(|i| i + 1 < n).collect(),
            range: vec![1.0; n],
            pts,
        };
        let mut r = Reference::new(6, 0.0);
        r.set(&sp);
        let c = r.closest([0.41, 0.9]).unwrap();
        assert!(c.normal[0].abs() < 0.05, "{c:?}");
        assert!((c.residual.abs() - 0.1).abs() < 0.005, "{c:?}");
    }

    #[test]
    fn empty_reference_answers_nothing() {
        let mut r = Reference::new(6, 0.0);
        r.set(&ScanPoints::default());
        assert!(r.is_empty());
        assert!(r.closest([0.0, 0.0]).is_none());
    }
}
