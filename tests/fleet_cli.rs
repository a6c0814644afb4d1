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
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            let seed = (seed0 + day).to_string();
            let out = odocal(&[
                "simulate",
                "--duration",
                "20",
                "--seed",
                &seed,
                "--out",
                path.to_str().unwrap(),
            ]);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
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
        e.contains("run.mcap: no date YYYY-MM-DD in its path"),
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
