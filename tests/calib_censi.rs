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

/// Khepera-sized settings: ranges ±10 % around the nominal 21 mm radius and
/// 90 mm axle, measurement σ of the laser displacement per tuple, velocity
/// model σ and floors scaled to a robot moving at ~1 cm/s.
pub fn khepera_params(method: Method) -> CalibParams {
    let mut p = CalibParams {
        method,
        seed: 7,
        ranges: Some(Ranges::around(0.021, 0.021, 0.09, 0.1)),
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
    let nominal = DiffDrive {
        r_right: 0.021,
        r_left: 0.021,
        wheel_base: 0.09,
    };
    let mut cal = build(&khepera_params(method), nominal).unwrap();
    let r = run(cal.as_mut(), &st, nominal);
    Some((r.final_drive(), authors, tuples.len()))
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b
}

#[test]
fn adaptive_pf_on_lstraight_lands_within_two_percent_of_the_authors() {
    let Some((k, a, _)) = calibrate("lstraight", Method::AdaptivePf) else {
        return;
    };
    assert!(
        rel(k.r_right, a.r_diam / 2.0) < 0.02,
        "{} vs {}",
        k.r_right,
        a.r_diam / 2.0
    );
    assert!(
        rel(k.r_left, a.l_diam / 2.0) < 0.02,
        "{} vs {}",
        k.r_left,
        a.l_diam / 2.0
    );
    assert!(
        rel(k.wheel_base, a.axle) < 0.02,
        "{} vs {}",
        k.wheel_base,
        a.axle
    );
    // Right and left radii differ in the same sense as the authors' (E_d > 1).
    assert!(k.r_right > k.r_left);
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
    let Some((k, a, _)) = calibrate("lstraight", Method::AdaptivePf) else {
        return;
    };
    eprintln!(
        "lstraight: {k:?} vs authors r_R {} r_L {} axle {}",
        a.r_diam / 2.0,
        a.l_diam / 2.0,
        a.axle
    );
    assert!(
        rel(k.r_right, a.r_diam / 2.0) < 0.01,
        "{} vs {}",
        k.r_right,
        a.r_diam / 2.0
    );
    assert!(
        rel(k.r_left, a.l_diam / 2.0) < 0.01,
        "{} vs {}",
        k.r_left,
        a.l_diam / 2.0
    );
    assert!(
        rel(k.wheel_base, a.axle) < 0.01,
        "{} vs {}",
        k.wheel_base,
        a.axle
    );
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
    for (name, got, want) in [
        ("r_right", k.r_right, a.r_diam / 2.0),
        ("r_left", k.r_left, a.l_diam / 2.0),
        ("wheel_base", k.wheel_base, a.axle),
    ] {
        assert!(rel(got, want) < 0.01, "{set} {name}: {got} vs {want}");
    }
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
    let nominal = DiffDrive {
        r_right: 0.021,
        r_left: 0.021,
        wheel_base: 0.09,
    };
    let e = batch::estimate(
        &problem,
        &nominal,
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

/// Radii and axle within 0.5 % of the authors', laser position within 3 mm
/// and yaw within 0.5°, without being given the laser pose.
fn batch_matches_the_authors(set: &str) {
    let Some((e, a)) = batch_on(set) else {
        return;
    };
    for (name, got, want) in [
        ("r_right", e.r_right.value, a.r_diam / 2.0),
        ("r_left", e.r_left.value, a.l_diam / 2.0),
        ("wheel_base", e.wheel_base.value, a.axle),
    ] {
        assert!(rel(got, want) < 0.005, "{set} {name}: {got} vs {want}");
    }
    assert!((e.laser.x.value - a.l_x).abs() < 3e-3, "{set} laser x");
    assert!((e.laser.y.value - a.l_y).abs() < 3e-3, "{set} laser y");
    let dyaw = odocal::geom::wrap_angle(e.laser.yaw.value - a.l_theta);
    assert!(
        dyaw.abs() < 0.5f64.to_radians(),
        "{set} laser yaw {dyaw} rad off"
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
