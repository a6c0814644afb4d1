//! Simulated sensors: ray casts at analytically known distances, stream
//! rates, whole encoder ticks, the laser seen from its true mount, the gyro
//! bias, determinism and finiteness of everything the recording holds.

use nalgebra::Point2;
use odocal::effects::Effect;
use odocal::geom;
use odocal::recording::Recording;
use odocal::robot::RobotConfig;
use odocal::sim::{simulate, worlds, SimConfig, Truth, World};
use std::f64::consts::{FRAC_PI_2, PI};

fn sim(scenario: &str, duration: f64, seed: u64, effects: &[Effect]) -> (Recording, Truth) {
    let mut cfg = SimConfig::default();
    cfg.scenario.name = scenario.into();
    cfg.duration_s = duration;
    cfg.seed = seed;
    simulate(&cfg, &RobotConfig::default(), effects, &mut |_| {}).unwrap()
}

#[test]
fn square_room_rays_hit_walls_at_analytic_distances() {
    let w = worlds::builtin("square-room").unwrap();
    let cases = [
        ((5.0, 2.0), -FRAC_PI_2, 2.0),              // floor wall y = 0
        ((2.0, 8.0), PI, 2.0),                      // west wall x = 0
        ((8.0, 8.0), 0.0, 2.0),                     // east wall x = 10
        ((5.0, 2.0), FRAC_PI_2, 2.6),               // centre table edge y = 4.6
        ((2.0, 2.0), -3.0 * PI / 4.0, 8f64.sqrt()), // the corner (0, 0)
    ];
    for ((x, y), a, want) in cases {
        let r = w.cast_ray(Point2::new(x, y), a, 20.0).unwrap();
        assert!(
            (r - want).abs() < 1e-9,
            "from ({x}, {y}) at {a}: {r} vs {want}"
        );
    }
    // A fan equals the single rays.
    let mut fan = vec![0.0; 9];
    w.cast_fan(Point2::new(5.0, 2.0), -PI, PI / 8.0, 20.0, &mut fan);
    for (i, r) in fan.iter().enumerate() {
        let one = w.cast_ray(Point2::new(5.0, 2.0), -PI + i as f64 * PI / 8.0, 20.0);
        assert_eq!(Some(*r), one);
    }
    // A JSON world round-trips.
    let text = serde_json::to_string(&w.to_spec()).unwrap();
    let back = World::from_json("copy", &text).unwrap();
    assert_eq!(back.segments(), w.segments());
}

#[test]
fn streams_have_their_rates_and_encoders_count_whole_ticks() {
    let (rec, truth) = sim("corridor-loop", 6.0, 1, &[]);
    let robot = RobotConfig::default();
    let rate = |stamps: Vec<f64>| {
        let d: Vec<f64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
        let (lo, hi) = d
            .iter()
            .fold((f64::MAX, f64::MIN), |a, &x| (a.0.min(x), a.1.max(x)));
        (1.0 / hi, 1.0 / lo)
    };
    let near =
        |(lo, hi): (f64, f64), hz: f64| (lo - hz).abs() < 1e-6 * hz && (hi - hz).abs() < 1e-6 * hz;
    assert!(near(
        rate(rec.scans.iter().map(|s| s.stamp).collect()),
        50.0
    ));
    assert!(near(
        rate(rec.wheels.iter().map(|s| s.stamp).collect()),
        100.0
    ));
    assert!(near(
        rate(rec.gyro.iter().map(|s| s.stamp).collect()),
        100.0
    ));
    assert!(near(
        rate(rec.reference.iter().map(|s| s.stamp).collect()),
        10.0
    ));
    assert!(rec.scans.len() >= 299 && rec.wheels.len() == 601 && rec.reference.len() == 61);
    let q = robot.rad_per_tick();
    for s in &rec.wheels {
        for a in [s.left, s.right] {
            assert!(
                (a / q - (a / q).round()).abs() < 1e-6,
                "{a} is not whole ticks"
            );
        }
    }
    assert!(rec.wheels.last().unwrap().right > 10.0, "the wheels turned");
    let s = &rec.scans[0];
    assert_eq!(s.ranges.len(), 541);
    assert!((s.angle_min + 135f64.to_radians()).abs() < 1e-12);
    assert!((s.angle_increment - 0.5f64.to_radians()).abs() < 1e-12);
    assert!((s.scan_time - 0.02).abs() < 1e-12 && s.time_increment > 0.0);
    assert!(rec.reference.iter().all(|p| p.has_heading));
    assert_eq!(rec.base_from_laser, Some(robot.laser.unwrap().pose()));
    assert_eq!(truth.trajectory.len(), 601);
    assert_eq!(truth.world, "corridor-loop");
    assert_eq!(
        truth.walls,
        worlds::builtin("corridor-loop").unwrap().segments()
    );
    assert!(truth.parameters.len() >= 61);
}

#[test]
fn back_mounted_laser_sees_the_corridor_walls() {
    // 25 s: along the first corridor and round its corner.
    let (rec, _) = sim("corridor-loop", 25.0, 3, &[]);
    let valid: usize = rec.scans.iter().map(|s| s.valid_count()).sum();
    let total: usize = rec.scans.iter().map(|s| s.ranges.len()).sum();
    let frac = valid as f64 / total as f64;
    assert!(frac > 0.8, "only {frac:.2} of beams valid");
    // The beam at −90° in the backward-facing laser frame points to the
    // chair's left, at the inner corridor wall 1.25 m away at the start.
    let s = &rec.scans[0];
    let left = s.ranges[(s.ranges.len() - 1) / 2 - 180] as f64;
    assert!((left - 1.25).abs() < 0.05, "{left}");
}

#[test]
fn laser_offset_moves_only_the_true_laser() {
    let off = Effect::LaserOffset {
        x: 0.1,
        y: -0.05,
        yaw: 0.03,
    };
    let mut cfg = SimConfig {
        duration_s: 0.5,
        ..Default::default()
    };
    cfg.laser.noise_sigma = 0.0;
    let robot = RobotConfig::default();
    let (rec, truth) = simulate(&cfg, &robot, &[off], &mut |_| {}).unwrap();
    assert_eq!(
        rec.base_from_laser,
        Some(robot.laser.unwrap().pose()),
        "the bag keeps the nominal mount"
    );
    assert!((truth.laser_mount.x - (robot.laser.unwrap().x + 0.1)).abs() < 1e-12);
    assert!((truth.laser_mount.y - (robot.laser.unwrap().y - 0.05)).abs() < 1e-12);
    assert!((truth.laser_mount.yaw - (robot.laser.unwrap().yaw + 0.03)).abs() < 1e-12);
    // The chair stands still at first: every beam is a ray from the true laser pose.
    let world = worlds::builtin("corridor-loop").unwrap();
    let p0 = truth.trajectory().poses[0];
    let laser = p0 * truth.laser_mount.pose();
    let s = &rec.scans[0];
    for i in (0..s.ranges.len()).step_by(20) {
        let a = geom::heading(&laser) + s.beam_angle(i);
        let o = Point2::new(laser.translation.x, laser.translation.y);
        let want = world
            .cast_ray(o, a, 20.0)
            .map_or(f32::INFINITY, |r| r as f32);
        assert!(
            (s.ranges[i] - want).abs() < 1e-4,
            "beam {i}: {} vs {want}",
            s.ranges[i]
        );
    }
    let (plain, _) = simulate(&cfg, &robot, &[], &mut |_| {}).unwrap();
    assert_ne!(plain.scans[0].ranges, s.ranges);
}

#[test]
fn gyro_bias_is_the_mean_gyro_error() {
    let bias = 0.005;
    let (rec, truth) = sim("figure-eight", 20.0, 4, &[Effect::GyroBias { bias }]);
    let traj = truth.trajectory();
    let mut errs = Vec::new();
    for w in rec.gyro.windows(2) {
        let (a, b) = (
            traj.pose_at(w[0].stamp).unwrap(),
            traj.pose_at(w[1].stamp).unwrap(),
        );
        let true_rate =
            geom::wrap_angle(geom::heading(&b) - geom::heading(&a)) / (w[1].stamp - w[0].stamp);
        errs.push(w[1].wz - true_rate);
    }
    let mean = errs.iter().sum::<f64>() / errs.len() as f64;
    // σ = 0.002 rad/s over ~2000 samples: the mean is known to ≈ 5e-5.
    assert!((mean - bias).abs() < 2.5e-4, "mean gyro error {mean}");
}

#[test]
fn same_seed_same_recording_other_seed_differs_and_nothing_is_nan() {
    let e = [Effect::parse("radius_step:time=1,right=0.004,left=0.002").unwrap()];
    let (a, ta) = sim("hall", 3.0, 9, &e);
    let (b, tb) = sim("hall", 3.0, 9, &e);
    assert_eq!(a.scans, b.scans);
    assert_eq!(a.wheels, b.wheels);
    assert_eq!(a.gyro, b.gyro);
    assert_eq!(a.reference, b.reference);
    assert_eq!(ta, tb);
    let (c, _) = sim("hall", 3.0, 10, &e);
    assert_ne!(a.scans, c.scans);
    assert_ne!(a.gyro, c.gyro);
    // Streams are independent: another seed changes the noise, not the truth.
    assert_eq!(a.scans.len(), c.scans.len());
    for s in &a.scans {
        assert!(s.ranges.iter().all(|r| !r.is_nan()));
        assert!(s.stamp.is_finite());
    }
    assert!(a
        .wheels
        .iter()
        .all(|w| w.left.is_finite() && w.right.is_finite()));
    assert!(a.gyro.iter().all(|g| g.wz.is_finite()));
    assert!(a
        .reference
        .iter()
        .all(|p| geom::xyt(&p.pose).iter().all(|v| v.is_finite())));
    // The truth says what was injected; the recording cannot.
    assert_eq!(
        ta.effect_specs,
        vec!["radius_step:time=1,right=0.004,left=0.002"]
    );
    let back = Truth::from_json(&ta.to_json()).unwrap();
    assert_eq!(back.effects, ta.effects);
    assert_eq!(back.settings, ta.settings);
    assert_eq!(back.trajectory.len(), ta.trajectory.len());
    for (p, q) in back.trajectory.iter().zip(&ta.trajectory) {
        assert!((p.x - q.x).abs() < 1e-12 && (p.theta - q.theta).abs() < 1e-12);
    }
    let before = ta.parameters_at(0.95).unwrap();
    let after = ta.parameters_at(1.0).unwrap();
    assert!((after.r_right - before.r_right - 0.004).abs() < 1e-12);
    assert!(!format!("{:?}", a.source).contains("radius"));
}

#[test]
fn fine_resolution_at_25_hz_gives_1081_beams() {
    let mut cfg = SimConfig {
        duration_s: 2.0,
        ..Default::default()
    };
    cfg.laser.rate_hz = 25.0;
    cfg.laser.resolution_deg = 0.25;
    let (rec, _) = simulate(&cfg, &RobotConfig::default(), &[], &mut |_| {}).unwrap();
    assert!(rec.scans.iter().all(|s| s.ranges.len() == 1081));
    assert_eq!(
        rec.scans.len(),
        50,
        "25 Hz for 2 s, last sweep inside the run"
    );
    assert!((rec.scans[1].stamp - 0.04).abs() < 1e-12);
    let s = &rec.scans[0];
    assert!((s.beam_angle(1080) - 135f64.to_radians()).abs() < 1e-9);
    // One 360° turn per scan period: 0.25° of it per beam.
    assert!((s.time_increment - 0.04 / 1440.0).abs() < 1e-15);
}
