//! Evaluation against references that are not full SE(2) trajectories: the
//! LEGO robot's overhead tracker (positions only, ≈ 5 Hz on its own clock),
//! checked against a closed-form computation from the tracker's original text
//! file; a reference whose quaternions are placeholders; reports without a
//! reference; and the demo from an installed copy of the binary.

use crate::support::{self, odocal};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use odocal::eval::{self, Alignment, EvalOptions, SyncOptions, Trajectory3};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "odocal failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// `(t, x, y)` (s, m) of the tracker's `P t_ms x_mm y_mm` lines.
fn tracker_points(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.first() == Some(&"P")).then(|| {
                let v = |i: usize| f[i].parse::<f64>().unwrap();
                [v(1) / 1e3, v(2) / 1e3, v(3) / 1e3]
            })
        })
        .collect()
}

/// `(t, x, y)` of a TUM file.
fn tum_points(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<f64> = l.split_whitespace().map(|v| v.parse().unwrap()).collect();
            [f[0], f[1], f[2]]
        })
        .collect()
}

/// The tracker linearly interpolated at each estimate stamp inside its span
/// with the surrounding samples at most `max_gap` s apart, then the rigid
/// planar fit in closed form (Horn 1987 in 2D: θ = atan2(Σ cross, Σ dot) of
/// the centred points) and the RMSE of the residual distances: `(pairs, rmse)`.
fn closed_form_ape(tracker: &[[f64; 3]], estimate: &[[f64; 3]], max_gap: f64) -> (usize, f64) {
    let mut pairs = Vec::new();
    for e in estimate {
        let Some(i) = tracker
            .windows(2)
            .position(|w| w[0][0] <= e[0] && e[0] <= w[1][0])
        else {
            continue;
        };
        let (a, b) = (tracker[i], tracker[i + 1]);
        if b[0] - a[0] > max_gap {
            continue;
        }
        let s = if b[0] > a[0] {
            (e[0] - a[0]) / (b[0] - a[0])
        } else {
            0.0
        };
        let r = [a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])];
        pairs.push(([e[1], e[2]], r));
    }
    let n = pairs.len() as f64;
    let mean = |side: usize, axis: usize| {
        pairs
            .iter()
            .map(|p| if side == 0 { p.0[axis] } else { p.1[axis] })
            .sum::<f64>()
            / n
    };
    let (ex, ey) = (mean(0, 0), mean(0, 1));
    let (rx, ry) = (mean(1, 0), mean(1, 1));
    let (mut dot, mut cross) = (0.0, 0.0);
    for (e, r) in &pairs {
        let (a, b) = ([e[0] - ex, e[1] - ey], [r[0] - rx, r[1] - ry]);
        dot += a[0] * b[0] + a[1] * b[1];
        cross += a[0] * b[1] - a[1] * b[0];
    }
    let (s, c) = cross.atan2(dot).sin_cos();
    let sq: f64 = pairs
        .iter()
        .map(|(e, r)| {
            let (a, b) = ([e[0] - ex, e[1] - ey], [r[0] - rx, r[1] - ry]);
            (b[0] - (c * a[0] - s * a[1])).powi(2) + (b[1] - (s * a[0] + c * a[1])).powi(2)
        })
        .sum();
    (pairs.len(), (sq / n).sqrt())
}

fn lego_config(dir: &Path) -> PathBuf {
    let cfg = dir.join("lego.toml");
    std::fs::write(&cfg, "[topics]\nreference = \"/reference\"\n").unwrap();
    cfg
}

#[test]
fn lego_raw_odometry_against_the_tracker() {
    let Some(data) = support::shared_data("lego_raw_odometry_against_the_tracker") else {
        return;
    };
    let dir = support::scratch("lego_raw_odometry_against_the_tracker");
    let bag = data.join("lego-robot/lego-robot.mcap");
    let (bag_s, cfg) = (bag.to_str().unwrap(), lego_config(&dir));
    let raw = dir.join("raw");
    ok(&odocal(&[
        "calibrate",
        "--input",
        bag_s,
        "--robot",
        "lego-robot",
        "--method",
        "none",
        "--out",
        raw.to_str().unwrap(),
    ]));
    let est = raw.join("trajectory.tum");
    // Without the topic configured, the refusal names the one to set.
    let out = odocal(&[
        "eval",
        "--estimate",
        est.to_str().unwrap(),
        "--reference",
        bag_s,
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("PointStamped on /reference") && err.contains("reference = \"/reference\""),
        "{err}"
    );
    let args = [
        "eval",
        "--estimate",
        est.to_str().unwrap(),
        "--reference",
        bag_s,
        "--config",
        cfg.to_str().unwrap(),
    ];
    let v: Value = serde_json::from_str(&ok(&odocal(&[&args[..], &["--json"]].concat()))).unwrap();
    for k in ["ape_rot_deg", "rpe_rot_deg", "rmse_theta"] {
        assert!(v[k].is_null(), "{k} must be null, not a number: {}", v[k]);
    }
    assert!(v["rotation_omitted"]
        .as_str()
        .unwrap()
        .contains("positions only"));
    assert_eq!(v["alignment"]["kind"], "se2");
    assert!(v["alignment"]["reason"]
        .as_str()
        .unwrap()
        .contains("positions only"));
    assert_eq!(v["pairing"]["method"], "resampled");
    let (paired, of) = (v["paired"].as_u64().unwrap(), v["of"].as_u64().unwrap());
    assert_eq!(v["matched"], v["paired"]);
    assert!(paired * 10 >= of * 9, "most poses pair: {paired} of {of}");
    // The same figure from the tracker's original text file, computed apart.
    let tracker = tracker_points(&data.join("lego-robot/raw/robot4_reference.txt"));
    assert_eq!(tracker.len(), 278);
    let (n, rmse) = closed_form_ape(&tracker, &tum_points(&est), 0.5);
    assert_eq!(paired as usize, n);
    let ours = v["ape"]["rmse"].as_f64().unwrap();
    assert!(
        (ours - rmse).abs() < 1e-6 * rmse,
        "APE {ours} vs closed form {rmse}"
    );
    assert_eq!(v["rmse_xy"], v["ape"]["rmse"]);
    // Nominal 150 mm track: the data's README finds 0.74 m after fitting only the start.
    assert!(ours > 0.3 && ours < 1.0, "APE {ours} m");
    // The tracker's text file as TUM with placeholder quaternions: detected
    // as positions only from the data, the same figures.
    let tum = dir.join("tracker.tum");
    let lines: Vec<String> = tracker
        .iter()
        .map(|p| format!("{} {} {} 0 0 0 0 1", p[0], p[1], p[2]))
        .collect();
    std::fs::write(&tum, lines.join("\n")).unwrap();
    let out = odocal(&[
        "eval",
        "--estimate",
        est.to_str().unwrap(),
        "--reference",
        tum.to_str().unwrap(),
        "--json",
    ]);
    let t: Value = serde_json::from_str(&ok(&out)).unwrap();
    assert!(t["ape_rot_deg"].is_null() && t["rmse_theta"].is_null());
    assert_eq!(
        (&t["alignment"]["kind"], &t["paired"]),
        (&v["alignment"]["kind"], &v["paired"])
    );
    let tum_rmse = t["ape"]["rmse"].as_f64().unwrap();
    assert!(
        (tum_rmse - rmse).abs() < 1e-6 * rmse,
        "TUM {tum_rmse} vs {rmse}"
    );
    // Human output: no rotation line, the pairing and the alignment named.
    let text = ok(&odocal(&args));
    assert!(
        !text.contains("rot (deg)") && !text.contains("RMSE θ"),
        "{text}"
    );
    assert!(
        text.contains(&format!("paired poses     {paired} of {of}")),
        "{text}"
    );
    assert!(text.contains("alignment        se2"), "{text}");
    // Nearest stamps within evo's 0.01 s pair few of these poses, and say so.
    let near = ok(&odocal(
        &[&args[..], &["--resample-reference", "false"]].concat(),
    ));
    assert!(near.contains("paired poses     26 of 217"), "{near}");
    assert!(
        near.contains("fewer than half of the poses paired"),
        "{near}"
    );
}

#[test]
fn lego_demo_report_has_no_rotation_and_no_dead_link() {
    let Some(data) = support::shared_data("lego_demo_report_has_no_rotation_and_no_dead_link")
    else {
        return;
    };
    let dir = support::scratch("lego_demo_report");
    let (bag, cfg, out) = (
        data.join("lego-robot/lego-robot.mcap"),
        lego_config(&dir),
        dir.join("out"),
    );
    ok(&odocal(&[
        "demo",
        "--input",
        bag.to_str().unwrap(),
        "--robot",
        "lego-robot",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    check_report(&report, &out);
    assert!(
        report.contains("| trajectory | APE RMSE (m) | drift (%)"),
        "{report}"
    );
    assert!(
        !report.contains("RMSE θ") && report.contains("origin-heading"),
        "{report}"
    );
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // The demo states what it assumed, as `calibrate` does.
    let a = &s["assumptions"];
    assert_eq!(a["r_right"]["source"], "robot_file", "{a}");
    assert_eq!(a["prior"]["value"], "wheels", "{a}");
    assert!(report.contains("## Assumptions") && report.contains("the robot file"));
    let raw = &s["raw_odometry_eval"];
    assert!(raw["rmse_theta"].is_null() && raw["ape_rot_deg"].is_null());
    assert_eq!(raw["alignment"]["kind"], "origin-heading");
    assert!(raw["paired"].as_u64().unwrap() * 10 >= raw["of"].as_u64().unwrap() * 9);
}

/// Every image the report links exists beside it, and every table has rows.
fn check_report(report: &str, dir: &Path) {
    for part in report.split("](").skip(1) {
        let target = &part[..part.find(')').unwrap()];
        assert!(
            dir.join(target).is_file(),
            "dead link {target} in\n{report}"
        );
    }
    let lines: Vec<&str> = report.lines().collect();
    for (i, l) in lines.iter().enumerate() {
        if l.starts_with("| ---") {
            let next = lines.get(i + 1).copied().unwrap_or("");
            assert!(
                next.starts_with('|'),
                "empty table above line {}:\n{report}",
                i + 2
            );
        }
    }
}

#[test]
fn demo_report_without_reference_has_no_empty_table_or_dead_link() {
    use odocal::pipeline::demo::{bundled, run_on, DemoInput};
    use odocal::pipeline::{read_options, Config, Nominal};
    let dir = support::scratch("demo_without_reference");
    let cfg = Config::default();
    let nominal = Nominal::load(None).unwrap();
    let robot = &nominal.robot;
    let mut rec = odocal::io::read_mcap_bytes(
        bundled::RECORDING,
        bundled::RECORDING_NAME,
        &read_options(&cfg, robot),
    )
    .unwrap();
    // The first 20 s, without the reference.
    let t_end = rec.scans[0].stamp + 20.0;
    rec.scans.retain(|s| s.stamp < t_end);
    rec.wheels.retain(|s| s.stamp < t_end);
    rec.gyro.retain(|s| s.stamp < t_end);
    rec.reference.clear();
    let input = DemoInput {
        recording: &rec,
        name: "no-reference",
        truth: None,
        nominal: &nominal,
        config: &cfg,
    };
    let s = run_on(&input, &dir, &mut odocal::viz::NullLogger, &mut |_, _| {}).unwrap();
    assert!(s.raw_odometry_eval.is_none() && s.methods.iter().all(|m| m.eval.is_none()));
    assert!(
        s.eval_notes[0].contains("no reference"),
        "{:?}",
        s.eval_notes
    );
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    check_report(&report, &dir);
    assert!(
        !report.contains("APE") && !report.contains("errors.png"),
        "{report}"
    );
    assert!(report.contains("no reference"), "{report}");
}

#[test]
fn diagnose_report_without_reference_links_only_written_plots() {
    let test = "diagnose_report_without_reference_links_only_written_plots";
    let Some(data) = support::shared_data(test) else {
        return;
    };
    let dir = support::scratch(test);
    let bag = data.join("mines-rover/exp1.mcap");
    let report_dir = dir.join("report");
    ok(&odocal(&[
        "diagnose",
        "--measured",
        bag.to_str().unwrap(),
        "--robot",
        "mines-rover",
        "--report",
        report_dir.to_str().unwrap(),
    ]));
    let report = std::fs::read_to_string(report_dir.join("report.md")).unwrap();
    check_report(&report, &report_dir);
    assert!(!report.contains("vs reference"), "{report}");
}

/// A tracker's positions written as TUM with identity quaternions.
fn placeholder_reference(truth: &[(f64, f64, f64, f64)]) -> Trajectory3 {
    let poses = truth
        .iter()
        .map(|&(_, x, y, _)| {
            Isometry3::from_parts(Translation3::new(x, y, 0.0), UnitQuaternion::identity())
        })
        .collect();
    Trajectory3::from_parts(truth.iter().map(|p| p.0).collect(), poses).unwrap()
}

#[test]
fn origin_alignment_takes_the_heading_of_a_position_only_reference() {
    // A curve in the tracker's frame (t, x, y, θ); the estimate is the same
    // path in its odometry frame: started at the origin facing +x.
    let truth: Vec<(f64, f64, f64, f64)> = (0..200)
        .map(|i| {
            let t = i as f64 * 0.1;
            let th = 2.1 + 0.15 * t;
            let r = 0.3 / 0.15;
            (
                t,
                1.5 + r * (th.sin() - 2.1f64.sin()),
                1.2 - r * (th.cos() - 2.1f64.cos()),
                th,
            )
        })
        .collect();
    let (x0, y0, th0) = (truth[0].1, truth[0].2, truth[0].3);
    let est_poses: Vec<_> = truth
        .iter()
        .map(|&(_, x, y, th)| {
            let (dx, dy) = (x - x0, y - y0);
            let (s, c) = th0.sin_cos();
            Isometry3::from_parts(
                Translation3::new(c * dx + s * dy, -s * dx + c * dy, 0.0),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), th - th0),
            )
        })
        .collect();
    // The estimate is sampled 0.05 s after the tracker, as its own clock would.
    let shifted: Vec<f64> = truth.iter().map(|p| p.0 + 0.05).collect();
    let est_at = |k: usize, s: f64| est_poses[k].lerp_slerp(&est_poses[k + 1], s);
    let est_mid: Vec<_> = (0..199).map(|k| est_at(k, 0.5)).collect();
    let estimate = Trajectory3::from_parts(shifted[..199].to_vec(), est_mid).unwrap();
    let reference = placeholder_reference(&truth);
    assert!(reference.orientation_undefined());
    let opts = EvalOptions {
        align: Alignment::Origin,
        position_only: true,
        sync: SyncOptions::default(),
        ..Default::default()
    };
    // Without the heading from the first metre, the flat orientation would
    // turn the whole path: an error of metres.
    let r = eval::evaluate(&estimate, Some(&reference), None, &opts).unwrap();
    let m = r.trajectory.unwrap();
    assert_eq!(m.alignment.kind, "origin-heading");
    assert_eq!((m.paired, m.of), (199, 199));
    // Both sides are chord midpoints of the same arc: equal after a rigid move.
    assert!(m.ape.max < 1e-9, "APE max {} m", m.ape.max);
    assert!(m.ape_rot_deg.is_none() && m.rmse_theta.is_none());
    // The same quaternions with a real heading are not flagged.
    let straight = Trajectory3::from_parts(
        vec![0.0, 1.0, 2.0],
        (0..3)
            .map(|i| Isometry3::translation(i as f64, 0.0, 0.0))
            .collect(),
    )
    .unwrap();
    assert!(!straight.orientation_undefined());
}

#[test]
fn installed_binary_runs_the_demo_without_the_repository() {
    let repo = env!("CARGO_MANIFEST_DIR");
    let dir = support::scratch("installed_binary");
    let bin = dir.join("bin/odocal");
    std::fs::create_dir_all(bin.parent().unwrap()).unwrap();
    std::fs::copy(env!("CARGO_BIN_EXE_odocal"), &bin).unwrap();
    let bytes = std::fs::read(&bin).unwrap();
    let needle = format!("{repo}/scans");
    assert!(
        !bytes.windows(needle.len()).any(|w| w == needle.as_bytes()),
        "the binary names {needle}"
    );
    let (home, out) = (dir.join("home"), dir.join("out"));
    std::fs::create_dir_all(&home).unwrap();
    let run = Command::new(&bin)
        .args(["demo", "--json", "--out"])
        .arg(&out)
        .current_dir(&home)
        .env("HOME", &home)
        .env_remove("CARGO_MANIFEST_DIR")
        .output()
        .unwrap();
    let v: Value = serde_json::from_str(&ok(&run)).unwrap();
    assert_eq!(v["input"], "wheelchair-corridor.mcap (bundled)");
    assert!(v["scans"].as_u64().unwrap() > 1000);
    assert!(
        v["methods"][0]["final_errors"].is_array(),
        "the bundled truth was read"
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    check_report(&report, &out);
    for f in ["report.md", "summary.json"] {
        let text = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(!text.contains(repo), "{f} names {repo}");
    }
    // A bundled robot by name, from the installed copy.
    let run = Command::new(&bin)
        .args(["simulate", "--robot", "khepera", "--duration", "1", "--out"])
        .arg(dir.join("k.mcap"))
        .current_dir(&home)
        .output()
        .unwrap();
    ok(&run);
    let bad = Command::new(&bin)
        .args(["simulate", "--robot", "no-such-robot", "--out"])
        .arg(dir.join("x.mcap"))
        .current_dir(&home)
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("lego-robot"));
}
