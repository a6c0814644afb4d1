//! `odocal inspect` against what others wrote: a bag rewritten by the Python
//! `mcap` and `rosbags` packages (renamed wheel joints, then as a ROS 1 bag
//! and rosbag2 SQLite file and folder), whose topics, counts and times the
//! Python `mcap` reader counts independently; and the shared real data,
//! whose topics, counts and mountings the data README publishes. The robot
//! file it proposes, once the kinematics are filled in, makes `calibrate`
//! read the wheels that the default settings could not find.

use crate::support::{odocal, python_with, scratch, shared_data};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

fn inspect(path: &Path, extra: &[&str]) -> Value {
    let mut args = vec!["inspect", path.to_str().unwrap(), "--json"];
    args.extend_from_slice(extra);
    let out = odocal(&args);
    assert!(
        out.status.success(),
        "inspect {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

fn topic<'a>(v: &'a Value, name: &str) -> &'a Value {
    v["topics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["topic"] == name)
        .unwrap_or_else(|| panic!("no topic {name} in {}", v["topics"]))
}

fn tool(test: &str, script: &str, args: &[&str]) -> Option<String> {
    let py = python_with(test, &["rosbags", "mcap"])?;
    let mut cmd = Command::new(py);
    if script.ends_with(".py") {
        cmd.arg(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tools")
                .join(script),
        );
    } else {
        cmd.args(["-c", script]);
    }
    let o = cmd.args(args).output().expect("run python");
    assert!(
        o.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    Some(String::from_utf8_lossy(&o.stdout).into_owned())
}

/// Per topic: type, count, first and last log time (ns), by the Python
/// `mcap` reader.
const COUNT_TOPICS: &str = r#"
import json, sys
from mcap.reader import make_reader
out = {}
with open(sys.argv[1], "rb") as f:
    for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
        t = out.setdefault(channel.topic, [schema.name, 0, message.log_time, message.log_time])
        t[1] += 1
        t[2] = min(t[2], message.log_time)
        t[3] = max(t[3], message.log_time)
print(json.dumps(out))
"#;

/// The first 20 s of the bundled bag with the wheel joints renamed, written
/// by `tools/wheel_sources.py`, and its ROS 1 bag and rosbag2 forms.
fn renamed_bags(test: &str, dir: &Path) -> Option<(PathBuf, Vec<PathBuf>)> {
    let src = dir.join("renamed.mcap");
    let args = [BUNDLED, src.to_str()?, "rename", "--until", "20"];
    tool(test, "wheel_sources.py", &args)?;
    let conv = dir.join("conv");
    tool(
        test,
        "bag_convert.py",
        &[src.to_str()?, conv.to_str()?, "--ros1-compression", "lz4"],
    )?;
    let db3 = std::fs::read_dir(conv.join("db3"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "db3"))
        .unwrap();
    Some((
        src,
        vec![
            conv.join("bag.bag"),
            db3,
            conv.join("db3"),
            conv.join("mcap"),
        ],
    ))
}

#[test]
fn inspect_reads_every_bag_format_as_an_independent_reader_counts_it() {
    let dir = scratch("inspect_formats");
    let Some((src, forms)) = renamed_bags("inspect_formats", &dir) else {
        return;
    };
    let counted: Value = serde_json::from_str(
        &tool("inspect_formats", COUNT_TOPICS, &[src.to_str().unwrap()]).unwrap(),
    )
    .unwrap();
    let reference = inspect(&src, &[]);
    for form in std::iter::once(&src).chain(&forms) {
        let v = inspect(form, &[]);
        let what = form.display().to_string();
        let topics = counted.as_object().unwrap();
        assert_eq!(
            v["topics"].as_array().unwrap().len(),
            topics.len(),
            "{what}"
        );
        for (name, c) in topics {
            let t = topic(&v, name);
            let ty = c[0].as_str().unwrap();
            assert_eq!(t["type"], ty, "{what} {name}");
            assert_eq!(t["count"], c[1], "{what} {name}");
            for (key, ns) in [("first_s", &c[2]), ("last_s", &c[3])] {
                let s = ns.as_u64().unwrap() as f64 * 1e-9;
                let got = t[key].as_f64().unwrap();
                assert!((got - s).abs() < 1e-6, "{what} {name} {key}: {got} vs {s}");
            }
        }
        // The chair's LMS111 sits 0.45 m behind the axle, facing backwards.
        let l = &v["laser"];
        assert_eq!(l["source"], "tf_static", "{what}");
        let m: Vec<f64> = serde_json::from_value(l["base_from_laser"].clone()).unwrap();
        assert!(
            (m[0] + 0.45).abs() < 1e-9 && m[1].abs() < 1e-9,
            "{what}: {m:?}"
        );
        assert!(
            (m[2].abs() - std::f64::consts::PI).abs() < 1e-6,
            "{what}: {m:?}"
        );
        // Same answer whatever the container.
        assert_eq!(v["uses"], reference["uses"], "{what}");
        assert_eq!(v["missing"], reference["missing"], "{what}");
    }
    let w = &reference["uses"]["wheels"];
    assert_eq!(w["topic"], "/joint_states");
    assert_eq!(w["configured"], false);
    let set: Vec<String> = serde_json::from_value(w["set"].clone()).unwrap();
    assert!(
        set.iter()
            .any(|s| s.contains("left_joint = \"wheel_l_joint\"")),
        "{set:?}"
    );
    assert!(
        set.iter()
            .any(|s| s.contains("right_joint = \"wheel_r_joint\"")),
        "{set:?}"
    );
}

#[test]
fn the_proposed_robot_file_makes_calibrate_find_the_renamed_wheels() {
    let dir = scratch("inspect_robot");
    let Some((src, forms)) = renamed_bags("inspect_robot", &dir) else {
        return;
    };
    let bag = &forms[0];
    // Without the joints: refused, naming the keys and `odocal inspect`.
    let out_dir = dir.join("cal");
    let args = |robot: &str| {
        vec![
            "calibrate".to_string(),
            "--input".into(),
            bag.display().to_string(),
            "--robot".into(),
            robot.into(),
            "--method".into(),
            "none".into(),
            "--out".into(),
            out_dir.display().to_string(),
            "--json".into(),
        ]
    };
    let run = |a: Vec<String>| odocal(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let bare = dir.join("bare.toml");
    std::fs::write(&bare, "r_right = 0.32\nr_left = 0.32\nwheel_base = 0.65\n").unwrap();
    let o = run(args(bare.to_str().unwrap()));
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("left_joint") && e.contains("odocal inspect"),
        "{e}"
    );

    // inspect writes a robot file; without kinematics it is refused by name.
    let proposed = dir.join("robot.toml");
    let v = inspect(&src, &["--write-robot", proposed.to_str().unwrap()]);
    assert_eq!(v["wrote_robot"], proposed.display().to_string());
    let text = std::fs::read_to_string(&proposed).unwrap();
    assert_eq!(text, v["robot_toml"].as_str().unwrap());
    let o = run(args(proposed.to_str().unwrap()));
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("r_right"));

    // Filled in: calibrate reads the wheels.
    let filled = text
        .replace("# r_right = 0.0", "r_right = 0.32")
        .replace("# r_left = 0.0", "r_left = 0.32")
        .replace("# wheel_base = 0.0", "wheel_base = 0.65");
    std::fs::write(&proposed, filled).unwrap();
    let o = run(args(proposed.to_str().unwrap()));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(s["wheel_source"]["messages"].as_u64().unwrap() > 100, "{s}");
}

#[test]
fn inspect_tells_the_real_recordings_as_their_readme_describes_them() {
    let Some(d) = shared_data("inspect_real") else {
        return;
    };
    // Topics and counts, mountings (data README).
    let intel = inspect(&d.join("slam-benchmark/intel.mcap"), &[]);
    assert_eq!(topic(&intel, "/scan")["count"], 13631);
    assert_eq!(topic(&intel, "/odom")["count"], 26915);
    let span = intel["span_s"][2].as_f64().unwrap();
    assert!((span - 2691.0).abs() < 1.0, "{span}");
    assert_eq!(
        intel["laser"]["base_from_laser"],
        serde_json::json!([0.0, 0.0, 0.0])
    );
    // Intel's odometry twist is zero throughout: no wheel stream to calibrate.
    assert!(
        intel["uses"]["wheels"]["topic"].is_null(),
        "{}",
        intel["uses"]["wheels"]
    );
    assert!(intel["missing"]["icp"].as_array().unwrap().is_empty());
    assert!(!intel["missing"]["calibrate"].as_array().unwrap().is_empty());

    let fr079 = inspect(&d.join("slam-benchmark/fr079.mcap"), &[]);
    let m = fr079["laser"]["base_from_laser"][0].as_f64().unwrap();
    assert!((m - 0.04).abs() < 1e-9, "{m}");
    // fr079 sets the twist: its odometry is proposed as the wheels.
    let w = &fr079["uses"]["wheels"];
    assert_eq!(w["topic"], "/odom");
    assert_eq!(w["wheels"]["source"], "odometry");

    let lego = inspect(&d.join("lego-robot/lego-robot.mcap"), &[]);
    for t in ["/joint_states", "/scan", "/reference"] {
        assert_eq!(topic(&lego, t)["count"], 278, "{t}");
    }
    let l: Vec<f64> = serde_json::from_value(lego["laser"]["base_from_laser"].clone()).unwrap();
    assert!(
        (l[0] - 0.03).abs() < 1e-9 && (l[2] + 0.06981317).abs() < 1e-7,
        "{l:?}"
    );
    assert_eq!(lego["uses"]["wheels"]["configured"], true);
    assert_eq!(lego["uses"]["reference"]["topic"], "/reference");
    assert_eq!(
        lego["config_toml"].as_str().unwrap().trim(),
        "[topics]\nreference = \"/reference\""
    );

    let rover = inspect(&d.join("mines-rover/exp1.mcap"), &[]);
    assert_eq!(topic(&rover, "/scan")["count"], 756);
    let r = rover["laser"]["base_from_laser"][0].as_f64().unwrap();
    assert!((r - 0.145).abs() < 1e-9);
    let beams = &topic(&rover, "/scan")["detail"]["beams"];
    assert_eq!(beams, 682);

    // A CARMEN log: its laser lines and the mounting they state.
    let clf = inspect(&d.join("slam-benchmark/mit-csail.clf"), &[]);
    assert_eq!(clf["format"], "CARMEN log");
    assert_eq!(clf["topics"][0]["count"], 1988);
    assert_eq!(clf["laser"]["source"], "log");
    assert!(
        clf["missing"]["icp"].as_array().unwrap().is_empty(),
        "{}",
        clf["missing"]
    );
}

#[test]
fn inspect_refuses_what_is_not_a_recording_by_name() {
    let dir = scratch("inspect_bad");
    let cut = dir.join("cut.mcap");
    let bytes = std::fs::read(BUNDLED).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let o = odocal(&["inspect", cut.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cut.mcap"));
    let o = odocal(&["inspect", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("metadata.yaml"));
    // --write-robot never overwrites the input.
    let o = odocal(&["inspect", BUNDLED, "--write-robot", BUNDLED]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn tick_counters_are_proposed_with_their_type_and_what_the_bag_cannot_tell() {
    let dir = scratch("inspect_ticks");
    let bag = dir.join("ticks.mcap");
    let args = [
        BUNDLED,
        bag.to_str().unwrap(),
        "ticks",
        "--ticks-per-rev",
        "8800",
        "--bits",
        "16",
        "--until",
        "20",
    ];
    if tool("inspect_ticks", "wheel_sources.py", &args).is_none() {
        return;
    }
    let robot = dir.join("robot.toml");
    let v = inspect(&bag, &["--write-robot", robot.to_str().unwrap()]);
    let w = &v["uses"]["wheels"];
    assert_eq!(w["topic"], "/wheel_ticks");
    assert_eq!(w["wheels"]["source"], "ticks");
    assert_eq!(w["wheels"]["ticks_type"], "std_msgs/msg/Int32MultiArray");
    assert!(w["why"].as_str().unwrap().contains("left_index"), "{w}");
    // The written [wheels] table reads, once the kinematics, the ticks per
    // revolution and the counters' order (data = [right, left]) are given.
    let text = std::fs::read_to_string(&robot).unwrap();
    let filled = text
        .replace("# r_right = 0.0", "r_right = 0.32")
        .replace("# r_left = 0.0", "r_left = 0.32")
        .replace("# wheel_base = 0.0", "wheel_base = 0.65")
        .replace("# ticks_per_rev = 0", "ticks_per_rev = 8800")
        .replace("left_index = 0", "left_index = 1")
        .replace("right_index = 1", "right_index = 0")
        .replace("# ticks_wrap_bits = 16", "ticks_wrap_bits = 16");
    std::fs::write(&robot, filled).unwrap();
    let out = dir.join("cal");
    let o = odocal(&[
        "calibrate",
        "--input",
        bag.to_str().unwrap(),
        "--robot",
        robot.to_str().unwrap(),
        "--method",
        "none",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["wheel_source"]["kind"], "ticks", "{s}");
}

/// `inspect` says which stream `icp` and `calibrate` will start each scan
/// pair from, as those runs then state it: with a wheel stream and the
/// robot's own odometry, the odometry unless a robot file states the
/// wheels' kinematics; the real CARMEN log, its odometry.
#[test]
fn inspect_names_the_scan_matchers_prior_as_the_runs_take_it() {
    use odocal::io::{read_recording, write_mcap, ReadOptions, WriteOptions};
    let d = scratch("inspect_prior");
    let mut rec = read_recording(Path::new(BUNDLED), &ReadOptions::default()).unwrap();
    let end = rec.scans[0].stamp + 3.0;
    rec.scans.retain(|s| s.stamp <= end);
    rec.wheels.retain(|s| s.stamp <= end);
    rec.reference.retain(|s| s.stamp <= end);
    rec.odom = std::mem::take(&mut rec.reference);
    let bag = d.join("both.mcap");
    write_mcap(&bag, &rec, &WriteOptions::default()).unwrap();
    for (robot, want) in [(None, "odometry"), (Some("wheelchair"), "wheels")] {
        let extra: Vec<&str> = robot.iter().flat_map(|r| ["--robot", *r]).collect();
        let v = inspect(&bag, &extra);
        assert_eq!(v["prior"]["stream"], want, "{}", v["prior"]);
        let mut args = vec!["icp", "--input", bag.to_str().unwrap(), "--json", "--out"];
        let tum = d.join("both.tum");
        args.push(tum.to_str().unwrap());
        args.extend(&extra);
        let out = odocal(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let run: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(run["assumptions"]["prior"]["value"], want);
    }
    assert_eq!(
        inspect(Path::new(BUNDLED), &[])["prior"]["stream"],
        "wheels"
    );
    if let Some(data) = shared_data("inspect_names_the_scan_matchers_prior_as_the_runs_take_it") {
        let clf = data.join("slam-benchmark/mit-csail.clf");
        assert_eq!(inspect(&clf, &[])["prior"]["stream"], "odometry");
    }
}
