//! The joint batch calibration and the online filters started from it on
//! the real robots of the shared data, each figure against a source odocal
//! did not compute: the LEGO robot's landmark map and overhead tracker
//! (`tools/lego_scanner_check.py` measures the tracker's scale against the
//! map, 1.107 ± 0.002, and the lag of the scans behind the wheels from the
//! landmarks' headings, 0.49 s), and the Mines rover's scan-matching tick
//! check of the data README (2050 / 2160 ticks per revolution on exp1 /
//! exp2: exp1's effective radius 5.4 % larger).

use crate::support::{odocal, scratch, shared_data};
use serde_json::Value;
use std::path::Path;
use std::process::Output;

fn ok(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// `calibrate --json` of `rec` with the bundled robot `robot` and `extra`.
fn calibrate(rec: &Path, robot: &str, out: &Path, extra: &[&str]) -> Value {
    let mut args = vec![
        "calibrate",
        "--input",
        rec.to_str().unwrap(),
        "--robot",
        robot,
        "--out",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    ok(&odocal(&args))
}

fn vs(v: &Value) -> (f64, f64) {
    (v["value"].as_f64().unwrap(), v["std"].as_f64().unwrap())
}

#[test]
fn lego_batch_finds_the_late_scans_and_its_scale_is_the_trackers() {
    let Some(data) = shared_data("lego_batch") else {
        return;
    };
    let rec = data.join("lego-robot/lego-robot.mcap");
    let dir = scratch("lego_batch");
    let b = calibrate(&rec, "lego-robot", &dir.join("b"), &["--method", "batch"]);
    // The landmarks' headings follow the wheels 0.49 s later; a wheel
    // period is 0.25 s, so the batch states it in a note.
    let (dt, dt_std) = vs(&b["time_offset"]);
    assert!(
        (-0.56..-0.40).contains(&dt) && dt_std < 0.03,
        "{dt} ± {dt_std}"
    );
    let notes = b["notes"].as_array().unwrap();
    assert!(notes
        .iter()
        .any(|n| n.as_str().unwrap().contains("wheel periods")));
    assert!(b["std_widening"].as_f64().unwrap() > 1.0);

    // Its odometry against the tracker, which is in step with the wheels:
    // the trajectory, on the laser clock, moved back by the time offset. At
    // least as close as the data README's dead reckoning fitted to the
    // tracker itself (0.349 mm/tick, width fitted: 56 mm), and the
    // similarity that fits it has the tracker's scale against the map.
    let none = calibrate(
        &rec,
        "lego-robot",
        &dir.join("none"),
        &["--init", "batch", "--method", "none"],
    );
    assert_eq!(none["assumptions"]["time_offset"]["source"], "estimated");
    let cfg = dir.join("ref.toml");
    std::fs::write(&cfg, "[topics]\nreference = \"/reference\"\n").unwrap();
    let e = ok(&odocal(&[
        "eval",
        "--estimate",
        dir.join("none/trajectory.tum").to_str().unwrap(),
        "--reference",
        rec.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--align",
        "sim2",
        "--t-offset",
        &dt.to_string(),
        "--json",
    ]));
    let scale = e["alignment"]["scale"].as_f64().unwrap();
    assert!((1.107 - scale).abs() < 0.035, "scale {scale}");
    let ape = e["ape"]["rmse"].as_f64().unwrap();
    assert!(ape <= 0.056, "APE {ape}");
}

/// The data README's tick check finds exp1's effective radius 5.4 % larger
/// than exp2's (2050 and 2160 ticks per revolution from scan matching).
/// That difference lies in a handful of intervals where the scan matcher,
/// matching scan to scan at speed, reports a fraction of the wheels' travel
/// with a confident covariance: least squares over every interval puts
/// exp1/exp2 at 1.04–1.07, as the tick check does, and the batch's robust
/// rule, dropping the intervals the rest contradicts (6 of 67 on exp2),
/// puts it at 0.98, as the default matcher does with or without that rule.
/// Both sessions carry the same latency.
#[test]
fn mines_sessions_radii_differ_only_through_stalled_matches() {
    let Some(data) = shared_data("mines_batch") else {
        return;
    };
    let dir = scratch("mines_batch");
    let cfg = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let s2s = cfg("s2s.toml", "[icp]\nlocal_map = false\n");
    let s2s_ls = cfg(
        "s2s_ls.toml",
        "[icp]\nlocal_map = false\n[calib.batch]\noutlier_probability = 0.0\n",
    );
    let ratio = |cfg: Option<&Path>, tag: &str| {
        let mut r = Vec::new();
        for e in ["exp1", "exp2"] {
            let rec = data.join(format!("mines-rover/{e}.mcap"));
            let mut extra = vec!["--method", "batch"];
            if let Some(c) = cfg {
                extra.extend(["--config", c.to_str().unwrap()]);
            }
            let b = calibrate(&rec, "mines-rover", &dir.join(format!("{e}-{tag}")), &extra);
            let (dt, _) = vs(&b["time_offset"]);
            assert!((-0.25..-0.12).contains(&dt), "{e} {tag}: time offset {dt}");
            r.push((0.5 * (vs(&b["r_right"]).0 + vs(&b["r_left"]).0), dt));
        }
        let lag = (r[0].1 - r[1].1).abs();
        assert!(
            lag < 0.025,
            "{tag}: the sessions' latencies differ by {lag} s"
        );
        r[0].0 / r[1].0
    };
    // With every interval the tick check's 5 % shows; equal radii (the one
    // robot file of both sessions, 1.0) lie over three half-widths below
    // the window and fail it.
    let as_the_tick_check = |r: f64| (1.04..1.07).contains(&r);
    assert!(!as_the_tick_check(1.0));
    let least_squares = ratio(Some(&s2s_ls), "s2s-ls");
    assert!(
        as_the_tick_check(least_squares),
        "scan to scan, least squares {least_squares}"
    );
    // Without the stalled matches the 5 % is gone: the ratio within 0.0225
    // of 0.98, equal radii (1.0) included. What the sessions show with them
    // kept, the tick check's 1.054 and the least-squares fit above, lies
    // over three such half-widths away and must fail the same check.
    let stalls_gone = |r: f64| (r - 0.98).abs() < 0.0225;
    assert!(1.054 - 0.98 >= 3.0 * 0.0225 && !stalls_gone(1.054));
    assert!(!stalls_gone(least_squares), "least squares {least_squares}");
    let robust = ratio(Some(&s2s), "s2s");
    assert!(stalls_gone(robust), "scan to scan, robust {robust}");
    let default = ratio(None, "default");
    assert!(stalls_gone(default), "default matcher {default}");
}

#[test]
fn a_time_offset_beyond_the_accepted_limit_is_refused_naming_the_key() {
    let Some(data) = shared_data("batch_time_limit") else {
        return;
    };
    let dir = scratch("batch_time_limit");
    let cfg = dir.join("c.toml");
    std::fs::write(&cfg, "[calib.batch]\nmax_time_offset_s = 0.3\n").unwrap();
    let rec = data.join("lego-robot/lego-robot.mcap");
    let out = odocal(&[
        "calibrate",
        "--input",
        rec.to_str().unwrap(),
        "--robot",
        "lego-robot",
        "--method",
        "batch",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("max_time_offset_s") && err.contains("lego-robot.mcap"),
        "{err}"
    );
    assert!(!dir.join("o/summary.json").exists());
}

#[test]
fn init_batch_refuses_csv_inputs() {
    let dir = scratch("init_batch_csv");
    let (m, w) = (dir.join("m.csv"), dir.join("w.csv"));
    std::fs::write(&m, "t0,t1,dx,dy,dtheta\n").unwrap();
    std::fs::write(&w, "t,left,right\n").unwrap();
    let out = odocal(&[
        "calibrate",
        "--motions",
        m.to_str().unwrap(),
        "--wheels",
        w.to_str().unwrap(),
        "--init",
        "batch",
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--init batch needs --input"));
    assert!(!dir.join("o/summary.json").exists());
}

/// Local (< 10 s) and all relation errors (m) of `odocal icp` on `log`.
fn relation_errors(log: &Path, relations: &Path, dir: &Path) -> (u64, f64, f64) {
    let tum = dir.join(format!(
        "{}.tum",
        log.file_name().unwrap().to_str().unwrap()
    ));
    let icp = ok(&odocal(&[
        "icp",
        "--input",
        log.to_str().unwrap(),
        "--out",
        tum.to_str().unwrap(),
        "--json",
    ]));
    let e = ok(&odocal(&[
        "eval",
        "--estimate",
        tum.to_str().unwrap(),
        "--reference",
        tum.to_str().unwrap(),
        "--relations",
        relations.to_str().unwrap(),
        "--json",
    ]));
    let r = &e["relations"];
    (
        icp["failed_pairs"].as_u64().unwrap(),
        r["local"]["trans_mean"].as_f64().unwrap(),
        r["trans_mean"].as_f64().unwrap(),
    )
}

/// The one benchmark log the shared data has as CARMEN text and as MCAP
/// gives the same local relation errors both ways (they differ only in how
/// the two-decimal ranges reach float32, which ICP's iterations amplify a
/// little). The long relations are not compared: they sum hundreds of
/// pairs, and one fast-turn or corridor pair that the rounding tips into a
/// neighbouring minimum moves them by 20 % or more (0.21 against 0.25 m).
#[test]
fn mit_csail_from_carmen_and_from_mcap_give_the_same_relation_errors() {
    let Some(data) = shared_data("carmen_vs_mcap") else {
        return;
    };
    let dir = scratch("carmen_vs_mcap");
    let b = data.join("slam-benchmark");
    let rel = b.join("mit-csail.relations");
    let clf = relation_errors(&b.join("mit-csail.clf"), &rel, &dir);
    let mcap = relation_errors(&b.join("mit-csail.mcap"), &rel, &dir);
    // 1,987 pairs: a handful of borderline pairs may fall either side of
    // the quality checks with the other rounding (the CARMEN log read
    // without its laser pose once failed 679).
    assert!(
        clf.0.abs_diff(mcap.0) <= 10 && clf.0.max(mcap.0) <= 20,
        "failed pairs {} (CARMEN) vs {} (MCAP)",
        clf.0,
        mcap.0
    );
    assert!(
        (clf.1 / mcap.1 - 1.0).abs() < 0.03,
        "local {clf:?} vs {mcap:?}"
    );
    eprintln!("all relations: CARMEN {:.3} m, MCAP {:.3} m", clf.2, mcap.2);
}
