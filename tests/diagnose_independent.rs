//! The diagnosis against laws it does not share: a clean simulated bag
//! rewritten by `tools/rewrite_effects.py` (Python `mcap` + `rosbags`, its own
//! arithmetic, nothing of odocal's `effects::Departures`), then `odocal
//! diagnose` on the rewritten bag. Table effects are named with their sizes
//! within 20 %; a fault outside the table (an out-of-round wheel, a gyro's
//! scale) is named as that fault and never as a table effect; tyres deflecting
//! under load are their standing radii and the fault `tyre_load_transfer`;
//! `calibrate`'s online mounting check finds a laser
//! shifted where `/tf_static` does not say. Each case's assertion is also
//! run on the clean bag, where it must fail.

use crate::support::{odocal, ok_json, python_tool, python_with, scratch};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A 150 s random walk (seed 303), with the simulator's `effects` (none:
/// the clean bag): it turns both ways and reverses its turns, so every table
/// effect below is visible in it.
fn simulated(dir: &Path, name: &str, effects: &[&str]) -> PathBuf {
    simulated_in(dir, name, "random-walk", "303", effects)
}

/// A 150 s drive of `scenario` (seed `seed`) with the simulator's `effects`.
fn simulated_in(dir: &Path, name: &str, scenario: &str, seed: &str, effects: &[&str]) -> PathBuf {
    let bag = dir.join(format!("{name}.mcap"));
    let mut args = vec![
        "simulate",
        "--scenario",
        scenario,
        "--seed",
        seed,
        "--duration",
        "150",
        "--out",
        bag.to_str().unwrap(),
    ];
    for e in effects {
        args.extend(["--effect", *e]);
    }
    let out = odocal(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    bag
}

fn clean(dir: &Path) -> PathBuf {
    simulated(dir, "clean", &[])
}

/// The same drive with tyres whose rolling radius follows their load
/// (`tyre_load`, physics in the simulator rather than a law of the effect
/// table): 100 kg, the centre of mass 6.5 cm left of the middle and 0.5 m
/// high, 50 kN/m tyres.
fn loaded(dir: &Path) -> PathBuf {
    let tyres = "tyre_load:mass=100,com_y=0.065,height=0.5,stiffness=50000";
    simulated(dir, "tyres", &[tyres])
}

fn diagnose(bag: &Path) -> Value {
    ok_json(&odocal(&[
        "diagnose",
        "--measured",
        bag.to_str().unwrap(),
        "--json",
    ]))
}

/// `clean` rewritten by `law` (the bag's path).
fn rewrite(py: &str, dir: &Path, clean: &Path, law: &str) -> PathBuf {
    let dst = dir.join(format!("{}.mcap", law.replace([':', '=', ','], "_")));
    python_tool(
        py,
        "rewrite_effects.py",
        &[clean.to_str().unwrap(), dst.to_str().unwrap(), law],
    );
    dst
}

fn rewritten(py: &str, dir: &Path, clean: &Path, law: &str) -> Value {
    diagnose(&rewrite(py, dir, clean, law))
}

/// The named cause `effect`'s parameter `key`, if named.
fn cause(d: &Value, effect: &str, key: &str) -> Option<f64> {
    d["causes"]
        .as_array()?
        .iter()
        .find(|c| c["effect"] == effect)?["parameters"][key]
        .as_f64()
}

/// The named fault `name`'s parameter `key`, if named.
fn fault(d: &Value, name: &str, key: &str) -> Option<f64> {
    d["faults"].as_array()?.iter().find(|f| f["name"] == name)?["parameters"][key].as_f64()
}

fn within(x: Option<f64>, truth: f64) -> bool {
    x.is_some_and(|x| (x - truth).abs() <= 0.2 * truth.abs())
}

fn causes(d: &Value) -> usize {
    d["causes"].as_array().map_or(0, Vec::len)
}

#[test]
fn effects_written_by_an_independent_tool_are_named_and_faults_stay_faults() {
    let Some(py) = python_with("diagnose_independent", &["mcap", "rosbags"]) else {
        return;
    };
    let dir = scratch("diagnose_independent");
    let bag = clean(&dir);
    let none = diagnose(&bag);
    assert_eq!(none["verdict"], "no-discrepancy", "{none}");

    // A right wheel 1.2 % larger: radius_scale right within 20 %.
    let radius = |d: &Value| within(cause(d, "radius_scale", "right"), 0.012);
    let d = rewritten(&py, &dir, &bag, "radius:right_wheel=0.012");
    assert!(radius(&d), "{}", d["causes"]);
    assert!(!radius(&none), "the clean bag names no radius");

    // The laser 5 cm to the left of where /tf_static says, not turned: the
    // sideways shift is seen through the turns.
    let sideways = |d: &Value| within(cause(d, "laser_offset", "y"), 0.05);
    let d = rewritten(&py, &dir, &bag, "mounting:0,0.05,0");
    assert!(sideways(&d), "{}", d["causes"]);
    assert!(!sideways(&none), "the clean bag names no laser offset");

    // An out-of-round right wheel read as p − 0.03 sin p: the fault, at its
    // size, and no table effect standing in for part of it.
    let round = |d: &Value| within(fault(d, "wheel_out_of_round", "right"), 0.03);
    let d = rewritten(&py, &dir, &bag, "out_of_round:right_wheel=0.03");
    assert!(round(&d), "{}", d["faults"]);
    assert_eq!(
        causes(&d),
        0,
        "a table effect named for a fault: {}",
        d["causes"]
    );
    assert!(!round(&none), "the clean bag names no out-of-round wheel");

    // A gyro reading 2 % high is in no table: the gyro's fault, at its size
    // against the scan matching, and no table effect named for it.
    let gyro = |d: &Value| within(fault(d, "gyro_scale", "scale"), 0.02) && causes(d) == 0;
    let d = rewritten(&py, &dir, &bag, "gyro_scale:0.02");
    assert!(gyro(&d), "{} {} {}", d["verdict"], d["causes"], d["faults"]);
    assert!(!gyro(&none), "the clean bag names no gyro scale");

    // Loaded tyres: standing, the right wheel carries 100·g·(0.5 − 0.1) N
    // and the left 100·g·(0.5 + 0.1) N, so their radii shrink by 7.85 and
    // 11.77 mm of 0.32 m: a radius scale of −0.0245 and −0.0368, named alone.
    let g = 9.80665;
    let truth = |share: f64| -100.0 * g * share / 50_000.0 / 0.32;
    let tyres = |d: &Value| {
        causes(d) == 1
            && within(cause(d, "radius_scale", "right"), truth(0.4))
            && within(cause(d, "radius_scale", "left"), truth(0.6))
    };
    let d = diagnose(&loaded(&dir));
    assert!(tyres(&d), "{} {}", d["verdict"], d["causes"]);
    assert!(!tyres(&none), "the clean bag names no radius scale");
}

/// The square (seed 302) turns only in place, where scan-to-scan ICP reads
/// the turns 0.4 % short (`docs/results/icp-instrument.md`). A gyro reading
/// 2 % high is compared with the scan matching's turns read on the
/// instrument's scale, and once it is set aside the scan matching alone
/// times the turns: the fault at its size, no table effect beside it. The
/// negative control is the same bag with the instrument's model off, where
/// ICP's own error makes the scale 29 % too large and a wheel base 0.4 %
/// wider is named beside it.
#[test]
fn a_gyro_scale_is_read_against_the_scan_matchers_own_turn_error() {
    let Some(py) = python_with("diagnose_gyro_square", &["mcap", "rosbags"]) else {
        return;
    };
    let dir = scratch("diagnose_gyro_square");
    let bag = simulated_in(&dir, "square", "square", "302", &[]);
    let gyro_bag = rewrite(&py, &dir, &bag, "gyro_scale:0.02");
    let gyro = |d: &Value| within(fault(d, "gyro_scale", "scale"), 0.02) && causes(d) == 0;
    let d = diagnose(&gyro_bag);
    assert!(gyro(&d), "{} {} {}", d["verdict"], d["causes"], d["faults"]);
    let off = dir.join("instrument-off.toml");
    std::fs::write(&off, "[diagnose.instrument]\nenabled = false\n").unwrap();
    let d = ok_json(&odocal(&[
        "diagnose",
        "--measured",
        gyro_bag.to_str().unwrap(),
        "--config",
        off.to_str().unwrap(),
        "--json",
    ]));
    assert!(
        !gyro(&d),
        "without the instrument's model: {} {}",
        d["causes"],
        d["faults"]
    );
}

#[test]
fn the_online_check_finds_a_laser_two_centimetres_from_its_stated_mounting() {
    let Some(py) = python_with("diagnose_independent_online", &["mcap", "rosbags"]) else {
        return;
    };
    let dir = scratch("diagnose_independent_online");
    let bag = clean(&dir);
    let calibrate = |bag: &Path| {
        ok_json(&odocal(&[
            "calibrate",
            "--input",
            bag.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
            "--json",
        ]))
    };
    // The chair's laser sits at x −0.45 m, y 0 (turned by π); the rewritten
    // /tf_static says 2 cm to the right of that, or 2 cm behind it.
    let found = |d: &Value| {
        let l = &d["laser"];
        let (x, y) = (
            l["x"]["value"].as_f64().unwrap(),
            l["y"]["value"].as_f64().unwrap(),
        );
        l["contradicted"] == true && (x + 0.45).abs() < 0.005 && y.abs() < 0.005
    };
    for law in ["mounting:0,0.02,0", "mounting:0.02,0,0"] {
        let dst = dir.join(format!("{}.mcap", law.replace([':', ','], "_")));
        python_tool(
            &py,
            "rewrite_effects.py",
            &[bag.to_str().unwrap(), dst.to_str().unwrap(), law],
        );
        let d = calibrate(&dst);
        assert!(found(&d), "{law}: {}", d["laser"]);
    }
    // Negative control: the clean bag's stated mounting is kept.
    let d = calibrate(&bag);
    assert_eq!(d["laser"]["contradicted"], false, "{}", d["laser"]);
    assert!(!found(&d));
}

/// Loaded tyres on the figure eight (seed 301) and the corridor loop (seed
/// 304), whose speed changes little: the load a turn moves onto the outer
/// wheel shortens its radius by κ v ω of the nominal (κ = m h / (D k r) =
/// 100 · 0.5 / (0.65 · 50,000 · 0.32) s²/m), which at one speed is the law
/// of an encoder gain with the radii a little larger. The diagnosis names
/// the standing radii alone among the table effects and the turn's part as
/// `tyre_load_transfer` at its size, says it cannot tell it from a gain
/// (`told_apart` 0) and leaves the question open (`partly-explained`),
/// never naming an encoder gain. (The figure eight's selection names a gain
/// first, the corridor loop's radii 0.8 % short.) Negative controls: the
/// same tyres with the centre of mass on the ground (no load moves) name no
/// such fault, and an encoder gain on the random walk, whose changes of
/// speed tell the two laws apart, stays an encoder gain at its size.
#[test]
fn loaded_tyres_are_a_fault_beside_their_standing_radii_never_an_encoder_gain() {
    let dir = scratch("diagnose_tyre_load");
    let kappa = 100.0 * 0.5 / (0.65 * 50_000.0 * 0.32);
    let g = 9.80665;
    let standing = |share: f64| -100.0 * g * share / 50_000.0 / 0.32;
    let tyres =
        |height: &str| format!("tyre_load:mass=100,com_y=0.065,height={height},stiffness=50000");
    let named = |d: &Value| {
        causes(d) == 1
            && within(cause(d, "radius_scale", "right"), standing(0.4))
            && within(cause(d, "radius_scale", "left"), standing(0.6))
            && within(fault(d, "tyre_load_transfer", "kappa"), kappa)
    };
    for (scenario, seed) in [("figure-eight", "301"), ("corridor-loop", "304")] {
        let high = format!("tyres-high-{scenario}");
        let d = diagnose(&simulated_in(&dir, &high, scenario, seed, &[&tyres("0.5")]));
        let what = format!(
            "{scenario}: {} {} {}",
            d["verdict"], d["causes"], d["faults"]
        );
        assert!(named(&d), "{what}");
        assert_eq!(
            fault(&d, "tyre_load_transfer", "told_apart"),
            Some(0.0),
            "{what}"
        );
        assert_eq!(d["verdict"], "partly-explained", "{what}");
        assert!(cause(&d, "encoder_gain", "k").is_none(), "{what}");

        let flat = format!("tyres-flat-{scenario}");
        let flat = diagnose(&simulated_in(&dir, &flat, scenario, seed, &[&tyres("0")]));
        let what = format!("{scenario}: {} {}", flat["causes"], flat["faults"]);
        assert!(!named(&flat), "{what}");
        assert!(
            fault(&flat, "tyre_load_transfer", "kappa").is_none(),
            "{what}"
        );
    }

    let gain = diagnose(&simulated_in(
        &dir,
        "gain",
        "random-walk",
        "303",
        &["encoder_gain:k=0.005"],
    ));
    assert!(
        within(cause(&gain, "encoder_gain", "k"), 0.005),
        "{} {}",
        gain["causes"],
        gain["faults"]
    );
    assert!(fault(&gain, "tyre_load_transfer", "kappa").is_none());
}
