//! The `odocal` binary end to end: the commands chain (simulate → icp →
//! calibrate → eval → demo), print design.md's JSON keys, and answer bad input
//! with exit code 2 and a message naming the file.

use crate::support::{assert_recovered, odocal, ok_json as json, scratch};
use serde_json::Value;
use std::path::Path;

fn has_keys(v: &Value, keys: &[&str]) {
    for k in keys {
        let mut cur = v;
        for part in k.split('.') {
            cur = cur
                .get(part)
                .unwrap_or_else(|| panic!("missing key {k} in {v}"));
        }
    }
}

fn no_temp_files(dir: &Path) {
    for e in std::fs::read_dir(dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            !name.contains(".tmp-"),
            "temporary file left behind: {name}"
        );
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn cli_pipeline_chains_and_prints_the_contract_keys() {
    let d = scratch("cli_pipeline");
    let bag = d.join("run.mcap");
    let truth = d.join("truth.json");
    let sim = json(&odocal(&[
        "simulate",
        "--scenario",
        "square",
        "--duration",
        "30",
        "--seed",
        "5",
        "--effect",
        "radius_scale:right=0.01,left=-0.01",
        "--out",
        s(&bag),
        "--truth",
        s(&truth),
        "--json",
    ]));
    assert!(sim["scans"].as_u64().unwrap() >= 1400, "{sim}");
    let t: Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    assert_eq!(t["effect_specs"][0], "radius_scale:right=0.01,left=-0.01");

    let tum = d.join("icp.tum");
    let motions = d.join("motions.csv");
    let icp = json(&odocal(&[
        "icp",
        "--input",
        s(&bag),
        "--out",
        s(&tum),
        "--motions",
        s(&motions),
        "--json",
    ]));
    has_keys(
        &icp,
        &[
            "pairs",
            "failed_pairs",
            "mean_iterations",
            "wall_s",
            "pairs_per_s",
        ],
    );
    assert_eq!(
        icp["pairs"].as_u64().unwrap() + 1,
        sim["scans"].as_u64().unwrap()
    );
    let header = std::fs::read_to_string(&motions).unwrap();
    // The contract's columns first, the information split appended.
    assert!(header.starts_with(
        "t0,t1,dx,dy,dtheta,cov_xx,cov_xy,cov_xt,cov_yy,cov_yt,cov_tt,iterations,inliers,valid,\
         scan_share_x,scan_share_y,scan_share_theta,scan_dx,scan_dy,scan_dtheta\n"
    ));

    // The intermediate files carry no gyro: leave it out of both runs so that
    // they see the same measurements.
    let no_gyro = d.join("no-gyro.toml");
    std::fs::write(&no_gyro, "[measurements]\nuse_gyro = false\n").unwrap();
    let cal_dir = d.join("cal");
    let cal = json(&odocal(&[
        "calibrate",
        "--config",
        s(&no_gyro),
        "--input",
        s(&bag),
        "--method",
        "dkf",
        "--out",
        s(&cal_dir),
        "--json",
    ]));
    has_keys(
        &cal,
        &[
            "method",
            "final.r_right",
            "final.r_left",
            "final.wheel_base",
            "std.r_right",
            "std.r_left",
            "std.wheel_base",
            "iterations",
            "mean_iteration_ms",
            "multipliers.left_wheel_radius",
            "multipliers.right_wheel_radius",
            "multipliers.wheel_separation",
        ],
    );
    assert_eq!(cal["method"], "dkf");
    // The injected radii are found: each within 1 mm of the simulator's
    // true one, which lies 3.2 mm from the nominal the filter starts from.
    let rr = cal["final"]["r_right"].as_f64().unwrap();
    for k in ["r_right", "r_left"] {
        let (est, truth, nominal) = (
            cal["final"][k].as_f64().unwrap(),
            t["parameters"][0][k].as_f64().unwrap(),
            t["nominal"][k].as_f64().unwrap(),
        );
        assert_recovered(k, est, truth, nominal, 1e-3);
    }
    let csv = std::fs::read_to_string(cal_dir.join("calibration.csv")).unwrap();
    assert!(csv.starts_with(
        "t,r_right,r_left,wheel_base,std_r_right,std_r_left,std_wheel_base,particles,process_sigma,change\n"
    ));
    assert!(cal_dir.join("trajectory.tum").is_file() && cal_dir.join("summary.json").is_file());
    no_temp_files(&cal_dir);

    // Calibration from the intermediate files gives the same kind of answer.
    let wheels = d.join("wheels.csv");
    let rec = odocal::io::read_recording(&bag, &odocal::io::ReadOptions::default()).unwrap();
    odocal::io::csv::write_wheels(&wheels, &rec.wheels).unwrap();
    let cal2 = json(&odocal(&[
        "calibrate",
        "--motions",
        s(&motions),
        "--wheels",
        s(&wheels),
        "--method",
        "dkf",
        "--out",
        s(&d.join("cal2")),
        "--json",
    ]));
    let rr2 = cal2["final"]["r_right"].as_f64().unwrap();
    assert!((rr2 - rr).abs() < 1e-6, "{rr2} vs {rr}");

    // The proposed filter recorded for the Rerun viewer (or refused cleanly
    // when built without it).
    let rrd = d.join("calib.rrd");
    let pf_dir = d.join("pf");
    let args = [
        "calibrate",
        "--input",
        s(&bag),
        "--method",
        "adaptive-pf",
        "--particles",
        "400",
        "--out",
        s(&pf_dir),
        "--rrd",
        s(&rrd),
    ];
    let out = odocal(&args);
    if cfg!(feature = "rerun") {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        #[cfg(feature = "rerun")]
        check_run_rrd(
            "cli_calibrate_rrd",
            &rrd,
            sim["scans"].as_u64().unwrap() as usize,
            csv_rows(&pf_dir.join("calibration.csv")),
            change_entries(&json_file(&pf_dir.join("summary.json"))),
            false,
        );
    } else {
        assert_eq!(out.status.code(), Some(2));
        assert!(!rrd.exists());
    }

    let ev = json(&odocal(&[
        "eval",
        "--estimate",
        s(&tum),
        "--reference",
        s(&bag),
        "--align",
        "origin",
        "--plot",
        s(&d.join("eval.png")),
        "--json",
    ]));
    // One PNG: the x–y overlay above translation and rotation error panels,
    // with the estimate's red path drawn.
    let png = png::Decoder::new(std::io::Cursor::new(
        std::fs::read(d.join("eval.png")).unwrap(),
    ));
    let mut reader = png.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (1100, 800 + 80 + 2 * 340));
    let red = buf[..info.buffer_size()]
        .chunks_exact(3)
        .filter(|p| p[0] == 214 && p[1] == 39 && p[2] == 40)
        .count();
    assert!(red > 500, "{red} estimate pixels");
    has_keys(
        &ev,
        &[
            "matched",
            "ape.rmse",
            "ape.mean",
            "ape.median",
            "ape.std",
            "ape.min",
            "ape.max",
            "ape_rot_deg.rmse",
            "rpe.rmse",
            "rpe_rot_deg.rmse",
            "drift_percent",
            "final_error",
        ],
    );
    assert!(ev["ape"]["rmse"].as_f64().unwrap() < 1.0, "{ev}");
    let rep = d.join("diag");
    let dg = json(&odocal(&[
        "diagnose",
        "--measured",
        s(&bag),
        "--holdout",
        "0.3",
        "--report",
        s(&rep),
        "--json",
    ]));
    has_keys(
        &dg,
        &[
            "verdict",
            "causes",
            "gain.heldout_rmse_before",
            "gain.heldout_rmse_after",
            "gain.relative",
        ],
    );
    assert!([
        "explained",
        "partly-explained",
        "no-discrepancy",
        "unexplained"
    ]
    .contains(&dg["verdict"].as_str().unwrap()));
    for f in ["report.md", "residuals.png", "regressors.png"] {
        assert!(rep.join(f).is_file(), "{f} missing");
    }
    no_temp_files(&d);
    std::fs::remove_dir_all(&d).unwrap();
}

/// Simulates into `d/run.mcap` and `d/truth.json` with seed 2 and `args`.
fn simulated(d: &std::path::Path, args: &[&str]) -> (std::path::PathBuf, std::path::PathBuf) {
    let (bag, truth) = (d.join("run.mcap"), d.join("truth.json"));
    let mut all = vec![
        "simulate",
        "--seed",
        "2",
        "--out",
        s(&bag),
        "--truth",
        s(&truth),
    ];
    all.extend_from_slice(args);
    all.push("--json");
    json(&odocal(&all));
    (bag, truth)
}

#[test]
fn cli_demo_on_a_short_recording_writes_report_plots_and_recording() {
    let d = scratch("cli_demo");
    let (bag, truth) = simulated(&d, &["--scenario", "figure-eight", "--duration", "12"]);
    let out = d.join("demo");
    let sum = json(&odocal(&[
        "demo",
        "--input",
        s(&bag),
        "--truth",
        s(&truth),
        "--out",
        s(&out),
        "--json",
    ]));
    assert_eq!(sum["methods"].as_array().unwrap().len(), 5);
    for f in [
        "report.md",
        "radii.png",
        "particles.png",
        "trajectories.png",
        "errors.png",
        "summary.json",
    ] {
        let p = out.join(f);
        assert!(p.is_file(), "{f} missing");
        if f.ends_with(".png") {
            assert_eq!(&std::fs::read(&p).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
        }
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in [
        "## Calibration",
        "adaptive-pf",
        "dkf",
        "APE RMSE",
        "radii.png",
    ] {
        assert!(report.contains(needle), "report lacks {needle}");
    }
    #[cfg(feature = "rerun")]
    check_run_rrd(
        "cli_demo_rrd",
        &out.join("demo.rrd"),
        sum["scans"].as_u64().unwrap() as usize,
        csv_rows(&out.join("adaptive-pf/calibration.csv")),
        change_entries(&sum),
        true,
    );
    no_temp_files(&out);
    std::fs::remove_dir_all(&d).unwrap();
}

/// The demo's report and summary name what changed where the Adaptive-PF's
/// change detector fired: a right wheel 4 mm larger from 30 s on, hidden in
/// the truth file, comes out as a radius step on the right wheel.
#[test]
fn cli_demo_names_a_radius_step_in_its_report() {
    let d = scratch("cli_demo_step");
    let step = "radius_step:time=30,right=0.004,left=0";
    let (bag, _) = simulated(&d, &["--duration", "60", "--effect", step]);
    let out = d.join("demo");
    let sum = json(&odocal(&[
        "demo",
        "--input",
        s(&bag),
        "--out",
        s(&out),
        "--json",
    ]));
    let changes = sum["changes"].as_array().expect("changes named");
    let step = changes
        .iter()
        .find(|c| c["effect"] == "radius_step")
        .unwrap_or_else(|| panic!("no radius step named: {changes:?}"));
    assert_eq!(step["parameter"], "right", "{step}");
    let size = step["estimate"].as_f64().unwrap();
    assert!((size - 0.004).abs() < 0.2 * 0.004, "step {size} m");
    let onset = step["onset_s"].as_f64().unwrap();
    assert!((onset - 30.0).abs() < 1.0, "onset {onset} s");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("## What changed"), "{report}");
    assert!(report.contains("radius_step right ="), "{report}");
    // Negative control: the same drive without the step names none.
    std::fs::create_dir_all(d.join("clean")).unwrap();
    let (clean, _) = simulated(&d.join("clean"), &["--duration", "60"]);
    let out = d.join("demo-clean");
    let sum = json(&odocal(&[
        "demo",
        "--input",
        s(&clean),
        "--out",
        s(&out),
        "--json",
    ]));
    let none = sum["changes"].as_array().map_or(0, |c| {
        c.iter().filter(|c| c["effect"] == "radius_step").count()
    });
    assert_eq!(none, 0, "a step named without one: {}", sum["changes"]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn cli_bad_input_exits_2_naming_the_file() {
    let d = scratch("cli_bad");
    let garbage = d.join("garbage.mcap");
    std::fs::write(&garbage, b"\x89MCAP0\r\n this is not an mcap").unwrap();
    let bad_tum = d.join("bad.tum");
    std::fs::write(&bad_tum, "0 0 0 0 0 0 0 1\n1 0 0 nan 0 0 0 1\n").unwrap();
    let out_tum = d.join("o.tum");
    let x_mcap = d.join("x.mcap");
    let c_dir = d.join("c");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "icp",
                "--input",
                "/nonexistent/x.mcap",
                "--out",
                s(&out_tum),
            ],
            "/nonexistent/x.mcap",
        ),
        (
            vec!["icp", "--input", s(&garbage), "--out", s(&out_tum)],
            "garbage.mcap",
        ),
        (
            vec![
                "eval",
                "--estimate",
                s(&bad_tum),
                "--reference",
                s(&bad_tum),
            ],
            "line 2",
        ),
        (
            vec!["simulate", "--effect", "wobble", "--out", s(&x_mcap)],
            "wobble",
        ),
        (
            vec!["simulate", "--scenario", "moon-base", "--out", s(&x_mcap)],
            "moon-base",
        ),
        (
            vec!["calibrate", "--input", s(&garbage), "--out", s(&c_dir)],
            "garbage.mcap",
        ),
        (vec!["icp", "--input", s(&garbage)], "--out"),
        (vec!["frobnicate"], "frobnicate"),
        (vec!["diagnose", "--measured", s(&garbage)], "garbage.mcap"),
        (
            vec!["diagnose", "--measured", s(&garbage), "--holdout", "1.5"],
            "holdout",
        ),
    ];
    for (args, needle) in cases {
        let o = odocal(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(needle),
            "{args:?}: message lacks '{needle}': {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    assert!(!out_tum.exists(), "no output is written for bad input");
    assert!(!d.join("x.mcap").exists());
    std::fs::remove_dir_all(&d).unwrap();
}

#[cfg(feature = "rerun")]
fn csv_rows(path: &Path) -> usize {
    std::fs::read_to_string(path).unwrap().lines().count() - 1
}

/// The text entries a run's `changes` (summary JSON) puts in its recording:
/// one per firing named, one per later firing on the same change.
#[cfg(feature = "rerun")]
fn change_entries(summary: &serde_json::Value) -> usize {
    summary["changes"].as_array().map_or(0, |cs| {
        cs.iter()
            .map(|c| 1 + c["refired_s"].as_array().map_or(0, Vec::len))
            .sum()
    })
}

/// A JSON file's content.
#[cfg(feature = "rerun")]
fn json_file(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Opens a recording the CLI wrote with the official rerun-sdk
/// (tools/rrd_check.py) and checks entities, timelines and row counts against
/// the run's own outputs: one scan row per scan, one ICP row per pair, one
/// particle cloud and one estimate per filter step, one text entry per
/// change named.
#[cfg(feature = "rerun")]
fn check_run_rrd(test: &str, rrd: &Path, scans: usize, steps: usize, changes: usize, map: bool) {
    use odocal::viz::entity;
    use serde_json::json;
    let Some(py) = crate::support::python_with(test, &["rerun", "pyarrow"]) else {
        return;
    };
    assert!(rrd.is_file(), "{} missing", rrd.display());
    let mut entities = serde_json::Map::new();
    if map {
        entities.insert(entity::MAP.into(), json!({"static": true, "rows": 1}));
    }
    // Each trajectory: its full line (static) and the line grown along both
    // timelines (at most 300 rows, the default).
    for kind in odocal::viz::TrajectoryKind::ALL {
        entities.insert(
            kind.full_entity().into(),
            json!({"static": true, "rows": 1, "instances": {"LineStrips2D:strips": 1}}),
        );
        entities.insert(
            kind.entity().into(),
            json!({"timelines": [entity::SCAN, entity::TIME]}),
        );
    }
    // The robot at every scan, its laser and heading, the scan in the laser frame.
    for e in [entity::ROBOT, entity::SCAN_POINTS] {
        entities.insert(
            e.into(),
            json!({"rows": scans, "first": {"scan": 0}, "last": {"scan": scans - 1}}),
        );
    }
    for e in [entity::LASER, entity::ROBOT_HEADING] {
        entities.insert(e.into(), json!({"static": true, "rows": 1}));
    }
    // One ellipse per scan match (these runs have no failed pair).
    for e in [
        entity::ICP_ITERATIONS,
        entity::ICP_COV_TRACE,
        entity::ICP_COVARIANCE,
    ] {
        entities.insert(e.into(), json!({"rows": scans - 1, "first": {"scan": 1}}));
    }
    // The trail of every match's ellipse: a block of 2^L ellipses on level L
    // for each binary digit the count of matches has had, level L first
    // used at the 2^L-th match (scan 2^L); at the last scan it shows all
    // `scans - 1` of them.
    let matches = scans - 1;
    let mut level = 0;
    while 1 << level <= matches {
        entities.insert(
            entity::trail_level(level),
            json!({"first": {"scan": 1 << level}}),
        );
        level += 1;
    }
    let cursors = [
        json!({"prefix": entity::ICP_COVARIANCE_TRAIL, "timeline": entity::SCAN,
        "at": scans - 1, "component": "LineStrips2D:strips", "want": matches}),
    ];
    for e in [
        entity::PARTICLES,
        entity::PARTICLES_SHOWN,
        entity::EST_R_RIGHT,
        entity::EST_R_LEFT,
        entity::EST_WHEEL_BASE,
        entity::STD_R_RIGHT,
        entity::STD_R_LEFT,
        entity::STD_WHEEL_BASE,
        entity::PARTICLES_COUNT,
        entity::PROCESS_SIGMA,
    ] {
        entities.insert(e.into(), json!({ "rows": steps }));
    }
    // One text entry per firing named (and per firing on a change named
    // before it).
    if changes > 0 {
        entities.insert(entity::CHANGES.into(), json!({ "rows": changes }));
    }
    let expect = json!({
        "version": "0.36.3",
        "timelines": [entity::SCAN, entity::TIME],
        "exact": true,
        "entities": entities,
        "cursors": cursors,
    });
    let exp = rrd.with_extension("expect.json");
    std::fs::write(&exp, serde_json::to_vec_pretty(&expect).unwrap()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/rrd_check.py");
    let out = std::process::Command::new(py)
        .arg(script)
        .arg(rrd)
        .arg(&exp)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rrd_check failed on {}:\n{}\n{}",
        rrd.display(),
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    );
}

/// The bundled demo recording is what scans/README.md says: its command
/// reproduces the same bytes, recording and truth.
#[test]
fn cli_bundled_recording_regenerates_byte_for_byte() {
    let d = scratch("cli_bundled");
    let scans = Path::new(env!("CARGO_MANIFEST_DIR")).join("scans");
    let readme = std::fs::read_to_string(scans.join("README.md")).unwrap();
    let line = readme
        .lines()
        .find(|l| l.starts_with("| `wheelchair-corridor.mcap`"))
        .unwrap();
    let cmd = line
        .split('`')
        .find(|c| c.starts_with("odocal simulate"))
        .unwrap();
    let mut args: Vec<String> = cmd.split_whitespace().skip(1).map(String::from).collect();
    for a in args.iter_mut() {
        if let Some(name) = a.strip_prefix("scans/") {
            *a = match name {
                "wheelchair-corridor.toml" => scans.join(name),
                other => d.join(other),
            }
            .display()
            .to_string();
        }
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = odocal(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in ["wheelchair-corridor.mcap", "wheelchair-corridor.truth.json"] {
        assert!(
            std::fs::read(d.join(f)).unwrap() == std::fs::read(scans.join(f)).unwrap(),
            "{f} differs from what its command writes"
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Runs odocal, requires exit code 2, and gives what it said on stderr.
fn refused(args: &[&str]) -> String {
    let o = odocal(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    err
}

#[test]
fn calibrating_without_wheel_data_names_the_file() {
    let d = scratch("no_wheels_named");
    // A CARMEN log of three scans and no odometry: nothing to calibrate from.
    let log = d.join("scans-only.clf");
    let ranges = vec!["5.0"; 180].join(" ");
    let text: String = (0..3)
        .map(|k| {
            let t = 1.0 + 0.1 * k as f64;
            format!("FLASER 180 {ranges} 0 0 0 0 0 0 {t} host {t}\n")
        })
        .collect();
    std::fs::write(&log, text).unwrap();
    let out = d.join("cal");
    let err = refused(&["calibrate", "--input", s(&log), "--out", s(&out)]);
    assert!(err.contains("scans-only.clf"), "{err}");
    assert!(err.contains("no wheel encoder data"), "{err}");
    assert!(
        err.contains("CARMEN log has no wheel topic") && err.contains("diagnose"),
        "says what the log lacks and what reads it: {err}"
    );
    // The CSV path: a wheels file of one sample.
    let wheels = d.join("one-sample.csv");
    std::fs::write(&wheels, "t,left,right\n0.0,0.0,0.0\n").unwrap();
    let motions = d.join("motions.csv");
    std::fs::write(&motions, format!("{}\n", odocal::io::csv::MOTIONS_HEADER)).unwrap();
    let from_csv = [
        "calibrate",
        "--motions",
        s(&motions),
        "--wheels",
        s(&wheels),
        "--out",
        s(&out),
    ];
    let err = refused(&from_csv);
    assert!(err.contains("one-sample.csv"), "{err}");
    assert!(!out.join("summary.json").exists());
    // Two wheel samples but a header-only motions file: no observation at all.
    std::fs::write(&wheels, "t,left,right\n0.0,0.0,0.0\n1.0,1.0,1.0\n").unwrap();
    let err = refused(&from_csv);
    assert!(
        err.contains("motions.csv") && err.contains("no velocity observation"),
        "{err}"
    );
    assert!(!out.join("summary.json").exists());
}
