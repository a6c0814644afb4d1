//! What changed at a firing of the change detector, through the whole chain:
//! `odocal simulate` with a known change → `odocal calibrate` (ICP on the
//! simulated scans, the Adaptive-PF and its detector) → the named change in
//! `--json`, `summary.json` and the history's `change` column, against the
//! simulator's truth.

use crate::support::{odocal, scratch};
use std::path::Path;

/// Simulates 60 s with `effect`, calibrates, returns the `--json` output and
/// the history CSV.
fn run(dir: &Path, effect: &str) -> (serde_json::Value, String) {
    let bag = dir.join("run.mcap");
    let truth = dir.join("truth.json");
    let out = dir.join("cal");
    let s = odocal(&[
        "simulate",
        "--seed",
        "2",
        "--duration",
        "60",
        "--effect",
        effect,
        "--out",
        bag.to_str().unwrap(),
        "--truth",
        truth.to_str().unwrap(),
    ]);
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let c = odocal(&[
        "calibrate",
        "--input",
        bag.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    let json: serde_json::Value = serde_json::from_slice(&c.stdout).unwrap();
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["changes"], summary["changes"]);
    let csv = std::fs::read_to_string(out.join("calibration.csv")).unwrap();
    (json, csv)
}

/// The `change` column's non-empty entries, with their row's time.
fn named_rows(csv: &str) -> Vec<(f64, String)> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.last(), Some(&"change"));
    assert_eq!(
        header[..9].join(","),
        "t,r_right,r_left,wheel_base,std_r_right,std_r_left,std_wheel_base,particles,process_sigma"
    );
    lines
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), header.len(), "{l}");
            (!f[9].is_empty()).then(|| (f[0].parse().unwrap(), f[9].to_string()))
        })
        .collect()
}

#[test]
fn a_radius_step_on_the_right_wheel_is_named_with_its_size() {
    let d = scratch("change-naming-step");
    let truth = 0.005;
    let (json, csv) = run(&d, &format!("radius_step:time=30,right={truth},left=0"));
    let changes = json["changes"].as_array().expect("the detector fired");
    let first = &changes[0];
    assert_eq!(first["effect"], "radius_step", "{first}");
    assert_eq!(first["parameter"], "right", "{first}");
    let est = first["estimate"].as_f64().unwrap();
    assert!(
        (est - truth).abs() < 0.2 * truth,
        "step {est} m vs {truth} m"
    );
    let se = first["stderr"].as_f64().unwrap();
    assert!(se > 0.0 && se < 0.2 * truth, "stderr {se}");
    assert!(first["delta_bic"].as_f64().unwrap() > 10.0);
    // The left wheel did not change: its size is small against the right's.
    let left = first["parameters"]["left"].as_f64().unwrap();
    assert!(left.abs() < 0.2 * truth, "left {left}");
    // The detector fires after the step, within the window.
    let t = first["time_s"].as_f64().unwrap();
    assert!((30.0..40.0).contains(&t), "fired at {t} s");
    let onset = first["onset_s"].as_f64().unwrap();
    assert!((onset - 30.0).abs() < 1.0, "onset {onset} s");
    let rows = named_rows(&csv);
    assert_eq!(rows.len(), changes.len());
    assert!((rows[0].0 - t).abs() < 1e-6 && rows[0].1 == "radius_step");
}

#[test]
fn a_latency_change_is_not_named_a_radius_step() {
    let d = scratch("change-naming-latency");
    let (json, csv) = run(&d, "latency_change:time=30,delay=0.08");
    let changes = json["changes"].as_array().expect("the detector fired");
    for c in changes {
        assert_ne!(c["effect"], "radius_step", "{c}");
    }
    let first = &changes[0];
    assert_eq!(first["effect"], "latency", "{first}");
    let est = first["estimate"].as_f64().unwrap();
    assert!((est - 0.08).abs() < 0.2 * 0.08, "latency {est} s vs 0.08 s");
    assert_eq!(named_rows(&csv).len(), changes.len());
}
