//! The current scan as the registration's source: its points deskewed by
//! the pair's guess, thinned, each with its own surface normal.

use super::PriorSource;
use crate::geom::{self, Pose2};
use crate::icp::preprocess::{Preprocessor, ScanPoints};
use crate::icp::reference::Reference;
use serde::{Deserialize, Serialize};

/// Motion compensation and thinning of the source. Units: m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SourceSettings {
    /// Compensate the motion during each sweep with the pair's guess.
    pub deskew: bool,
    /// Keep every n-th beam (1 = all).
    pub beam_stride: usize,
    /// At most one point per voxel of this size (m); 0 keeps every point.
    pub voxel_size: f64,
}

impl Default for SourceSettings {
    fn default() -> Self {
        Self {
            deskew: true,
            beam_stride: 1,
            voxel_size: 0.0,
        }
    }
}

/// The current scan's points, and the source thinned from them.
#[derive(Debug, Clone, Default)]
pub struct Source {
    set: SourceSettings,
    /// All valid points of the current scan (base frame).
    pub cur: ScanPoints,
    /// The points registered.
    pub src: Vec<[f64; 2]>,
    /// Index in `cur` of each point of `src`.
    kept: Vec<usize>,
    /// Own surface normal of each point of `src` (NaN where none was fitted).
    pub normals: Vec<[f64; 2]>,
}

impl Source {
    /// Empty buffers.
    pub fn new(set: SourceSettings) -> Self {
        Self {
            set,
            ..Default::default()
        }
    }

    /// The base's velocity `(v, ω)` (m/s, rad/s) during a sweep of a pair
    /// `dt` s long guessed at `prior` (from `source`), to deskew by: none
    /// without a guess or with deskewing off.
    pub fn twist(&self, prior: &Pose2, source: PriorSource, dt: f64) -> Option<(f64, f64)> {
        (self.set.deskew && source != PriorSource::None).then(|| {
            let (ds, dth) = geom::arc_of_increment(prior);
            (ds / dt, dth / dt)
        })
    }

    /// The source points of the current scan (downsampled) and their own
    /// surface normals from `own`, the scan's lines.
    pub fn prepare(&mut self, pre: &mut Preprocessor, own: &Reference) {
        let p = &self.set;
        pre.downsample(
            &self.cur.pts,
            p.beam_stride,
            p.voxel_size,
            &mut self.src,
            &mut self.kept,
        );
        self.normals.clear();
        self.normals.extend(
            self.kept
                .iter()
                .map(|&i| own.normal(i).unwrap_or([f64::NAN; 2])),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deskewing_uses_the_guess_over_the_pair() {
        let s = Source::default();
        let prior = geom::pose(0.2, 0.0, 0.0);
        let (v, w) = s.twist(&prior, PriorSource::Given, 0.1).unwrap();
        assert!((v - 2.0).abs() < 1e-12 && w.abs() < 1e-12);
        assert!(s.twist(&prior, PriorSource::None, 0.1).is_none());
        let off = Source::new(SourceSettings {
            deskew: false,
            ..Default::default()
        });
        assert!(off.twist(&prior, PriorSource::Given, 0.1).is_none());
    }

    #[test]
    fn thinned_points_keep_their_own_normals() {
        let mut s = Source::new(SourceSettings {
            beam_stride: 2,
            ..Default::default()
        });
        // A wall 2 m ahead, and one stray point far from it.
        let mut pts: Vec<[f64; 2]> = (0..20).map(|i| [2.0, 0.05 * i as f64]).collect();
        pts.push([5.0, 5.0]);
        let mut link = vec![true; 21];
        link[19] = false;
        link[20] = false;
        let range = pts.iter().map(|p| p[0].hypot(p[1])).collect();
        s.cur = ScanPoints { pts, link, range };
        let mut own = Reference::new(8, 0.3);
        own.set_lines(&s.cur);
        let mut pre = Preprocessor::new(Pose2::identity(), 0.0, 30.0, 6.0, 0.5);
        s.prepare(&mut pre, &own);
        assert_eq!(s.src.len(), 11);
        assert_eq!(s.src[1], [2.0, 0.1]);
        let n = s.normals[1];
        assert!(n[0].abs() > 0.999 && n[1].abs() < 1e-6, "{n:?}");
        assert!(s.normals[10][0].is_nan());
    }
}
