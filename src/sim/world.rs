//! A 2D world of wall segments (m, world frame) with fast ray casting (a
//! uniform grid, cross-checked against parry's BVH) and point clearance
//! queries (parry's polyline).

use super::grid::Grid;
use super::SimError;
use nalgebra::Point2;
use parry2d_f64::math::Vector;
use parry2d_f64::query::{PointQuery, Ray, RayCast};
use parry2d_f64::shape::Polyline;
use serde::{Deserialize, Serialize};

/// A world as written in JSON: free segments `[x0, y0, x1, y1]` and closed
/// polygons `[[x, y], ...]` (m, world frame). Polygons are closed automatically.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WorldSpec {
    /// Free wall segments `[x0, y0, x1, y1]` (m).
    pub segments: Vec<[f64; 4]>,
    /// Closed outlines (pillars, furniture, rooms), vertices in order (m).
    pub polygons: Vec<Vec<[f64; 2]>>,
}

impl WorldSpec {
    /// Parses the JSON form `{"segments": [...], "polygons": [...]}`.
    pub fn from_json(text: &str) -> Result<Self, SimError> {
        serde_json::from_str(text).map_err(|e| SimError::World(format!("world JSON: {e}")))
    }

    /// Every wall as a segment `[x0, y0, x1, y1]`, polygons unrolled into their edges.
    pub fn all_segments(&self) -> Vec<[f64; 4]> {
        let mut out = self.segments.clone();
        for poly in &self.polygons {
            for (i, a) in poly.iter().enumerate() {
                let b = poly[(i + 1) % poly.len()];
                out.push([a[0], a[1], b[0], b[1]]);
            }
        }
        out
    }
}

/// Walls as line segments, binned for ray casting and in a BVH for distance
/// queries. Units: m, world frame.
#[derive(Clone)]
pub struct World {
    name: String,
    segments: Vec<[f64; 4]>,
    shape: Polyline,
    grid: Grid,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("name", &self.name)
            .field("segments", &self.segments.len())
            .finish()
    }
}

impl World {
    /// Builds a world from segments `[x0, y0, x1, y1]` (m). Refuses an empty
    /// world, non-finite coordinates and zero-length segments.
    pub fn from_segments(name: &str, segments: Vec<[f64; 4]>) -> Result<Self, SimError> {
        if segments.is_empty() {
            return Err(SimError::World(format!("world '{name}' has no walls")));
        }
        let mut vertices = Vec::with_capacity(2 * segments.len());
        let mut indices = Vec::with_capacity(segments.len());
        for (i, s) in segments.iter().enumerate() {
            if !s.iter().all(|v| v.is_finite()) {
                return Err(SimError::World(format!(
                    "world '{name}': segment {i} has a non-finite coordinate"
                )));
            }
            if (s[2] - s[0]).hypot(s[3] - s[1]) < 1e-9 {
                return Err(SimError::World(format!(
                    "world '{name}': segment {i} has zero length"
                )));
            }
            let k = vertices.len() as u32;
            vertices.push(Vector::new(s[0], s[1]));
            vertices.push(Vector::new(s[2], s[3]));
            indices.push([k, k + 1]);
        }
        Ok(Self {
            name: name.to_string(),
            grid: Grid::new(&segments),
            segments,
            shape: Polyline::new(vertices, Some(indices)),
        })
    }

    /// Builds a world from its JSON description.
    pub fn from_spec(name: &str, spec: &WorldSpec) -> Result<Self, SimError> {
        if spec.polygons.iter().any(|p| p.len() < 2) {
            return Err(SimError::World(format!(
                "world '{name}': a polygon needs at least 2 vertices"
            )));
        }
        Self::from_segments(name, spec.all_segments())
    }

    /// Parses and builds a world from JSON text (file reading is the caller's).
    pub fn from_json(name: &str, text: &str) -> Result<Self, SimError> {
        Self::from_spec(name, &WorldSpec::from_json(text)?)
    }

    /// The world's name (built-in name or the caller's label).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The walls as `[x0, y0, x1, y1]` (m).
    pub fn segments(&self) -> &[[f64; 4]] {
        &self.segments
    }

    /// The walls as a JSON-ready spec (all as free segments).
    pub fn to_spec(&self) -> WorldSpec {
        WorldSpec {
            segments: self.segments.clone(),
            polygons: Vec::new(),
        }
    }

    /// Axis-aligned bounds `(min_x, min_y, max_x, max_y)` (m).
    pub fn bounds(&self) -> [f64; 4] {
        self.segments.iter().fold(
            [f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY],
            |b, s| {
                [
                    b[0].min(s[0]).min(s[2]),
                    b[1].min(s[1]).min(s[3]),
                    b[2].max(s[0]).max(s[2]),
                    b[3].max(s[1]).max(s[3]),
                ]
            },
        )
    }

    /// Distance (m) from `origin` along the world-frame direction `angle` (rad)
    /// to the first wall, if one lies within `max_range` (m).
    #[inline]
    pub fn cast_ray(&self, origin: Point2<f64>, angle: f64, max_range: f64) -> Option<f64> {
        let (s, c) = angle.sin_cos();
        self.grid.cast(origin.x, origin.y, c, s, max_range)
    }

    /// Same as [`cast_ray`](Self::cast_ray) through parry's BVH: slower, an
    /// independent implementation to check the grid against.
    pub fn cast_ray_bvh(&self, origin: Point2<f64>, angle: f64, max_range: f64) -> Option<f64> {
        let (s, c) = angle.sin_cos();
        let ray = Ray::new(Vector::new(origin.x, origin.y), Vector::new(c, s));
        self.shape
            .cast_local_ray(&ray, max_range, false)
            .filter(|t| *t <= max_range)
    }

    /// Casts a fan of rays from one origin: ray `i` leaves at world angle
    /// `first + i·increment` (rad). Writes the range (m) or `+inf` (no wall
    /// within `max_range`) into `out`, one per ray.
    pub fn cast_fan(
        &self,
        origin: Point2<f64>,
        first: f64,
        increment: f64,
        max_range: f64,
        out: &mut [f64],
    ) {
        for (i, r) in out.iter_mut().enumerate() {
            let a = first + i as f64 * increment;
            *r = self.cast_ray(origin, a, max_range).unwrap_or(f64::INFINITY);
        }
    }

    /// Casts independent rays `(origin, world angle)`; writes range (m) or
    /// `+inf` per ray into `out` (same length as `rays`).
    pub fn cast_rays(&self, rays: &[(Point2<f64>, f64)], max_range: f64, out: &mut [f64]) {
        for ((o, a), r) in rays.iter().zip(out.iter_mut()) {
            *r = self.cast_ray(*o, *a, max_range).unwrap_or(f64::INFINITY);
        }
    }

    /// Distance (m) from a point to the nearest wall.
    pub fn distance(&self, p: Point2<f64>) -> f64 {
        self.shape
            .distance_to_local_point(Vector::new(p.x, p.y), false)
    }

    /// Smallest distance (m) from the straight segment `a`–`b` to any wall,
    /// sampled every `step` m (exact at the samples).
    pub fn clearance_along(&self, a: Point2<f64>, b: Point2<f64>, step: f64) -> f64 {
        let n = ((b - a).norm() / step.max(1e-3)).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| self.distance(a + (b - a) * (i as f64 / n as f64)))
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> World {
        let spec = WorldSpec {
            segments: vec![],
            polygons: vec![vec![[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]],
        };
        World::from_spec("box", &spec).unwrap()
    }

    #[test]
    fn rays_hit_box_walls_at_known_distances() {
        let w = unit_box();
        let o = Point2::new(1.0, 1.0);
        assert!((w.cast_ray(o, 0.0, 20.0).unwrap() - 3.0).abs() < 1e-12);
        assert!((w.cast_ray(o, std::f64::consts::PI, 20.0).unwrap() - 1.0).abs() < 1e-12);
        assert!((w.cast_ray(o, std::f64::consts::FRAC_PI_2, 20.0).unwrap() - 1.0).abs() < 1e-12);
        let diag = w.cast_ray(o, std::f64::consts::FRAC_PI_4, 20.0).unwrap();
        assert!((diag - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(w.cast_ray(o, 0.0, 2.5), None, "beyond max range");
        assert!((w.distance(Point2::new(3.5, 1.0)) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn grid_and_bvh_agree_on_random_rays() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for w in [super::super::worlds::cluttered(600, 3), unit_box()] {
            let [x0, y0, x1, y1] = w.bounds();
            let mut hits = 0;
            for _ in 0..3000 {
                let o = Point2::new(
                    rng.random_range(x0 - 2.0..x1 + 2.0),
                    rng.random_range(y0 - 2.0..y1 + 2.0),
                );
                let a = rng.random_range(-4.0..4.0);
                let max = rng.random_range(0.5..30.0);
                let (g, b) = (w.cast_ray(o, a, max), w.cast_ray_bvh(o, a, max));
                match (g, b) {
                    (Some(g), Some(b)) => {
                        assert!((g - b).abs() < 1e-9, "{g} vs {b}");
                        hits += 1;
                    }
                    (None, None) => {}
                    other => panic!("grid and BVH disagree: {other:?} from {o} at {a}"),
                }
            }
            assert!(hits > 500, "enough hits to compare: {hits}");
            // Axis-parallel rays, exactly.
            let c = Point2::new((x0 + x1) / 2.0 + 0.01, (y0 + y1) / 2.0 + 0.01);
            for a in [
                0.0,
                std::f64::consts::FRAC_PI_2,
                std::f64::consts::PI,
                -std::f64::consts::FRAC_PI_2,
            ] {
                let (g, b) = (w.cast_ray(c, a, 100.0), w.cast_ray_bvh(c, a, 100.0));
                assert!((g.unwrap() - b.unwrap()).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn json_worlds_parse_and_bad_ones_are_refused() {
        let w = World::from_json(
            "j",
            r#"{"segments": [[0,0,1,0]], "polygons": [[[2,2],[3,2],[3,3]]]}"#,
        )
        .unwrap();
        assert_eq!(w.segments().len(), 4);
        assert!(World::from_json("j", r#"{"walls": []}"#).is_err());
        assert!(World::from_json("j", r#"{"segments": []}"#).is_err());
        assert!(World::from_json("j", r#"{"segments": [[0,0,0,0]]}"#).is_err());
        assert!(World::from_json("j", r#"{"segments": [[0,0,1]]}"#).is_err());
    }
}
