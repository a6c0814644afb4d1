//! odocal's MCAP reader against an independent decoder (`tools/mcap_dump.py`,
//! built on the `mcap` and `mcap_ros2` Python packages), on every shared bag.

use std::path::Path;

use serde_json::Value;

use crate::support::{python_with, shared_data};
use odocal::io::{read_recording, ros_schema::schema_text, ReadOptions};
use odocal::recording::Recording;

/// Runs `tools/mcap_dump.py` on `bag` (decoding every message of `all`).
pub fn dump(py: &str, bag: &Path, all: &[&str]) -> Value {
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/mcap_dump.py");
    let mut cmd = std::process::Command::new(py);
    cmd.arg(tool).arg(bag);
    for t in all {
        cmd.args(["--all", t]);
    }
    let out = cmd.output().expect("run mcap_dump.py");
    assert!(
        out.status.success(),
        "mcap_dump.py {}: {}",
        bag.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("mcap_dump.py prints JSON")
}

/// A JSON number or one of "nan", "inf", "-inf".
pub fn f(v: &Value) -> f64 {
    match v {
        Value::String(s) if s == "nan" => f64::NAN,
        Value::String(s) if s == "inf" => f64::INFINITY,
        Value::String(s) if s == "-inf" => f64::NEG_INFINITY,
        _ => v.as_f64().unwrap_or_else(|| panic!("not a number: {v}")),
    }
}

/// `header.stamp` in s, as ROS defines it (sec + nanosec · 1e-9).
pub fn stamp(m: &Value) -> f64 {
    let h = &m["header"];
    h["sec"].as_i64().unwrap() as f64 + h["nanosec"].as_u64().unwrap() as f64 * 1e-9
}

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
        "{what}: odocal {a} vs independent {b}"
    );
}

fn yaw(p: &Value) -> f64 {
    let (x, y, z, w) = (f(&p["qx"]), f(&p["qy"]), f(&p["qz"]), f(&p["qw"]));
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

fn pose_close(a: &odocal::geom::Pose2, p: &Value, what: &str) {
    let v = a.translation.vector;
    close(v.x, f(&p["x"]), what);
    close(v.y, f(&p["y"]), what);
    close(
        odocal::geom::wrap_angle(a.rotation.angle() - yaw(p)),
        0.0,
        what,
    );
}

/// Asserts that `rec` (read by odocal with `opts`) holds what the independent
/// decoder found in `d`: counts of every configured topic and the decoded
/// values of the sampled messages. Returns how many values were compared.
pub fn compare(rec: &Recording, d: &Value, opts: &ReadOptions, lj: &str, rj: &str) -> usize {
    let t = &opts.topics;
    let topics = d["topics"].as_object().unwrap();
    let count = |topic: &str| {
        topics
            .get(topic)
            .map(|v| v["count"].as_u64().unwrap() as usize)
    };
    assert_eq!(count(&t.scan).unwrap_or(0), rec.scans.len(), "scan count");
    assert_eq!(count(&t.odom).unwrap_or(0), rec.odom.len(), "odom count");
    assert_eq!(count(&t.joint_states).unwrap_or(0), rec.wheels.len());
    assert_eq!(count(&t.imu).unwrap_or(0), rec.gyro.len(), "imu count");
    assert_eq!(count(&t.reference).unwrap_or(0), rec.reference.len());
    let msgs = |topic: &str| {
        topics
            .get(topic)
            .map(|v| v["messages"].as_array().unwrap().clone())
            .unwrap_or_default()
    };
    let mut n = 0;
    for m in msgs(&t.scan) {
        let i = m["index"].as_u64().unwrap() as usize;
        let s = &rec.scans[i];
        close(s.stamp, stamp(&m), "scan stamp");
        for (k, v) in [
            ("angle_min", s.angle_min),
            ("angle_increment", s.angle_increment),
            ("range_min", s.range_min),
            ("range_max", s.range_max),
            ("time_increment", s.time_increment),
            ("scan_time", s.scan_time),
        ] {
            assert_eq!(v as f32, f(&m[k]) as f32, "scan {i} {k}");
        }
        let r = m["ranges"].as_array().unwrap();
        assert_eq!(r.len(), s.ranges.len());
        for (a, b) in s.ranges.iter().zip(r) {
            let b = f(b) as f32;
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "scan {i}: {a} vs {b}"
            );
        }
        n += 1;
    }
    for m in msgs(&t.odom) {
        let i = m["index"].as_u64().unwrap() as usize;
        close(rec.odom[i].stamp, stamp(&m), "odom stamp");
        pose_close(&rec.odom[i].pose, &m["pose"], "odom pose");
        n += 1;
    }
    for m in msgs(&t.joint_states) {
        let i = m["index"].as_u64().unwrap() as usize;
        let names: Vec<&str> = m["name"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        let il = names.iter().position(|&x| x == lj).unwrap();
        let ir = names.iter().position(|&x| x == rj).unwrap();
        close(rec.wheels[i].stamp, stamp(&m), "joint stamp");
        close(rec.wheels[i].left, f(&m["position"][il]), "left wheel");
        close(rec.wheels[i].right, f(&m["position"][ir]), "right wheel");
        n += 1;
    }
    for m in msgs(&t.imu) {
        let i = m["index"].as_u64().unwrap() as usize;
        close(rec.gyro[i].stamp, stamp(&m), "imu stamp");
        close(rec.gyro[i].wz, f(&m["angular_velocity"][2]), "gyro");
        n += 1;
    }
    for m in msgs(&t.reference) {
        let i = m["index"].as_u64().unwrap() as usize;
        let r = &rec.reference[i];
        close(r.stamp, stamp(&m), "reference stamp");
        if let Some(p) = m.get("point") {
            assert!(!r.has_heading);
            close(r.pose.translation.vector.x, f(&p[0]), "reference x");
            close(r.pose.translation.vector.y, f(&p[1]), "reference y");
        } else {
            assert!(r.has_heading);
            pose_close(&r.pose, &m["pose"], "reference pose");
        }
        n += 1;
    }
    if let Some(m) = msgs(&t.tf_static).first() {
        let tr = &m["transforms"][0];
        let b = rec.base_from_laser.expect("base_from_laser");
        close(b.translation.vector.x, f(&tr["translation"][0]), "laser x");
        close(b.translation.vector.y, f(&tr["translation"][1]), "laser y");
        let q = &tr["rotation"];
        let y = (2.0 * (f(&q[3]) * f(&q[2]) + f(&q[0]) * f(&q[1])))
            .atan2(1.0 - 2.0 * (f(&q[1]).powi(2) + f(&q[2]).powi(2)));
        close(b.rotation.angle(), y, "laser yaw");
        n += 1;
    }
    n
}

#[test]
fn real_bags_match_independent_decoder() {
    let test = "real_bags_match_independent_decoder";
    let (Some(dir), Some(py)) = (shared_data(test), python_with(test, &["mcap", "mcap_ros2"]))
    else {
        return;
    };
    let bags = [
        "slam-benchmark/intel.mcap",
        "slam-benchmark/aces.mcap",
        "slam-benchmark/fr079.mcap",
        "slam-benchmark/mit-csail.mcap",
        "lego-robot/lego-robot.mcap",
        "mines-rover/exp1.mcap",
        "mines-rover/exp2.mcap",
    ];
    for rel in bags {
        let mut opts = ReadOptions::default();
        if rel.starts_with("lego") {
            opts.topics.reference = "/reference".into();
        }
        let path = dir.join(rel);
        let rec = read_recording(&path, &opts).unwrap();
        let d = dump(&py, &path, &[]);
        let n = compare(&rec, &d, &opts, "left_wheel", "right_wheel");
        // Six sampled messages per stream at least, so the test cannot pass vacuously.
        assert!(n >= 13, "{rel}: only {n} messages compared");
    }
}

#[test]
fn schema_texts_match_real_bags_and_rosbags() {
    let test = "schema_texts_match_real_bags_and_rosbags";
    let (Some(dir), Some(py)) = (
        shared_data(test),
        python_with(test, &["mcap", "mcap_ros2", "rosbags"]),
    ) else {
        return;
    };
    let mut seen = 0;
    for rel in [
        "slam-benchmark/fr079.mcap",
        "lego-robot/lego-robot.mcap",
        "mines-rover/exp1.mcap",
    ] {
        let d = dump(&py, &dir.join(rel), &[]);
        for (topic, v) in d["topics"].as_object().unwrap() {
            let name = v["schema"].as_str().unwrap();
            let ours = schema_text(name).unwrap_or_else(|| panic!("{rel} {topic}: {name} unknown"));
            assert_eq!(ours, v["schema_text"].as_str().unwrap(), "{rel} {topic}");
            seen += 1;
        }
    }
    assert!(seen >= 8);
    // Every type odocal writes or reads, against rosbags' own generator.
    let types = [
        "builtin_interfaces/msg/Time",
        "std_msgs/msg/Header",
        "sensor_msgs/msg/LaserScan",
        "sensor_msgs/msg/JointState",
        "sensor_msgs/msg/Imu",
        "nav_msgs/msg/Odometry",
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/PointStamped",
        "tf2_msgs/msg/TFMessage",
    ];
    let code = format!(
        "import json\nfrom rosbags.typesys import Stores, get_typestore\n\
         ts = get_typestore(Stores.ROS2_HUMBLE)\n\
         print(json.dumps({{t: ts.generate_msgdef(t, ros_version=2)[0] for t in {types:?}}}))"
    );
    let out = std::process::Command::new(&py)
        .args(["-c", &code])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let theirs: Value = serde_json::from_slice(&out.stdout).unwrap();
    for t in types {
        assert_eq!(schema_text(t).unwrap(), theirs[t].as_str().unwrap(), "{t}");
    }
}
