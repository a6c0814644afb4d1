//! The literature comparison as a library call: every method on the same
//! runs with a known hidden truth, then a load change the filters follow online.

use odocal::calib::CalibParams;
use odocal::classic::{GaParams, HeadingPfParams};
use odocal::experiments::{
    draw_hidden_truth, literature_run, ClassicMethod, ClassicResult, LiteratureParams,
};
use odocal::robot::DiffDrive;

fn short() -> LiteratureParams {
    let mut p = LiteratureParams {
        evaluation_length_m: 15.0,
        ..LiteratureParams::default()
    };
    p.compare.square_side = 3.0;
    p.compare.runs_per_direction = 2;
    p.compare.evaluation_runs = 1;
    p.compare.ga = GaParams {
        population: 30,
        generations: 40,
        ..GaParams::default()
    };
    p.compare.pf = HeadingPfParams {
        particles: 100,
        ..HeadingPfParams::default()
    };
    p
}

fn row(rows: &[ClassicResult], m: ClassicMethod) -> &ClassicResult {
    rows.iter().find(|r| r.method == m).expect("method present")
}

fn radius_err(r: &ClassicResult) -> f64 {
    let e = r.param_errors.expect("truth known");
    0.5 * (e.r_right + e.r_left)
}

#[test]
fn literature_methods_beat_no_calibration_and_filters_follow_a_load_change() {
    let nominal = DiffDrive {
        r_right: 0.32,
        r_left: 0.32,
        wheel_base: 0.65,
    };
    let p = short();
    let seed = 11;
    let r = literature_run(&nominal, &CalibParams::default(), &p, seed).unwrap();
    // The hidden truth is the one drawn from the seed, within the set bounds.
    let t = draw_hidden_truth(&nominal, p.radius_error, p.wheel_base_error, seed);
    assert_eq!(r.truth.r_right, t.r_right);
    assert!((t.wheel_base / 0.65 - 1.0).abs() <= p.wheel_base_error);
    println!(
        "{}\nafter the load change:\n{}",
        odocal::experiments::markdown_table(&r.rows),
        odocal::experiments::markdown_table(&r.changed)
    );
    let names: Vec<&str> = r.rows.iter().map(|x| x.method.name()).collect();
    assert_eq!(
        names,
        [
            "none",
            "tacho-heading",
            "umbmark",
            "ga",
            "heading-pf",
            "adaptive-pf",
            "dkf"
        ]
    );
    for x in r.rows.iter().chain(&r.changed) {
        assert!(
            [x.rmse_xy, x.rmse_theta, x.path_error_percent, x.compute_ms]
                .iter()
                .all(|v| v.is_finite()),
            "{x:?}"
        );
    }
    let none = row(&r.rows, ClassicMethod::None);
    // The Adaptive-PF's evaluation path: position and end errors under a
    // third of the uncalibrated ones (measured: 0.009 m against 0.14 m,
    // 0.09 % against 2.1 %); the uncalibrated row fails the same check.
    let a_third_of_none = |x: &ClassicResult| {
        x.rmse_xy < none.rmse_xy / 3.0 && x.path_error_percent < none.path_error_percent / 3.0
    };
    assert!(!a_third_of_none(none));
    let apf = row(&r.rows, ClassicMethod::AdaptivePf);
    assert!(a_third_of_none(apf), "{apf:?} vs {none:?}");
    // Every calibration that estimates the wheel base gets it closer than nominal.
    for m in [
        ClassicMethod::Umbmark,
        ClassicMethod::Ga,
        ClassicMethod::AdaptivePf,
        ClassicMethod::Dkf,
    ] {
        let x = row(&r.rows, m);
        let (e, e0) = (x.param_errors.unwrap(), none.param_errors.unwrap());
        assert!(e.wheel_base < e0.wheel_base, "{m:?}: {e:?} vs {e0:?}");
        assert!(x.rmse_theta < none.rmse_theta, "{m:?}");
    }
    // The radii are checked over repetitions (below): on one run of this
    // short square, the Adaptive-PF's radii land in a wide spread (the first
    // sample of each corner, before the gyro follows the wheels, moves a
    // wheel base nothing had observed yet), so one seed passes or fails a
    // millimetre bound by chance.
    // The heading source bounds the heading error of heading-pf below GA odometry's.
    assert!(
        row(&r.rows, ClassicMethod::HeadingPf).rmse_theta
            < row(&r.rows, ClassicMethod::Ga).rmse_theta
    );

    // After the radii grow by 4 and 2 mm, the one-time calibrations are off by
    // about that much; a filter calibrating online gets closer.
    assert_eq!(r.changed.len(), 6);
    let stale = row(&r.changed, ClassicMethod::Ga);
    assert!(radius_err(stale) > 2e-3, "{:?}", stale.param_errors);
    let online = [ClassicMethod::AdaptivePf, ClassicMethod::Dkf]
        .map(|m| radius_err(row(&r.changed, m)))
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    assert!(
        online < 0.5 * radius_err(stale),
        "{online} vs {}",
        radius_err(stale)
    );

    // Same seed, same result (compute times aside).
    let again = literature_run(&nominal, &CalibParams::default(), &p, seed).unwrap();
    for (a, b) in r.rows.iter().zip(&again.rows) {
        assert_eq!(a.final_params, b.final_params);
        assert_eq!(a.rmse_xy, b.rmse_xy);
    }
}

/// The Adaptive-PF's radii over five repetitions of the default comparison
/// (seeds 11–15, each its own hidden truth): the median of the mean radius
/// error under half the uncalibrated robot's median (measured: 0.33 mm
/// against 0.94 mm); the uncalibrated row fails the same check. One run is
/// not enough: the spread from run to run is wide (see above).
#[test]
fn the_adaptive_pf_halves_the_radius_error_over_repetitions() {
    let nominal = DiffDrive {
        r_right: 0.32,
        r_left: 0.32,
        wheel_base: 0.65,
    };
    let p = LiteratureParams::default();
    let median = |mut x: Vec<f64>| {
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    };
    let (mut apf, mut none) = (Vec::new(), Vec::new());
    for seed in 11..16 {
        let r = literature_run(&nominal, &CalibParams::default(), &p, seed).unwrap();
        apf.push(radius_err(row(&r.rows, ClassicMethod::AdaptivePf)));
        none.push(radius_err(row(&r.rows, ClassicMethod::None)));
    }
    let (apf, none) = (median(apf), median(none));
    println!("median mean-radius error: adaptive-pf {apf:.6} m, none {none:.6} m");
    let halves = |x: f64| x < 0.5 * none;
    assert!(!halves(none));
    assert!(halves(apf), "{apf} vs {none}");
}
