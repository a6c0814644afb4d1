//! A real rover as a fleet: the Mines rover's two sessions, before and after
//! a known radius change written into their wheel streams by an independent
//! tool (`tools/scale_wheels.py`: the `mcap` and `rosbags` packages divide
//! every JointState position and velocity by 1.05, so the same motion reads
//! as radii 5 % larger). The fleet raises an alarm on both radii, and its
//! calibrations see the change's size; the same fleet without the change
//! raises none.
//!
//! The two sessions as recorded are not the change: their radii differ by
//! about 2 % (the tick check's 5 % lies in stalled scan matches, see
//! `calib_real.rs`), and a robot needs two calibrations on each side of a
//! step before the fleet judges it. With two per side the rover's own
//! session-to-session scatter (about twice the reported std, which the fleet
//! measures on itself) keeps a 5 % step from its 5σ threshold when the
//! sessions alternate; in recording order the change reads as growth.

use crate::support::{odocal, ok_json, python_tool, python_with, scratch, shared_data};
use serde_json::Value;
use std::path::Path;

/// The radius change written into the "after" recordings.
const GROWTH: f64 = 1.05;

/// Links or writes the four recordings of one robot: exp1 and exp2 on days
/// 1–2, then (scaled by `after` when given) on days 3–4.
fn lay_out(data: &Path, fleet: &Path, py: Option<&str>) {
    for (day, session) in [(1, "exp1"), (2, "exp2"), (3, "exp1"), (4, "exp2")] {
        let src = data.join(format!("mines-rover/{session}.mcap"));
        let dst = fleet.join(format!("mines/2024-06-0{day}/{session}.mcap"));
        std::fs::create_dir_all(dst.parent().unwrap()).unwrap();
        match (day > 2, py) {
            (true, Some(py)) => {
                let scale = GROWTH.to_string();
                let args = [
                    src.to_str().unwrap(),
                    dst.to_str().unwrap(),
                    "--scale",
                    &scale,
                ];
                python_tool(py, "scale_wheels.py", &args);
            }
            _ => std::fs::copy(&src, &dst).map(|_| ()).unwrap(),
        }
    }
}

fn run_fleet(fleet: &Path, out: &Path) -> Value {
    ok_json(&odocal(&[
        "fleet",
        fleet.to_str().unwrap(),
        "--robot",
        "mines-rover",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]))
}

/// The mean of a radius over the table's rows of days `days`.
fn mean_radius(summary: &Value, key: &str, days: std::ops::Range<f64>) -> f64 {
    let v: Vec<f64> = summary["table"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| days.contains(&r["day"].as_f64().unwrap()))
        .map(|r| r[key][0].as_f64().expect("calibrated"))
        .collect();
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn a_real_rovers_radius_change_is_raised_and_its_absence_is_not() {
    let Some(data) = shared_data("fleet_real") else {
        return;
    };
    let Some(py) = python_with("fleet_real", &["mcap", "rosbags", "numpy"]) else {
        return;
    };
    let d = scratch("fleet_real");
    lay_out(&data, &d.join("changed"), Some(&py));
    let changed = run_fleet(&d.join("changed"), &d.join("out-changed"));
    // The four points are 75.1, 76.3, 78.4, 80.6 mm (right): the sessions'
    // own 1.6 % difference lines up with the change, so the fleet may read a
    // step or a steady growth (wear); either alarm must name both radii and
    // say that they grew.
    let alarms = changed["alarms"].as_array().unwrap();
    let alarm = alarms
        .iter()
        .find(|a| a["kind"] == "step" || a["kind"] == "wear")
        .unwrap_or_else(|| panic!("no step or wear alarm: {alarms:#?}"));
    let values = alarm["values"].as_object().unwrap();
    for wheel in ["r_right", "r_left"] {
        let grew = values
            .iter()
            .filter(|(k, _)| k.starts_with(wheel) && !k.contains("std"))
            .map(|(_, v)| v.as_f64().unwrap())
            .collect::<Vec<_>>();
        assert!(
            !grew.is_empty() && grew.iter().all(|&v| v > 0.0),
            "{wheel} not named as grown: {alarm:#}"
        );
        // The calibrations themselves see the change written into the
        // wheels, 5 % of the radius, within 1.5 % (30 % of the change).
        let before = mean_radius(&changed, wheel, 0.0..2.0);
        let after = mean_radius(&changed, wheel, 2.0..4.0);
        assert!(
            (after / before - GROWTH).abs() < 0.015,
            "{wheel}: {after} / {before} against the {GROWTH} written"
        );
    }
    // Negative control: the same four recordings without the change.
    lay_out(&data, &d.join("same"), None);
    let same = run_fleet(&d.join("same"), &d.join("out-same"));
    assert_eq!(
        same["alarms"].as_array().map(Vec::len),
        Some(0),
        "alarms on unchanged recordings: {:#}",
        same["alarms"]
    );
}
