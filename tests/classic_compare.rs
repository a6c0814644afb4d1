//! Every classic method on the same simulated runs (core-kinematics generator).

use odocal::classic::{
    drive_segments, irregular_path, square_segments, DriveParams, GaParams, HeadingPfParams, Turn,
};
use odocal::experiments::{
    compare_classic, markdown_table, ClassicMethod, CompareParams, CompareScenario,
};
use odocal::robot::DiffDrive;

use crate::support::assert_recovered;

#[test]
fn classic_methods_side_by_side() {
    let nominal = DiffDrive {
        r_right: 0.32,
        r_left: 0.32,
        wheel_base: 0.65,
    };
    let truth = DiffDrive {
        r_right: 0.32 * 1.005,
        r_left: 0.32 * 0.997,
        wheel_base: 0.65 * 1.015,
    };
    let drive = DriveParams {
        rate_hz: 5.0,
        slip_sigma: 0.005,
        ticks_per_rev: 8800.0,
        ..DriveParams::default()
    };
    let p = CompareParams {
        runs_per_direction: 3,
        evaluation_runs: 2,
        ga: GaParams {
            generations: 80,
            ..GaParams::default()
        },
        pf: HeadingPfParams {
            particles: 200,
            ..HeadingPfParams::default()
        },
        ..CompareParams::default()
    };
    let mut calls = Vec::new();
    let rows = compare_classic(&nominal, Some(&truth), &p, |sc, seed| {
        calls.push(sc);
        let segs = match sc {
            CompareScenario::Square => square_segments(6.0, Turn::Cw),
            CompareScenario::SquareCcw => square_segments(6.0, Turn::Ccw),
            CompareScenario::Evaluation => irregular_path(40.0, seed),
        };
        Ok::<_, String>(drive_segments(&nominal, &truth, &segs, &drive, seed))
    })
    .unwrap();
    println!("{}", markdown_table(&rows));
    assert_eq!(
        calls
            .iter()
            .filter(|c| **c == CompareScenario::Square)
            .count(),
        3
    );
    assert_eq!(
        calls
            .iter()
            .filter(|c| **c == CompareScenario::Evaluation)
            .count(),
        2
    );
    let names: Vec<_> = rows.iter().map(|r| r.method).collect();
    assert_eq!(
        names,
        [
            ClassicMethod::None,
            ClassicMethod::TachoHeading,
            ClassicMethod::Umbmark,
            ClassicMethod::Ga,
            ClassicMethod::HeadingPf
        ]
    );
    let by = |m| rows.iter().find(|r| r.method == m).unwrap();
    let none = by(ClassicMethod::None);
    for m in [
        ClassicMethod::Umbmark,
        ClassicMethod::Ga,
        ClassicMethod::HeadingPf,
    ] {
        assert!(
            by(m).rmse_xy < 0.2 * none.rmse_xy,
            "{m:?} does not beat no calibration"
        );
    }
    // The heading gain corrects the wheel base (not the unequal radii, so the
    // path barely improves: reported, not asserted).
    let th = by(ClassicMethod::TachoHeading).param_errors.unwrap();
    assert!(
        th.wheel_base < 0.2 * none.param_errors.unwrap().wheel_base,
        "{th:?}"
    );
    // UMBmark and the GA both find the diameter ratio; only the GA (open
    // pieces with known ends) sees the common scale.
    // Within 0.3 mm on the radii (hidden departures 1.6 and 0.96 mm) and
    // 3 mm on the wheel base (9.75 mm); the nominal fails the same checks.
    let ga = by(ClassicMethod::Ga).final_params;
    for (k, got, t, n, tol) in [
        (
            "r_right",
            ga.r_right,
            truth.r_right,
            nominal.r_right,
            0.3e-3,
        ),
        ("r_left", ga.r_left, truth.r_left, nominal.r_left, 0.3e-3),
        (
            "wheel_base",
            ga.wheel_base,
            truth.wheel_base,
            nominal.wheel_base,
            3e-3,
        ),
    ] {
        assert_recovered(&format!("GA {k}"), got, t, n, tol);
    }
    // The diameter ratio off by 0.8 %: found to 0.1 %.
    let um = by(ClassicMethod::Umbmark).final_params;
    let ratio = |d: &DiffDrive| d.r_right / d.r_left;
    assert_recovered("UMBmark ratio", ratio(&um), ratio(&truth), 1.0, 1e-3);
    // Heading fusion keeps the heading closest to the truth.
    assert!(by(ClassicMethod::HeadingPf).rmse_theta < by(ClassicMethod::Ga).rmse_theta);
    // JSON keys for `calibrate --json`-style output.
    let j = serde_json::to_value(&rows[2]).unwrap();
    assert_eq!(j["method"], "umbmark");
    assert!(j["final"]["wheel_base"].is_f64() && j["details"]["e_max_syst"].is_f64());
    assert!(rows
        .iter()
        .all(|r| r.rmse_xy.is_finite() && r.path_error_percent.is_finite()));
}

#[test]
fn classic_methods_on_the_simulator_squares() {
    use odocal::effects::Effect;
    use odocal::experiments::{compare_on_simulator, sim_run};
    use odocal::robot::RobotConfig;
    let robot = RobotConfig::default();
    let effects = [
        Effect::RadiusScale {
            right: 0.005,
            left: -0.003,
        },
        Effect::WheelBaseScale { scale: 0.015 },
    ];
    let nominal = robot.diff_drive();
    let truth = DiffDrive {
        r_right: 0.32 * 1.005,
        r_left: 0.32 * 0.997,
        wheel_base: 0.65 * 1.015,
    };
    let sq = sim_run(&robot, &effects, CompareScenario::Square, 3).unwrap();
    let l = sq.truth.path_length();
    assert!((l - 24.0).abs() < 0.1, "one loop of the 6 m square: {l} m");
    let p = CompareParams {
        runs_per_direction: 2,
        evaluation_runs: 1,
        ga: GaParams {
            generations: 60,
            ..GaParams::default()
        },
        pf: HeadingPfParams {
            particles: 100,
            ..HeadingPfParams::default()
        },
        ..CompareParams::default()
    };
    let rows = compare_on_simulator(&robot, &effects, &p).unwrap();
    // A failing run is an error, not a panic.
    let err = compare_classic(&nominal, None, &p, |_, _| {
        Err::<odocal::classic::SimRun, _>("no such scenario")
    });
    assert!(err.unwrap_err().to_string().contains("no such scenario"));
    println!("{}", markdown_table(&rows));
    let by = |m| rows.iter().find(|r| r.method == m).unwrap();
    let none = by(ClassicMethod::None);
    for m in [ClassicMethod::Umbmark, ClassicMethod::Ga] {
        assert!(by(m).rmse_xy < 0.3 * none.rmse_xy, "{m:?}");
    }
    let um = by(ClassicMethod::Umbmark).final_params;
    let ratio = |d: &DiffDrive| d.r_right / d.r_left;
    assert_recovered("UMBmark ratio", ratio(&um), ratio(&truth), 1.0, 1e-3);
}
