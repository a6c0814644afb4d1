//! The figures of the diagnosis over many seeds (naming rate, estimate
//! errors, null false-positive rate). Long: run on demand with
//! `cargo test --release --no-default-features --test lib diagnose_figures -- --ignored --nocapture`.

use crate::diagnose_synthetic::{check, draw, run};
use odocal::diagnose::synthetic::SyntheticSpec;
use odocal::diagnose::Verdict;
use odocal::effects::EFFECT_NAMES;
use rand::{RngExt, SeedableRng};

#[test]
#[ignore = "long sweep; prints the figures of docs/results.md"]
fn diagnose_figures() {
    let seeds = 10u64;
    let mut rng = rand::rngs::StdRng::seed_from_u64(31337);
    for name in EFFECT_NAMES {
        let (mut ok, mut errs) = (0, Vec::new());
        for seed in 0..seeds {
            let (e, duration) = draw(name, &mut rng);
            let spec = SyntheticSpec {
                duration,
                sigma_v: rng.random_range(0.005..0.01),
                sigma_w: rng.random_range(0.005..0.01),
                effects: vec![e],
                ..Default::default()
            };
            let d = run(&spec, 5000 + seed);
            if check(&d, &[e], name).is_ok() {
                ok += 1;
            }
            if let Some(c) = d.causes.iter().find(|c| c.effect == name) {
                for (k, v) in e.params() {
                    if k != "time" {
                        errs.push(((c.parameters[k] - v) / v).abs());
                    }
                }
            }
        }
        errs.sort_by(|a, b| a.total_cmp(b));
        let med = errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN);
        let max = errs.last().copied().unwrap_or(f64::NAN);
        println!(
            "{name:18} correct {ok}/{seeds}  rel. error median {:.1} % max {:.1} %",
            100.0 * med,
            100.0 * max
        );
    }
    let n = 100;
    let mut fp = 0;
    for seed in 0..n {
        let d = run(
            &SyntheticSpec {
                duration: 90.0,
                ..Default::default()
            },
            9000 + seed,
        );
        if d.verdict != Verdict::NoDiscrepancy {
            fp += 1;
        }
    }
    println!("null: {fp}/{n} not no-discrepancy");
    let (mut un, mut other) = (0, Vec::new());
    for seed in 0..20 {
        let spec = SyntheticSpec {
            duration: 90.0,
            out_of_roundness: rng.random_range(0.004..0.01),
            ..Default::default()
        };
        let d = run(&spec, 7000 + seed);
        if d.verdict == Verdict::Unexplained {
            un += 1;
        } else {
            let named: Vec<String> = d.causes.iter().map(|c| c.effect.clone()).collect();
            other.push(format!(
                "a={:.4} {:?} {named:?}",
                spec.out_of_roundness, d.verdict
            ));
        }
    }
    println!("out-of-roundness: {un}/20 unexplained; others: {other:?}");
    let pairs = [
        ("radius_scale", "latency"),
        ("wheel_base_scale", "gyro_bias"),
        ("encoder_gain", "laser_offset"),
        ("radius_step", "turn_slip"),
        ("radius_scale", "wheel_base_scale"),
        ("latency", "gyro_bias"),
    ];
    let mut ok = 0;
    for (i, (a, b)) in pairs.iter().enumerate() {
        for seed in 0..5u64 {
            let (ea, _) = draw(a, &mut rng);
            let (eb, _) = draw(b, &mut rng);
            let spec = SyntheticSpec {
                duration: 90.0,
                effects: vec![ea, eb],
                ..Default::default()
            };
            if check(&run(&spec, 8000 + 10 * i as u64 + seed), &[ea, eb], "pair").is_ok() {
                ok += 1;
            }
        }
    }
    println!("pairs: {ok}/{} both named within 20 %", 5 * pairs.len());
}
