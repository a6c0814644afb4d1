//! Bad input never panics and never yields silent numbers: every case is an
//! `InputError` naming the file, and the topic and message index where known.

use crate::io_roundtrip::synthetic;
use crate::io_time::Msg;
use crate::support::{scratch, shared_data};
use odocal::io::ros_msgs::{Header, JointStateMsg, LaserScanMsg, PoseStampedMsg, RosMsg, Time};
use odocal::io::{encode_mcap, read_mcap_bytes, read_recording, ReadOptions, WriteOptions};
use odocal::InputError;

/// An MCAP with one channel per entry: (topic, schema name, messages); the
/// log time of message i is (i + 1) ms.
fn bag(channels: &[(&str, &str, Vec<Vec<u8>>)]) -> Vec<u8> {
    let timed: Vec<(&str, &str, Vec<Msg>)> = channels
        .iter()
        .map(|(topic, ty, msgs)| {
            let msgs = msgs
                .iter()
                .enumerate()
                .map(|(i, m)| Msg {
                    log_ns: 1_000_000 * (i as u64 + 1),
                    data: m.clone(),
                })
                .collect();
            (*topic, *ty, msgs)
        })
        .collect();
    crate::io_time::bag(&timed)
}

fn scan(stamp: f64, beams: usize) -> LaserScanMsg {
    LaserScanMsg {
        header: Header {
            stamp: Time::from_seconds(stamp),
            frame_id: "laser".into(),
        },
        angle_min: -1.0,
        angle_max: -1.0 + 0.01 * beams.saturating_sub(1) as f32,
        angle_increment: 0.01,
        range_min: 0.1,
        range_max: 10.0,
        ranges: vec![1.0; beams],
        ..Default::default()
    }
}

fn scans(stamps: &[f64]) -> Vec<Vec<u8>> {
    stamps.iter().map(|&t| scan(t, 5).encode()).collect()
}

fn read(bytes: &[u8]) -> Result<odocal::recording::Recording, InputError> {
    read_mcap_bytes(bytes, "bad.mcap", &ReadOptions::default())
}

fn expect_err(bytes: &[u8], topic: &str, index: usize, needle: &str) -> InputError {
    let e = read(bytes).expect_err("bad input must be an error");
    assert_eq!(e.file, "bad.mcap");
    assert_eq!(e.topic.as_deref(), Some(topic), "{e}");
    assert_eq!(
        e.position.as_deref(),
        Some(format!("message {index}").as_str()),
        "{e}"
    );
    assert!(e.message.contains(needle), "'{needle}' not in: {e}");
    e
}

const SCAN: &str = "sensor_msgs/msg/LaserScan";

#[test]
fn missing_file_names_the_file() {
    let dir = scratch("missing_file_names_the_file");
    let p = dir.join("nope.mcap");
    let e = read_recording(&p, &ReadOptions::default()).unwrap_err();
    assert_eq!(e.file, p.display().to_string());
    assert!(e.message.contains("cannot read"), "{e}");
}

#[test]
fn truncated_mcap_names_the_last_readable_message() {
    let full = encode_mcap(&synthetic(), &WriteOptions::default()).unwrap();
    let n = full.len();
    for cut in [0, 7, 8, 50, n / 3, n / 2, n - 200, n - 9, n - 1] {
        let e = read_mcap_bytes(&full[..cut], "cut.mcap", &ReadOptions::default())
            .expect_err("a truncated file is an error");
        assert_eq!(e.file, "cut.mcap");
        assert!(e.message.contains("truncated"), "{e}");
    }
    // Cut inside the summary: every message is intact, the error says which
    // one was last.
    let e = read_mcap_bytes(&full[..n - 200], "cut.mcap", &ReadOptions::default()).unwrap_err();
    assert!(e.topic.is_some() && e.position.is_some(), "{e}");
}

#[test]
fn corrupt_chunk_bytes_are_an_error() {
    let mut b = encode_mcap(&synthetic(), &WriteOptions::default()).unwrap();
    let summary = mcap::Summary::read(&b).unwrap().unwrap();
    let chunk = &summary.chunk_indexes[0];
    let mid = (chunk.chunk_start_offset + chunk.chunk_length / 2) as usize;
    for k in 0..16 {
        b[mid + k] ^= 0x5a;
    }
    let e = read(&b).expect_err("corrupt chunk");
    assert_eq!(e.file, "bad.mcap");
    assert!(e.message.contains("corrupt"), "{e}");
    assert!(
        e.position.as_deref().unwrap_or("").starts_with("after"),
        "{e}"
    );
}

#[test]
fn cdr_message_shorter_than_its_schema() {
    // Cut inside the ranges: the sequence count promises more than is left.
    let mut msgs = scans(&[1.0, 1.1, 1.2]);
    let n = msgs[2].len();
    msgs[2].truncate(n - 10);
    let e = expect_err(
        &bag(&[("/scan", SCAN, msgs)]),
        "/scan",
        2,
        "sequence of 5 elements",
    );
    assert!(
        e.to_string().starts_with("bad.mcap, /scan, message 2: CDR"),
        "{e}"
    );
    // Cut inside the fixed fields: header (4) + stamp (8) + "laser" (4 + 6),
    // pad to 24, then float32 angle_min .. range_max at 24..52.
    let mut msgs = scans(&[1.0]);
    msgs[0].truncate(30);
    expect_err(
        &bag(&[("/scan", SCAN, msgs)]),
        "/scan",
        0,
        "expected float32 at byte 28",
    );
}

#[test]
fn unknown_schema_on_configured_topic() {
    let b = bag(&[(
        "/scan",
        "sensor_msgs/msg/PointCloud2",
        vec![vec![0, 1, 0, 0]],
    )]);
    let e = read(&b).unwrap_err();
    assert_eq!(e.topic.as_deref(), Some("/scan"));
    assert!(e.message.contains("sensor_msgs/PointCloud2"), "{e}");
    assert!(e.message.contains(SCAN), "{e}");
}

#[test]
fn unknown_schema_on_other_topic_is_ignored() {
    let b = bag(&[
        ("/scan", SCAN, scans(&[1.0, 2.0])),
        ("/camera", "sensor_msgs/msg/Image", vec![vec![1, 2, 3]]),
    ]);
    assert_eq!(read(&b).unwrap().scans.len(), 2);
}

#[test]
fn scan_with_zero_beams() {
    let msgs = vec![scan(1.0, 5).encode(), scan(1.1, 0).encode()];
    expect_err(&bag(&[("/scan", SCAN, msgs)]), "/scan", 1, "zero beams");
}

#[test]
fn scan_with_nan_geometry() {
    let mut s = scan(1.0, 5);
    s.angle_increment = f32::NAN;
    let msgs = vec![scan(0.9, 5).encode(), scan(0.95, 5).encode(), s.encode()];
    expect_err(
        &bag(&[("/scan", SCAN, msgs)]),
        "/scan",
        2,
        "angle_increment",
    );
    let mut s = scan(1.0, 5);
    s.range_max = f32::INFINITY;
    expect_err(
        &bag(&[("/scan", SCAN, vec![s.encode()])]),
        "/scan",
        0,
        "range_max",
    );
}

fn joints(names: &[&str], pos: &[f64], vel: &[f64], t: f64) -> Vec<u8> {
    JointStateMsg {
        header: Header {
            stamp: Time::from_seconds(t),
            frame_id: String::new(),
        },
        name: names.iter().map(|s| s.to_string()).collect(),
        position: pos.to_vec(),
        velocity: vel.to_vec(),
        effort: vec![],
    }
    .encode()
}

const JS: &str = "sensor_msgs/msg/JointState";

#[test]
fn joint_state_without_wheel_joints() {
    let msgs = vec![
        joints(&["left_wheel", "right_wheel"], &[0.0, 0.0], &[], 1.0),
        joints(&["caster", "right_wheel"], &[0.0, 0.0], &[], 1.1),
    ];
    expect_err(
        &bag(&[("/joint_states", JS, msgs)]),
        "/joint_states",
        1,
        "left_wheel",
    );
}

#[test]
fn joint_state_velocities_are_integrated() {
    // 2 rad/s left, -1 rad/s right for 1 s, names in a different order.
    let msgs: Vec<_> = (0..=10)
        .map(|k| {
            joints(
                &["right_wheel", "x", "left_wheel"],
                &[],
                &[-1.0, 9.0, 2.0],
                5.0 + 0.1 * k as f64,
            )
        })
        .collect();
    let r = read(&bag(&[("/joint_states", JS, msgs)])).unwrap();
    assert_eq!(r.wheels.len(), 11);
    let last = r.wheels[10];
    assert!(
        (last.left - 2.0).abs() < 1e-9 && (last.right + 1.0).abs() < 1e-9,
        "{last:?}"
    );
}

#[test]
fn time_going_backwards_beyond_tolerance() {
    // 0.5 s back: real logs do that; fixed by sorting.
    let r = read(&bag(&[("/scan", SCAN, scans(&[10.0, 11.0, 10.5, 12.0]))])).unwrap();
    let stamps: Vec<f64> = r.scans.iter().map(|s| s.stamp).collect();
    assert_eq!(stamps, [10.0, 10.5, 11.0, 12.0]);
    // 3 s back: corrupt clock.
    let b = bag(&[("/scan", SCAN, scans(&[10.0, 11.0, 12.0, 9.0]))]);
    expect_err(&b, "/scan", 3, "backwards");
    // Unless the tolerance allows it.
    let opts = ReadOptions {
        reorder_tolerance: 5.0,
        ..Default::default()
    };
    assert_eq!(
        read_mcap_bytes(&b, "bad.mcap", &opts).unwrap().scans.len(),
        4
    );
}

#[test]
fn zero_stamp_falls_back_to_log_time_and_pose_reference_is_read() {
    let mut p = PoseStampedMsg::default();
    p.pose.position.x = 3.0;
    p.pose.orientation = odocal::io::ros_msgs::Quat::from_yaw(0.5);
    let b = bag(&[(
        "/ground_truth",
        "geometry_msgs/msg/PoseStamped",
        vec![p.encode()],
    )]);
    let r = read(&b).unwrap();
    assert_eq!(r.reference.len(), 1);
    assert_eq!(r.reference[0].stamp, 0.001);
    assert!(r.reference[0].has_heading);
    assert!((r.reference[0].pose.rotation.angle() - 0.5).abs() < 1e-12);
}

#[test]
fn carmen_file_errors_name_file_and_line() {
    let dir = scratch("carmen_file_errors_name_file_and_line");
    let p = dir.join("bad.clf");
    std::fs::write(
        &p,
        "ODOM 0 0 0 0 0 0 1.0 h 1.0\nODOM 0 0 zero 0 0 0 2.0 h 2.0\n",
    )
    .unwrap();
    let e = read_recording(&p, &ReadOptions::default()).unwrap_err();
    assert_eq!(e.file, p.display().to_string());
    assert_eq!(e.topic.as_deref(), Some("ODOM"));
    assert_eq!(e.position.as_deref(), Some("line 2"));
}

#[test]
fn cut_or_damaged_real_bag_never_panics() {
    let Some(dir) = shared_data("cut_or_damaged_real_bag_never_panics") else {
        return;
    };
    let opts = ReadOptions {
        topics: odocal::io::TopicConfig {
            reference: "/reference".into(),
            ..Default::default()
        },
        ..Default::default()
    };
    let full = std::fs::read(dir.join("lego-robot/lego-robot.mcap")).unwrap();
    let n = full.len();
    let mut errors = 0;
    for k in 0..97 {
        let cut = k * n / 97 + k;
        errors += read_mcap_bytes(&full[..cut.min(n - 1)], "cut", &opts).is_err() as usize;
    }
    assert_eq!(errors, 97, "every truncation is detected");
    // Damaged bytes anywhere: Ok or Err, never a panic.
    for k in 0..61 {
        let mut b = full.clone();
        let at = 8 + k * (n - 16) / 61;
        b[at] ^= 0xff;
        b[at + 1] = b[at + 1].wrapping_add(77);
        let _ = read_mcap_bytes(&b, "damaged", &opts);
    }
}

#[test]
fn all_zero_quaternion_means_no_heading() {
    use odocal::io::ros_msgs::{OdometryMsg, Quat};
    let zero = Quat {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 0.0,
    };
    let mut p = PoseStampedMsg::default();
    p.header.stamp = Time::from_seconds(1.0);
    p.pose.position.x = 2.0;
    p.pose.orientation = zero;
    let mut q = p.clone();
    q.header.stamp = Time::from_seconds(2.0);
    q.pose.orientation = odocal::io::ros_msgs::Quat::from_yaw(0.3);
    // A reference: read as a position without heading.
    let b = bag(&[(
        "/ground_truth",
        "geometry_msgs/msg/PoseStamped",
        vec![p.encode(), q.encode()],
    )]);
    let r = read(&b).unwrap();
    assert!(!r.reference[0].has_heading);
    assert!(r.reference[1].has_heading);
    assert_eq!(r.reference[0].pose.translation.vector.x, 2.0);
    // Robot odometry without a heading cannot be used: an error.
    let mut o = OdometryMsg::default();
    o.header.stamp = Time::from_seconds(1.0);
    o.pose.orientation = zero;
    let b = bag(&[("/odom", "nav_msgs/msg/Odometry", vec![o.encode()])]);
    expect_err(&b, "/odom", 0, "all-zero orientation");
}

#[test]
fn wheel_rates_that_integrate_past_f64_are_an_error() {
    let msgs: Vec<_> = (0..3)
        .map(|k| {
            joints(
                &["left_wheel", "right_wheel"],
                &[],
                &[1e308, 1.0],
                1.0 + k as f64,
            )
        })
        .collect();
    let e = read(&bag(&[("/joint_states", JS, msgs)])).unwrap_err();
    assert_eq!(e.topic.as_deref(), Some("/joint_states"));
    assert!(e.message.contains("non-finite angle"), "{e}");
}

#[test]
fn transform_chain_that_overflows_is_an_error() {
    use odocal::io::ros_msgs::{TfMessage, TransformStamped, Vec3};
    let tf = |parent: &str, child: &str| TransformStamped {
        header: Header {
            stamp: Time::from_seconds(1.0),
            frame_id: parent.into(),
        },
        child_frame_id: child.into(),
        translation: Vec3 {
            x: 1e308,
            y: 0.0,
            z: 0.0,
        },
        rotation: odocal::io::ros_msgs::Quat::from_yaw(0.0),
    };
    let m = TfMessage {
        transforms: vec![tf("base_link", "mount"), tf("mount", "laser")],
    };
    let b = bag(&[
        ("/scan", SCAN, scans(&[1.0])),
        ("/tf_static", "tf2_msgs/msg/TFMessage", vec![m.encode()]),
    ]);
    let e = read(&b).unwrap_err();
    assert_eq!(e.topic.as_deref(), Some("/tf_static"));
    assert!(e.message.contains("overflows"), "{e}");
}
