//! What a scan is matched against: points in a fixed frame with their surface
//! links and a kd-tree, built once per reference (never per iteration).

use super::preprocess::ScanPoints;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// A reference point set with its nearest-neighbour index.
#[derive(Default)]
pub struct Reference {
    pts: Vec<[f64; 2]>,
    link: Vec<bool>,
    tree: Option<ImmutableKdTree<f64, 2>>,
}

/// The closest point of the reference surface to a query.
#[derive(Debug, Clone, Copy)]
pub struct Closest {
    /// The point on the reference (m).
    pub target: [f64; 2],
    /// Unit normal of the surface there, when a segment carries it.
    pub normal: Option<[f64; 2]>,
}

impl Reference {
    /// Number of reference points.
    pub fn len(&self) -> usize {
        self.pts.len()
    }

    /// True when there is nothing to match against.
    pub fn is_empty(&self) -> bool {
        self.pts.is_empty() || self.tree.is_none()
    }

    /// Replaces the content with `scan`'s points and rebuilds the tree.
    pub fn set(&mut self, scan: &ScanPoints) {
        self.pts.clear();
        self.link.clear();
        self.pts.extend_from_slice(&scan.pts);
        self.link.extend_from_slice(&scan.link);
        self.rebuild();
    }

    /// Replaces the content with several point sets, each mapped by a pose
    /// `frame_from_set` first; links never cross from one set to the next.
    pub fn set_many<'a>(
        &mut self,
        sets: impl Iterator<Item = (&'a crate::geom::Pose2, &'a ScanPoints)>,
    ) {
        self.pts.clear();
        self.link.clear();
        for (pose, s) in sets {
            let (c, sn) = (pose.rotation.cos_angle(), pose.rotation.sin_angle());
            let t = pose.translation.vector;
            self.pts.extend(
                s.pts
                    .iter()
                    .map(|p| [c * p[0] - sn * p[1] + t.x, sn * p[0] + c * p[1] + t.y]),
            );
            self.link.extend_from_slice(&s.link);
            if let Some(l) = self.link.last_mut() {
                *l = false;
            }
        }
        self.rebuild();
    }

    fn rebuild(&mut self) {
        self.tree = if self.pts.is_empty() {
            None
        } else {
            ImmutableKdTree::new_from_slice(&self.pts).ok()
        };
    }

    /// The closest point to `q` on the reference polyline: the nearest
    /// reference point, moved onto the linked segment on either side of it
    /// when that is closer (Besl & McKay's closest point on the model shape).
    /// `None` when the reference is empty, or when the closest point is an
    /// isolated sample or the open end of a surface: those move with the
    /// viewpoint (sampling, occlusion edges) and would pull the estimate
    /// towards zero motion.
    pub fn closest(&self, q: [f64; 2]) -> Option<Closest> {
        let tree = self.tree.as_ref()?;
        let nn = tree
            .query(&q)
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        let j = nn.item as usize;
        let a = self.pts[j];
        let before = j > 0 && self.link[j - 1];
        let after = self.link[j] && j + 1 < self.pts.len();
        let mut best: Option<(f64, bool, Closest)> = None;
        let mut try_seg = |b: [f64; 2]| {
            let (ux, uy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = ux * ux + uy * uy;
            if len2 <= 0.0 {
                return;
            }
            let s_raw = ((q[0] - a[0]) * ux + (q[1] - a[1]) * uy) / len2;
            let s = s_raw.clamp(0.0, 1.0);
            let f = [a[0] + s * ux, a[1] + s * uy];
            let d2 = (q[0] - f[0]).powi(2) + (q[1] - f[1]).powi(2);
            if best.as_ref().is_none_or(|b| d2 < b.0) {
                let len = len2.sqrt();
                let c = Closest {
                    target: f,
                    normal: Some([-uy / len, ux / len]),
                };
                best = Some((d2, s_raw < 0.0, c));
            }
        };
        if before {
            try_seg(self.pts[j - 1]);
        }
        if after {
            try_seg(self.pts[j + 1]);
        }
        match best {
            // Beyond the vertex on a surface that ends there: open end.
            Some((_, true, _)) if !(before && after) => None,
            Some((_, _, c)) => Some(c),
            None => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_lies_on_the_linked_segment() {
        let sp = ScanPoints {
            pts: vec![[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]],
            link: vec![true, false, false],
            range: vec![1.0; 3],
        };
        let mut r = Reference::default();
        r.set(&sp);
        let c = r.closest([0.3, 0.2]).unwrap();
        assert!((c.target[0] - 0.3).abs() < 1e-12 && c.target[1].abs() < 1e-12);
        assert!(c.normal.unwrap()[1].abs() > 0.999);
        // isolated samples and open ends give no correspondence
        assert!(r.closest([5.2, 5.1]).is_none());
        assert!(r.closest([-0.2, 0.1]).is_none());
        assert!(r.closest([1.2, 0.1]).is_none());
    }

    #[test]
    fn empty_reference_answers_nothing() {
        let mut r = Reference::default();
        r.set(&ScanPoints::default());
        assert!(r.is_empty());
        assert!(r.closest([0.0, 0.0]).is_none());
    }
}
