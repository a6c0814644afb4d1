//! The figures of the diagnosis over many seeds (naming rate, estimate
//! errors, null false-positive rate), each asserted against a floor that
//! the do-nothing diagnosis (nothing named) fails. Every recording is drawn
//! first, in one order, and the diagnoses run in parallel, so the figures
//! do not depend on the thread count. Print them with
//! `cargo test --release --no-default-features --test lib diagnose_figures -- --nocapture`.

use crate::diagnose_synthetic::{check, draw, draw_pair, run};
use odocal::diagnose::synthetic::SyntheticSpec;
use odocal::diagnose::Verdict;
use odocal::effects::EFFECT_NAMES;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;

/// Each effect named right (exactly it, every estimate within 20 %, held-
/// out gain) in at least this many of [`SEEDS`] runs.
const NAMED_AT_LEAST: usize = 9;
/// Seeds per effect.
const SEEDS: u64 = 10;
/// The median relative error of an effect's estimates at most this.
const MEDIAN_ERROR: f64 = 0.1;

#[test]
fn diagnose_figures() {
    let seeds = SEEDS;
    let mut rng = rand::rngs::StdRng::seed_from_u64(31337);
    let mut short = Vec::new();
    // The do-nothing diagnosis: a null run's, which names nothing.
    let nothing = run(
        &SyntheticSpec {
            duration: 60.0,
            ..Default::default()
        },
        9999,
    );
    assert!(nothing.causes.is_empty(), "{:?}", nothing.causes);
    // Every draw in one sequence from the one generator (effects, then
    // out-of-roundness, then pairs) before any diagnosis runs.
    let mut single = Vec::new();
    for name in EFFECT_NAMES {
        for seed in 0..seeds {
            let (e, duration) = draw(name, &mut rng);
            let spec = SyntheticSpec {
                duration,
                sigma_v: rng.random_range(0.005..0.01),
                sigma_w: rng.random_range(0.005..0.01),
                effects: vec![e],
                ..Default::default()
            };
            single.push((e, spec, 5000 + seed));
        }
    }
    let out_of_round: Vec<(SyntheticSpec, u64)> = (0..20)
        .map(|seed| {
            let spec = SyntheticSpec {
                duration: 90.0,
                out_of_roundness: rng.random_range(0.004..0.01),
                ..Default::default()
            };
            (spec, 7000 + seed)
        })
        .collect();
    let pairs = [
        ("radius_scale", "latency"),
        ("wheel_base_scale", "gyro_bias"),
        ("encoder_gain", "laser_offset"),
        ("radius_step", "turn_slip"),
        ("radius_scale", "wheel_base_scale"),
        ("latency", "gyro_bias"),
    ];
    let mut paired = Vec::new();
    for (i, (a, b)) in pairs.iter().enumerate() {
        for seed in 0..5u64 {
            let (effects, spec) = draw_pair(a, b, &mut rng);
            paired.push((effects, spec, 8000 + 10 * i as u64 + seed));
        }
    }

    let diagnosed: Vec<_> = single
        .par_iter()
        .map(|(_, spec, seed)| run(spec, *seed))
        .collect();
    for (i, name) in EFFECT_NAMES.iter().enumerate() {
        let (mut ok, mut errs) = (0, Vec::new());
        let start = i * seeds as usize;
        for ((e, _, _), d) in single
            .iter()
            .zip(&diagnosed)
            .skip(start)
            .take(seeds as usize)
        {
            if check(d, &[*e], name).is_ok() {
                ok += 1;
            }
            // The same check fails the diagnosis that names nothing.
            assert!(check(&nothing, &[*e], name).is_err(), "{name}");
            if let Some(c) = d.causes.iter().find(|c| c.effect == *name) {
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
        // An effect never named leaves no errors: its median is NaN and fails.
        if ok < NAMED_AT_LEAST || !(med <= MEDIAN_ERROR) {
            short.push(format!("{name}: {ok}/{seeds}, median {med:.3}"));
        }
    }
    let n = 100;
    let fp = (0..n)
        .into_par_iter()
        .filter(|seed| {
            let spec = SyntheticSpec {
                duration: 90.0,
                ..Default::default()
            };
            run(&spec, 9000 + seed).verdict != Verdict::NoDiscrepancy
        })
        .count();
    println!("null: {fp}/{n} not no-discrepancy");
    // At most 5 % false positives (the null test's 95 %).
    if fp > 5 {
        short.push(format!("null: {fp}/{n} not no-discrepancy"));
    }
    let oor = |d: &odocal::diagnose::Diagnosis| {
        d.causes.is_empty() && d.faults.iter().any(|f| f.name == "wheel_out_of_round")
    };
    assert!(!oor(&nothing));
    let (mut named_oor, mut other) = (0, Vec::new());
    let diagnosed: Vec<_> = out_of_round
        .par_iter()
        .map(|(spec, seed)| run(spec, *seed))
        .collect();
    for ((spec, _), d) in out_of_round.iter().zip(&diagnosed) {
        if oor(d) {
            named_oor += 1;
        } else {
            let named: Vec<String> = d.causes.iter().map(|c| c.effect.clone()).collect();
            other.push(format!(
                "a={:.4} {:?} {named:?}",
                spec.out_of_roundness, d.verdict
            ));
        }
    }
    println!("out-of-roundness: {named_oor}/20 named as itself; others: {other:?}");
    if named_oor < 19 {
        short.push(format!("out-of-roundness: {named_oor}/20"));
    }
    let ok = paired
        .par_iter()
        .filter(|(truth, spec, seed)| check(&run(spec, *seed), truth, "pair").is_ok())
        .count();
    for (truth, _, _) in &paired {
        assert!(check(&nothing, truth, "pair").is_err());
    }
    println!("pairs: {ok}/{} both named within 20 %", paired.len());
    if ok + 2 < paired.len() {
        short.push(format!("pairs: {ok}/{}", paired.len()));
    }
    assert!(short.is_empty(), "below the floors: {short:#?}");
}
