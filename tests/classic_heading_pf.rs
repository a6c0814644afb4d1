//! The heading-fusion particle filter of \[GAHeading\] on simulated irregular paths.

use odocal::classic::{
    drive_segments, heading_pf, irregular_path, simulate_heading, DriveParams, HeadingPfParams,
    HeadingSourceParams,
};
use odocal::experiments::{
    heading_pf_experiment, path_error_markdown, PfExperimentParams, SeedPathError,
};
use odocal::geom::Pose2;
use odocal::robot::{wheel_odometry, DiffDrive};

fn end_error(a: &odocal::traj::Trajectory, b: &odocal::traj::Trajectory) -> f64 {
    (a.poses.last().unwrap().translation.vector - b.poses.last().unwrap().translation.vector).norm()
}

#[test]
fn heading_fusion_beats_odometry_alone_under_slip() {
    let k = DiffDrive {
        r_right: 0.0632,
        r_left: 0.0628,
        wheel_base: 0.369,
    };
    let drive = DriveParams {
        slip_sigma: 0.03,
        rate_hz: 10.0,
        ..DriveParams::default()
    };
    let (mut odo_sum, mut pf_sum) = (0.0, 0.0);
    for seed in 0..4 {
        let run = drive_segments(&k, &k, &irregular_path(22.0, seed), &drive, 100 + seed);
        let h = simulate_heading(&run.truth, &HeadingSourceParams::default(), seed);
        assert!(!h.is_empty());
        let p = HeadingPfParams {
            particles: 200,
            seed,
            ..HeadingPfParams::default()
        };
        let pf = heading_pf(&k, &run.wheels, &h, &Pose2::identity(), &p).unwrap();
        assert_eq!(pf.len(), run.wheels.len());
        // Same seed, same path.
        assert_eq!(
            heading_pf(&k, &run.wheels, &h, &Pose2::identity(), &p).unwrap(),
            pf
        );
        odo_sum += end_error(
            &wheel_odometry(&k, &run.wheels, Pose2::identity()),
            &run.truth,
        );
        pf_sum += end_error(&pf, &run.truth);
    }
    println!(
        "22 m, 3 % slip: mean end error odometry {:.3} m, heading PF {:.3} m",
        odo_sum / 4.0,
        pf_sum / 4.0
    );
    assert!(pf_sum < 0.6 * odo_sum, "pf {pf_sum} odo {odo_sum}");
    assert!(heading_pf(
        &k,
        &[],
        &[],
        &Pose2::identity(),
        &HeadingPfParams::default()
    )
    .unwrap()
    .is_empty());
    assert!(heading_pf(
        &k,
        &[],
        &[(0.0, f64::NAN)],
        &Pose2::identity(),
        &HeadingPfParams::default()
    )
    .is_err());
}

#[test]
fn table_2_experiment_orders_the_scenarios_like_the_seed() {
    let p = PfExperimentParams {
        lengths: vec![22.0],
        trials: 3,
        pf: HeadingPfParams {
            particles: 200,
            ..HeadingPfParams::default()
        },
        ..PfExperimentParams::default()
    };
    let seed = [SeedPathError {
        scenario: "calibrated_odometry".into(),
        length_m: 22.0,
        error_percent: Some(0.234),
    }];
    let (rows, params) = heading_pf_experiment(&p, &seed).unwrap();
    for r in &rows {
        println!(
            "{} {} m: {:.3} % ± {:.3} (seed {:?})",
            r.scenario, r.length_m, r.error_percent, r.error_std, r.seed_error_percent
        );
    }
    println!("GA under slip: {params:?} (truth {:?})", p.truth);
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[1].seed_error_percent, Some(0.234));
    assert!(
        rows[0].error_percent > 3.0 * rows[1].error_percent,
        "calibration helps"
    );
    assert!(
        rows[2].error_percent < rows[1].error_percent,
        "heading fusion helps"
    );
    let within = |k: f64| (k / p.truth.k_left - 1.0).abs() < 0.01;
    assert!(
        within(params.k_left),
        "{} vs {}",
        params.k_left,
        p.truth.k_left
    );
    // The negative control: the uncalibrated gain fails the same check.
    assert!(!within(p.uncalibrated.k_left));
    let md = path_error_markdown(&rows);
    assert_eq!(md.lines().count(), 5);
    assert!(md.contains("| calibrated_odometry | 22 |") && md.contains("| 0.234 |"));
}
