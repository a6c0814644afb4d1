//! Scenarios: where the chair drives (a world and a route), resolved from the
//! configuration and checked for clearance from the walls. The chair executes
//! the commands exactly (its true wheel rates realise them), so the body
//! trajectory is the integral of the commands, whatever the effects.

use super::config::{ScenarioConfig, ScenarioSpec, SimConfig, WorldRef};
use super::path::Path;
use super::world::World;
use super::{stream_rng, worlds, SimError, STREAM_SCENARIO};
use nalgebra::Point2;
use rand::RngExt;

/// Names of the built-in scenarios.
pub const BUILTIN_SCENARIOS: [&str; 6] = [
    "corridor-loop",
    "hall",
    "square",
    "square-ccw",
    "figure-eight",
    "random-walk",
];

/// How the chair gets along its waypoints.
#[derive(Debug, Clone)]
pub enum Route {
    /// A smooth path followed by a feedback controller (rounded corners).
    Smooth(Path),
    /// Straight legs, stopping and turning in place at each waypoint.
    StopAndTurn {
        /// Waypoints (m, world frame).
        waypoints: Vec<Point2<f64>>,
        /// Whether the last leg returns to the first waypoint and repeats.
        closed: bool,
    },
}

/// A scenario ready to drive: its name, world and route.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Built-in name or the custom spec's name.
    pub name: String,
    /// Where it happens.
    pub world: World,
    /// What the chair drives.
    pub route: Route,
}

impl Scenario {
    /// Resolves the configured scenario and world, and checks that the route
    /// keeps `min_clearance` from every wall.
    pub fn from_config(cfg: &SimConfig) -> Result<Self, SimError> {
        let sc = &cfg.scenario;
        let (name, default_world, route_of): (String, WorldRef, RouteSource) = match &sc.custom {
            Some(spec) => (
                spec.name.clone(),
                spec.world
                    .clone()
                    .unwrap_or(WorldRef::Name("square-room".into())),
                RouteSource::Custom(spec.clone()),
            ),
            None => {
                let w = match sc.name.as_str() {
                    "corridor-loop" => "corridor-loop",
                    "hall" | "figure-eight" | "random-walk" => "hall",
                    "square" | "square-ccw" => "square-room",
                    other => {
                        return Err(SimError::Scenario(format!(
                            "unknown scenario '{other}' (known: {})",
                            BUILTIN_SCENARIOS.join(", ")
                        )))
                    }
                };
                (
                    sc.name.clone(),
                    WorldRef::Name(w.into()),
                    RouteSource::Builtin,
                )
            }
        };
        let world = resolve_world(cfg.world.world.as_ref().unwrap_or(&default_world))?;
        let route = match route_of {
            RouteSource::Custom(spec) => custom_route(&spec, sc)?,
            RouteSource::Builtin => builtin_route(&name, sc, &world, cfg)?,
        };
        let clearance = match &route {
            Route::Smooth(p) => p.clearance(&world),
            Route::StopAndTurn { waypoints, closed } => {
                let n = waypoints.len();
                let legs = if *closed { n } else { n - 1 };
                (0..legs)
                    .map(|i| world.clearance_along(waypoints[i], waypoints[(i + 1) % n], 0.02))
                    .fold(f64::INFINITY, f64::min)
            }
        };
        if clearance < sc.min_clearance {
            return Err(SimError::Scenario(format!(
                "scenario '{name}' passes {clearance:.2} m from a wall in world '{}' (need ≥ {} m)",
                world.name(),
                sc.min_clearance
            )));
        }
        Ok(Self { name, world, route })
    }
}

enum RouteSource {
    Custom(ScenarioSpec),
    Builtin,
}

fn resolve_world(r: &WorldRef) -> Result<World, SimError> {
    match r {
        WorldRef::Name(n) => worlds::builtin(n).ok_or_else(|| {
            SimError::World(format!(
                "unknown world '{n}' (known: {})",
                worlds::BUILTIN_WORLDS.join(", ")
            ))
        }),
        WorldRef::Map(spec) => World::from_spec("custom", spec),
    }
}

fn smooth(
    waypoints: &[[f64; 2]],
    radius: f64,
    closed: bool,
    sc: &ScenarioConfig,
) -> Result<Route, SimError> {
    let mut p = Path::rounded(waypoints, radius, closed)?;
    p.plan_speed(sc.cruise_speed, sc.turn_rate, 0.8 * sc.max_accel);
    Ok(Route::Smooth(p))
}

fn custom_route(spec: &ScenarioSpec, sc: &ScenarioConfig) -> Result<Route, SimError> {
    if spec.stop_and_turn {
        let w: Vec<_> = spec
            .waypoints
            .iter()
            .map(|p| Point2::new(p[0], p[1]))
            .collect();
        if w.len() < 2 || w.windows(2).any(|p| (p[1] - p[0]).norm() < 0.1) {
            return Err(SimError::Scenario(format!(
                "scenario '{}': need ≥ 2 waypoints, 0.1 m apart",
                spec.name
            )));
        }
        return Ok(Route::StopAndTurn {
            waypoints: w,
            closed: spec.closed,
        });
    }
    if !(spec.corner_radius.is_finite() && spec.corner_radius > 0.0) {
        return Err(SimError::Scenario("corner_radius must be > 0".into()));
    }
    smooth(&spec.waypoints, spec.corner_radius, spec.closed, sc)
}

fn builtin_route(
    name: &str,
    sc: &ScenarioConfig,
    world: &World,
    cfg: &SimConfig,
) -> Result<Route, SimError> {
    let square = |ccw: bool| {
        let mut w = vec![
            Point2::new(2.0, 2.0),
            Point2::new(2.0, 8.0),
            Point2::new(8.0, 8.0),
            Point2::new(8.0, 2.0),
        ];
        if ccw {
            w[1..].reverse();
        }
        Route::StopAndTurn {
            waypoints: w,
            closed: true,
        }
    };
    Ok(match name {
        // Counter-clockwise round the corridor centre line.
        "corridor-loop" => smooth(
            &[[1.25, 1.25], [28.75, 1.25], [28.75, 18.75], [1.25, 18.75]],
            1.25,
            true,
            sc,
        )?,
        // Round the hall, weaving between the pillar rows.
        "hall" => smooth(
            &[
                [2.5, 2.5],
                [28.0, 2.5],
                [28.0, 15.5],
                [17.5, 15.5],
                [17.5, 9.0],
                [7.5, 9.0],
                [7.5, 15.5],
                [2.5, 15.5],
            ],
            1.0,
            true,
            sc,
        )?,
        "square" => square(false),
        "square-ccw" => square(true),
        "figure-eight" => {
            // Lemniscate of Bernoulli, half-width 5 m, centred in the open part of the hall.
            let (a, c) = (5.0, Point2::new(24.0, 9.0));
            let n = 1400;
            let pts = (0..n)
                .map(|i| {
                    let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                    let d = 1.0 + t.sin().powi(2);
                    Point2::new(c.x + a * t.cos() / d, c.y + a * t.sin() * t.cos() / d)
                })
                .collect();
            let mut p = Path::from_points(pts, true)?;
            p.plan_speed(sc.cruise_speed, sc.turn_rate, 0.8 * sc.max_accel);
            Route::Smooth(p)
        }
        "random-walk" => {
            let need = sc.cruise_speed * cfg.duration_s + 10.0;
            smooth(&random_waypoints(world, cfg.seed, need)?, 0.8, false, sc)?
        }
        _ => unreachable!("names checked by the caller"),
    })
}

/// Random waypoints in free space: legs 2–6 m, turns ≤ 100°, every leg ≥ 1 m
/// from walls, until the path is `length` m long. Deterministic in `seed`.
fn random_waypoints(world: &World, seed: u64, length: f64) -> Result<Vec<[f64; 2]>, SimError> {
    let mut rng = stream_rng(seed, STREAM_SCENARIO, 0);
    let [x0, y0, x1, y1] = world.bounds();
    let mut p = Point2::new(3.0, 3.0);
    for _ in 0..1000 {
        let q = Point2::new(rng.random_range(x0..x1), rng.random_range(y0..y1));
        if world.distance(q) > 1.5 {
            p = q;
            break;
        }
    }
    let mut heading: f64 = rng.random_range(-3.1..3.1);
    let mut out = vec![[p.x, p.y]];
    let mut total = 0.0;
    let mut stuck = 0;
    while total < length {
        let turn_limit = if stuck > 200 {
            3.1
        } else {
            100f64.to_radians()
        };
        let h = heading + rng.random_range(-turn_limit..turn_limit);
        let len = rng.random_range(2.0..6.0);
        let q = p + nalgebra::Vector2::new(h.cos(), h.sin()) * len;
        if world.distance(q) > 1.2 && world.clearance_along(p, q, 0.05) > 1.0 {
            out.push([q.x, q.y]);
            total += len;
            p = q;
            heading = h;
            stuck = 0;
        } else {
            stuck += 1;
            if stuck > 2000 {
                return Err(SimError::Scenario(
                    "random walk: no free direction from here".into(),
                ));
            }
        }
    }
    Ok(out)
}
