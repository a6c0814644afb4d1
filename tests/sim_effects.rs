//! Simulator truth vs nominal odometry: without effects the nominal model
//! reproduces the true path to encoder quantisation; each kinematic effect
//! distorts it by the expected factor, at the expected time.

use odocal::effects::Effect;
use odocal::geom::{self, Pose2};
use odocal::recording::WheelSample;
use odocal::robot::{wheel_odometry, RobotConfig};
use odocal::sim::{drive, encoder_samples, Drive, Scenario, SimConfig, TrueRobot, WheelTrack};
use odocal::traj::Trajectory;

/// Drives `scenario` for `duration` s with `effects` and returns the true
/// motion, the encoder samples and the nominal odometry from them.
fn odometry(
    scenario: &str,
    duration: f64,
    effects: &[Effect],
) -> (Drive, Vec<WheelSample>, Trajectory) {
    let mut cfg = SimConfig::default();
    cfg.scenario.name = scenario.into();
    cfg.duration_s = duration;
    let robot = RobotConfig::default();
    let scn = Scenario::from_config(&cfg).unwrap();
    let d = drive(&scn, &cfg.scenario, duration, 1.0 / cfg.integration_hz);
    let truth = TrueRobot::new(&robot, effects);
    let track = WheelTrack::new(&d, &truth);
    let wheels = encoder_samples(
        &cfg.encoder,
        robot.ticks_per_rev,
        &track,
        &truth,
        cfg.seed,
        duration,
    );
    let start = geom::pose(d.x[0], d.y[0], d.theta[0]);
    let odo = wheel_odometry(&robot.diff_drive(), &wheels, start);
    (d, wheels, odo)
}

fn true_pose(d: &Drive, t: f64) -> Pose2 {
    let [x, y, th] = d.pose_at(t);
    geom::pose(x, y, th)
}

/// Net (unwrapped) heading change (rad) of a trajectory.
fn turned(t: &Trajectory) -> f64 {
    t.poses
        .windows(2)
        .map(|p| geom::wrap_angle(geom::heading(&p[1]) - geom::heading(&p[0])))
        .sum()
}

#[test]
fn nominal_odometry_reproduces_the_truth_without_effects() {
    for scenario in ["corridor-loop", "square", "figure-eight"] {
        let (d, wheels, odo) = odometry(scenario, 120.0, &[]);
        assert_eq!(odo.len(), wheels.len());
        let (mut pos, mut head) = (0.0f64, 0.0f64);
        for (t, p) in odo.stamps.iter().zip(&odo.poses) {
            let e = geom::between(&true_pose(&d, *t), p);
            pos = pos.max(e.translation.vector.norm());
            head = head.max(geom::heading(&e).abs());
        }
        // One tick is 0.23 mm of travel and 0.35 mrad of heading; over a
        // 100 m run the error stays at that level (no systematic drift).
        eprintln!("{scenario}: max position error {pos:.5} m, heading {head:.6} rad");
        assert!(pos < 0.01, "{scenario}: {pos} m");
        assert!(head < 1.5e-3, "{scenario}: {head} rad");
    }
}

#[test]
fn radius_scale_stretches_the_path_by_the_expected_factor() {
    let s = 0.02;
    let e = [Effect::RadiusScale { right: s, left: s }];
    let (d, _, odo) = odometry("corridor-loop", 120.0, &e);
    let true_len: f64 = d.v.iter().map(|v| v.abs() * d.dt).sum();
    let ratio = true_len / odo.path_length();
    assert!((ratio - (1.0 + s)).abs() < 2e-4, "ratio {ratio}");
    // Unequal radii bend the nominal path: heading error grows with distance.
    let e = [Effect::RadiusScale {
        right: 0.01,
        left: -0.01,
    }];
    let (d, _, odo) = odometry("square", 60.0, &e);
    let t_end = *odo.stamps.last().unwrap();
    let err = geom::between(&true_pose(&d, t_end), odo.poses.last().unwrap());
    assert!(geom::heading(&err).abs() > 0.1, "{}", geom::heading(&err));
}

#[test]
fn wheel_base_scale_and_turn_slip_scale_the_nominal_heading_change() {
    let (_, _, base) = odometry("square", 60.0, &[]);
    let (_, _, wide) = odometry("square", 60.0, &[Effect::WheelBaseScale { scale: 0.03 }]);
    let ratio = turned(&wide) / turned(&base);
    assert!((ratio - 1.03).abs() < 1e-3, "ratio {ratio}");
    // Turn slip: D_eff = D (1 + k|W|); in-place turns at 0.6 rad/s peak
    // over-read by up to 6 %, on average less (the rate ramps).
    let (_, _, slip) = odometry("square", 60.0, &[Effect::TurnSlip { k: 0.1 }]);
    let ratio = turned(&slip) / turned(&base);
    assert!(ratio > 1.02 && ratio < 1.06, "ratio {ratio}");
}

#[test]
fn radius_step_changes_the_odometry_scale_at_its_time() {
    let e = [Effect::RadiusStep {
        time: 30.0,
        right: 0.0064,
        left: 0.0064,
    }];
    let (d, _, odo) = odometry("corridor-loop", 60.0, &e);
    // Speed ratio true/nominal: 1 before, (0.32 + 0.0064)/0.32 = 1.02 after.
    let speed_ratio = |t0: f64, t1: f64| {
        let i0 = odo.stamps.iter().position(|t| *t >= t0).unwrap();
        let i1 = odo.stamps.iter().position(|t| *t >= t1).unwrap();
        let nominal: f64 = odo.poses[i0..=i1]
            .windows(2)
            .map(|p| (p[1].translation.vector - p[0].translation.vector).norm())
            .sum();
        let truth: f64 = (((t0 / d.dt) as usize)..((t1 / d.dt) as usize))
            .map(|k| d.v[k] * d.dt)
            .sum();
        truth / nominal
    };
    let before = speed_ratio(20.0, 29.9);
    let after = speed_ratio(30.1, 40.0);
    assert!((before - 1.0).abs() < 1e-3, "{before}");
    assert!((after - 1.02).abs() < 1e-3, "{after}");
}

#[test]
fn latency_delays_the_encoder_stream_by_whole_samples() {
    let (_, plain, _) = odometry("corridor-loop", 20.0, &[]);
    let (_, late, _) = odometry("corridor-loop", 20.0, &[Effect::Latency { delay: 0.04 }]);
    assert_eq!(plain.len(), late.len());
    // Same stamps; the late stream holds what the plain one held 4 samples before.
    for k in 4..plain.len() {
        assert_eq!(late[k].stamp, plain[k].stamp);
        assert!((late[k].right - plain[k - 4].right).abs() < 1e-9);
        assert!((late[k].left - plain[k - 4].left).abs() < 1e-9);
    }
    assert!(plain.last().unwrap().right != late.last().unwrap().right);
}

#[test]
fn encoder_gain_over_reads_fast_wheels() {
    let (_, plain, _) = odometry("corridor-loop", 60.0, &[]);
    let (_, gain, _) = odometry("corridor-loop", 60.0, &[Effect::EncoderGain { k: 0.02 }]);
    let (a, b) = (plain.last().unwrap().right, gain.last().unwrap().right);
    // Wheels turn at ≈ 2.5 rad/s when cruising: ≈ 5 % over-read.
    let over = b / a - 1.0;
    assert!(over > 0.03 && over < 0.06, "{over}");
}
