//! Every effect of the table through the whole chain as a user meets it:
//! `odocal simulate --effect SPEC` writes a bag (the truth kept in its own
//! file), then `odocal diagnose --measured BAG --json` diagnoses the nominal
//! wheelchair from the bag alone. The effect must be the one cause named,
//! each of its parameters within 20 % of the hidden value (a radius step's
//! time within 2 s), and the nominal robot (every parameter zero) is put
//! through the same check and must fail it. Magnitudes are the blind
//! suite's (`src/experiments/blind/cases.rs`): 90 s runs, laser at 25 Hz.

use crate::support::{odocal, ok_json, scratch};
use serde_json::Value;

/// Length of each run (s), as the blind suite's.
const DURATION: &str = "90";

/// The parameters of `truth` (the truth file's structured effect) that
/// `got` (the named cause's parameters) misses: beyond 20 % of the hidden
/// value, or 2 s for a step's time, or not reported.
fn misses(truth: &Value, got: &Value) -> Vec<String> {
    let mut out = Vec::new();
    for (k, want) in truth.as_object().unwrap() {
        let Some(want) = want.as_f64() else {
            continue; // the effect's name
        };
        let tol = if k == "time" { 2.0 } else { 0.2 * want.abs() };
        match got[k].as_f64() {
            Some(g) if (g - want).abs() < tol => {}
            g => out.push(format!("{k}: {g:?} vs {want}")),
        }
    }
    out
}

/// Simulates `spec` on `scenario`, diagnoses the bag from the command
/// line and checks the named cause against the truth file.
fn chain(spec: &str, scenario: &str, seed: u64) {
    let name = spec.split(':').next().unwrap();
    let d = scratch(&format!("diagnose-chain-{name}"));
    let (bag, truth, cfg) = (d.join("run.mcap"), d.join("truth.json"), d.join("sim.toml"));
    std::fs::write(&cfg, "[sim.laser]\nrate_hz = 25.0\n").unwrap();
    let seed = seed.to_string();
    ok_json(&odocal(&[
        "simulate",
        "--scenario",
        scenario,
        "--seed",
        &seed,
        "--duration",
        DURATION,
        "--effect",
        spec,
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        bag.to_str().unwrap(),
        "--truth",
        truth.to_str().unwrap(),
        "--json",
    ]));
    let t: Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let hidden = &t["effects"][0];
    assert_eq!(hidden["effect"], name, "{t}");
    let v = ok_json(&odocal(&[
        "diagnose",
        "--measured",
        bag.to_str().unwrap(),
        "--json",
    ]));
    let causes = v["causes"].as_array().unwrap();
    let named: Vec<&str> = causes.iter().filter_map(|c| c["effect"].as_str()).collect();
    eprintln!("{spec} on {scenario}: {} {causes:?}", v["verdict"]);
    assert_eq!(named, [name], "{spec}: {}", v["verdict"]);
    let got = &causes[0]["parameters"];
    let m = misses(hidden, got);
    assert!(m.is_empty(), "{spec}: {m:?}");
    // The nominal robot's answer, every parameter zero, misses each one.
    let mut nominal = got.clone();
    for x in nominal.as_object_mut().unwrap().values_mut() {
        *x = 0.0.into();
    }
    assert_eq!(
        misses(hidden, &nominal).len(),
        hidden.as_object().unwrap().len() - 1,
        "{spec}: the nominal answer passes"
    );
}

#[test]
fn chain_radius_scale() {
    chain("radius_scale:right=0.015,left=-0.01", "figure-eight", 301);
}

#[test]
fn chain_wheel_base_scale() {
    chain("wheel_base_scale:scale=-0.03", "hall", 302);
}

#[test]
fn chain_radius_step() {
    chain(
        "radius_step:time=27,right=0.004,left=-0.003",
        "figure-eight",
        303,
    );
}

#[test]
fn chain_radius_drift() {
    chain("radius_drift:right=-0.08,left=-0.03", "corridor-loop", 304);
}

/// On the random walk, whose speed changes: on the figure eight, at one
/// speed, an encoder gain is the law of tyres deflecting under load, and the
/// diagnosis leaves which one it is open (`tests/diagnose_independent.rs`).
#[test]
fn chain_encoder_gain() {
    chain("encoder_gain:k=0.01", "random-walk", 305);
}

#[test]
fn chain_latency() {
    chain("latency:delay=0.04", "square", 306);
}

#[test]
fn chain_laser_offset() {
    chain("laser_offset:x=0.05,y=0.02,yaw=0.02", "hall", 307);
}

#[test]
fn chain_gyro_bias() {
    chain("gyro_bias:bias=0.005", "square-ccw", 308);
}

#[test]
fn chain_turn_slip() {
    chain("turn_slip:k=0.1", "figure-eight", 309);
}
