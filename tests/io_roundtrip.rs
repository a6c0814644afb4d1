//! A recording written by `write_mcap` reads back equal, is byte-for-byte
//! deterministic, and decodes with independent tools (mcap + mcap_ros2).

use std::f64::consts::PI;

use crate::io_crosscheck::{compare, dump};
use crate::support::{python_with, scratch, shared_data};
use odocal::geom::{self, wrap_angle};
use odocal::io::{encode_mcap, read_recording, write_mcap, ReadOptions, WriteOptions};
use odocal::recording::{GyroSample, Recording, StampedPose, WheelSample};
use odocal::scan::LaserScan;

/// A recording with every stream, REP 117 special ranges, f32-exact scan
/// geometry and a laser mounted backwards.
pub fn synthetic() -> Recording {
    let t0 = 1_700_000_000.25;
    let scans = (0..60)
        .map(|k| LaserScan {
            stamp: t0 + 0.1 * k as f64,
            angle_min: -(PI as f32 / 2.0) as f64,
            angle_increment: (PI as f32 / 180.0) as f64,
            time_increment: 1e-4f32 as f64,
            scan_time: 0.1f32 as f64,
            range_min: 0.05f32 as f64,
            range_max: 30.0,
            ranges: (0..181)
                .map(|i| match (i + k) % 37 {
                    0 => f32::NAN,
                    1 => f32::INFINITY,
                    2 => f32::NEG_INFINITY,
                    j => 0.5 + j as f32 * 0.173,
                })
                .collect(),
        })
        .collect();
    let wheels = (0..300)
        .map(|k| {
            let t = 0.02 * k as f64;
            WheelSample {
                stamp: t0 + t,
                left: 3.0 * t + 0.1 * t * t,
                right: 3.2 * t - 0.05 * t * t,
            }
        })
        .collect();
    let gyro = (0..600)
        .map(|k| GyroSample {
            stamp: t0 + 0.01 * k as f64,
            wz: 0.3 * (0.01 * k as f64).sin(),
        })
        .collect();
    let path = |k: usize, off: f64| {
        let t = 0.05 * k as f64;
        StampedPose {
            stamp: t0 + t,
            pose: geom::pose(t.cos() + off, 2.0 * t.sin(), wrap_angle(1.3 * t)),
            has_heading: true,
        }
    };
    Recording {
        source: "synthetic".into(),
        scans,
        wheels,
        gyro,
        odom: (0..120).map(|k| path(k, 0.1)).collect(),
        reference: (0..120).map(|k| path(k, 0.0)).collect(),
        base_from_laser: Some(geom::pose(-0.45, 0.02, PI)),
        ..Default::default()
    }
}

fn assert_pose_eq(a: &StampedPose, b: &StampedPose, what: &str) {
    assert!(
        (a.stamp - b.stamp).abs() < 1e-9,
        "{what} stamp {} {}",
        a.stamp,
        b.stamp
    );
    assert!(
        (a.pose.translation.vector - b.pose.translation.vector).norm() < 1e-12,
        "{what}"
    );
    assert!(wrap_angle(a.pose.rotation.angle() - b.pose.rotation.angle()).abs() < 1e-12);
    assert_eq!(a.has_heading, b.has_heading, "{what}");
}

/// Equal up to the nanosecond stamps and float32 scan fields of the format.
pub fn assert_recordings_equal(a: &Recording, b: &Recording) {
    assert_eq!(a.scans.len(), b.scans.len());
    for (x, y) in a.scans.iter().zip(&b.scans) {
        assert!((x.stamp - y.stamp).abs() < 1e-9);
        assert_eq!(x.angle_min as f32, y.angle_min as f32);
        assert_eq!(x.angle_increment as f32, y.angle_increment as f32);
        assert_eq!(x.range_min as f32, y.range_min as f32);
        assert_eq!(x.range_max as f32, y.range_max as f32);
        assert_eq!(x.time_increment as f32, y.time_increment as f32);
        assert_eq!(x.scan_time as f32, y.scan_time as f32);
        let bits = |s: &LaserScan| s.ranges.iter().map(|r| r.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(x), bits(y));
    }
    assert_eq!(a.wheels.len(), b.wheels.len());
    for (x, y) in a.wheels.iter().zip(&b.wheels) {
        assert!((x.stamp - y.stamp).abs() < 1e-9);
        assert_eq!((x.left, x.right), (y.left, y.right));
    }
    assert_eq!(a.gyro.len(), b.gyro.len());
    for (x, y) in a.gyro.iter().zip(&b.gyro) {
        assert!((x.stamp - y.stamp).abs() < 1e-9);
        assert_eq!(x.wz, y.wz);
    }
    assert_eq!(a.odom.len(), b.odom.len());
    for (x, y) in a.odom.iter().zip(&b.odom) {
        assert_pose_eq(x, y, "odom");
    }
    assert_eq!(a.reference.len(), b.reference.len());
    for (x, y) in a.reference.iter().zip(&b.reference) {
        assert_pose_eq(x, y, "reference");
    }
    match (a.base_from_laser, b.base_from_laser) {
        (None, None) => {}
        (Some(p), Some(q)) => {
            assert!((p.translation.vector - q.translation.vector).norm() < 1e-12);
            assert!(wrap_angle(p.rotation.angle() - q.rotation.angle()).abs() < 1e-12);
        }
        (p, q) => panic!("base_from_laser {p:?} vs {q:?}"),
    }
}

#[test]
fn written_bag_reads_back_equal_and_is_deterministic() {
    let dir = scratch("written_bag_reads_back_equal");
    let rec = synthetic();
    let path = dir.join("rec.mcap");
    write_mcap(&path, &rec, &WriteOptions::default()).unwrap();
    let back = read_recording(&path, &ReadOptions::default()).unwrap();
    assert_recordings_equal(&rec, &back);
    // Same recording, same bytes (no wall clock, no thread-dependent output).
    let bytes = std::fs::read(&path).unwrap();
    for _ in 0..3 {
        assert!(bytes == encode_mcap(&rec, &WriteOptions::default()).unwrap());
    }
    write_mcap(&path, &rec, &WriteOptions::default()).unwrap();
    assert!(bytes == std::fs::read(&path).unwrap());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn position_only_reference_is_written_as_points() {
    let dir = scratch("position_only_reference");
    let mut rec = synthetic();
    for p in &mut rec.reference {
        p.pose = geom::pose(
            p.pose.translation.vector.x,
            p.pose.translation.vector.y,
            0.0,
        );
        p.has_heading = false;
    }
    let path = dir.join("rec.mcap");
    write_mcap(&path, &rec, &WriteOptions::default()).unwrap();
    let back = read_recording(&path, &ReadOptions::default()).unwrap();
    assert_recordings_equal(&rec, &back);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn written_bag_decodes_with_independent_tools() {
    let test = "written_bag_decodes_with_independent_tools";
    let Some(py) = python_with(test, &["mcap", "mcap_ros2"]) else {
        return;
    };
    let dir = scratch(test);
    let rec = synthetic();
    let path = dir.join("rec.mcap");
    let wo = WriteOptions::default();
    write_mcap(&path, &rec, &wo).unwrap();
    let t = &wo.topics;
    let d = dump(
        &py,
        &path,
        &[&t.scan, &t.joint_states, &t.imu, &t.odom, &t.reference],
    );
    assert_eq!(d["profile"], "ros2");
    let topics = d["topics"].as_object().unwrap();
    let mut names: Vec<&str> = topics.keys().map(|s| s.as_str()).collect();
    names.sort();
    assert_eq!(
        names,
        [
            "/ground_truth",
            "/imu",
            "/joint_states",
            "/odom",
            "/scan",
            "/tf_static"
        ]
    );
    for (topic, v) in topics {
        assert_eq!(v["schema_encoding"], "ros2msg", "{topic}");
        assert_eq!(v["message_encoding"], "cdr", "{topic}");
        assert!(
            v["metadata"].get("offered_qos_profiles").is_some(),
            "{topic}"
        );
    }
    assert_eq!(topics["/ground_truth"]["schema"], "nav_msgs/msg/Odometry");
    let tf = &topics["/tf_static"]["messages"][0]["transforms"][0];
    assert_eq!(tf["header"]["frame_id"], "base_link");
    assert_eq!(tf["child_frame_id"], "laser");
    let js = &topics["/joint_states"]["messages"][0];
    assert_eq!(js["name"][0], "left_wheel");
    assert_eq!(js["name"][1], "right_wheel");
    // Velocities are the wheel rates: d/dt (3 t + 0.1 t²) at the middle.
    let mid = &topics["/joint_states"]["messages"][150];
    let t = 0.02 * 150.0;
    assert!((mid["velocity"][0].as_f64().unwrap() - (3.0 + 0.2 * t)).abs() < 1e-4);
    // Every message of every stream, decoded by the independent tool.
    let n = compare(
        &rec,
        &d,
        &ReadOptions::default(),
        "left_wheel",
        "right_wheel",
    );
    assert_eq!(n, 60 + 300 + 600 + 120 + 120 + 1);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn real_bags_survive_write_and_read() {
    let test = "real_bags_survive_write_and_read";
    let Some(data) = shared_data(test) else {
        return;
    };
    let dir = scratch(test);
    for (rel, reference) in [
        ("slam-benchmark/mit-csail.mcap", "/ground_truth"),
        ("lego-robot/lego-robot.mcap", "/reference"),
    ] {
        let mut ro = ReadOptions::default();
        ro.topics.reference = reference.into();
        let rec = read_recording(&data.join(rel), &ro).unwrap();
        let mut wo = WriteOptions::default();
        wo.topics.reference = reference.into();
        let path = dir.join("copy.mcap");
        write_mcap(&path, &rec, &wo).unwrap();
        assert_recordings_equal(&rec, &read_recording(&path, &ro).unwrap());
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// The same messages re-chunked with another compression.
fn recompress(bytes: &[u8], c: Option<mcap::Compression>) -> Vec<u8> {
    let mut w = mcap::WriteOptions::new()
        .compression(c)
        .chunk_size(Some(64 * 1024))
        .create(std::io::Cursor::new(Vec::new()))
        .unwrap();
    for m in mcap::MessageStream::new(bytes).unwrap() {
        w.write(&m.unwrap()).unwrap();
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

#[test]
fn lz4_and_uncompressed_chunks_read_the_same() {
    let rec = synthetic();
    let zstd = encode_mcap(&rec, &WriteOptions::default()).unwrap();
    for c in [Some(mcap::Compression::Lz4), None] {
        let b = recompress(&zstd, c);
        assert!(b != zstd);
        let back = odocal::io::read_mcap_bytes(&b, "re.mcap", &ReadOptions::default()).unwrap();
        assert_recordings_equal(&rec, &back);
    }
}
