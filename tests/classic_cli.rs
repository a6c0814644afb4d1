//! `odocal experiment` for the literature comparison and the seed tables:
//! files written, JSON keys, exit codes, determinism.

use crate::support::{scratch, shared_data};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn odocal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(args)
        .output()
        .expect("run odocal")
}

fn ok_json(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "odocal failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A short setting: 3 m squares, 2 each way, one 12 m evaluation path, a
/// small GA and few particles, so a debug build runs it in seconds.
const SHORT: &str = r#"
[literature]
evaluation_length_m = 12.0
particles = 400
[literature.compare]
square_side = 3.0
runs_per_direction = 2
evaluation_runs = 1
[literature.compare.ga]
population = 20
generations = 15
[literature.compare.pf]
particles = 100
[umbmark]
runs_per_direction = 2
side = 2.0
[heading_pf]
lengths = [10.0]
calibration_runs = 4
[heading_pf.ga]
population = 20
generations = 15
[heading_pf.pf]
particles = 100
"#;

fn files(dir: &Path, name: &str) {
    for ext in ["md", "json", "png"] {
        let p = dir.join(format!("{name}.{ext}"));
        let len = std::fs::metadata(&p)
            .unwrap_or_else(|_| panic!("{} missing", p.display()))
            .len();
        assert!(len > 100, "{} is only {len} bytes", p.display());
    }
    let png = std::fs::read(dir.join(format!("{name}.png"))).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn experiment_literature_writes_every_method_side_by_side() {
    let d = scratch("experiment_literature");
    let settings = d.join("short.toml");
    std::fs::write(&settings, SHORT).unwrap();
    let out = d.join("out");
    let args = [
        "experiment",
        "literature",
        "--runs",
        "2",
        "--seed",
        "5",
        "--settings",
        s(&settings),
        "--out",
        s(&out),
        "--json",
    ];
    let v = ok_json(&odocal(&args));
    files(&out, "literature");
    assert_eq!(v["runs"], 2);
    let methods: Vec<&str> = v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert_eq!(
        methods,
        [
            "none",
            "tacho-heading",
            "umbmark",
            "ga",
            "heading-pf",
            "adaptive-pf",
            "dkf"
        ]
    );
    for r in v["rows"].as_array().unwrap() {
        for k in [
            "err_r_right",
            "err_r_left",
            "err_wheel_base",
            "rmse_xy",
            "rmse_theta",
            "path_error_percent",
            "compute_ms",
        ] {
            let x = r[k]["median"]
                .as_f64()
                .unwrap_or_else(|| panic!("{k} in {r}"));
            assert!(x.is_finite() && x >= 0.0, "{k} = {x}");
        }
    }
    // Each repetition has its own hidden truth, the same for every method.
    let runs = v["per_run"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    assert_ne!(runs[0]["truth"], runs[1]["truth"]);
    for run in runs {
        let t = &run["truth"];
        for row in run["rows"].as_array().unwrap() {
            // error = |final − truth| for the parameters each method reports.
            for k in ["r_right", "r_left", "wheel_base"] {
                let e = row["param_errors"][k].as_f64().unwrap();
                let f = row["final"][k].as_f64().unwrap();
                assert!((e - (f - t[k].as_f64().unwrap()).abs()).abs() < 1e-12);
            }
        }
    }
    let md = std::fs::read_to_string(out.join("literature.md")).unwrap();
    assert!(md.contains("| adaptive-pf |") && md.contains("## Findings"));
    assert!(md.contains("assumptions"));

    // Same seed, same numbers (compute times aside).
    let out2 = d.join("out2");
    let mut args2 = args;
    args2[9] = s(&out2);
    let w = ok_json(&odocal(&args2));
    for (a, b) in v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .zip(w["rows"].as_array().unwrap())
    {
        assert_eq!(a["rmse_xy"], b["rmse_xy"]);
        assert_eq!(a["err_r_right"], b["err_r_right"]);
    }
}

#[test]
fn experiment_umbmark_and_bad_arguments() {
    let d = scratch("experiment_umbmark");
    let settings = d.join("short.toml");
    std::fs::write(&settings, SHORT).unwrap();
    let out = d.join("out");
    let v = ok_json(&odocal(&[
        "experiment",
        "umbmark",
        "--runs",
        "2",
        "--settings",
        s(&settings),
        "--out",
        s(&out),
        "--json",
    ]));
    files(&out, "umbmark");
    assert_eq!(v["cycles"].as_array().unwrap().len(), 2);
    for c in v["cycles"].as_array().unwrap() {
        let (b, a) = (
            c["result"]["before"]["e_max_syst"].as_f64().unwrap(),
            c["result"]["after"]["e_max_syst"].as_f64().unwrap(),
        );
        assert!(a < b, "correction must shrink E_max,syst: {b} -> {a}");
    }
    // Unknown settings key, unknown experiment, missing tables: exit code 2.
    std::fs::write(&settings, "[literature]\nbogus = 1\n").unwrap();
    let o = odocal(&[
        "experiment",
        "literature",
        "--settings",
        s(&settings),
        "--out",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("short.toml"));
    let o = odocal(&["experiment", "nosuch", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let o = odocal(&["experiment", "square", "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--tables"));
}

#[test]
fn experiment_seed_tables_square_and_tachometer() {
    let Some(data) = shared_data("experiment_seed_tables_square_and_tachometer") else {
        return;
    };
    let tables = data.join("seed-tables");
    let d = scratch("experiment_seed_tables");
    let out = d.join("out");
    let v = ok_json(&odocal(&[
        "experiment",
        "square",
        "--runs",
        "3",
        "--tables",
        s(&tables),
        "--out",
        s(&out),
        "--json",
    ]));
    files(&out, "square");
    // Seed 001's closure error as its text states it: 0.47 m in x, 0.38 m
    // in y, from the table's last corner (odometry against actual).
    assert!((v["measured"]["closure_dx"].as_f64().unwrap() + 0.47).abs() < 1e-12);
    assert!((v["measured"]["closure_dy"].as_f64().unwrap() - 0.38).abs() < 1e-12);
    let (before, after) = (
        v["fit"]["rms_before"].as_f64().unwrap(),
        v["fit"]["rms_after"].as_f64().unwrap(),
    );
    assert!(after < 0.5 * before, "{before} -> {after}");
    assert_eq!(v["fit"]["effects"].as_array().unwrap().len(), 2);

    let v = ok_json(&odocal(&[
        "experiment",
        "tachometer",
        "--tables",
        s(&tables),
        "--out",
        s(&out),
        "--json",
    ]));
    files(&out, "tachometer");
    // Seed 001 publishes the gain rounded to one decimal: "a proportional
    // gain of 3.2" (from its five 90° trials).
    let gain = v["heading_gain"]["gain"].as_f64().unwrap();
    assert!((gain - 3.2).abs() <= 0.05, "heading gain {gain}");
    let slope = v["tachometer"]["right"]["slope"].as_f64().unwrap();
    assert!(slope > 0.9 && slope < 1.0);
    assert_eq!(v["speed_pairs"].as_array().unwrap().len(), 6);
}
