//! A uniform grid over the wall segments for fast ray casting: each cell lists
//! the segments crossing it, and a ray walks the cells in order
//! \[AmanatidesWoo1987\], stopping at the first cell that holds a hit.

use crate::geom::cells::Bins;

/// Segments binned into square cells (m, world frame).
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Cell `c` holds the segments `bins.cell(c)`.
    bins: Bins,
    /// Segments as origin and direction `[px, py, ex, ey]`.
    segs: Vec<[f64; 4]>,
}

impl Grid {
    /// Bins `segments` (`[x0, y0, x1, y1]`, m); cells of about half the mean
    /// wall spacing, between 0.2 and 1 m, at most 4 million of them.
    pub(crate) fn new(segments: &[[f64; 4]]) -> Self {
        let mut b = [f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY];
        for s in segments {
            b = [
                b[0].min(s[0]).min(s[2]),
                b[1].min(s[1]).min(s[3]),
                b[2].max(s[0]).max(s[2]),
                b[3].max(s[1]).max(s[3]),
            ];
        }
        let margin = 1e-6;
        let (x0, y0) = (b[0] - margin, b[1] - margin);
        let (w, h) = (b[2] - b[0] + 2.0 * margin, b[3] - b[1] + 2.0 * margin);
        let area = (w * h).max(1e-6);
        let cell = (0.5 * (area / segments.len() as f64).sqrt())
            .clamp(0.2, 1.0)
            .max((area / 4e6).sqrt());
        let nx = ((w / cell).ceil() as usize).max(1);
        let ny = ((h / cell).ceil() as usize).max(1);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (k, s) in segments.iter().enumerate() {
            let ix0 = (((s[0].min(s[2]) - x0) / cell).floor() as usize).min(nx - 1);
            let ix1 = (((s[0].max(s[2]) - x0) / cell).floor() as usize).min(nx - 1);
            let iy0 = (((s[1].min(s[3]) - y0) / cell).floor() as usize).min(ny - 1);
            let iy1 = (((s[1].max(s[3]) - y0) / cell).floor() as usize).min(ny - 1);
            for iy in iy0..=iy1 {
                for ix in ix0..=ix1 {
                    let eps = 1e-9;
                    let bx = [
                        x0 + ix as f64 * cell - eps,
                        x0 + (ix + 1) as f64 * cell + eps,
                    ];
                    let by = [
                        y0 + iy as f64 * cell - eps,
                        y0 + (iy + 1) as f64 * cell + eps,
                    ];
                    if segment_touches_box(s, bx, by) {
                        pairs.push(((iy * nx + ix) as u32, k as u32));
                    }
                }
            }
        }
        let mut bins = Bins::default();
        bins.build(nx * ny, &pairs);
        let segs = segments
            .iter()
            .map(|s| [s[0], s[1], s[2] - s[0], s[3] - s[1]])
            .collect();
        Self {
            x0,
            y0,
            cell,
            nx,
            ny,
            bins,
            segs,
        }
    }

    /// Distance along the unit direction `(dx, dy)` from `(ox, oy)` to the
    /// nearest segment, if within `max` (m).
    #[inline]
    pub(crate) fn cast(&self, ox: f64, oy: f64, dx: f64, dy: f64, max: f64) -> Option<f64> {
        let (ix_inv, iy_inv) = (1.0 / dx, 1.0 / dy);
        let (t_enter, t_exit) = self.clip(ox, oy, ix_inv, iy_inv, max)?;
        let px = ox + dx * t_enter;
        let py = oy + dy * t_enter;
        let mut ix = (((px - self.x0) / self.cell).floor().max(0.0) as usize).min(self.nx - 1);
        let mut iy = (((py - self.y0) / self.cell).floor().max(0.0) as usize).min(self.ny - 1);
        let (step_x, step_y) = (dx >= 0.0, dy >= 0.0);
        // An axis-parallel ray never crosses the other axis' cell borders.
        let mut tnx = if dx != 0.0 {
            self.next_border(self.x0, ix, step_x, ox, ix_inv)
        } else {
            f64::INFINITY
        };
        let mut tny = if dy != 0.0 {
            self.next_border(self.y0, iy, step_y, oy, iy_inv)
        } else {
            f64::INFINITY
        };
        let (dtx, dty) = (self.cell * ix_inv.abs(), self.cell * iy_inv.abs());
        let mut best = f64::INFINITY;
        loop {
            best = self.nearest_in_cell(iy * self.nx + ix, ox, oy, dx, dy, best);
            let t_cell_exit = tnx.min(tny);
            if best <= t_cell_exit || t_cell_exit >= t_exit {
                break;
            }
            if tnx < tny {
                if !step_cell(&mut ix, step_x, self.nx) {
                    break;
                }
                tnx += dtx;
            } else {
                if !step_cell(&mut iy, step_y, self.ny) {
                    break;
                }
                tny += dty;
            }
        }
        (best <= max).then_some(best)
    }

    /// The stretch `(t_enter, t_exit)` of the ray from `(ox, oy)` (inverse
    /// direction `(ix_inv, iy_inv)`) inside the grid's box and within `max`
    /// (slab method), `None` when it misses.
    #[inline(always)]
    fn clip(&self, ox: f64, oy: f64, ix_inv: f64, iy_inv: f64, max: f64) -> Option<(f64, f64)> {
        let (gx1, gy1) = (
            self.x0 + self.nx as f64 * self.cell,
            self.y0 + self.ny as f64 * self.cell,
        );
        let (tx0, tx1) = ((self.x0 - ox) * ix_inv, (gx1 - ox) * ix_inv);
        let (ty0, ty1) = ((self.y0 - oy) * iy_inv, (gy1 - oy) * iy_inv);
        let t_enter = tx0.min(tx1).max(ty0.min(ty1)).max(0.0);
        let t_exit = tx0.max(tx1).min(ty0.max(ty1)).min(max);
        // Both are NaN-free: f64::min/max drop a NaN operand.
        if t_enter > t_exit {
            return None;
        }
        Some((t_enter, t_exit))
    }

    /// Ray parameter at which the ray from `o` (inverse direction `inv`
    /// along one axis) leaves cell `i` of that axis, whose grid starts at
    /// `start`, going up when `up`.
    #[inline(always)]
    fn next_border(&self, start: f64, i: usize, up: bool, o: f64, inv: f64) -> f64 {
        let b = start + (i + up as usize) as f64 * self.cell;
        (b - o) * inv
    }

    /// The smaller of `best` and the ray parameter of the nearest hit, in
    /// cell `c`, of the ray from `(ox, oy)` along `(dx, dy)`.
    #[inline(always)]
    fn nearest_in_cell(&self, c: usize, ox: f64, oy: f64, dx: f64, dy: f64, best: f64) -> f64 {
        let mut best = best;
        for &k in self.bins.cell(c) {
            let [sx, sy, ex, ey] = self.segs[k as usize];
            // o + t d = s + u e  →  t = (w × e) / (d × e), u = (w × d) / (d × e).
            let den = dx * ey - dy * ex;
            if den == 0.0 {
                continue;
            }
            let (wx, wy) = (sx - ox, sy - oy);
            let t = (wx * ey - wy * ex) / den;
            let u = (wx * dy - wy * dx) / den;
            if t >= 0.0 && t < best && (0.0..=1.0).contains(&u) {
                best = t;
            }
        }
        best
    }
}

/// Moves cell index `i` one cell up (when `up`) or down; false when that
/// leaves the `n` cells of the axis.
#[inline(always)]
fn step_cell(i: &mut usize, up: bool, n: usize) -> bool {
    if up {
        *i += 1;
        *i < n
    } else if *i == 0 {
        false
    } else {
        *i -= 1;
        true
    }
}

/// Whether segment `[x0, y0, x1, y1]` meets the box `bx × by` (Liang–Barsky clip).
fn segment_touches_box(s: &[f64; 4], bx: [f64; 2], by: [f64; 2]) -> bool {
    let (dx, dy) = (s[2] - s[0], s[3] - s[1]);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, s[0] - bx[0]),
        (dx, bx[1] - s[0]),
        (-dy, s[1] - by[0]),
        (dy, by[1] - s[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    t0 <= t1
}
