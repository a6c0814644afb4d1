//! Hidden-effect tests of the diagnosis on synthetic streams from a known
//! true model (8800-tick quantised encoders at 50 Hz, ICP-like motions at
//! 25 Hz with σ 0.005–0.01, gyro at 100 Hz with σ 0.002 rad/s): the right
//! effect named, each estimate within 20 % of the truth, positive held-out
//! gain; null data → no-discrepancy; an effect outside the list → unexplained.

use odocal::diagnose::synthetic::{synthesize, SyntheticSpec};
use odocal::diagnose::{diagnose, DiagnoseParams, Diagnosis, Measured, Verdict};
use odocal::effects::{Effect, EFFECT_NAMES};
use odocal::robot::RobotConfig;
use rand::{RngExt, SeedableRng};

pub(crate) fn run(spec: &SyntheticSpec, seed: u64) -> Diagnosis {
    let robot = RobotConfig::default();
    let s = synthesize(&robot, spec, seed);
    let m = Measured {
        wheels: &s.wheels,
        motions: &s.motions,
        gyro: &s.gyro,
        reference: &s.reference,
    };
    diagnose(&robot, &m, &DiagnoseParams::default()).unwrap()
}

/// A realistic random magnitude (and sign) of an effect, and a recording
/// length long enough for it to matter.
pub(crate) fn draw(name: &str, rng: &mut rand::rngs::StdRng) -> (Effect, f64) {
    let mut m = |lo: f64, hi: f64| {
        let s = if rng.random_range(0.0..1.0) < 0.5 {
            -1.0
        } else {
            1.0
        };
        s * rng.random_range(lo..hi)
    };
    let e = match name {
        "radius_scale" => Effect::RadiusScale {
            right: m(0.005, 0.015),
            left: m(0.005, 0.015),
        },
        "wheel_base_scale" => Effect::WheelBaseScale {
            scale: m(0.02, 0.05),
        },
        "radius_step" => Effect::RadiusStep {
            time: m(25.0, 45.0).abs(),
            right: m(0.002, 0.005),
            left: m(0.002, 0.005),
        },
        "radius_drift" => Effect::RadiusDrift {
            right: m(0.02, 0.04),
            left: m(0.02, 0.04),
        },
        "encoder_gain" => Effect::EncoderGain {
            k: m(0.005, 0.02).abs(),
        },
        "latency" => Effect::Latency {
            delay: m(0.02, 0.06).abs(),
        },
        "laser_offset" => Effect::LaserOffset {
            x: m(0.03, 0.08),
            y: m(0.02, 0.05),
            yaw: m(0.01, 0.03),
        },
        "gyro_bias" => Effect::GyroBias {
            bias: m(0.002, 0.01),
        },
        "turn_slip" => Effect::TurnSlip {
            k: m(0.05, 0.15).abs(),
        },
        _ => unreachable!(),
    };
    // A drift of a few cm per hour needs minutes to show.
    let duration = if name == "radius_drift" { 240.0 } else { 90.0 };
    (e, duration)
}

/// Two effects drawn in order (`a` then `b`) and the 90 s synthetic run
/// holding both.
pub(crate) fn draw_pair(
    a: &str,
    b: &str,
    rng: &mut rand::rngs::StdRng,
) -> ([Effect; 2], SyntheticSpec) {
    let (ea, _) = draw(a, rng);
    let (eb, _) = draw(b, rng);
    let spec = SyntheticSpec {
        duration: 90.0,
        effects: vec![ea, eb],
        ..Default::default()
    };
    ([ea, eb], spec)
}

/// Checks that the diagnosis names exactly the injected effects, with every
/// parameter within 20 % of the truth, and gains on the held-out part.
pub(crate) fn check(d: &Diagnosis, truth: &[Effect], what: &str) -> Result<(), String> {
    let mut named: Vec<&str> = d.causes.iter().map(|c| c.effect.as_str()).collect();
    let mut want: Vec<&str> = truth.iter().map(|e| e.name()).collect();
    named.sort();
    want.sort();
    if d.verdict != Verdict::Explained || named != want {
        return Err(format!("{what}: {:?} {named:?}, want {want:?}", d.verdict));
    }
    for e in truth {
        let c = d.causes.iter().find(|c| c.effect == e.name()).unwrap();
        for (k, v) in e.params() {
            let est = c.parameters[k];
            if (est - v).abs() > 0.2 * v.abs() {
                return Err(format!("{what}: {k} = {est}, truth {v}"));
            }
        }
    }
    if !(d.gain.relative > 0.0 && d.gain.heldout_rmse_after < d.gain.heldout_rmse_before) {
        return Err(format!("{what}: no held-out gain {:?}", d.gain));
    }
    Ok(())
}

#[test]
fn every_effect_is_named_estimated_within_20_percent_and_gains() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(2024);
    let mut failures = Vec::new();
    let mut runs = 0;
    for name in EFFECT_NAMES {
        for seed in 0..2u64 {
            let (e, duration) = draw(name, &mut rng);
            let spec = SyntheticSpec {
                duration,
                sigma_v: rng.random_range(0.005..0.01),
                sigma_w: rng.random_range(0.005..0.01),
                effects: vec![e],
                ..Default::default()
            };
            let d = run(&spec, 100 + seed);
            runs += 1;
            if let Err(m) = check(&d, &[e], &e.to_string()) {
                failures.push(m);
            }
            // The negative control: the same diagnosis with the effect named
            // at a quarter of its estimate fails the same check.
            let mut short = d.clone();
            for c in &mut short.causes {
                c.parameters.values_mut().for_each(|v| *v *= 0.25);
            }
            if short
                .causes
                .iter()
                .any(|c| c.parameters.values().any(|v| *v != 0.0))
            {
                assert!(
                    check(&short, &[e], "control").is_err(),
                    "{e}: a quarter passes"
                );
            }
        }
    }
    assert_eq!(runs, 2 * EFFECT_NAMES.len());
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn combinations_of_two_effects_are_both_named() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(77);
    let mut failures = Vec::new();
    for (a, b) in [
        ("radius_scale", "latency"),
        ("wheel_base_scale", "gyro_bias"),
        ("encoder_gain", "laser_offset"),
        ("radius_step", "turn_slip"),
    ] {
        let ([ea, eb], spec) = draw_pair(a, b, &mut rng);
        let d = run(&spec, 7);
        if let Err(m) = check(&d, &[ea, eb], &format!("{ea} + {eb}")) {
            failures.push(m);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn null_recordings_give_no_discrepancy_in_at_least_95_percent_of_seeds() {
    let seeds = 20;
    let mut ok = 0;
    let mut named = Vec::new();
    for seed in 0..seeds {
        let spec = SyntheticSpec {
            duration: 60.0,
            ..Default::default()
        };
        let d = run(&spec, 1000 + seed);
        if d.verdict == Verdict::NoDiscrepancy {
            ok += 1;
        }
        named.extend(d.causes.iter().map(|c| c.effect.clone()));
    }
    assert!(
        ok * 100 >= 95 * seeds,
        "{ok}/{seeds} no-discrepancy; named {named:?}"
    );
}

#[test]
fn mis_scaled_icp_sigma_changes_neither_the_null_nor_the_naming() {
    // The ICP covariance halves (over-confident) or doubles the true σ.
    for (f, seed) in [(0.5, 1), (2.0, 2)] {
        let spec = SyntheticSpec {
            duration: 60.0,
            reported_sigma_factor: f,
            ..Default::default()
        };
        let d = run(&spec, seed);
        assert_eq!(
            d.verdict,
            Verdict::NoDiscrepancy,
            "factor {f}: {:?}",
            d.causes
        );
        let s = d.noise_scale["icp_v"];
        assert!((s * f - 1.0).abs() < 0.1, "noise scale {s} for factor {f}");
        let e = Effect::WheelBaseScale { scale: 0.03 };
        let spec = SyntheticSpec {
            effects: vec![e],
            ..spec
        };
        check(&run(&spec, seed), &[e], "wheel base with mis-scaled σ").unwrap();
    }
}

#[test]
fn wheel_out_of_roundness_is_named_as_itself_not_as_a_table_effect() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for seed in 0..3 {
        let spec = SyntheticSpec {
            duration: 90.0,
            out_of_roundness: rng.random_range(0.004..0.01),
            ..Default::default()
        };
        let d = run(&spec, 300 + seed);
        assert!(d.causes.is_empty(), "{:?}", d.causes);
        let f = d
            .faults
            .iter()
            .find(|f| f.name == "wheel_out_of_round")
            .unwrap_or_else(|| panic!("amplitude {}: {:?}", spec.out_of_roundness, d.faults));
        // Both wheels wobble by the same amplitude in the synthetic streams.
        for k in ["right", "left"] {
            let a = f.parameters[k];
            assert!(
                (a - spec.out_of_roundness).abs() < 0.3 * spec.out_of_roundness,
                "{k}: {a} vs {}",
                spec.out_of_roundness
            );
        }
        assert_eq!(d.verdict, Verdict::Explained);
    }
}

#[test]
fn result_serialises_with_design_keys() {
    let e = Effect::GyroBias { bias: 0.005 };
    let spec = SyntheticSpec {
        duration: 60.0,
        effects: vec![e],
        ..Default::default()
    };
    let d = run(&spec, 9);
    let j = serde_json::to_value(&d).unwrap();
    assert_eq!(j["verdict"], "explained");
    assert_eq!(j["causes"][0]["effect"], "gyro_bias");
    assert!(j["causes"][0]["parameters"]["bias"].as_f64().unwrap() > 0.004);
    assert!(j["causes"][0]["stderr"]["bias"].as_f64().unwrap() > 0.0);
    assert!(j["causes"][0]["delta_bic"].as_f64().unwrap() > 10.0);
    for k in ["heldout_rmse_before", "heldout_rmse_after", "relative"] {
        assert!(j["gain"][k].is_number(), "{k}");
    }
    assert!(j.get("series").is_none());
    // The synthetic reference is the truth: a gyro bias leaves the wheel
    // trajectory unchanged; a wheel-base error shrinks the held-out RPE.
    let t = d.gain.trajectory.unwrap();
    assert!(t.windows >= 3 && (t.rpe_before - t.rpe_after).abs() < 1e-12);
    let e = Effect::WheelBaseScale { scale: 0.04 };
    let w = run(
        &SyntheticSpec {
            duration: 60.0,
            effects: vec![e],
            ..Default::default()
        },
        9,
    );
    let t = w.gain.trajectory.unwrap();
    assert!(t.rpe_after < 0.5 * t.rpe_before, "{t:?}");
    assert_eq!(d.series.t.len(), d.series.v_before.len());
    let null = run(
        &SyntheticSpec {
            duration: 60.0,
            ..Default::default()
        },
        9,
    );
    assert_eq!(
        serde_json::to_value(&null).unwrap()["verdict"],
        "no-discrepancy"
    );
}
