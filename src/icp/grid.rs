//! Exact nearest-neighbour search among a reference's points, within a
//! radius: a uniform grid of square cells whose points are stored cell by
//! cell (a counting sort, built once per reference), searched ring by ring
//! outwards from the query's cell until no unvisited cell can hold a closer
//! point.
//!
//! Why not a kd-tree: the reference is a few hundred to a few thousand points
//! on walls, queried by points that lie within centimetres of them, and only
//! a neighbour within the correspondence gate is of any use. The grid answers
//! such a query from the cells around it with no descent, no backtracking
//! and no allocation. Measured with callgrind over the Intel log: about 850
//! instructions per query against the kd-tree's 1,090 (kiddo's immutable
//! tree), plus 0.2 M per grid built (once per keyframe); reading ring 1 row
//! by row (below) took it to 626 per query on the first 2,500 Intel scans
//! (from 736). What remains is the local map's density: five overlapping
//! keyframes put five points where a scan has one, and a query scans them
//! all in its cells (~17 points, ~14 instructions each).

use crate::geom::cells::Bins;

/// Points binned into square cells ([`Bins`]: cell `c` holds the points
/// `xy[bins.range(c)]`, whose original indices are `bins.items()` there).
#[derive(Debug, Clone, Default)]
pub struct PointGrid {
    x0: f64,
    y0: f64,
    cell: f64,
    inv: f64,
    nx: usize,
    ny: usize,
    bins: Bins,
    /// The points in storage order (cell by cell), copied for the searches
    /// to read without indirection.
    xy: Vec<[f64; 2]>,
    /// `(cell, index)` of each finite point while binning (scratch).
    pairs: Vec<(u32, u32)>,
}

/// Cells per point at most (bounds the grid over sparse, wide maps).
const MAX_CELLS_PER_POINT: f64 = 64.0;

impl PointGrid {
    /// Whether the grid holds no point.
    pub fn is_empty(&self) -> bool {
        self.xy.is_empty()
    }

    /// Rebuilds the grid over `pts` (m) with cells of `cell` m, widened
    /// where the points spread over so large an area that the grid would
    /// exceed `MAX_CELLS_PER_POINT` cells per point. Non-finite points are
    /// left out (never found).
    pub fn build(&mut self, pts: &[[f64; 2]], cell: f64) {
        self.xy.clear();
        let mut b = [f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY];
        let mut finite = 0usize;
        // Plain comparisons: the points are finite, so `f64::min`'s NaN
        // handling is not needed.
        for p in pts.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
            if p[0] < b[0] {
                b[0] = p[0];
            }
            if p[1] < b[1] {
                b[1] = p[1];
            }
            if p[0] > b[2] {
                b[2] = p[0];
            }
            if p[1] > b[3] {
                b[3] = p[1];
            }
            finite += 1;
        }
        if finite == 0 {
            self.nx = 0;
            self.ny = 0;
            return;
        }
        let (w, h) = (b[2] - b[0], b[3] - b[1]);
        let area_cell = (w * h / (MAX_CELLS_PER_POINT * finite as f64)).sqrt();
        self.cell = cell.max(area_cell).max(1e-6);
        self.inv = 1.0 / self.cell;
        self.x0 = b[0];
        self.y0 = b[1];
        self.nx = (w * self.inv) as usize + 1;
        self.ny = (h * self.inv) as usize + 1;
        self.bin(pts, finite);
    }

    /// Each finite point's cell, then [`Bins`]' counting sort, then the
    /// points copied in storage order.
    fn bin(&mut self, pts: &[[f64; 2]], finite: usize) {
        let (x0, y0, inv) = (self.x0, self.y0, self.inv);
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        // A finite point lies at or beyond (x0, y0): its scaled offsets are
        // non-negative (`as i64` truncates them as `as usize` would, with
        // a cheaper conversion); rounding may put the farthest at n.
        let cell_of = |p: &[f64; 2]| {
            let ix = (((p[0] - x0) * inv) as i64).min(nx - 1);
            let iy = (((p[1] - y0) * inv) as i64).min(ny - 1);
            (iy * nx + ix) as u32
        };
        self.pairs.clear();
        self.pairs.reserve(finite);
        for (i, p) in pts.iter().enumerate() {
            if p[0].is_finite() && p[1].is_finite() {
                self.pairs.push((cell_of(p), i as u32));
            }
        }
        self.bins.build(self.nx * self.ny, &self.pairs);
        self.xy
            .extend(self.bins.items().iter().map(|&i| pts[i as usize]));
    }

    /// Index and squared distance (m²) of the point nearest to `q` among
    /// those closer than `max_dist` m; `None` when there is none. Ties go
    /// to the point met first.
    pub fn nearest(&self, q: [f64; 2], max_dist: f64) -> Option<(usize, f64)> {
        if self.xy.is_empty() || !(q[0].is_finite() && q[1].is_finite()) {
            return None;
        }
        let fx = (q[0] - self.x0) * self.inv;
        let fy = (q[1] - self.y0) * self.inv;
        let (cx, cy) = (floor(fx), floor(fy));
        // Distance from q to the nearest border of its own (possibly
        // virtual, outside the grid) cell: every point of ring r + 1 is at
        // least r cells plus this far away.
        let m = (fx - cx).min(cx + 1.0 - fx).min(fy - cy).min(cy + 1.0 - fy) * self.cell;
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        let (ix, iy) = (cx as i64, cy as i64);
        let mut best = (usize::MAX, max_dist * max_dist);
        let mut r = 2;
        if (0..nx).contains(&ix) && (0..ny).contains(&iy) {
            // q's own cell is in the grid: rings from 0 (`m - cell`: the
            // bound below at ring 0, exactly).
            if m - self.cell >= max_dist {
                return None;
            }
            if !self.search_rings_0_1(q, ix, iy, m, max_dist, &mut best) {
                return self.found(best);
            }
        } else {
            // Rings beyond the grid on every side hold nothing.
            let far = |v: f64, n: i64| (-v).max(v - (n - 1) as f64).max(0.0);
            let r_min = far(cx, nx).max(far(cy, ny));
            if (r_min - 1.0) * self.cell + m >= max_dist {
                return None;
            }
            r = r_min as i64;
        }
        let (cx, cy) = (ix, iy);
        let r_max = (cx.max(nx - 1 - cx)).max(cy.max(ny - 1 - cy));
        while r <= r_max {
            self.search_ring(q, cx, cy, r, &mut best);
            let bound = r as f64 * self.cell + m;
            if bound * bound >= best.1 || bound > max_dist {
                break;
            }
            r += 1;
        }
        self.found(best)
    }

    /// The answer of [`nearest`](Self::nearest) from `best` (slot, squared
    /// distance).
    #[inline]
    fn found(&self, best: (usize, f64)) -> Option<(usize, f64)> {
        (best.0 != usize::MAX).then(|| (self.bins.items()[best.0] as usize, best.1))
    }

    /// Rings 0 and 1 around cell (`cx`, `cy`), which lies in the grid, where
    /// nearly every search ends: the same points in the same order as
    /// [`search_ring`](Self::search_ring) would visit them (first of equals
    /// kept), but each row of ring 1 read as one run of consecutive cells
    /// (consecutive in storage too), and the distances from `q` to the
    /// three columns and rows computed once. A row's run spans the cells
    /// that can hold a point closer than `best` when the row starts; the
    /// cells `search_ring` would skip later in the row hold none closer
    /// (reading them changes nothing). Whether a ring 2 must follow, from
    /// `m` (see `nearest`).
    fn search_rings_0_1(
        &self,
        q: [f64; 2],
        cx: i64,
        cy: i64,
        m: f64,
        max_dist: f64,
        best: &mut (usize, f64),
    ) -> bool {
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        let own = (cy * nx + cx) as usize;
        self.search_cells(q, own, own, best);
        if m * m >= best.1 || m > max_dist {
            return false;
        }
        let gx: [f64; 3] = std::array::from_fn(|i| {
            self.gap(self.x0 + (cx - 1 + i as i64) as f64 * self.cell, q[0])
        });
        let gy: [f64; 3] = std::array::from_fn(|i| {
            self.gap(self.y0 + (cy - 1 + i as i64) as f64 * self.cell, q[1])
        });
        let gx2 = gx.map(|g| g * g);
        for (dy, y) in [(gy[0], cy - 1), (gy[2], cy + 1)] {
            if !(0..ny).contains(&y) {
                continue;
            }
            let dy2 = dy * dy;
            let near = |i: usize| gx2[i] + dy2 < best.1;
            let lo = if cx > 0 && near(0) { cx - 1 } else { cx };
            let hi = if cx + 1 < nx && near(2) { cx + 1 } else { cx };
            if lo < cx || hi > cx || near(1) {
                self.search_cells(q, (y * nx + lo) as usize, (y * nx + hi) as usize, best);
            }
        }
        let dy2 = gy[1] * gy[1];
        for (i, x) in [(0, cx - 1), (2, cx + 1)] {
            if (0..nx).contains(&x) && gx2[i] + dy2 < best.1 {
                let c = (cy * nx + x) as usize;
                self.search_cells(q, c, c, best);
            }
        }
        let bound = self.cell + m;
        bound * bound < best.1 && bound <= max_dist
    }

    /// Visits the cells at Chebyshev distance `r` from cell (`cx`, `cy`)
    /// that lie in the grid, updating `best` (slot, squared distance). A
    /// cell farther from `q` than the best point found so far is skipped
    /// unread (a wall passes through a few of the eight cells around the
    /// query's, and its nearest point is usually in the first).
    fn search_ring(&self, q: [f64; 2], cx: i64, cy: i64, r: i64, best: &mut (usize, f64)) {
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        let (x_lo, x_hi) = ((cx - r).max(0), (cx + r).min(nx - 1));
        if r == 0 {
            if (0..nx).contains(&cx) && (0..ny).contains(&cy) {
                let c = (cy * nx + cx) as usize;
                self.search_cells(q, c, c, best);
            }
            return;
        }
        for y in [cy - r, cy + r] {
            if (0..ny).contains(&y) {
                for x in x_lo..=x_hi {
                    self.search_cell_within(q, x, y, best);
                }
            }
        }
        let (y_lo, y_hi) = ((cy - r + 1).max(0), (cy + r - 1).min(ny - 1));
        for x in [cx - r, cx + r] {
            if (0..nx).contains(&x) {
                for y in y_lo..=y_hi {
                    self.search_cell_within(q, x, y, best);
                }
            }
        }
    }

    /// Distance (m) along one axis from coordinate `v` to the cell span
    /// `[lo, lo + cell]`; 0 inside it.
    #[inline]
    fn gap(&self, lo: f64, v: f64) -> f64 {
        (lo - v).max(v - lo - self.cell).max(0.0)
    }

    /// [`search_cells`](Self::search_cells) of cell (`x`, `y`) unless every
    /// point of it is at least as far from `q` as `best`.
    #[inline]
    fn search_cell_within(&self, q: [f64; 2], x: i64, y: i64, best: &mut (usize, f64)) {
        let (lx, ly) = (
            self.x0 + x as f64 * self.cell,
            self.y0 + y as f64 * self.cell,
        );
        let (dx, dy) = (self.gap(lx, q[0]), self.gap(ly, q[1]));
        if dx * dx + dy * dy < best.1 {
            let c = (y * self.nx as i64 + x) as usize;
            self.search_cells(q, c, c, best);
        }
    }

    /// Reads the points of the consecutive cells `c_lo..=c_hi` in storage
    /// order, updating `best` (slot, squared distance) with any strictly
    /// closer one.
    #[inline]
    fn search_cells(&self, q: [f64; 2], c_lo: usize, c_hi: usize, best: &mut (usize, f64)) {
        let std::ops::Range { start: a, end: b } = self.bins.span(c_lo, c_hi);
        // Locals rather than `best` in the loop: no store per point.
        let (mut slot, mut d2_min) = *best;
        let xy = &self.xy[..b];
        for (k, p) in xy.iter().enumerate().skip(a) {
            let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
            let d2 = dx * dx + dy * dy;
            if d2 < d2_min {
                (slot, d2_min) = (k, d2);
            }
        }
        *best = (slot, d2_min);
    }
}

/// `x.floor()` without a call into libm (the baseline x86-64 target has no
/// rounding instruction).
#[inline]
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the nearest point within `max` (first of equals).
    fn brute(pts: &[[f64; 2]], q: [f64; 2], max: f64) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, p) in pts.iter().enumerate() {
            let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
            if d2 < max * max && best.is_none_or(|b| d2 < b.1) {
                best = Some((i, d2));
            }
        }
        best
    }

    #[test]
    fn answers_as_brute_force_inside_outside_and_at_the_radius() {
        // Walls, a cluster and a few strays, queried on a lattice that
        // reaches well beyond the points, with radii from tiny to huge.
        let mut pts = Vec::new();
        for i in 0..200 {
            let s = i as f64 * 0.037;
            pts.push([s, 0.013 * (i % 5) as f64]);
            pts.push([3.1 + 0.002 * (i % 3) as f64, -2.0 + s * 0.8]);
        }
        pts.extend([[-4.0, 9.0], [12.0, -3.5], [1.0, 1.0], [1.0, 1.0]]);
        let mut g = PointGrid::default();
        for cell in [0.05, 0.3, 2.0] {
            g.build(&pts, cell);
            for qi in 0..60 {
                for qj in 0..50 {
                    let q = [-6.0 + 0.33 * qi as f64, -5.0 + 0.31 * qj as f64];
                    for max in [0.01, 0.2, 1.0, 50.0] {
                        let got = g.nearest(q, max);
                        let want = brute(&pts, q, max);
                        assert_eq!(got.map(|g| g.1), want.map(|w| w.1), "{q:?} {max}");
                        if let Some((i, d2)) = got {
                            let p = pts[i];
                            assert_eq!((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2), d2);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn of_equal_points_the_first_is_found() {
        // The same point three times (in one cell whatever the grid), among
        // others, queried from all sides and from inside its cell.
        let mut pts: Vec<[f64; 2]> = (0..40).map(|i| [0.05 * i as f64, 0.3]).collect();
        pts.insert(7, [0.61, 0.52]);
        pts.push([0.61, 0.52]);
        pts.insert(20, [0.61, 0.52]);
        let mut g = PointGrid::default();
        for cell in [0.05, 0.2, 1.0] {
            g.build(&pts, cell);
            for q in [
                [0.61, 0.55],
                [0.58, 0.52],
                [0.65, 0.6],
                [0.6, 0.5],
                [0.62, 0.53],
            ] {
                assert_eq!(g.nearest(q, 1.0).map(|n| n.0), Some(7), "{q:?} {cell}");
            }
        }
    }

    #[test]
    fn empty_and_non_finite_find_nothing() {
        let mut g = PointGrid::default();
        g.build(&[], 0.1);
        assert!(g.nearest([0.0, 0.0], 10.0).is_none());
        g.build(&[[f64::NAN, 0.0], [1.0, 1.0]], 0.1);
        assert_eq!(g.nearest([1.0, 1.2], 1.0).map(|n| n.0), Some(1));
        assert!(g.nearest([f64::NAN, 1.0], 1.0).is_none());
    }
}
