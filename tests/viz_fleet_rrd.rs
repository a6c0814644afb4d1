//! `odocal fleet --rrd`: the fleet's Rerun recording read back with the
//! official rerun-sdk (tools/rrd_check.py): one entity per robot and
//! parameter with a row per calibrated recording (the value and its ±2σ
//! band) on the `date` timeline at the recordings' dates, the alarms marked
//! and logged, a plot per robot in the blueprint; and `--rrd` naming one of
//! the fleet's own outputs refused before any work.
#![cfg(feature = "rerun")]

use crate::fleet_cli::tiny_fleet;
use crate::support::{odocal, scratch};
use crate::viz_rrd::run_check;
use serde_json::{json, Value};

/// 2026-03-01 and 2026-03-02, 00:00 UTC, in seconds since 1970 (`date -d`).
const MARCH_1: f64 = 1_772_323_200.0;
const MARCH_2: f64 = 1_772_409_600.0;

#[test]
fn fleet_recording_has_a_history_per_robot_and_its_alarms() {
    let d = scratch("fleet_rrd");
    let data = d.join("data");
    tiny_fleet(&data);
    // A third day for chair-a that cannot be read: an `insufficient` alarm
    // on a day without a calibration.
    let bad = data.join("chair-a/2026-03-03/run.mcap");
    std::fs::create_dir_all(bad.parent().unwrap()).unwrap();
    std::fs::write(&bad, b"\x89MCAP0\r\nnot really").unwrap();
    let rrd = d.join("fleet.rrd");
    let out = odocal(&[
        "fleet",
        data.to_str().unwrap(),
        "--out",
        d.join("out").to_str().unwrap(),
        "--rrd",
        rrd.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: Value = serde_json::from_slice(&out.stdout).unwrap();
    let alarms = s["alarms"].as_array().unwrap();
    assert_eq!(alarms.len(), 1, "{alarms:?}");
    assert_eq!(
        (alarms[0]["robot"].as_str(), alarms[0]["kind"].as_str()),
        (Some("chair-a"), Some("insufficient"))
    );
    assert!(rrd.is_file());

    let mut entities = serde_json::Map::new();
    for robot in ["chair-a", "chair-b"] {
        for p in ["r_right", "r_left", "wheel_base"] {
            // Two calibrated days: value, −2σ, +2σ each.
            entities.insert(
                format!("fleet/{robot}/{p}"),
                json!({"rows": 2, "instances": {"Scalars:scalars": 6},
                       "first": {"date": MARCH_1}, "last": {"date": MARCH_2}}),
            );
        }
    }
    let day3 = MARCH_2 + 86_400.0;
    entities.insert(
        "fleet/chair-a/alarm_marks".into(),
        json!({"rows": 1, "instances": {"Scalars:scalars": 1},
               "first": {"date": day3}}),
    );
    entities.insert(
        "fleet/chair-a/alarms".into(),
        json!({"rows": 1, "instances": {"TextLog:text": 1, "TextLog:level": 1},
               "first": {"date": day3}}),
    );
    let expect = json!({
        "version": "0.36.3",
        "timelines": ["date"],
        "exact": true,
        "entities": entities,
        "blueprint": ["/fleet/chair-a", "/fleet/chair-b", "/fleet"],
    });
    run_check(
        "fleet_recording_has_a_history_per_robot_and_its_alarms",
        &rrd,
        &expect,
    );

    // `--rrd` onto the fleet's own table: refused before any work.
    let out = odocal(&[
        "fleet",
        data.to_str().unwrap(),
        "--out",
        d.join("out2").to_str().unwrap(),
        "--rrd",
        d.join("out2/fleet.csv").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("fleet.csv"), "{err}");
    assert!(!d.join("out2/cache").exists(), "work was done: {err}");
}
