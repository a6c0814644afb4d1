//! Through the command line, inputs that parse but make no sense end with
//! exit code 2 and a message naming the file (and topic, line, key or cap),
//! never exit 0 with a wrong number: a stage that produced nothing usable,
//! robot and effect values outside their physical ranges, motions that break
//! the covariance or speed rules, a truth file of another recording,
//! special files as inputs, caps and negative numbers, a damaged MCAP magic,
//! absurd TUM values. Every bad input is written by the test itself.

use crate::io_time::{bag, Msg};
use crate::support::{odocal, scratch};
use odocal::io::ros_msgs::{Header, JointStateMsg, LaserScanMsg, RosMsg, Time};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);
const BUNDLED_TRUTH: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.truth.json"
);

/// Asserts exit code 2 and that stderr holds every needle; returns stderr.
fn refused(o: &Output, needles: &[&str]) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A room-like 181-beam scan at `t`; `blind` puts every range beyond range_max.
fn scan(t: f64, blind: bool) -> Vec<u8> {
    let inc = std::f32::consts::PI / 180.0;
    LaserScanMsg {
        header: Header {
            stamp: Time::from_seconds(t),
            frame_id: "laser".into(),
        },
        angle_min: -90.0 * inc,
        angle_max: 90.0 * inc,
        angle_increment: inc,
        range_min: 0.1,
        range_max: 30.0,
        ranges: (0..181)
            .map(|i| {
                if blind {
                    100.0
                } else {
                    2.0 + 0.5 * (i as f32 * 0.15).sin() + 0.01 * i as f32
                }
            })
            .collect(),
        ..Default::default()
    }
    .encode()
}

fn wheels(t: f64) -> Vec<u8> {
    JointStateMsg {
        header: Header {
            stamp: Time::from_seconds(t),
            frame_id: String::new(),
        },
        name: vec!["left_wheel".into(), "right_wheel".into()],
        position: vec![0.0, 0.0],
        velocity: vec![],
        effort: vec![],
    }
    .encode()
}

/// A bag of 20 scans at 10 Hz (those whose index `blind` says are blind)
/// and standing wheels at 50 Hz.
fn scan_bag(dir: &Path, name: &str, blind: impl Fn(usize) -> bool) -> PathBuf {
    let scans = (0..20)
        .map(|i| Msg {
            log_ns: 1_000_000_000 + 100_000_000 * i as u64,
            data: scan(1.0 + 0.1 * i as f64, blind(i)),
        })
        .collect();
    let joints = (0..100)
        .map(|i| Msg {
            log_ns: 1_000_000_000 + 20_000_000 * i as u64,
            data: wheels(1.0 + 0.02 * i as f64),
        })
        .collect();
    let bytes = bag(&[
        ("/scan", "sensor_msgs/msg/LaserScan", scans),
        ("/joint_states", "sensor_msgs/msg/JointState", joints),
    ]);
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn every_scan_pair_failing_is_an_error_and_a_few_are_not() {
    let d = scratch("cli_all_pairs_failed");
    // The bags state no mounting: the robot file puts the laser at the origin.
    let robot = d.join("robot.toml");
    std::fs::write(
        &robot,
        "r_right = 0.3\nr_left = 0.3\nwheel_base = 0.6\n[laser]\nx = 0.0\ny = 0.0\nyaw = 0.0\n",
    )
    .unwrap();
    let blind = scan_bag(&d, "blind.mcap", |_| true);
    let o = odocal(&[
        "icp",
        "--input",
        s(&blind),
        "--robot",
        s(&robot),
        "--out",
        s(&d.join("t.tum")),
    ]);
    refused(
        &o,
        &["blind.mcap", "/scan", "every scan pair failed: 19 of 19"],
    );
    assert!(!d.join("t.tum").exists(), "nothing written");
    let o = odocal(&[
        "calibrate",
        "--input",
        s(&blind),
        "--robot",
        s(&robot),
        "--out",
        s(&d.join("cal")),
    ]);
    refused(&o, &["blind.mcap", "every scan pair failed"]);
    assert!(!d.join("cal").join("summary.json").exists());
    // Two blind scans among twenty: their pairs fail, the run goes on.
    let some = scan_bag(&d, "some.mcap", |i| i == 7 || i == 13);
    let o = odocal(&[
        "icp",
        "--input",
        s(&some),
        "--robot",
        s(&robot),
        "--out",
        s(&d.join("t.tum")),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stats: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let failed = stats["failed_pairs"].as_u64().unwrap();
    assert!((1..19).contains(&failed), "{stats}");
    // Two seconds are too few to diagnose: the message names the file.
    let o = odocal(&["diagnose", "--measured", s(&some), "--robot", s(&robot)]);
    refused(&o, &["some.mcap", "not enough data to diagnose"]);
}

#[test]
fn robot_and_effect_values_outside_physical_ranges_are_refused() {
    let d = scratch("cli_physical_ranges");
    // Radii in millimetres instead of metres.
    let robot = d.join("mm.toml");
    std::fs::write(&robot, "r_right = 320\nr_left = 320\nwheel_base = 0.65\n").unwrap();
    let o = odocal(&[
        "simulate",
        "--duration",
        "1",
        "--robot",
        s(&robot),
        "--out",
        s(&d.join("a.mcap")),
    ]);
    refused(&o, &["mm.toml", "r_right = 320", "[0.001, 2] m"]);
    let robot = d.join("ticks.toml");
    std::fs::write(
        &robot,
        "r_right = 0.3\nr_left = 0.3\nwheel_base = 0.6\nticks_per_rev = 1e9\n",
    )
    .unwrap();
    let o = odocal(&[
        "simulate",
        "--duration",
        "1",
        "--robot",
        s(&robot),
        "--out",
        s(&d.join("a.mcap")),
    ]);
    refused(&o, &["ticks.toml", "ticks_per_rev", "100000000"]);
    for (spec, needle) in [
        ("radius_scale:right=0.8", "[-0.5, 0.5]"),
        ("latency:delay=5", "[0, 1] (s)"),
        ("gyro_bias:bias=3", "rad/s"),
        ("laser_offset:x=20", "[-1, 1] (m)"),
    ] {
        let o = odocal(&[
            "simulate",
            "--duration",
            "1",
            "--effect",
            spec,
            "--out",
            s(&d.join("a.mcap")),
        ]);
        refused(&o, &[spec, needle, "outside the physical range"]);
    }
    assert!(!d.join("a.mcap").exists());
}

/// A motions CSV with one valid row `row` after a good one, and standing wheels.
fn csv_inputs(d: &Path, row: &str) -> (PathBuf, PathBuf) {
    let m = d.join("motions.csv");
    let good = "0.0,0.1,0.05,0,0.01,1e-6,0,0,1e-6,0,1e-6,5,100,1";
    std::fs::write(
        &m,
        format!("{}\n{good}\n{row}\n", odocal::io::csv::MOTIONS_HEADER_CORE),
    )
    .unwrap();
    let w = d.join("wheels.csv");
    let rows: Vec<String> = (0..30)
        .map(|i| format!("{},{},{}", 0.01 * i as f64, 0.0, 0.0))
        .collect();
    std::fs::write(&w, format!("t,left,right\n{}\n", rows.join("\n"))).unwrap();
    (m, w)
}

#[test]
fn motions_that_break_covariance_or_speed_rules_are_refused() {
    let d = scratch("cli_motions");
    let cases = [
        // Negative variance along y.
        (
            "0.1,0.2,0.05,0,0.01,1e-6,0,0,-1e-6,0,1e-6,5,100,1",
            "positive semidefinite",
        ),
        // |cov_xy| larger than both variances: an indefinite matrix.
        (
            "0.1,0.2,0.05,0,0.01,1e-6,1e-3,0,1e-6,0,1e-6,5,100,1",
            "positive semidefinite",
        ),
        // 5 m in 0.1 s: 50 m/s.
        (
            "0.1,0.2,5.0,0,0.01,1e-6,0,0,1e-6,0,1e-6,5,100,1",
            "max_speed",
        ),
        // A valid row that spans no time.
        (
            "0.1,0.1,0.0,0,0.0,1e-6,0,0,1e-6,0,1e-6,5,100,1",
            "span time",
        ),
    ];
    for (row, needle) in cases {
        let (m, w) = csv_inputs(&d, row);
        let o = odocal(&[
            "calibrate",
            "--motions",
            s(&m),
            "--wheels",
            s(&w),
            "--out",
            s(&d.join("cal")),
        ]);
        refused(&o, &["motions.csv", "line 3", needle]);
    }
    // A failed row may hold anything: it never becomes an observation (the
    // run is then refused for having too little to start the filters from,
    // not for the row).
    let (m, w) = csv_inputs(&d, "0.1,0.2,5.0,0,0.01,1e-6,0,0,-1e-6,0,1e-6,5,100,0");
    let o = odocal(&[
        "calibrate",
        "--motions",
        s(&m),
        "--wheels",
        s(&w),
        "--method",
        "dkf",
        "--out",
        s(&d.join("cal")),
    ]);
    refused(
        &o,
        &["motions.csv", "wheels.csv", "the filters never started"],
    );
    // Wheels that do not overlap the motions: both files named.
    let w2 = d.join("late.csv");
    std::fs::write(&w2, "t,left,right\n100,0,0\n101,0,0\n").unwrap();
    let o = odocal(&[
        "calibrate",
        "--motions",
        s(&m),
        "--wheels",
        s(&w2),
        "--out",
        s(&d.join("cal2")),
    ]);
    refused(
        &o,
        &["motions.csv", "late.csv", "the filters never started"],
    );
}

#[test]
fn a_truth_file_of_another_recording_is_refused_naming_both() {
    let d = scratch("cli_truth");
    let mut truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(BUNDLED_TRUTH).unwrap()).unwrap();
    truth["duration_s"] = serde_json::json!(120.0);
    let other = d.join("other.truth.json");
    std::fs::write(&other, truth.to_string()).unwrap();
    let o = odocal(&[
        "demo",
        "--input",
        BUNDLED,
        "--truth",
        s(&other),
        "--out",
        s(&d.join("demo")),
    ]);
    refused(
        &o,
        &[
            "other.truth.json",
            "wheelchair-corridor.mcap",
            "lasts 120 s",
        ],
    );
    assert!(!d.join("demo").join("report.md").exists());
}

#[test]
fn special_files_caps_and_negative_numbers_are_refused_by_name() {
    let d = scratch("cli_caps");
    let out = d.join("t.tum");
    let o = odocal(&["icp", "--input", "/dev/zero", "--out", s(&out)]);
    refused(&o, &["/dev/zero", "character device", "regular file"]);
    let fifo = d.join("pipe.mcap");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let o = odocal(&["icp", "--input", s(&fifo), "--out", s(&out)]);
    refused(&o, &["pipe.mcap", "pipe (FIFO)"]);
    let o = odocal(&[
        "simulate",
        "--duration",
        "-5",
        "--out",
        s(&d.join("a.mcap")),
    ]);
    refused(&o, &["duration_s", "-5"]);
    let o = odocal(&[
        "simulate",
        "--duration",
        "1e6",
        "--out",
        s(&d.join("a.mcap")),
    ]);
    refused(&o, &["86400 s"]);
    for n in ["-5", "0", "2000000"] {
        let o = odocal(&[
            "calibrate",
            "--input",
            BUNDLED,
            "--particles",
            n,
            "--out",
            s(&d.join("cal")),
        ]);
        refused(&o, &[n, "1000000"]);
    }
    let o = odocal(&["diagnose", "--measured", BUNDLED, "--holdout", "-0.3"]);
    refused(&o, &["--holdout", "-0.3"]);
}

#[test]
fn a_damaged_mcap_magic_and_absurd_tum_values_are_named() {
    let d = scratch("cli_magic_tum");
    let mut bytes = std::fs::read(BUNDLED).unwrap();
    bytes[3] ^= 0x04;
    let bad = d.join("flipped.mcap");
    std::fs::write(&bad, &bytes).unwrap();
    let o = odocal(&["icp", "--input", s(&bad), "--out", s(&d.join("t.tum"))]);
    refused(&o, &["flipped.mcap", "not an MCAP (bad magic at byte 3"]);
    let good = d.join("ref.tum");
    std::fs::write(&good, "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n").unwrap();
    for (text, needle) in [
        (
            "0 0 0 0 0 0 0 1\n1 1e300 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n",
            "coordinate",
        ),
        (
            "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n1e300 2 0 0 0 0 0 1\n",
            "timestamp",
        ),
    ] {
        let est = d.join("est.tum");
        std::fs::write(&est, text).unwrap();
        let o = odocal(&["eval", "--estimate", s(&est), "--reference", s(&good)]);
        let err = refused(&o, &["est.tum", needle]);
        assert!(err.contains("line 2") || err.contains("line 3"), "{err}");
    }
    // The same bound in a KITTI file.
    let kitti = d.join("est.kitti");
    std::fs::write(
        &kitti,
        "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1e300 0 1 0 0 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n",
    )
    .unwrap();
    let times = d.join("times.txt");
    std::fs::write(&times, "0\n1\n2\n").unwrap();
    let o = odocal(&[
        "eval",
        "--estimate",
        s(&kitti),
        "--estimate-times",
        s(&times),
        "--reference",
        s(&good),
    ]);
    refused(&o, &["est.kitti", "line 2", "coordinate"]);
}
