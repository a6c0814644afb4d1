//! `odocal calibrate --method batch` through the whole chain: a simulated
//! wheelchair whose radii, laser mounting and encoder latency differ from
//! the nominal ones the bag states (the simulator keeps them in its truth
//! file), and Censi et al.'s tuples on the command line.

use crate::support::{odocal, ok_json as json, scratch, shared_data};
use serde_json::Value;
use std::path::Path;

/// Asserts |estimate − truth| < 3 std and returns the error in stds.
fn within_3_std(name: &str, v: &Value, truth: f64, angle: bool) -> f64 {
    let (x, s) = (v["value"].as_f64().unwrap(), v["std"].as_f64().unwrap());
    let mut d = x - truth;
    if angle {
        d = odocal::geom::wrap_angle(d);
    }
    assert!(
        s > 0.0 && d.abs() < 3.0 * s,
        "{name}: {x} vs truth {truth} (std {s})"
    );
    d / s
}

#[test]
fn batch_recovers_radii_mounting_and_latency_of_a_simulated_chair() {
    let dir = scratch("batch_sim");
    let (bag, truth) = (dir.join("b.mcap"), dir.join("truth.json"));
    let sim = odocal(&[
        "simulate",
        "--scenario",
        "figure-eight",
        "--seed",
        "3",
        "--duration",
        "60",
        "--effect",
        "laser_offset:x=0.03,y=-0.02,yaw=0.02",
        // Under one encoder period (100 Hz): a larger lag is refused.
        "--effect",
        "latency:delay=0.008",
        "--effect",
        "radius_scale:right=0.01,left=-0.005",
        "--out",
        bag.to_str().unwrap(),
        "--truth",
        truth.to_str().unwrap(),
    ]);
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    let t: Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let p = &t["parameters"][0];
    let m = &t["laser_mount"];
    let out = dir.join("cal");
    let j = json(&odocal(&[
        "calibrate",
        "--input",
        bag.to_str().unwrap(),
        "--method",
        "batch",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]));
    let f = |v: &Value| v.as_f64().unwrap();
    let z = [
        within_3_std("r_right", &j["r_right"], f(&p["r_right"]), false),
        within_3_std("r_left", &j["r_left"], f(&p["r_left"]), false),
        within_3_std("wheel_base", &j["wheel_base"], f(&p["wheel_base"]), false),
        within_3_std("laser x", &j["laser"]["x"], f(&m["x"]), false),
        within_3_std("laser y", &j["laser"]["y"], f(&m["y"]), false),
        within_3_std("laser yaw", &j["laser"]["yaw"], f(&m["yaw"]), true),
        within_3_std(
            "time_offset",
            &j["time_offset"],
            f(&t["effects"][1]["delay"]),
            false,
        ),
    ];
    eprintln!("errors in stds: {z:?}");
    // The stds are tight enough to mean something: the mounting offset
    // (3 cm, 2 cm, 0.02 rad) and the latency are resolved.
    assert!(j["laser"]["x"]["std"].as_f64().unwrap() < 0.01);
    assert!(j["laser"]["yaw"]["std"].as_f64().unwrap() < 0.005);
    assert!(j["time_offset"]["std"].as_f64().unwrap() < 0.004);
    assert_eq!(j["assumptions"]["laser"]["source"], "estimated");
    assert_eq!(j["assumptions"]["prior"]["value"], "wheels");
    let names = j["correlation"]["names"].as_array().unwrap();
    assert_eq!(names.len(), 7);
    assert_eq!(j["correlation"]["matrix"].as_array().unwrap().len(), 7);
    for k in ["r_right", "laser_yaw", "time_offset"] {
        assert_eq!(
            j["observability"]["parameters"][k]["observable"], true,
            "{k}"
        );
    }
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(written, j);
}

#[test]
fn batch_calibrates_censi_tuples_from_the_command_line() {
    let Some(d) = shared_data("batch_tuples_cli") else {
        return;
    };
    let tuples = d.join("censi-calibration/lmov.tuple");
    let robot = Path::new(env!("CARGO_MANIFEST_DIR")).join("scans/robots/khepera.toml");
    let dir = scratch("batch_tuples_cli");
    let (input, robot) = (tuples.to_str().unwrap(), robot.to_str().unwrap());
    let out = dir.join("cal");
    let j = json(&odocal(&[
        "calibrate",
        "--input",
        input,
        "--robot",
        robot,
        "--method",
        "batch",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]));
    // The authors' lmov_results.json: axle 0.0883953, laser y −0.0387078.
    assert!((j["wheel_base"]["value"].as_f64().unwrap() - 0.0883953).abs() < 0.0005);
    assert!((j["laser"]["y"]["value"].as_f64().unwrap() + 0.0387078).abs() < 0.003);
    assert!(j["time_offset"].is_null());
    assert_eq!(j["assumptions"]["laser"]["source"], "estimated");
    // The online filters need a mounting the tuples do not carry.
    let filt = odocal(&[
        "calibrate",
        "--input",
        input,
        "--robot",
        robot,
        "--out",
        dir.join("pf").to_str().unwrap(),
    ]);
    assert_eq!(filt.status.code(), Some(2));
    let msg = String::from_utf8_lossy(&filt.stderr);
    assert!(
        msg.contains("[laser]") && msg.contains("--method batch"),
        "{msg}"
    );
}
