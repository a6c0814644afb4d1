//! `odocal fleet` from the command line on a tiny fleet written by
//! `odocal simulate`: the folder layout and the manifest give the same
//! table, a re-run takes every result from the cache, a changed file is
//! calibrated again, bad manifests and a missing Ray engine are refused
//! with exit 2 naming what to fix.

use crate::support::{odocal, ok_json, scratch};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// Two robots × two days of 20 s corridor runs, laid out ROBOT/DATE/run.mcap.
pub fn tiny_fleet(dir: &Path) {
    for (robot, seed0) in [("chair-a", 10), ("chair-b", 20)] {
        for day in 0..2 {
            let path = dir.join(format!("{robot}/2026-03-0{}/run.mcap", day + 1));
            simulate_at(&path, seed0 + day, None);
        }
    }
}

fn fleet(source: &Path, out: &Path) -> Value {
    ok_json(&odocal(&[
        "fleet",
        source.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]))
}

#[test]
fn a_folder_and_a_manifest_give_one_table_and_reruns_use_the_cache() {
    let d = scratch("fleet_cli");
    let data = d.join("data");
    tiny_fleet(&data);
    let first = fleet(&data, &d.join("out"));
    assert_eq!(
        (first["recordings"].as_u64(), first["processed"].as_u64()),
        (Some(4), Some(4))
    );
    assert_eq!(first["epoch"], "2026-03-01");
    let table = std::fs::read_to_string(d.join("out/fleet.csv")).unwrap();
    assert_eq!(table.lines().count(), 5, "{table}");
    assert!(
        table.lines().nth(1).unwrap().starts_with("chair-a,"),
        "{table}"
    );
    for f in ["fleet.json", "report.md", "fleet.png"] {
        assert!(d.join("out").join(f).is_file(), "{f}");
    }
    // The same recordings through a manifest (paths relative to it).
    let manifest = data.join("manifest.csv");
    let mut text = String::from("robot,path,start\n");
    for (robot, day) in [
        ("chair-a", 1),
        ("chair-a", 2),
        ("chair-b", 1),
        ("chair-b", 2),
    ] {
        text.push_str(&format!(
            "{robot},{robot}/2026-03-0{day}/run.mcap,2026-03-0{day}\n"
        ));
    }
    std::fs::write(&manifest, text).unwrap();
    let by_manifest = fleet(&manifest, &d.join("out"));
    assert_eq!(
        by_manifest["processed"].as_u64(),
        Some(0),
        "every result cached"
    );
    assert_eq!(by_manifest["robots"], first["robots"]);
    // A recording whose bytes change is calibrated again, the others not.
    let changed = data.join("chair-b/2026-03-02/run.mcap");
    let out = odocal(&[
        "simulate",
        "--duration",
        "20",
        "--seed",
        "99",
        "--out",
        changed.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let again = fleet(&data, &d.join("out"));
    assert_eq!(
        (again["processed"].as_u64(), again["cached"].as_u64()),
        (Some(1), Some(3))
    );
}

/// Simulates a 20 s corridor run into `path` whose clock starts at `start`
/// (`None`: at 0 s, a clock that is not a date).
pub fn simulate_at(path: &Path, seed: u32, start: Option<&str>) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let seed = seed.to_string();
    let mut args = vec![
        "simulate",
        "--duration",
        "20",
        "--seed",
        &seed,
        "--out",
        path.to_str().unwrap(),
    ];
    if let Some(s) = start {
        args.extend(["--start", s]);
    }
    let out = odocal(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A folder as users name their recordings (no dates, any sub-folder, any
/// order of names): each recording is placed by its own first stamp, a date
/// in the path serves only a recording whose clock is not a date, and
/// `fleet.json` says which was taken.
#[test]
fn undated_recordings_are_ordered_by_their_own_clock() {
    let d = scratch("fleet_undated");
    let data = d.join("data");
    // Names sort z-first against time: "a-late" is recorded last.
    simulate_at(
        &data.join("chair/a-late.mcap"),
        1,
        Some("2026-05-03T09:00:00"),
    );
    simulate_at(
        &data.join("chair/old/z-early.mcap"),
        2,
        Some("2026-05-01T08:30:00"),
    );
    simulate_at(&data.join("chair/2026-05-02/sim.mcap"), 3, None);
    let summary = fleet(&data, &d.join("out"));
    let order: Vec<(String, String, String)> = summary["starts"]
        .as_array()
        .expect("starts in fleet.json")
        .iter()
        .map(|s| {
            let name = s["recording"].as_str().unwrap();
            let name = Path::new(name).file_name().unwrap().to_string_lossy();
            (
                name.to_string(),
                s["start"].as_str().unwrap().to_string(),
                s["from"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    let want = [
        ("z-early.mcap", "2026-05-01T08:30:00Z", "recording"),
        ("sim.mcap", "2026-05-02T00:00:00Z", "path"),
        ("a-late.mcap", "2026-05-03T09:00:00Z", "recording"),
    ];
    let got: Vec<(&str, &str, &str)> = order
        .iter()
        .map(|(a, b, c)| (a.as_str(), b.as_str(), c.as_str()))
        .collect();
    assert_eq!(got, want);
    assert_eq!(summary["epoch"], "2026-05-01");
    let days: Vec<f64> = summary["table"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["day"].as_f64().unwrap())
        .collect();
    assert!(
        (days[0] - 8.5 / 24.0).abs() < 1e-6 && (days[2] - (2.0 + 9.0 / 24.0)).abs() < 1e-6,
        "{days:?}"
    );
    // Negative control: the same recording with a clock at 0 and no date in
    // its path cannot be placed, and the fleet says what to do.
    simulate_at(&data.join("chair/b-undated.mcap"), 4, None);
    let e = refused(&odocal(&[
        "fleet",
        data.to_str().unwrap(),
        "--out",
        d.join("out").to_str().unwrap(),
    ]));
    assert!(
        e.contains("b-undated.mcap") && e.contains("its clock is not a date"),
        "{e}"
    );
}

/// The same bytes under two days (a copied file) are calibrated once and
/// both rows carry that result; before, the two calibrations raced for one
/// output folder and one came out `insufficient`.
#[test]
fn a_copied_recording_is_calibrated_once_for_both_days() {
    let d = scratch("fleet_copy");
    let data = d.join("data");
    let first = data.join("chair/2026-05-01/run.mcap");
    simulate_at(&first, 5, None);
    let copy = data.join("chair/2026-05-02/run.mcap");
    std::fs::create_dir_all(copy.parent().unwrap()).unwrap();
    std::fs::copy(&first, &copy).unwrap();
    let summary = fleet(&data, &d.join("out"));
    assert_eq!(
        (summary["processed"].as_u64(), summary["cached"].as_u64()),
        (Some(1), Some(1)),
        "{summary:#}"
    );
    let rows = summary["table"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert!(
        rows.iter().all(|r| r["status"] == "calibrated"),
        "{rows:#?}"
    );
    assert_eq!(rows[0]["r_right"], rows[1]["r_right"]);
    assert_eq!(summary["alarms"].as_array().map(Vec::len), Some(0));
}

fn refused(out: &Output) -> String {
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stderr).to_string()
}

#[test]
fn bad_fleets_are_refused_naming_what_to_fix() {
    let d = scratch("fleet_bad");
    let m = d.join("manifest.csv");
    let out_dir = d.join("out");
    let run = |text: &str| {
        std::fs::write(&m, text).unwrap();
        refused(&odocal(&[
            "fleet",
            m.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ]))
    };
    let e = run("robot,file,start\n");
    assert!(e.contains("manifest.csv, line 1: no column 'path'"), "{e}");
    let e = run("robot,path,start\nchair,gone.mcap,2026-01-01\n");
    assert!(
        e.contains("line 2") && e.contains("gone.mcap does not exist"),
        "{e}"
    );
    std::fs::write(d.join("x.mcap"), b"").unwrap();
    let e = run("robot,path,start\nchair,x.mcap,yesterday\n");
    assert!(e.contains("line 2: start 'yesterday' is not a date"), "{e}");
    // A folder whose recordings carry no date.
    let undated = d.join("fleet/chair/run.mcap");
    std::fs::create_dir_all(undated.parent().unwrap()).unwrap();
    std::fs::write(&undated, b"").unwrap();
    let e = refused(&odocal(&[
        "fleet",
        d.join("fleet").to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]));
    assert!(
        e.contains("run.mcap") && e.contains("holds no date YYYY-MM-DD"),
        "{e}"
    );
    // The Ray engine without a Python that has the package.
    let out = Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args([
            "fleet",
            d.join("fleet").to_str().unwrap(),
            "--engine",
            "ray",
        ])
        .args(["--out", out_dir.to_str().unwrap()])
        .env("ODOCAL_PYTHON", d.join("no-python").to_str().unwrap())
        .output()
        .unwrap();
    let e = refused(&out);
    assert!(
        e.contains("--engine ray needs the Python package odocal"),
        "{e}"
    );
    assert!(e.contains("pip install './python[ray]'"), "{e}");
}

/// `--rrd` in a build without Rerun: refused before any work.
#[cfg(not(feature = "rerun"))]
#[test]
fn fleet_rrd_without_rerun_is_refused() {
    let d = scratch("fleet_rrd_no_rerun");
    tiny_fleet(&d.join("fleet"));
    let out_dir = d.join("out");
    let e = refused(&odocal(&[
        "fleet",
        d.join("fleet").to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--rrd",
        d.join("fleet.rrd").to_str().unwrap(),
    ]));
    assert!(e.contains("without the `rerun` feature"), "{e}");
    assert!(!out_dir.join("cache").exists(), "work was done: {e}");
    assert!(!d.join("fleet.rrd").exists());
}
