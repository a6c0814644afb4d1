//! No silent assumption, no absurd result: every nominal value a run used is
//! stated with its source; a laser mounting nobody states, wheels wired the
//! other way round, a motion that cannot determine a parameter and an
//! estimate far from the nominal robot each end in exit 2 with a message
//! saying what to fix — never in a number.

use crate::support::{odocal, ok_json as json, scratch, shared_data};
use odocal::io::{read_recording, write_mcap, ReadOptions, WriteOptions};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bundled() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scans/wheelchair-corridor.mcap")
}

fn wheelchair_toml() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scans/robots/wheelchair.toml"),
    )
    .unwrap()
}

/// Exit code 2 and the stderr message.
fn refused(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "expected a refusal: {err}");
    err
}

/// `odocal icp --json` over `bag` into `out` (TUM), with `--robot ROBOT`
/// when given; the process's output, success or not.
fn icp_output(bag: &Path, out: &Path, robot: Option<&str>) -> Output {
    let mut args = vec![
        "icp",
        "--input",
        bag.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend(robot.iter().flat_map(|r| ["--robot", *r]));
    odocal(&args)
}

/// The JSON of a successful [`icp_output`] run.
fn icp_json(bag: &Path, out: &Path, robot: Option<&str>) -> Value {
    json(&icp_output(bag, out, robot))
}

/// The bundled recording rewritten without its /tf_static, cut to `seconds`.
fn without_mount(d: &Path, seconds: f64) -> PathBuf {
    let mut rec = read_recording(&bundled(), &ReadOptions::default()).unwrap();
    let t0 = rec.scans[0].stamp;
    let end = t0 + seconds;
    rec.scans.retain(|s| s.stamp <= end);
    rec.wheels.retain(|s| s.stamp <= end);
    rec.gyro.retain(|s| s.stamp <= end);
    rec.reference.retain(|s| s.stamp <= end);
    rec.base_from_laser = None;
    let out = d.join(format!("nomount-{seconds}.mcap"));
    write_mcap(&out, &rec, &WriteOptions::default()).unwrap();
    out
}

#[test]
fn an_unstated_laser_mounting_is_never_assumed() {
    let d = scratch("checks_mount");
    let bag = without_mount(&d, 20.0);
    let tum = d.join("t.tum");
    let run = |robot: Option<&Path>| icp_output(&bag, &tum, robot.map(|r| r.to_str().unwrap()));
    // No robot file: the wheelchair's rear-facing mounting is not applied.
    let err = refused(&run(None));
    assert!(
        err.contains("nomount-20.mcap") && err.contains("[laser]"),
        "{err}"
    );
    assert!(!tum.exists());
    // A robot file without [laser]: the same refusal, not a default.
    let nolaser = d.join("nolaser.toml");
    let text: String = wheelchair_toml()
        .split("[laser]")
        .next()
        .unwrap()
        .to_string();
    std::fs::write(&nolaser, text).unwrap();
    refused(&run(Some(&nolaser)));
    // The robot file's [laser]: used, and said so.
    let robot = d.join("wheelchair.toml");
    std::fs::write(&robot, wheelchair_toml()).unwrap();
    let j = json(&run(Some(&robot)));
    assert_eq!(j["assumptions"]["laser"]["source"], "robot_file");
    assert_eq!(
        j["assumptions"]["laser"]["value"]["yaw"],
        std::f64::consts::PI
    );
    assert_eq!(j["assumptions"]["wheel_base"]["source"], "robot_file");
    // Its wheels are joint positions: no tick count is used, none is stated.
    assert!(j["assumptions"].get("ticks_per_rev").is_none());
    assert_eq!(j["assumptions"]["left_joint"]["source"], "robot_file");
}

#[test]
fn a_robot_file_must_state_the_kinematics() {
    let d = scratch("checks_robot_keys");
    let robot = d.join("partial.toml");
    std::fs::write(&robot, "name = \"khepera\"\nr_left = 0.021\n").unwrap();
    let out = odocal(&[
        "icp",
        "--input",
        bundled().to_str().unwrap(),
        "--robot",
        robot.to_str().unwrap(),
        "--out",
        d.join("t.tum").to_str().unwrap(),
    ]);
    let err = refused(&out);
    assert!(
        err.contains("partial.toml") && err.contains("r_right, wheel_base missing"),
        "{err}"
    );
}

#[test]
fn swapped_wheel_joints_are_named_not_calibrated() {
    let d = scratch("checks_swapped");
    let swapped = d.join("swapped.toml");
    let text = wheelchair_toml()
        .replace("left_joint = \"left_wheel\"", "left_joint = \"TMP\"")
        .replace(
            "right_joint = \"right_wheel\"",
            "right_joint = \"left_wheel\"",
        )
        .replace("left_joint = \"TMP\"", "left_joint = \"right_wheel\"");
    assert!(text.contains("left_joint = \"right_wheel\""));
    std::fs::write(&swapped, text).unwrap();
    let out_dir = d.join("cal");
    let out = odocal(&[
        "calibrate",
        "--input",
        bundled().to_str().unwrap(),
        "--robot",
        swapped.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let err = refused(&out);
    assert!(err.contains("Swap left_joint and right_joint"), "{err}");
    assert!(!out_dir.join("summary.json").exists());
}

#[test]
fn a_run_without_turns_cannot_give_the_wheel_base() {
    let d = scratch("checks_no_turns");
    // The corridor's first 8 s are straight.
    let bag = without_mount(&d, 8.0);
    let robot = d.join("wheelchair.toml");
    std::fs::write(&robot, wheelchair_toml()).unwrap();
    let out = odocal(&[
        "calibrate",
        "--input",
        bag.to_str().unwrap(),
        "--robot",
        robot.to_str().unwrap(),
        "--out",
        d.join("cal").to_str().unwrap(),
    ]);
    let err = refused(&out);
    assert!(err.contains("wheel_base") && err.contains("turns"), "{err}");
}

#[test]
fn an_estimate_far_from_the_nominal_robot_is_refused() {
    let d = scratch("checks_far");
    // The wheelchair's wheel base is 0.65 m; this file says 0.98 m.
    let robot = d.join("wide.toml");
    std::fs::write(
        &robot,
        wheelchair_toml().replace("wheel_base = 0.65", "wheel_base = 0.98"),
    )
    .unwrap();
    let out = odocal(&[
        "calibrate",
        "--input",
        bundled().to_str().unwrap(),
        "--robot",
        robot.to_str().unwrap(),
        "--out",
        d.join("cal").to_str().unwrap(),
    ]);
    let err = refused(&out);
    assert!(
        err.contains("calibration refused") && err.contains("wheel_base"),
        "{err}"
    );
}

#[test]
fn calibrate_states_its_assumptions_and_observability() {
    let d = scratch("checks_json");
    let out = odocal(&[
        "calibrate",
        "--input",
        bundled().to_str().unwrap(),
        "--method",
        "dkf",
        "--out",
        d.join("cal").to_str().unwrap(),
        "--json",
    ]);
    let j = json(&out);
    assert_eq!(j["assumptions"]["laser"]["source"], "tf_static");
    assert_eq!(j["assumptions"]["r_right"]["source"], "default");
    for p in ["r_right", "r_left", "wheel_base"] {
        assert_eq!(
            j["observability"]["parameters"][p]["observable"], true,
            "{p}"
        );
    }
    // The corridor loop turns left only: the wheel base is flagged weak.
    assert_eq!(j["observability"]["parameters"]["wheel_base"]["weak"], true);
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("cal/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["assumptions"], j["assumptions"]);
}

/// `icp` states the stream its initial guesses came from, and the wheel
/// model only when that stream is the wheels: the same recording with its
/// joint states, with only an odometry stream (its ground truth renamed),
/// and with neither; a stream named in `[icp] prior` that the recording
/// lacks is refused.
#[test]
fn icp_states_its_prior_and_the_wheel_model_only_when_it_used_it() {
    let d = scratch("checks_prior");
    let mut rec = read_recording(&bundled(), &ReadOptions::default()).unwrap();
    let end = rec.scans[0].stamp + 4.0;
    rec.scans.retain(|s| s.stamp <= end);
    rec.wheels.retain(|s| s.stamp <= end);
    rec.reference.retain(|s| s.stamp <= end);
    rec.gyro.clear();
    let wheels_only = rec.clone();
    rec.wheels.clear();
    rec.odom = std::mem::take(&mut rec.reference);
    let odom_only = rec.clone();
    rec.odom.clear();
    let cases = [
        ("wheels", wheels_only, true),
        ("odometry", odom_only, false),
        ("none", rec, false),
    ];
    for (want, rec, wheel_model) in cases {
        let bag = d.join(format!("{want}.mcap"));
        write_mcap(&bag, &rec, &WriteOptions::default()).unwrap();
        let j = icp_json(&bag, &d.join(format!("{want}.tum")), None);
        let a = &j["assumptions"];
        assert_eq!(a["prior"]["value"], want, "{a}");
        for k in ["r_right", "r_left", "wheel_base"] {
            assert_eq!(a.get(k).is_some(), wheel_model, "{want}: {k} in {a}");
        }
        assert_eq!(a["laser"]["source"], "tf_static");
    }
    let cfg = d.join("wheels.toml");
    std::fs::write(&cfg, "[icp]\nprior = \"wheels\"\n").unwrap();
    let bag = d.join("odometry.mcap");
    let err = refused(&odocal(&[
        "icp",
        "--input",
        bag.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        d.join("refused.tum").to_str().unwrap(),
    ]));
    assert!(
        err.contains("odometry.mcap") && err.contains("[icp] prior = \"wheels\""),
        "{err}"
    );
}

/// With both a wheel stream and the robot's own odometry, the prior is the
/// odometry unless a robot file states the wheels' kinematics. Which stream
/// was used is told by the data, not by the label: the odometry here is the
/// ground truth stamped 0.1 s late, and the clock check (the offset at which
/// the prior's turns fit the matched ones) finds those 0.1 s only when the
/// odometry was the prior.
#[test]
fn without_a_robot_file_the_recordings_own_odometry_is_the_prior() {
    let d = scratch("checks_prior_both");
    let mut rec = read_recording(&bundled(), &ReadOptions::default()).unwrap();
    rec.odom = std::mem::take(&mut rec.reference);
    for p in &mut rec.odom {
        p.stamp += 0.1;
    }
    let bag = d.join("both.mcap");
    write_mcap(&bag, &rec, &WriteOptions::default()).unwrap();
    let run = |robot: Option<&str>| icp_json(&bag, &d.join("both.tum"), robot);
    let odom = run(None);
    assert_eq!(odom["assumptions"]["prior"]["value"], "odometry");
    assert_eq!(odom["assumptions"]["prior"]["source"], "recording");
    assert!(odom["assumptions"].get("wheel_base").is_none());
    let wheels = run(Some("wheelchair"));
    assert_eq!(wheels["assumptions"]["prior"]["value"], "wheels");
    assert_eq!(wheels["assumptions"]["wheel_base"]["source"], "robot_file");
    // Both fits share the scans' own clock; the odometry's is 0.1 s later.
    let best = |j: &Value| j["prior_time_offset"]["best_s"].as_f64().unwrap();
    let (o, w) = (best(&odom), best(&wheels));
    assert!(w.abs() < 0.05, "wheel prior's offset {w} s");
    assert!((o - w - 0.1).abs() < 0.03, "odometry {o} s, wheels {w} s");
    // calibrate takes the same prior, and then does not pass the
    // odometry's clock off as the wheels'.
    let cal = |robot: Option<&str>| {
        let out = d.join(format!("cal-{}", robot.unwrap_or("none")));
        let mut args = vec![
            "calibrate",
            "--input",
            bag.to_str().unwrap(),
            "--method",
            "dkf",
            "--out",
            out.to_str().unwrap(),
            "--json",
        ];
        args.extend(robot.iter().flat_map(|r| ["--robot", *r]));
        json(&odocal(&args))["assumptions"].clone()
    };
    // The filters read the wheels at the offset they estimate themselves
    // (the wheels' own clock is the scans'), whichever prior the matcher
    // took: not the odometry's 0.1 s.
    for (robot, prior) in [(None, "odometry"), (Some("wheelchair"), "wheels")] {
        let a = cal(robot);
        assert_eq!(a["prior"]["value"], prior, "{a}");
        assert_eq!(a["time_offset"]["source"], "estimated", "{a}");
        let dt = a["time_offset"]["value"].as_f64().unwrap();
        assert!(dt.abs() < 0.03, "{robot:?}: wheels' offset {dt} s");
    }
}

/// Why the prior's kinematics matter, on real data: the Mines rover's
/// wheels integrated with the wheelchair's radii and wheel base (4 times its
/// own) fail many more pairs than with its robot file's; the run says which
/// kinematics it used, and its scale check finds them off.
#[test]
fn the_wheel_prior_with_the_robots_own_kinematics_fails_fewer_pairs() {
    let test = "the_wheel_prior_with_the_robots_own_kinematics_fails_fewer_pairs";
    let Some(data) = shared_data(test) else {
        return;
    };
    let d = scratch("checks_prior_rover");
    let bag = data.join("mines-rover/exp1.mcap");
    let run = |robot: Option<&str>| icp_json(&bag, &d.join("r.tum"), robot);
    let (assumed, own) = (run(None), run(Some("mines-rover")));
    assert_eq!(assumed["assumptions"]["wheel_base"]["source"], "default");
    assert_eq!(own["assumptions"]["wheel_base"]["source"], "robot_file");
    let failed = |j: &Value| j["failed_pairs"].as_u64().unwrap();
    assert!(
        failed(&assumed) > 2 * failed(&own),
        "failed pairs: {} with the wheelchair's kinematics, {} with the rover's",
        failed(&assumed),
        failed(&own)
    );
    // The scale check tells the two apart from the data: the wheelchair's
    // radii are 4.2 times the rover's and their ratio to the wheel base 2.1
    // times; with the rover's own the prior's scale is the scans'.
    let ratios = |j: &Value| {
        let s = &j["prior_scale"];
        [s["distance_ratio"].as_f64(), s["turn_ratio"].as_f64()].map(Option::unwrap)
    };
    let [d, t] = ratios(&assumed);
    assert!(d > 2.0 && t > 1.3, "wheelchair's kinematics: {d}, {t}");
    for r in ratios(&own) {
        assert!(
            (r - 1.0).abs() < 0.1,
            "rover's kinematics: {:?}",
            ratios(&own)
        );
    }
}

/// A CARMEN log states its mounting in its laser lines (MIT-CSAIL: the laser
/// pose is the odometry pose), so the log matches as well as its MCAP
/// conversion with its identity /tf_static (relations, \[Kummerle2009\]).
#[test]
fn a_carmen_log_states_its_own_mounting() {
    let Some(data) = shared_data("a_carmen_log_states_its_own_mounting") else {
        return;
    };
    let d = scratch("checks_carmen");
    let bench = data.join("slam-benchmark");
    let tum = d.join("m.tum");
    let j = icp_json(&bench.join("mit-csail.clf"), &tum, None);
    assert_eq!(j["assumptions"]["laser"]["source"], "log");
    // Its prior is the log's odometry: no wheel model is assumed.
    assert_eq!(j["assumptions"]["prior"]["value"], "odometry");
    assert!(j["assumptions"].get("wheel_base").is_none(), "{j}");
    assert!(j["failed_pairs"].as_u64().unwrap() < 40, "{j}");
    let e = json(&odocal(&[
        "eval",
        "--estimate",
        tum.to_str().unwrap(),
        "--reference",
        tum.to_str().unwrap(),
        "--relations",
        bench.join("mit-csail.relations").to_str().unwrap(),
        "--json",
    ]));
    let local = e["relations"]["local"]["trans_mean"].as_f64().unwrap();
    assert!(local < 0.032, "local relation error {local} m");
    // Diagnosing the log replays its odometry as virtual wheels: the wheel
    // model is stated, no tick count or joint name, the prior is the
    // odometry.
    let g = json(&odocal(&[
        "diagnose",
        "--measured",
        bench.join("mit-csail.clf").to_str().unwrap(),
        "--json",
    ]));
    let a = &g["assumptions"];
    assert_eq!(a["prior"]["value"], "odometry", "{a}");
    assert_eq!(a["wheel_base"]["source"], "default", "{a}");
    assert!(
        a.get("ticks_per_rev").is_none() && a.get("left_joint").is_none(),
        "{a}"
    );
    // The robot's own odometry has the scans' scale.
    for k in ["distance_ratio", "turn_ratio"] {
        let r = j["prior_scale"][k].as_f64().unwrap();
        assert!((0.85..1.15).contains(&r), "{k} {r}");
    }
}

#[test]
fn diagnose_states_its_assumptions_in_json_and_report() {
    let d = scratch("checks_diagnose");
    let report = d.join("rep");
    let j = json(&odocal(&[
        "diagnose",
        "--measured",
        bundled().to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(j["assumptions"]["laser"]["source"], "tf_static");
    assert_eq!(j["assumptions"]["wheel_base"]["source"], "default");
    assert_eq!(j["assumptions"]["prior"]["value"], "wheels");
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    assert!(md.contains("## Assumptions") && md.contains("the recording's /tf_static"));
}

/// Bags written by another tool (the Python `mcap` library): the mounting
/// only on /tf is read from there and said so; without any transform the
/// run stops naming the frames it looked for.
#[test]
fn a_mounting_on_tf_only_is_found_and_none_is_refused() {
    let test = "a_mounting_on_tf_only_is_found_and_none_is_refused";
    let Some(py) = crate::support::python_with(test, &["mcap"]) else {
        return;
    };
    let d = scratch("checks_tf_only");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/retopic_mcap.py");
    let rewrite = |out: &Path, args: &[&str]| {
        let s = Command::new(&py)
            .arg(&script)
            .arg(bundled())
            .arg(out)
            .args(args)
            .status()
            .unwrap();
        assert!(s.success());
    };
    let tf_only = d.join("tf-only.mcap");
    rewrite(&tf_only, &["--move", "/tf_static=/tf"]);
    let j = json(&odocal(&[
        "icp",
        "--input",
        tf_only.to_str().unwrap(),
        "--out",
        d.join("a.tum").to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(j["assumptions"]["laser"]["source"], "tf");
    assert_eq!(j["assumptions"]["laser"]["value"]["x"], -0.45);
    let none = d.join("none.mcap");
    rewrite(&none, &["--drop", "/tf_static"]);
    let err = refused(&odocal(&[
        "icp",
        "--input",
        none.to_str().unwrap(),
        "--out",
        d.join("b.tum").to_str().unwrap(),
    ]));
    assert!(
        err.contains("none.mcap") && err.contains("frame 'laser'") && err.contains("[laser]"),
        "{err}"
    );
}
