//! The nearest-neighbour index of a reference's points, built once per
//! reference (a keyframe or a local map) and queried once per source point
//! and association: the kiddo k-d tree (`ImmutableKdTree`, the design's
//! choice) or the hand-written uniform grid of [`super::grid`]. Both answer
//! the same exact query, the nearest point closer than a radius, so the
//! registration is the same whichever answers it (up to the order of exact
//! ties); only the cost differs (measured side by side in the manual's
//! performance page).

use kiddo::{Eytzinger, KdTree, SquaredEuclidean, VecOfArenas};
use serde::{Deserialize, Serialize};

use super::grid::PointGrid;

/// Which structure answers the nearest-neighbour queries (`[icp] neighbours`).
///
/// The default is the grid: over the whole `odocal icp` process of the four
/// benchmark logs, kiddo at its best measured form here (16-point leaves;
/// 8, 32 and 64 points and Donnelly stems were slower) took 15–30 % more CPU
/// time, the queries being about a quarter of the process (the manual's
/// performance page has the side-by-side).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NeighbourSearch {
    /// kiddo's k-d tree in its immutable layout (Eytzinger stems, arena
    /// leaves of `LEAF` points).
    KdTree,
    /// A uniform grid of square cells searched ring by ring (`icp::grid`).
    #[default]
    Grid,
}

/// Points per leaf of the k-d tree: 16 measured fastest on the benchmark
/// logs' local maps (8, 32 and 64 were 2–8 % slower over the whole process).
const LEAF: usize = 16;

/// kiddo's immutable tree layout (`ImmutableKdTree`: Eytzinger-ordered stems,
/// leaves as arenas) with `LEAF` points per leaf; items are point indices.
type Tree = KdTree<f64, u32, Eytzinger, VecOfArenas<f64, u32, 2, LEAF>, 2, LEAF>;

/// Cell size (m) of the grid: a few beam spacings at indoor ranges, so that a
/// query on a wall finds its neighbour in the 3 × 3 cells around it.
const GRID_CELL: f64 = 0.2;

/// An index over one point set, of the kind chosen at construction.
#[derive(Default)]
pub struct NeighbourIndex {
    kind: NeighbourSearch,
    /// The tree over the points (`None`: not built, or built over no point).
    tree: Option<Tree>,
    /// The grid, whose buffers are kept from one build to the next.
    grid: PointGrid,
    /// Whether the index holds the current point set.
    built: bool,
}

impl NeighbourIndex {
    /// An empty index that will be built as `kind`.
    pub fn new(kind: NeighbourSearch) -> Self {
        Self {
            kind,
            ..Default::default()
        }
    }

    /// Forgets the point set (keeping the grid's buffers).
    pub fn clear(&mut self) {
        self.tree = None;
        self.built = false;
    }

    /// True when no point can be found: not built, or built over none.
    pub fn is_empty(&self) -> bool {
        !self.built
            || match self.kind {
                NeighbourSearch::KdTree => self.tree.is_none(),
                NeighbourSearch::Grid => self.grid.is_empty(),
            }
    }

    /// Builds the index over `pts` (m); a point's index in `pts` is what
    /// [`nearest`](Self::nearest) returns. Points with a non-finite
    /// coordinate are never found (neither structure can place them).
    pub fn build(&mut self, pts: &[[f64; 2]]) {
        self.clear();
        match self.kind {
            NeighbourSearch::KdTree => self.tree = kd_tree(pts),
            NeighbourSearch::Grid => self.grid.build(pts, GRID_CELL),
        }
        self.built = true;
    }

    /// Index and squared distance (m²) of the point nearest to `q` among
    /// those closer than `max_dist` m; `None` when there is none.
    pub fn nearest(&self, q: [f64; 2], max_dist: f64) -> Option<(usize, f64)> {
        if !self.built || !(q[0].is_finite() && q[1].is_finite()) {
            return None;
        }
        match self.kind {
            NeighbourSearch::KdTree => {
                let tree = self.tree.as_ref()?;
                let found = tree
                    .query(&q)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                (found.distance < max_dist * max_dist)
                    .then_some((found.item as usize, found.distance))
            }
            NeighbourSearch::Grid => self.grid.nearest(q, max_dist),
        }
    }
}

/// kiddo's tree over the finite points of `pts`, each item its index in
/// `pts`; `None` when there is none. Non-finite points are left out: kiddo
/// reserves its float type's largest value and cannot order a NaN.
fn kd_tree(pts: &[[f64; 2]]) -> Option<Tree> {
    let finite = |p: &[f64; 2]| p[0].is_finite() && p[1].is_finite();
    let tree = if pts.iter().all(finite) {
        Tree::new_from_slice(pts)
    } else {
        let kept: Vec<(u32, [f64; 2])> = (0u32..)
            .zip(pts.iter().copied())
            .filter(|(_, p)| finite(p))
            .collect();
        Tree::new_from_entries(&kept)
    };
    tree.ok().filter(|t| t.size() > 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nearest by brute force, strictly closer than `max_dist`.
    fn brute(pts: &[[f64; 2]], q: [f64; 2], max_dist: f64) -> Option<(usize, f64)> {
        let d2 = |p: &[f64; 2]| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
        let best = pts
            .iter()
            .enumerate()
            .filter(|(_, p)| p[0].is_finite() && p[1].is_finite())
            .min_by(|a, b| d2(a.1).total_cmp(&d2(b.1)))?;
        (d2(best.1) < max_dist * max_dist).then(|| (best.0, d2(best.1)))
    }

    /// Walls along the axes (many equal coordinates: a k-d tree's hard case),
    /// a diagonal and scattered points, one of them NaN.
    fn room() -> Vec<[f64; 2]> {
        let mut pts = Vec::new();
        for i in 0..200 {
            let s = -3.0 + 0.03 * i as f64;
            pts.push([2.0, s]);
            pts.push([s, -1.5]);
            pts.push([s, 0.5 * s + 0.7]);
        }
        pts.push([f64::NAN, 1.0]);
        for k in 0..50 {
            let a = k as f64 * 0.7;
            pts.push([4.0 * a.sin(), 3.0 * (1.3 * a).cos()]);
        }
        pts
    }

    #[test]
    fn both_kinds_find_the_brute_force_nearest_within_the_radius() {
        let pts = room();
        for kind in [NeighbourSearch::KdTree, NeighbourSearch::Grid] {
            let mut index = NeighbourIndex::new(kind);
            assert!(index.is_empty());
            index.build(&pts);
            assert!(!index.is_empty());
            for i in 0..400 {
                let a = i as f64 * 0.37;
                let q = [
                    3.5 * a.cos() * (0.3 + 0.7 * (i % 7) as f64 / 6.0),
                    3.0 * a.sin(),
                ];
                for max_dist in [0.01, 0.05, 0.3, 10.0] {
                    let want = brute(&pts, q, max_dist);
                    let got = index.nearest(q, max_dist);
                    // Equal distances may name either point of a tie.
                    match (want, got) {
                        (None, None) => {}
                        (Some(w), Some(g)) => {
                            assert_eq!(w.1, g.1, "{kind:?} {q:?} {max_dist}");
                            let p = pts[g.0];
                            let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                            assert_eq!(d2, g.1, "{kind:?}: the index names its point");
                        }
                        _ => panic!("{kind:?} {q:?} {max_dist}: {want:?} against {got:?}"),
                    }
                }
            }
        }
    }

    #[test]
    fn exactly_at_the_radius_is_not_closer_than_it() {
        for kind in [NeighbourSearch::KdTree, NeighbourSearch::Grid] {
            let mut index = NeighbourIndex::new(kind);
            index.build(&[[0.0, 0.0], [3.0, 4.0]]);
            assert_eq!(index.nearest([0.0, 0.5], 0.5), None, "{kind:?}");
            assert_eq!(
                index.nearest([0.0, 0.5], 0.5001),
                Some((0, 0.25)),
                "{kind:?}"
            );
            assert_eq!(index.nearest([3.0, 3.0], 10.0), Some((1, 1.0)), "{kind:?}");
        }
    }

    #[test]
    fn nothing_is_found_in_an_empty_or_cleared_index_or_for_a_nan_query() {
        for kind in [NeighbourSearch::KdTree, NeighbourSearch::Grid] {
            let mut index = NeighbourIndex::new(kind);
            index.build(&[]);
            assert!(index.is_empty() && index.nearest([0.0, 0.0], 1e9).is_none());
            index.build(&[[f64::NAN, 0.0], [f64::INFINITY, 1.0]]);
            assert!(index.nearest([0.0, 0.0], 1e9).is_none(), "{kind:?}");
            index.build(&[[1.0, 1.0]]);
            assert!(index.nearest([f64::NAN, 0.0], 1e9).is_none());
            assert_eq!(index.nearest([1.0, 2.0], 2.0), Some((0, 1.0)));
            index.clear();
            assert!(index.is_empty() && index.nearest([1.0, 2.0], 2.0).is_none());
        }
    }

    #[test]
    fn a_point_among_non_finite_ones_keeps_its_own_index() {
        let pts = [
            [f64::NAN, 0.0],
            [5.0, 5.0],
            [f64::NEG_INFINITY, 2.0],
            [1.0, 0.0],
        ];
        for kind in [NeighbourSearch::KdTree, NeighbourSearch::Grid] {
            let mut index = NeighbourIndex::new(kind);
            index.build(&pts);
            assert_eq!(
                index.nearest([1.0, 0.1], 1.0).map(|f| f.0),
                Some(3),
                "{kind:?}"
            );
            assert_eq!(
                index.nearest([4.0, 5.0], 2.0).map(|f| f.0),
                Some(1),
                "{kind:?}"
            );
        }
    }
}
