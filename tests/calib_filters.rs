//! The calibrators on synthetic runs with known truth: convergence, the
//! Kalman baselines, determinism, degenerate inputs, and a radius step.

use crate::support::assert_recovered;
use odocal::calib::synth::{draw_truth, generate, RadiusStep, SynthParams};
use odocal::calib::*;
use odocal::robot::DiffDrive;

const NOMINAL: DiffDrive = DiffDrive {
    r_right: 0.32,
    r_left: 0.32,
    wheel_base: 0.65,
};

fn synth(seed: u64, duration: f64, step: Option<RadiusStep>) -> (synth::SynthData, Vec<CalibStep>) {
    let p = SynthParams {
        duration,
        radius_step: step,
        ..Default::default()
    };
    let d = generate(&p, draw_truth(seed), seed);
    let st = steps(&d.obs, &d.wheels, &d.gyro, p.gyro_sigma);
    (d, st)
}

fn calibrate(method: Method, seed: u64, st: &[CalibStep]) -> CalibrationRun {
    let p = CalibParams {
        method,
        seed,
        ..Default::default()
    };
    let mut cal = build(&p, NOMINAL).unwrap();
    run(cal.as_mut(), st, NOMINAL)
}

fn no_nan(r: &CalibrationRun) -> bool {
    r.history.iter().all(|h| {
        [
            h.r_right,
            h.r_left,
            h.wheel_base,
            h.std_r_right,
            h.std_r_left,
            h.std_wheel_base,
            h.process_sigma,
        ]
        .iter()
        .all(|x| x.is_finite())
    }) && r
        .trajectory
        .poses
        .iter()
        .all(|p| p.translation.vector.iter().all(|x| x.is_finite()))
}

#[test]
fn adaptive_pf_and_kalman_baselines_converge_to_the_truth() {
    // Two seeds whose drawn truths lie over three tolerances from the
    // nominal chair on every parameter (radii 5.1 to 9.6 mm off, wheel base
    // 29 and 15.5 mm).
    for seed in [13u64, 15] {
        let (d, st) = synth(seed, 60.0, None);
        let k = d.truth;
        let mut worst_end = 0.0f64;
        for m in [Method::AdaptivePf, Method::Dkf, Method::Akf] {
            let r = calibrate(m, seed, &st);
            let f = r.final_drive();
            let (er, el, ed) = (
                (f.r_right - k.r_right).abs(),
                (f.r_left - k.r_left).abs(),
                (f.wheel_base - k.wheel_base).abs(),
            );
            eprintln!(
                "{} seed {seed}: {:.3} {:.3} {:.3} mm",
                m.as_str(),
                er * 1e3,
                el * 1e3,
                ed * 1e3
            );
            // 0.4 % of the radius and 5 mm of the wheel base; the nominal,
            // put through the same checks, fails each.
            let what = |p: &str| format!("{} seed {seed}: {p}", m.as_str());
            let (tol_r, tol_d) = (1.25e-3, 5e-3);
            assert_recovered(
                &what("r_right"),
                f.r_right,
                k.r_right,
                NOMINAL.r_right,
                tol_r,
            );
            assert_recovered(&what("r_left"), f.r_left, k.r_left, NOMINAL.r_left, tol_r);
            assert_recovered(
                &what("wheel base"),
                f.wheel_base,
                k.wheel_base,
                NOMINAL.wheel_base,
                tol_d,
            );
            assert!(no_nan(&r));
            // The calibrated odometry stays close to the truth.
            let end = r.trajectory.poses.last().unwrap();
            let t_end = *r.trajectory.stamps.last().unwrap();
            let truth = d.reference.pose_at(t_end).unwrap();
            let miss = (end.translation.vector - truth.translation.vector).norm();
            assert!(miss < 0.5, "{}: end {miss} m off", m.as_str());
            worst_end = worst_end.max(miss);
        }
        // The uncalibrated model keeps its prior (the nominal the checks
        // above fail) and ends far worse than any of them: the drawn truth
        // is millimetres from the nominal radii, which over a 60 s drive
        // puts the nominal odometry metres off.
        let none = calibrate(Method::None, seed, &st);
        assert_eq!(none.final_drive(), NOMINAL);
        let end = none.trajectory.poses.last().unwrap();
        let truth = d.reference.pose_at(*none.trajectory.stamps.last().unwrap());
        let miss = (end.translation.vector - truth.unwrap().translation.vector).norm();
        assert!(
            miss > 10.0 * worst_end && miss > 1.0,
            "nominal odometry ends {miss} m off, calibrated ones at most {worst_end} m"
        );
    }
}

#[test]
fn same_seed_gives_the_same_numbers() {
    let (_, st) = synth(5, 10.0, None);
    for m in [Method::AdaptivePf, Method::Pf] {
        let a = calibrate(m, 3, &st);
        let b = calibrate(m, 3, &st);
        let c = calibrate(m, 4, &st);
        assert_eq!(a.history, b.history);
        assert_ne!(a.history, c.history);
    }
}

#[test]
fn degenerate_measurements_never_produce_nan() {
    let base = CalibStep::new(0.0, 0.02, 3.0, 2.9);
    let cases = [
        base,                                   // no measurement: predict only
        base.with(Kind::V, 0.9, 0.0),           // σ = 0 → floor
        base.with(Kind::W, 0.1, f64::INFINITY), // σ = ∞ → ignored
        base.with(Kind::W, 0.1, f64::NAN),      // σ = NaN → ignored
        base.with(Kind::V, f64::NAN, 0.01),     // value NaN → ignored
        base.with(Kind::V, 1e200, 1e-9),        // every log-weight −∞: reset
    ];
    for m in Method::ALL {
        let mut p = CalibParams {
            method: m,
            particles: Some(300),
            ..Default::default()
        };
        // A Gaussian likelihood: the Student-t weight would give the 1e200
        // measurement none, and the underflow this test exercises would not
        // happen.
        p.noise.robust_dof = 0.0;
        let mut cal = build(&p, NOMINAL).unwrap();
        let steps: Vec<CalibStep> = cases
            .iter()
            .cycle()
            .take(60)
            .enumerate()
            .map(|(i, s)| {
                let mut s = *s;
                s.t0 = i as f64 * 0.02;
                s.t1 = (i + 1) as f64 * 0.02;
                s
            })
            .collect();
        let r = run(cal.as_mut(), &steps, NOMINAL);
        assert!(no_nan(&r), "{}", m.as_str());
        if matches!(m, Method::AdaptivePf | Method::Pf) {
            assert!(
                r.weight_resets > 0,
                "{}: the underflow case must reset",
                m.as_str()
            );
        }
    }
}

/// Whether the detector's firing times `fired` (s) show a change at `step`:
/// at least one firing, none before the step, the first within `delay` s
/// of it.
fn fired_after(fired: &[f64], step: f64, delay: f64) -> Result<(), String> {
    match fired.first() {
        None => Err("the jump went unnoticed".into()),
        Some(&t) if t < step => Err(format!("fired at {t} s, before the step at {step} s")),
        Some(&t) if t > step + delay => Err(format!("fired at {t} s, over {delay} s late")),
        Some(_) => Ok(()),
    }
}

#[test]
fn a_radius_step_mid_run_is_retracked() {
    let step = RadiusStep {
        time: 25.0,
        right: 0.004,
        left: 0.002,
    };
    let (d, st) = synth(21, 60.0, Some(step));
    let p = CalibParams {
        seed: 21,
        ..Default::default()
    };
    let mut pf = ParticleFilter::new(&p.pf_settings());
    let r = run(&mut pf, &st, NOMINAL);
    // The change detector fired after the step, not before it: a twin of
    // the filter (same settings and seed) stepped by hand tells when.
    let mut twin = ParticleFilter::new(&p.pf_settings());
    let mut fired = Vec::new();
    for s in &st {
        let before = twin.jumps();
        twin.step(s);
        if twin.jumps() > before {
            fired.push(s.t1);
        }
    }
    assert_eq!(fired.len(), pf.jumps(), "the twin ran as the filter did");
    eprintln!(
        "the detector fired at {fired:?} s (step at {} s)",
        step.time
    );
    // Its score forgets with a time constant (5 s): the post-step residuals
    // fill it within two of them (measured: 30.5 s for the step at 25 s).
    let delay = 2.0 * p.change.window;
    fired_after(&fired, step.time, delay).unwrap();
    // The same check on a detector that never fires, or that fired before
    // the step as well, fails.
    assert!(fired_after(&[], step.time, delay).is_err());
    assert!(fired_after(&[step.time - 5.0, step.time + 1.0], step.time, delay).is_err());
    let f = r.final_drive();
    let k = d.truth_at(60.0);
    let before = r.history.iter().rfind(|h| h.t < 25.0).unwrap();
    let k0 = d.truth_at(0.0);
    // Converged before the step: within 1 mm of the first right radius,
    // which the nominal misses by 13.7 mm.
    let what = "right radius before the step";
    assert_recovered(what, before.r_right, k0.r_right, NOMINAL.r_right, 1e-3);
    // Retracked: each radius within 0.6 mm of the stepped one. The step
    // left out (the first radii, 4 and 2 mm away) fails the same check, and
    // so does a filter that stayed at its own pre-step estimates.
    let tol = 0.6e-3;
    assert_recovered(
        "right radius after the step",
        f.r_right,
        k.r_right,
        k0.r_right,
        tol,
    );
    assert_recovered(
        "left radius after the step",
        f.r_left,
        k.r_left,
        k0.r_left,
        tol,
    );
    assert!(
        (before.r_right - k.r_right).abs() >= tol && (before.r_left - k.r_left).abs() >= tol,
        "the pre-step estimates {} / {} pass the check",
        before.r_right,
        before.r_left
    );
}

#[test]
fn run_reports_design_keys_and_multipliers() {
    let (_, st) = synth(2, 5.0, None);
    let r = calibrate(Method::Dkf, 1, &st);
    let j = serde_json::to_value(&r.summary).unwrap();
    for k in [
        "method",
        "final",
        "std",
        "iterations",
        "mean_iteration_ms",
        "multipliers",
    ] {
        assert!(j.get(k).is_some(), "{k}");
    }
    assert_eq!(j["method"], "dkf");
    assert_eq!(j["iterations"], st.len());
    let m = &j["multipliers"];
    let f = r.summary.final_params;
    assert!((m["right_wheel_radius"].as_f64().unwrap() - f.r_right / 0.32).abs() < 1e-12);
    assert!((m["wheel_separation"].as_f64().unwrap() - f.wheel_base / 0.65).abs() < 1e-12);
    let row = serde_json::to_value(r.history[0]).unwrap();
    let keys: Vec<_> = row.as_object().unwrap().keys().cloned().collect();
    assert_eq!(keys.len(), 9);
    let params: CalibParams =
        toml::from_str("method = \"akf\"\nresampler = \"residual\"\ntrigger = \"max-weight\"")
            .unwrap();
    assert_eq!(
        (params.method, params.resampler, params.trigger),
        (Method::Akf, Scheme::Residual, Trigger::MaxWeight)
    );
}

#[test]
fn the_change_detector_stays_quiet_without_a_change() {
    for seed in [11u64, 12, 13] {
        let (d, st) = synth(seed, 60.0, None);
        let p = CalibParams {
            seed,
            ..Default::default()
        };
        let mut pf = ParticleFilter::new(&p.pf_settings());
        let r = run(&mut pf, &st, NOMINAL);
        assert_eq!(pf.jumps(), 0, "seed {seed}: false alarm");
        // Quiet, and not for want of learning: the right radius within 1 mm
        // of the truth, which the nominal misses by over three times that
        // (3.4 mm on seed 12, more on the others) and must fail.
        let f = r.final_drive();
        let what = format!("seed {seed}: r_right");
        assert_recovered(&what, f.r_right, d.truth.r_right, NOMINAL.r_right, 1e-3);
    }
}

/// The wheel base (m) a run held at `t` s.
fn base_at(r: &CalibrationRun, t: f64) -> f64 {
    r.history.iter().rfind(|h| h.t <= t).unwrap().wheel_base
}

/// How far (m) a run's wheel base strays after `t` s from where it was then.
fn wander_after(r: &CalibrationRun, t: f64) -> f64 {
    let d = base_at(r, t);
    r.history
        .iter()
        .filter(|h| h.t > t)
        .map(|h| (h.wheel_base - d).abs())
        .fold(0.0, f64::max)
}

/// Turns for 20 s (D becomes known), then drives straight for 60 s, where W
/// carries no information about D: no filter may let D wander.
#[test]
fn wheel_base_holds_still_where_it_is_unobservable() {
    let p = SynthParams {
        duration: 80.0,
        straight_from: Some(20.0),
        ..Default::default()
    };
    let seed = 31;
    let d = generate(&p, draw_truth(seed), seed);
    let st = steps(&d.obs, &d.wheels, &d.gyro, p.gyro_sigma);
    let mut failed = vec![];
    for m in [Method::AdaptivePf, Method::Pf, Method::Dkf, Method::Akf] {
        let r = calibrate(m, seed, &st);
        let (d20, dend) = (base_at(&r, 20.0), base_at(&r, 80.0));
        let wander = wander_after(&r, 20.0);
        eprintln!(
            "{}: D at 20 s {:.4}, end {:.4}, truth {:.4}, max wander {:.2} mm",
            m.as_str(),
            d20,
            dend,
            d.truth.wheel_base,
            wander * 1e3
        );
        let bound = 5e-3;
        if wander >= bound {
            failed.push(format!("{}: D wandered {wander} m", m.as_str()));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
    // Negative control: the fixed PF with [Farina]'s published process
    // noise (0.5 mm per step on every parameter) lets D walk where nothing
    // holds it, beyond the converging filters' bound.
    let p = CalibParams {
        method: Method::Pf,
        seed,
        preset: Preset::Published,
        ..Default::default()
    };
    let mut cal = build(&p, NOMINAL).unwrap();
    let r = run(cal.as_mut(), &st, NOMINAL);
    let wander = wander_after(&r, 20.0);
    assert!(
        wander >= 5e-3,
        "the published PF's D wandered only {wander} m"
    );
}

/// [Farina, Table I] on our data, small: the fixed PF with every
/// resampling scheme and trigger on the same synthetic runs. \[Farina\] finds
/// the four schemes close, the max-weight trigger the least accurate, and
/// picks systematic + N_eff. Checked here: max-weight is the least accurate
/// trigger for every scheme (its median radius error above both others'),
/// and systematic + N_eff is as accurate as the best configuration within
/// the run-to-run spread (its median radius error within 1.5× the best
/// median). That systematic + N_eff is strictly the best does not hold on
/// our data: the schemes tie (docs/results.md, "Resampling").
#[test]
fn a_small_table_i_keeps_the_seeds_findings() {
    use odocal::experiments::{montecarlo, table1_configs, MonteCarloParams};
    let mut mc = MonteCarloParams {
        runs: 6,
        seed: 3,
        ..Default::default()
    };
    mc.synth.duration = 30.0;
    let base = CalibParams {
        particles: Some(2000),
        ..Default::default()
    };
    let t = montecarlo(&mc, &table1_configs(&base));
    let err = |label: &str| {
        let r = t.rows.iter().find(|r| r.label == label).unwrap();
        0.5 * (r.err_r_right.median + r.err_r_left.median)
    };
    for s in Scheme::ALL {
        let [neff, max, every] =
            ["neff", "max-weight", "every"].map(|tr| err(&format!("{}/{tr}", s.as_str())));
        eprintln!(
            "{}: neff {neff:.5} max-weight {max:.5} every {every:.5}",
            s.as_str()
        );
        assert!(
            max > neff && max > every,
            "{}: {neff} {max} {every}",
            s.as_str()
        );
    }
    let best = t
        .rows
        .iter()
        .map(|r| err(&r.label))
        .fold(f64::INFINITY, f64::min);
    let sys = err("systematic/neff");
    assert!(sys <= 1.5 * best, "systematic/neff {sys} vs best {best}");
}
