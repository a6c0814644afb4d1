//! Built-in worlds (m, world frame, origin at the lower-left outer corner):
//! `corridor-loop` (a hospital-floor corridor ring), `hall` (open hall with
//! pillars and people) and `square-room` (room for a 6 m × 6 m UMBmark square).

use super::world::World;
use rand::{RngExt, SeedableRng};

/// Names of the built-in worlds.
pub const BUILTIN_WORLDS: [&str; 3] = ["corridor-loop", "hall", "square-room"];

/// A built-in world by name, `None` for an unknown name.
pub fn builtin(name: &str) -> Option<World> {
    let segs = match name {
        "corridor-loop" => corridor_loop(),
        "hall" => hall(),
        "square-room" => square_room(),
        _ => return None,
    };
    Some(World::from_segments(name, segs).expect("built-in worlds are valid"))
}

/// A departure from a straight wall at `at` m along it, `width` m wide:
/// `depth` > 0 protrudes into the free side (cabinet, pillar), < 0 is recessed
/// (door niche). With `door` set, the recess is a room behind a doorway of that
/// width (jambs stay on the wall line).
#[derive(Clone, Copy)]
struct Feature {
    at: f64,
    width: f64,
    depth: f64,
    door: Option<f64>,
}

const fn bump(at: f64, width: f64, depth: f64) -> Feature {
    Feature {
        at,
        width,
        depth,
        door: None,
    }
}

const fn room(at: f64, width: f64, depth: f64, door: f64) -> Feature {
    Feature {
        at,
        width,
        depth: -depth,
        door: Some(door),
    }
}

/// Appends a wall from `a` to `b` whose free side is the left side when `left_free`,
/// with its features (sorted by `at`).
fn wall(segs: &mut Vec<[f64; 4]>, a: [f64; 2], b: [f64; 2], left_free: bool, feats: &[Feature]) {
    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
    let u = [(b[0] - a[0]) / len, (b[1] - a[1]) / len];
    let sign = if left_free { 1.0 } else { -1.0 };
    let n = [-u[1] * sign, u[0] * sign];
    let p = |s: f64, d: f64| [a[0] + u[0] * s + n[0] * d, a[1] + u[1] * s + n[1] * d];
    let mut push = |p0: [f64; 2], p1: [f64; 2]| segs.push([p0[0], p0[1], p1[0], p1[1]]);
    let mut s = 0.0;
    for f in feats {
        let (s0, s1) = (f.at - f.width / 2.0, f.at + f.width / 2.0);
        push(p(s, 0.0), p(s0, 0.0));
        push(p(s0, 0.0), p(s0, f.depth));
        push(p(s0, f.depth), p(s1, f.depth));
        push(p(s1, f.depth), p(s1, 0.0));
        if let Some(door) = f.door {
            // Door jambs on the wall line, leaving a doorway into the room.
            push(p(s0, 0.0), p(f.at - door / 2.0, 0.0));
            push(p(f.at + door / 2.0, 0.0), p(s1, 0.0));
        }
        s = s1;
    }
    push(p(s, 0.0), p(len, 0.0));
}

/// The four walls of the axis-aligned rectangle `lo`–`hi`, counter-clockwise
/// from `lo` (bottom, right, top, left side), each with its features; the
/// free side is inside the rectangle when `inside_free`, outside otherwise.
fn rectangle_walls(
    segs: &mut Vec<[f64; 4]>,
    lo: [f64; 2],
    hi: [f64; 2],
    inside_free: bool,
    feats: [&[Feature]; 4],
) {
    let corners = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    for (k, f) in feats.iter().enumerate() {
        wall(segs, corners[k], corners[(k + 1) % 4], inside_free, f);
    }
}

/// A regular polygon (people, plants: 8 sides) of radius `r` at `c`.
fn ngon(segs: &mut Vec<[f64; 4]>, c: [f64; 2], r: f64, sides: usize) {
    let v = |i: usize| {
        let a = 2.0 * std::f64::consts::PI * i as f64 / sides as f64;
        [c[0] + r * a.cos(), c[1] + r * a.sin()]
    };
    for i in 0..sides {
        let (p, q) = (v(i), v(i + 1));
        segs.push([p[0], p[1], q[0], q[1]]);
    }
}

/// An axis-aligned box (furniture, pillars) from `(x0, y0)` to `(x1, y1)`.
fn rect(segs: &mut Vec<[f64; 4]>, x0: f64, y0: f64, x1: f64, y1: f64) {
    segs.push([x0, y0, x1, y0]);
    segs.push([x1, y0, x1, y1]);
    segs.push([x1, y1, x0, y1]);
    segs.push([x0, y1, x0, y0]);
}

/// Features of the corridor ring's outer walls (bottom, right, top, left):
/// door niches, cabinets and side rooms.
const CORRIDOR_OUTER: [&[Feature]; 4] = [
    &[
        bump(5.0, 1.2, -0.3),
        bump(9.5, 0.6, 0.2),
        room(15.0, 3.0, 2.5, 1.0),
        bump(21.0, 1.0, -0.25),
        bump(25.5, 2.0, 0.15),
    ],
    &[
        bump(4.5, 1.0, -0.3),
        room(10.0, 4.0, 3.0, 1.2),
        bump(15.5, 0.5, 0.2),
    ],
    &[
        bump(4.0, 0.8, 0.2),
        bump(8.0, 1.2, -0.3),
        bump(12.5, 1.2, -0.3),
        room(20.0, 3.5, 2.5, 1.0),
        bump(26.0, 1.5, 0.1),
    ],
    &[
        bump(5.0, 2.5, -0.4),
        bump(11.0, 0.6, 0.2),
        bump(15.0, 1.0, -0.3),
    ],
];

/// Features of the corridor ring's inner block (bottom, right, top, left).
const CORRIDOR_INNER: [&[Feature]; 4] = [
    &[
        bump(3.5, 1.0, -0.3),
        bump(8.0, 0.5, 0.2),
        bump(14.0, 1.2, -0.3),
        bump(19.5, 3.0, 0.12),
    ],
    &[
        bump(3.0, 1.0, -0.3),
        bump(8.5, 0.8, 0.15),
        bump(12.0, 1.5, -0.35),
    ],
    &[
        bump(4.0, 1.0, -0.3),
        bump(10.0, 2.0, 0.12),
        bump(16.0, 1.0, -0.3),
        bump(21.0, 0.5, 0.2),
    ],
    &[bump(4.0, 0.6, 0.2), bump(9.5, 1.4, -0.3)],
];

/// A 30 m × 20 m ring of 2.5 m wide corridors around a 25 m × 15 m block,
/// with door niches, cabinets and side rooms so no stretch is featureless.
/// The corridor centre line is the rectangle (1.25, 1.25)–(28.75, 18.75).
fn corridor_loop() -> Vec<[f64; 4]> {
    let mut s = Vec::new();
    // Outer walls: the corridor is inside them.
    rectangle_walls(&mut s, [0.0, 0.0], [30.0, 20.0], true, CORRIDOR_OUTER);
    // Inner block: the corridor is outside it.
    rectangle_walls(&mut s, [2.5, 2.5], [27.5, 17.5], false, CORRIDOR_INNER);
    s
}

/// Features of the hall's walls (bottom, right, top, left): door niches.
const HALL_WALLS: [&[Feature]; 4] = [
    &[bump(8.0, 1.2, -0.3), bump(20.0, 1.6, -0.3)],
    &[bump(14.0, 1.5, -0.3)],
    &[bump(6.0, 2.0, -0.3), bump(16.0, 1.2, -0.3)],
    &[bump(4.0, 1.2, -0.3)],
];

/// A 30 m × 18 m hall: two rows of 0.6 m pillars (x = 5, 10, 15; y = 6, 12)
/// in the left part, an open right part (x > 18), standing people (0.25 m
/// octagons), a bench and a desk.
fn hall() -> Vec<[f64; 4]> {
    let mut s = Vec::new();
    rectangle_walls(&mut s, [0.0, 0.0], [30.0, 18.0], true, HALL_WALLS);
    for x in [5.0, 10.0, 15.0] {
        for y in [6.0, 12.0] {
            rect(&mut s, x - 0.3, y - 0.3, x + 0.3, y + 0.3);
        }
    }
    for c in [[22.0, 13.5], [13.0, 4.0], [24.0, 4.5], [12.5, 14.5]] {
        ngon(&mut s, c, 0.25, 8);
    }
    rect(&mut s, 20.5, 16.8, 22.1, 17.3); // bench
    rect(&mut s, 0.3, 7.0, 1.1, 10.0); // desk
    s
}

/// Features of the square room's walls (bottom, right, top, left): door
/// niches in the bottom and top ones.
const SQUARE_ROOM_WALLS: [&[Feature]; 4] =
    [&[bump(3.0, 1.0, -0.3)], &[], &[bump(5.0, 1.0, -0.3)], &[]];

/// A 10 m × 10 m room with a door niche and furniture kept ≥ 0.9 m away from
/// the square path (2, 2)–(8, 8): a centre table, shelves, a cabinet, a chair
/// and a plant.
fn square_room() -> Vec<[f64; 4]> {
    let mut s = Vec::new();
    rectangle_walls(&mut s, [0.0, 0.0], [10.0, 10.0], true, SQUARE_ROOM_WALLS);
    rect(&mut s, 4.4, 4.6, 5.6, 5.4); // table
    rect(&mut s, 0.2, 9.4, 2.5, 9.8); // shelf
    rect(&mut s, 9.4, 3.0, 9.8, 6.0); // shelf
    rect(&mut s, 6.5, 0.2, 8.5, 0.6); // cabinet
    ngon(&mut s, [0.8, 5.0], 0.3, 8); // chair
    ngon(&mut s, [9.0, 9.0], 0.25, 8); // plant
    s
}

/// A walled 40 m × 40 m area scattered with octagons until it has about
/// `segments` walls: a stress world for ray-casting benchmarks.
pub fn cluttered(segments: usize, seed: u64) -> World {
    let mut s = Vec::new();
    rect(&mut s, 0.0, 0.0, 40.0, 40.0);
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    while s.len() + 8 <= segments.max(12) {
        let c = [rng.random_range(1.0..39.0), rng.random_range(1.0..39.0)];
        ngon(&mut s, c, rng.random_range(0.1..0.4), 8);
    }
    World::from_segments("cluttered", s).expect("cluttered world is valid")
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point2;

    #[test]
    fn every_builtin_builds_and_unknown_names_do_not() {
        for name in BUILTIN_WORLDS {
            let w = builtin(name).unwrap();
            assert!(w.segments().len() >= 20, "{name}");
        }
        assert!(builtin("moon").is_none());
    }

    #[test]
    fn corridor_centre_line_is_clear() {
        let w = builtin("corridor-loop").unwrap();
        let c = [[1.25, 1.25], [28.75, 1.25], [28.75, 18.75], [1.25, 18.75]];
        for i in 0..4 {
            let (a, b) = (c[i], c[(i + 1) % 4]);
            let d = w.clearance_along(Point2::new(a[0], a[1]), Point2::new(b[0], b[1]), 0.05);
            assert!(d > 0.9, "leg {i}: {d}");
        }
    }

    #[test]
    fn cluttered_world_has_the_requested_size() {
        let w = cluttered(2000, 1);
        assert!((1990..=2004).contains(&w.segments().len()));
    }
}
