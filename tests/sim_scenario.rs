//! Simulator scenarios: every built-in route stays clear of walls, respects the
//! motion limits, loops when the run is longer, and squares close exactly.

use nalgebra::Point2;
use odocal::sim::{drive, Drive, Scenario, ScenarioSpec, SimConfig, BUILTIN_SCENARIOS};

fn run(name: &str, duration: f64) -> (Scenario, Drive, SimConfig) {
    let mut cfg = SimConfig::default();
    cfg.scenario.name = name.into();
    cfg.duration_s = duration;
    let scn = Scenario::from_config(&cfg).unwrap();
    let d = drive(&scn, &cfg.scenario, duration, 1.0 / cfg.integration_hz);
    (scn, d, cfg)
}

/// Smallest wall distance (m) of the body along the run, sampled at 100 Hz.
fn min_clearance(scn: &Scenario, d: &Drive) -> f64 {
    (0..d.x.len())
        .step_by(10)
        .map(|k| scn.world.distance(Point2::new(d.x[k], d.y[k])))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn every_builtin_scenario_keeps_clear_of_walls_within_motion_limits() {
    assert_eq!(BUILTIN_SCENARIOS.len(), 6);
    for name in BUILTIN_SCENARIOS {
        let (scn, d, cfg) = run(name, 150.0);
        let sc = &cfg.scenario;
        let clear = min_clearance(&scn, &d);
        assert!(clear >= 0.4, "{name}: {clear:.3} m from a wall");
        let dt = d.dt;
        let tol = 1e-9;
        assert!(
            d.v.iter().all(|v| v.abs() <= sc.max_speed + tol),
            "{name} |v|"
        );
        assert!(
            d.w.iter().all(|w| w.abs() <= sc.max_turn_rate + tol),
            "{name} |w|"
        );
        let acc =
            d.v.windows(2)
                .map(|v| (v[1] - v[0]).abs() / dt)
                .fold(0.0, f64::max);
        let alpha =
            d.w.windows(2)
                .map(|w| (w[1] - w[0]).abs() / dt)
                .fold(0.0, f64::max);
        assert!(acc <= sc.max_accel * (1.0 + 1e-6), "{name}: accel {acc}");
        assert!(
            alpha <= sc.max_angular_accel * (1.0 + 1e-6),
            "{name}: ang. accel {alpha}"
        );
        let dist: f64 = d.v.iter().map(|v| v.abs() * dt).sum();
        assert!(dist > 40.0, "{name}: only {dist:.1} m driven in 150 s");
        assert!(d
            .x
            .iter()
            .chain(&d.y)
            .chain(&d.theta)
            .all(|v| v.is_finite()));
        eprintln!("{name}: clearance {clear:.3} m, {dist:.1} m, max accel {acc:.3}, {alpha:.3}");
    }
}

#[test]
fn corridor_loop_laps_repeat_when_the_run_is_long() {
    let (scn, d, _) = run("corridor-loop", 400.0);
    // More than three laps of the ~88 m loop, never drifting towards a wall.
    let dist: f64 = d.v.iter().map(|v| v * d.dt).sum();
    assert!(dist > 3.0 * 88.0, "{dist}");
    assert!(min_clearance(&scn, &d) >= 0.4);
    let turned = d.theta.last().unwrap() - d.theta[0];
    assert!(
        turned > 3.0 * 2.0 * std::f64::consts::PI,
        "counter-clockwise laps"
    );
}

#[test]
fn square_runs_stop_turn_in_place_and_close_each_lap() {
    for (name, sign) in [("square", -1.0), ("square-ccw", 1.0)] {
        let (_, d, _) = run(name, 200.0);
        // Turning only while standing still.
        assert!(d
            .v
            .iter()
            .zip(&d.w)
            .all(|(v, w)| v.abs() < 1e-12 || w.abs() < 1e-12));
        let turned = d.theta.last().unwrap() - d.theta[0];
        assert!(
            turned * sign > 2.0 * std::f64::consts::PI,
            "{name} turns {turned}"
        );
        // Whenever the chair stands still it is on a corner of the 6 m square,
        // lap after lap (no drift).
        let corners = [[2.0, 2.0], [2.0, 8.0], [8.0, 8.0], [8.0, 2.0]];
        let mut stops = 0;
        for k in 1..d.v.len() {
            if d.v[k] == 0.0 && d.w[k] == 0.0 {
                let on_corner = corners
                    .iter()
                    .any(|c| (d.x[k] - c[0]).abs() < 1e-6 && (d.y[k] - c[1]).abs() < 1e-6);
                assert!(on_corner, "{name}: stopped at {} {}", d.x[k], d.y[k]);
                stops += 1;
            }
        }
        let laps = stops;
        assert!(laps > 0, "{name}: no closed lap");
        // Legs are 6 m: the bounding box of the run is the 6 m square.
        let (xmin, xmax) =
            d.x.iter()
                .fold((f64::MAX, f64::MIN), |a, &x| (a.0.min(x), a.1.max(x)));
        assert!((xmax - xmin - 6.0).abs() < 1e-6);
    }
}

#[test]
fn custom_json_scenarios_drive_and_bad_ones_are_refused() {
    let mut cfg = SimConfig {
        duration_s: 60.0,
        ..Default::default()
    };
    cfg.scenario.custom = Some(
        ScenarioSpec::from_json(
            r#"{"name": "triangle", "world": "square-room",
                "waypoints": [[2,2],[8,2],[5,8]], "corner_radius": 0.8}"#,
        )
        .unwrap(),
    );
    let scn = Scenario::from_config(&cfg).unwrap();
    assert_eq!(scn.name, "triangle");
    let d = drive(&scn, &cfg.scenario, cfg.duration_s, 0.001);
    assert!(min_clearance(&scn, &d) >= 0.4);
    // Through a wall: refused.
    cfg.scenario.custom = Some(
        ScenarioSpec::from_json(r#"{"world": "square-room", "waypoints": [[2,2],[12,2]]}"#)
            .unwrap(),
    );
    assert!(Scenario::from_config(&cfg).is_err());
    cfg.scenario.custom = None;
    cfg.scenario.name = "moonwalk".into();
    assert!(Scenario::from_config(&cfg).is_err());
}

#[test]
fn random_walk_depends_on_the_seed_only() {
    let mut cfg = SimConfig::default();
    cfg.scenario.name = "random-walk".into();
    cfg.duration_s = 30.0;
    let a = drive(
        &Scenario::from_config(&cfg).unwrap(),
        &cfg.scenario,
        30.0,
        0.001,
    );
    let b = drive(
        &Scenario::from_config(&cfg).unwrap(),
        &cfg.scenario,
        30.0,
        0.001,
    );
    assert_eq!(a.x, b.x);
    cfg.seed = 2;
    let c = drive(
        &Scenario::from_config(&cfg).unwrap(),
        &cfg.scenario,
        30.0,
        0.001,
    );
    assert_ne!(a.x, c.x);
}
