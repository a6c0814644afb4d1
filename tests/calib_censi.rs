//! Calibration on the Khepera tuples of \[Censi2013\] (real data) against the
//! authors' maximum-likelihood estimates.

use odocal::calib::{build, run, steps, CalibParams, Method, Ranges};
use odocal::io::censi;
use odocal::motion::VelocityObs;
use odocal::robot::DiffDrive;
use std::path::PathBuf;

/// The shared data folder (same policy as `support::shared_data`; repeated
/// here so this file also compiles as its own test target).
fn shared_data(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("ODOCAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    if dir.is_dir() {
        return Some(dir);
    }
    if std::env::var_os("CI").is_some() {
        panic!("{test}: shared data not found at {}", dir.display());
    }
    eprintln!("SKIP {test}: shared data not found at {}", dir.display());
    None
}

/// The nominal values the calibrations here start from: 5–8 % off every set's
/// calibration by the authors (20.6–20.95 mm radii, 88.0–89.05 mm axle), the
/// radii on either side, so that the nominal fails each check below by at
/// least three times its tolerance (the negative control of every test).
/// The robot file's own 21 / 21 / 90 mm lie within 0.25 % of the authors'
/// radii: no check could tell a calibration from doing nothing there.
const NOMINAL: DiffDrive = DiffDrive {
    r_right: 0.0198,
    r_left: 0.0222,
    wheel_base: 0.0945,
};

/// Khepera-sized settings: ranges ±10 % around [`NOMINAL`], measurement σ
/// of the laser displacement per tuple, velocity model σ and floors scaled
/// to a robot moving at ~1 cm/s.
pub fn khepera_params(method: Method) -> CalibParams {
    let mut p = CalibParams {
        method,
        seed: 7,
        ranges: Some(Ranges::around(
            NOMINAL.r_right,
            NOMINAL.r_left,
            NOMINAL.wheel_base,
            0.1,
        )),
        ..Default::default()
    };
    p.noise.param_sigma = 1e-6;
    p.noise.sigma_floor = 1e-6;
    p.noise.model_sigma_v = 1e-4;
    p.noise.model_sigma_w = 1e-3;
    p.noise.kalman_param_sigma = 1e-8;
    p.noise.kalman_velocity_sigma = 0.01;
    p.adaptive.per_particle = 1e-6;
    p
}

fn calibrate(set: &str, method: Method) -> Option<(DiffDrive, censi::CensiResults, usize)> {
    let dir = shared_data("calib_censi")?.join("censi-calibration");
    let tuples = censi::read(&dir.join(format!("{set}.tuple"))).unwrap();
    let authors = censi::read_results(&dir.join(format!("{set}_results.json"))).unwrap();
    // Known mount: the authors' laser pose (their estimate), σ of the laser
    // displacement per tuple 1.5 mm and 0.3° (Hokuyo + CSM over ~1 s).
    let (wheels, motions) = censi::to_streams(&tuples, &authors.base_from_laser(), 1.5e-3, 5e-3);
    let obs: Vec<VelocityObs> = motions
        .iter()
        .filter_map(VelocityObs::from_motion)
        .collect();
    let st = steps(&obs, &wheels, &[], 0.0);
    let mut cal = build(&khepera_params(method), NOMINAL).unwrap();
    let r = run(cal.as_mut(), &st, NOMINAL);
    Some((r.final_drive(), authors, tuples.len()))
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b
}

/// Asserts `got` within `tol` of `want` (relative when `relative`, else
/// absolute), and that the do-nothing answer `nothing` misses it by at
/// least three times `tol` (the check's negative control).
fn check(what: &str, got: f64, want: f64, nothing: f64, tol: f64, relative: bool) {
    let off = |x: f64| {
        if relative {
            rel(x, want)
        } else {
            (x - want).abs()
        }
    };
    assert!(off(got) < tol, "{what}: {got} vs {want} (tolerance {tol})");
    assert!(
        off(nothing) >= 3.0 * tol,
        "{what}: doing nothing ({nothing}) is within three tolerances of {want}"
    );
}

/// Radii and axle of `k` within `tol` (relative) of the authors', each
/// also failed by [`NOMINAL`].
fn kinematics_within(set: &str, k: &DiffDrive, a: &censi::CensiResults, tol: f64) {
    for (name, got, want, nothing) in [
        ("r_right", k.r_right, a.r_diam / 2.0, NOMINAL.r_right),
        ("r_left", k.r_left, a.l_diam / 2.0, NOMINAL.r_left),
        ("wheel_base", k.wheel_base, a.axle, NOMINAL.wheel_base),
    ] {
        check(&format!("{set} {name}"), got, want, nothing, tol, true);
    }
}

#[test]
fn censi_tuples_parse_with_the_documented_counts() {
    let Some(d) = shared_data("censi_tuples_parse") else {
        return;
    };
    for (set, n) in [("lstraight", 4396), ("l90", 3295), ("lmov", 4345)] {
        let t = censi::read(&d.join(format!("censi-calibration/{set}.tuple"))).unwrap();
        assert_eq!(t.len(), n, "{set}");
        assert!(t.iter().all(|t| t.t > 0.7 && t.t < 1.3));
    }
}

#[test]
fn adaptive_pf_matches_the_authors_on_lstraight_within_one_percent() {
    within_one_percent_of_the_authors("lstraight");
    let Some((k, _, _)) = calibrate("lstraight", Method::AdaptivePf) else {
        return;
    };
    // Right and left radii differ in the same sense as the authors' (E_d >
    // 1); the nominal's are the other way round.
    assert!(k.r_right > k.r_left);
    assert!(NOMINAL.r_right < NOMINAL.r_left);
}

/// Runs the Adaptive-PF on `set` and asserts radii and axle within 1 % of
/// the authors' maximum-likelihood estimates (same settings for every set).
fn within_one_percent_of_the_authors(set: &str) {
    let Some((k, a, _)) = calibrate(set, Method::AdaptivePf) else {
        return;
    };
    eprintln!(
        "{set}: {k:?} vs authors r_R {} r_L {} axle {}",
        a.r_diam / 2.0,
        a.l_diam / 2.0,
        a.axle
    );
    kinematics_within(set, &k, &a, 0.01);
}

#[test]
fn adaptive_pf_matches_the_authors_on_l90_within_one_percent() {
    // Configuration B: laser turned by −89°, many turns in place.
    within_one_percent_of_the_authors("l90");
}

#[test]
fn adaptive_pf_matches_the_authors_on_lmov_within_one_percent() {
    // Configuration C: laser 39 mm off the axis, turned by −107°.
    within_one_percent_of_the_authors("lmov");
}

/// The batch calibration of `set` without the laser pose: the estimate and
/// the authors' numbers, each row printed.
fn batch_on(set: &str) -> Option<(odocal::calib::batch::BatchEstimate, censi::CensiResults)> {
    use odocal::calib::{batch, CheckParams};
    let dir = shared_data("calib_censi_batch")?.join("censi-calibration");
    let tuples = censi::read(&dir.join(format!("{set}.tuple"))).unwrap();
    let authors = censi::read_results(&dir.join(format!("{set}_results.json"))).unwrap();
    let problem = odocal::pipeline::batch::tuples_problem(&tuples);
    let e = batch::estimate(
        &problem,
        &NOMINAL,
        &batch::BatchParams::default(),
        &CheckParams::default(),
    )
    .unwrap();
    eprintln!(
        "{set}: r_R {:.6}±{:.1e} (authors {:.6}, {:+.3} %), r_L {:.6}±{:.1e} (authors {:.6}, {:+.3} %), \
         b {:.6}±{:.1e} (authors {:.6}, {:+.3} %), laser x {:.5}±{:.1e} y {:.5}±{:.1e} yaw {:.5}±{:.1e} \
         (authors {:.5} {:.5} {:.5}); closed form {:?}; dropped {} of {}; σ {:?}",
        e.r_right.value, e.r_right.std, authors.r_diam / 2.0, 100.0 * (e.r_right.value / (authors.r_diam / 2.0) - 1.0),
        e.r_left.value, e.r_left.std, authors.l_diam / 2.0, 100.0 * (e.r_left.value / (authors.l_diam / 2.0) - 1.0),
        e.wheel_base.value, e.wheel_base.std, authors.axle, 100.0 * (e.wheel_base.value / authors.axle - 1.0),
        e.laser.x.value, e.laser.x.std, e.laser.y.value, e.laser.y.std, e.laser.yaw.value, e.laser.yaw.std,
        authors.l_x, authors.l_y, authors.l_theta, e.closed_form, e.dropped, tuples.len(), e.noise_sigma
    );
    Some((e, authors))
}

/// Radii and axle within 0.5 % of the authors', laser position within
/// 0.5 mm and yaw within 0.1°, without being given the laser pose.
fn batch_matches_the_authors(set: &str) {
    let Some((e, a)) = batch_on(set) else {
        return;
    };
    let k = DiffDrive {
        r_right: e.r_right.value,
        r_left: e.r_left.value,
        wheel_base: e.wheel_base.value,
    };
    kinematics_within(set, &k, &a, 0.005);
    // The laser within 0.5 mm and 0.1° (the batch is within 0.07 mm and
    // 0.05° on all three); doing nothing is the laser at the base's origin.
    // lstraight's y is left out: the authors' 0.19 mm cannot be told from 0.
    check(
        &format!("{set} laser x"),
        e.laser.x.value,
        a.l_x,
        0.0,
        5e-4,
        false,
    );
    if set != "lstraight" {
        check(
            &format!("{set} laser y"),
            e.laser.y.value,
            a.l_y,
            0.0,
            5e-4,
            false,
        );
    }
    let dyaw = |yaw: f64| odocal::geom::wrap_angle(yaw - a.l_theta);
    let yaw_tol = 0.1f64.to_radians();
    check(
        &format!("{set} laser yaw"),
        dyaw(e.laser.yaw.value),
        0.0,
        dyaw(0.0),
        yaw_tol,
        false,
    );
    assert!(e.time_offset.is_none(), "tuples carry no time");
}

#[test]
fn batch_matches_the_authors_on_lstraight() {
    batch_matches_the_authors("lstraight");
}

#[test]
fn batch_matches_the_authors_on_l90() {
    batch_matches_the_authors("l90");
}

#[test]
fn batch_matches_the_authors_on_lmov() {
    batch_matches_the_authors("lmov");
}
