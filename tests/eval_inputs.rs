//! Bad input to the evaluation readers and to `evaluate`: every case is a clear
//! error naming the file and line (readers) or the problem (evaluation), never
//! a panic or a number.

use crate::support;
use nalgebra::Isometry3;
use odocal::eval::{self, EvalError, EvalOptions, SyncOptions, Trajectory3};
use odocal::io::kitti::{parse_kitti, read_kitti};
use odocal::io::relations::read_relations;
use odocal::io::tum::{parse_tum, read_tum, read_tum_2d, write_tum, write_tum_2d};
use odocal::InputError;
use std::fs;

const Q: &str = "0 0 0 1";

fn tum_err(text: &str) -> InputError {
    parse_tum(text, "bad.tum").expect_err(text)
}

#[test]
fn eval_tum_bad_input_is_named_by_line() {
    let cases: &[(&str, &str, Option<&str>)] = &[
        ("", "0 pose(s)", None),
        ("# only a comment\n\n", "0 pose(s)", None),
        (&format!("1.0 0 0 0 {Q}\n"), "1 pose(s)", None),
        (
            &format!("1.0 0 0 0 {Q}\n0.5 1 0 0 {Q}\n"),
            "decreasing timestamp",
            Some("line 2"),
        ),
        (
            &format!("1.0 0 0 0 {Q}\n2.0 1 0 0 {Q}\n2.0 2 0 0 {Q}\n"),
            "duplicate timestamp",
            Some("line 3"),
        ),
        (
            &format!("1.0 0 0 0 {Q}\n2.0 nan 0 0 {Q}\n"),
            "not finite",
            Some("line 2"),
        ),
        (
            &format!("1.0 0 0 0 {Q}\n2.0 1 0 0 0 0 0\n"),
            "expected 8 numbers",
            Some("line 2"),
        ),
        (
            &format!("# c\n1.0 0 0 0 {Q}\n2.0 1 0 x {Q}\n"),
            "column 4",
            Some("line 3"),
        ),
        (
            &format!("1.0 0 0 0 {Q} 7\n2.0 1 0 0 {Q}\n"),
            "expected 8 numbers",
            Some("line 1"),
        ),
        (
            "1.0 0 0 0 0 0 0 0\n2.0 1 0 0 0 0 0 1\n",
            "zero quaternion",
            Some("line 1"),
        ),
        (
            &format!("1.0 0 0 0 {Q}\n2.0 1 0 inf {Q}\n"),
            "not finite",
            Some("line 2"),
        ),
    ];
    assert!(cases.len() >= 10);
    for (text, msg, pos) in cases {
        let e = tum_err(text);
        assert_eq!(e.file, "bad.tum");
        assert!(e.message.contains(msg), "{text:?}: {e}");
        assert_eq!(e.position.as_deref(), *pos, "{text:?}: {e}");
    }
    // A missing file is an InputError too, naming the path.
    let e = read_tum(std::path::Path::new("/nonexistent/x.tum")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/x.tum"));
}

#[test]
fn eval_tum_round_trips_exactly() {
    let dir = support::scratch("eval_tum_round_trips_exactly");
    let text = concat!(
        "# t x y z qx qy qz qw\n1700000000.123456 1.5 -2.25 0.125 0 0 0.3826834323650898 0.9238795325112867\n",
        "1700000000.223456 1.6 -2.2 0.1 0.1 0.2 0.3 0.9273618495495703\n"
    );
    let t = parse_tum(text, "a").unwrap();
    write_tum(&dir.join("a.tum"), &t).unwrap();
    let back = read_tum(&dir.join("a.tum")).unwrap();
    assert_eq!(back.stamps, t.stamps);
    for (a, b) in t.poses.iter().zip(&back.poses) {
        assert_eq!(a.translation, b.translation);
        assert!(a.rotation.angle_to(&b.rotation) < 1e-15);
    }
    // Planar view: yaw of the first pose is 45°.
    let flat = read_tum_2d(&dir.join("a.tum")).unwrap();
    assert!((flat.poses[0].rotation.angle() - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
    write_tum_2d(&dir.join("b.tum"), &flat).unwrap();
    let again = read_tum_2d(&dir.join("b.tum")).unwrap();
    assert_eq!(again.stamps, flat.stamps);
    assert!((again.poses[1].rotation.angle() - flat.poses[1].rotation.angle()).abs() < 1e-15);
}

#[test]
fn eval_kitti_reads_matrices_and_refuses_bad_lines() {
    let poses = "1 0 0 0.5 0 1 0 0 0 0 1 0\n\
                 0 -1 0 1.5 1 0 0 2 0 0 1 -0.5\n";
    let t = parse_kitti(poses, "p.txt", "0.0\n0.1\n", "t.txt").unwrap();
    assert_eq!(t.len(), 2);
    assert_eq!(
        t.poses[1].translation.vector,
        nalgebra::Vector3::new(1.5, 2.0, -0.5)
    );
    assert!((t.poses[1].rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    let err = |p: &str, ts: &str| {
        parse_kitti(p, "p.txt", ts, "t.txt")
            .unwrap_err()
            .to_string()
    };
    assert!(err(poses, "0.0\n").contains("1 timestamps for 2 poses"));
    assert!(err(poses, "0.0\n0.0\n").contains("t.txt, timestamps, line 2"));
    assert!(err("1 0 0 0 0 1 0 0 0 0 1\n", "0\n").contains("p.txt, KITTI, line 1: expected 12"));
    assert!(err(
        "2 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n",
        "0\n1\n"
    )
    .contains("not a rotation"));
    assert!(err("1 0 0 0 0 1 0 0 0 0 1 0\n", "0\n").contains("1 pose(s)"));
    assert!(err("1 0 0 nan 0 1 0 0 0 0 1 0\n", "0\n").contains("not finite"));
    let dir = support::scratch("eval_kitti_reads_matrices");
    fs::write(dir.join("p.txt"), poses).unwrap();
    fs::write(dir.join("t.txt"), "5\n6\n").unwrap();
    assert_eq!(
        read_kitti(&dir.join("p.txt"), &dir.join("t.txt"))
            .unwrap()
            .stamps,
        vec![5.0, 6.0]
    );
}

#[test]
fn eval_relations_file_errors_name_the_line() {
    let dir = support::scratch("eval_relations_file_errors_name_the_line");
    let p = dir.join("x.relations");
    fs::write(&p, "").unwrap();
    assert!(read_relations(&p)
        .unwrap_err()
        .message
        .contains("no relations"));
    fs::write(&p, "1 2 0 0 0 0 0 0\n3 4 0 0 0 0 0\n").unwrap();
    let e = read_relations(&p).unwrap_err();
    assert_eq!(e.position.as_deref(), Some("line 2"));
    assert!(e.file.ends_with("x.relations"));
}

fn traj(stamps: &[f64]) -> Trajectory3 {
    Trajectory3::from_parts(
        stamps.to_vec(),
        stamps
            .iter()
            .map(|&t| Isometry3::translation(t, (t * 0.7).sin(), 0.0))
            .collect(),
    )
    .unwrap()
}

#[test]
fn eval_refuses_what_it_cannot_measure() {
    let o = EvalOptions::default();
    let r = traj(&[0.0, 1.0, 2.0, 3.0]);
    // No overlapping time range.
    let late = traj(&[10.0, 11.0, 12.0]);
    let e = eval::evaluate(&late, Some(&r), None, &o).unwrap_err();
    assert!(matches!(e, EvalError::NoOverlap { .. }), "{e}");
    assert!(e.to_string().contains("no overlapping time range"));
    // Overlap, but only one stamp within 0.01 s.
    let e = eval::evaluate(&traj(&[0.5, 1.005, 1.5]), Some(&r), None, &o).unwrap_err();
    assert!(
        matches!(e, EvalError::TooFewMatches { matched: 1, .. }),
        "{e}"
    );
    // One pose.
    let one = Trajectory3::from_parts(vec![1.0], vec![Isometry3::identity()]).unwrap();
    let e = eval::evaluate(&one, Some(&r), None, &o).unwrap_err();
    assert!(
        matches!(
            e,
            EvalError::TooFewPoses {
                what: "estimate",
                count: 1,
                ..
            }
        ),
        "{e}"
    );
    // NaN in a pose built in memory.
    let mut nan = traj(&[0.0, 1.0, 2.0]);
    nan.poses[1].translation.x = f64::NAN;
    let e = eval::evaluate(&nan, Some(&r), None, &o).unwrap_err();
    assert!(
        matches!(
            e,
            EvalError::NonFinite {
                what: "estimate",
                index: 1
            }
        ),
        "{e}"
    );
    // Negative max_diff, nothing to compare against, RPE delta too large.
    let bad = EvalOptions {
        sync: SyncOptions {
            max_diff: -1.0,
            ..Default::default()
        },
        ..o
    };
    assert!(matches!(
        eval::evaluate(&r, Some(&r), None, &bad),
        Err(EvalError::InvalidOption(_))
    ));
    assert!(matches!(
        eval::evaluate(&r, None, None, &o),
        Err(EvalError::InvalidOption(_))
    ));
    let far = EvalOptions {
        rpe_delta: eval::RpeDelta {
            value: 10.0,
            unit: eval::DeltaUnit::Frames,
        },
        ..o
    };
    assert!(matches!(
        eval::evaluate(&r, Some(&r), None, &far),
        Err(EvalError::NoRpePairs { .. })
    ));
    let frac = EvalOptions {
        rpe_delta: eval::RpeDelta {
            value: 1.5,
            unit: eval::DeltaUnit::Frames,
        },
        ..o
    };
    assert!(matches!(
        eval::evaluate(&r, Some(&r), None, &frac),
        Err(EvalError::InvalidOption(_))
    ));
}
