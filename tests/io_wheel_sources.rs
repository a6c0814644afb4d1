//! The wheels as other robots report them, written by an independent writer
//! (`tools/wheel_sources.py`: Python `mcap` + `rosbags`) from the bundled
//! simulated recording: a controller's `nav_msgs/Odometry` twist instead of
//! the JointState, encoder tick counters that wrap around, JointState with
//! other joint names. Calibrating the twist finds the multipliers the
//! simulator's truth implies for that controller; the ticks calibrate as the
//! JointState does; every bag reader reads both alike; what cannot be used
//! is refused naming the robot-file keys.

use std::path::{Path, PathBuf};

use odocal::io::{collect, open, ReadOptions};
use odocal::recording::{Recording, WheelValues};
use odocal::robot::RobotConfig;

use crate::support::{odocal, python_tool, python_with, scratch};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);
const TRUTH: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.truth.json"
);

/// The controller that publishes the twist: its configured wheel radius and
/// separation (m), deliberately not the chair's true 0.3188/0.3214/0.65.
const CTRL_RADIUS: f64 = 0.33;
const CTRL_SEPARATION: f64 = 0.67;

const ODOM_ROBOT: &str = "name = \"controller\"\nr_right = 0.33\nr_left = 0.33\n\
    wheel_base = 0.67\n[laser]\nx = -0.45\ny = 0.0\nyaw = 3.141592653589793\n\
    [wheels]\nsource = \"odometry\"\n";
/// Right counter first: the indices are not the defaults.
const TICKS_ROBOT: &str = "r_right = 0.32\nr_left = 0.32\nwheel_base = 0.65\n\
    ticks_per_rev = 8800\n[wheels]\nsource = \"ticks\"\ntopic = \"/wheel_ticks\"\n\
    ticks_type = \"std_msgs/msg/Int32MultiArray\"\nleft_index = 1\nright_index = 0\n\
    ticks_wrap_bits = 16\n";

/// Runs `tools/wheel_sources.py SRC OUT ARGS...`; `None` (skip) without
/// Python, mcap and rosbags outside CI.
fn wheel_sources(test: &str, src: &Path, out: &Path, args: &[&str]) -> Option<()> {
    let py = python_with(test, &["mcap", "rosbags", "numpy"])?;
    let mut all = vec![src.as_os_str(), out.as_os_str()];
    all.extend(args.iter().map(std::ffi::OsStr::new));
    python_tool(&py, "wheel_sources.py", &all);
    Some(())
}

/// The twist-only bag: JointState replaced by the controller's odometry.
fn odometry_bag(test: &str, dir: &Path, extra: &[&str]) -> Option<PathBuf> {
    let out = dir.join("odom.mcap");
    let (r, d) = (CTRL_RADIUS.to_string(), CTRL_SEPARATION.to_string());
    let mut args = vec!["odometry", "--radius", &r, "--separation", &d];
    args.extend(extra);
    wheel_sources(test, Path::new(BUNDLED), &out, &args)?;
    Some(out)
}

/// The ticks-only bag: 16-bit signed counters starting near their top, so
/// they wrap within the first metres and again and again after.
fn ticks_bag(test: &str, dir: &Path, extra: &[&str]) -> Option<PathBuf> {
    let out = dir.join("ticks.mcap");
    let mut args = vec![
        "ticks",
        "--ticks-per-rev",
        "8800",
        "--bits",
        "16",
        "--start",
        "32000",
    ];
    args.extend(extra);
    wheel_sources(test, Path::new(BUNDLED), &out, &args)?;
    Some(out)
}

/// `odocal calibrate --method dkf --json` on `input` with robot file `robot`.
fn calibrate(input: &Path, robot: &Path, out: &Path) -> serde_json::Value {
    let (i, r, o) = (path(input), path(robot), path(out));
    let run = odocal(&[
        "calibrate",
        "--input",
        i,
        "--robot",
        r,
        "--method",
        "dkf",
        "--out",
        o,
        "--json",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_slice(&run.stdout).unwrap()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// The simulator's true (r_right, r_left, wheel_base) at the end of the run.
fn final_truth() -> [f64; 3] {
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(TRUTH).unwrap()).unwrap();
    let last = t["parameters"].as_array().unwrap().last().unwrap().clone();
    assert!(num(&last["t"]) >= 74.9, "truth ends at {}", last["t"]);
    [
        num(&last["r_right"]),
        num(&last["r_left"]),
        num(&last["wheel_base"]),
    ]
}

#[test]
fn an_odometry_twist_calibrates_the_controllers_multipliers() {
    let test = "an_odometry_twist_calibrates_the_controllers_multipliers";
    let dir = scratch(test);
    let Some(bag) = odometry_bag(test, &dir, &[]) else {
        return;
    };
    let robot = dir.join("robot.toml");
    std::fs::write(&robot, ODOM_ROBOT).unwrap();
    let v = calibrate(&bag, &robot, &dir.join("out"));
    let ws = &v["wheel_source"];
    assert_eq!(ws["kind"], "odometry", "{ws}");
    assert_eq!(ws["topic"], "/odom");
    assert_eq!(ws["type"], "nav_msgs/msg/Odometry");
    assert_eq!(ws["values"], "twist");
    assert_eq!(ws["source"], "robot_file");
    assert_eq!(ws["messages"], 7501);
    let notes = ws["notes"].to_string();
    assert!(
        notes.contains("not seen") && notes.contains("lag"),
        "{notes}"
    );
    // What diff_drive_controller should be told: true / configured.
    let [rr, rl, d] = final_truth();
    let m = &v["multipliers"];
    let want = [
        // Within 0.3 % of multipliers that depart 3.4 % from 1.
        ("right_wheel_radius", rr / CTRL_RADIUS, 3e-3),
        ("left_wheel_radius", rl / CTRL_RADIUS, 3e-3),
        ("wheel_separation", d / CTRL_SEPARATION, 3e-3),
    ];
    let within = |got: &dyn Fn(&str) -> f64| -> Result<(), String> {
        for (key, truth, tol) in want {
            let g = got(key);
            if (g - truth).abs() >= tol {
                return Err(format!("{key}: {g:.5}, truth {truth:.5}"));
            }
        }
        Ok(())
    };
    within(&|key| num(&m[key])).unwrap();
    // The negative control: the controller's configured values (every
    // multiplier 1) fail the same check.
    assert!(within(&|_| 1.0).is_err());
    // The odometry's scales, by driving the controller with the true wheels:
    // a straight metre (each wheel turns 1/R_true) and an in-place turn.
    let reported_metre = CTRL_RADIUS * (1.0 / rr + 1.0 / rl) / 2.0;
    let reported_turn = CTRL_RADIUS * (1.0 / rr + 1.0 / rl) / CTRL_SEPARATION;
    let true_turn = 2.0 / d;
    let s = &v["odometry_scale"];
    let (linear, angular) = (num(&s["linear"]), num(&s["angular"]));
    assert!(
        (linear - 1.0 / reported_metre).abs() < 2e-3,
        "linear {linear}"
    );
    // (An odometry taken as right in distance, scale 1, fails that bound;
    // its turns here happen to be right within 0.3 %.)
    assert!((1.0 - 1.0 / reported_metre).abs() > 2e-3);
    assert!(
        (angular - true_turn / reported_turn).abs() < 3e-3,
        "angular {angular}, truth {}",
        true_turn / reported_turn
    );
    // The human output names the source.
    let human = odocal(&[
        "calibrate",
        "--input",
        path(&bag),
        "--robot",
        path(&robot),
        "--method",
        "dkf",
        "--out",
        path(&dir.join("out2")),
    ]);
    let err = String::from_utf8_lossy(&human.stderr);
    assert!(human.status.success(), "{err}");
    assert!(
        err.contains("wheels from /odom twist (nav_msgs/msg/Odometry), robot file [wheels] source"),
        "{err}"
    );
    assert!(err.contains("odometry_scale"), "{err}");
    // The same robot file without [wheels]: the bag's one wheel stream is
    // found and said to be, and calibrates to the same multipliers. Without
    // the finding this run stops at the JointState default (exit 2).
    let found_robot = dir.join("found.toml");
    std::fs::write(&found_robot, ODOM_ROBOT.split("[wheels]").next().unwrap()).unwrap();
    let found = calibrate(&bag, &found_robot, &dir.join("out3"));
    let fs = &found["wheel_source"];
    assert_eq!(fs["kind"], "odometry", "{fs}");
    assert_eq!(fs["topic"], "/odom");
    assert_eq!(fs["source"], "recording", "{fs}");
    assert!(
        fs["notes"][0]
            .as_str()
            .unwrap()
            .contains("one wheel stream"),
        "{fs}"
    );
    assert_eq!(found["multipliers"], v["multipliers"]);
}

#[test]
fn encoder_ticks_that_wrap_calibrate_as_the_joint_states_do() {
    let test = "encoder_ticks_that_wrap_calibrate_as_the_joint_states_do";
    let dir = scratch(test);
    let Some(bag) = ticks_bag(test, &dir, &[]) else {
        return;
    };
    let robot = dir.join("robot.toml");
    std::fs::write(&robot, TICKS_ROBOT).unwrap();
    let ticks = calibrate(&bag, &robot, &dir.join("ticks"));
    let wheelchair = dir.join("wheelchair.toml");
    std::fs::write(&wheelchair, TICKS_ROBOT.split("[wheels]").next().unwrap()).unwrap();
    let joints = calibrate(Path::new(BUNDLED), &wheelchair, &dir.join("joints"));
    assert_eq!(joints["wheel_source"]["kind"], "joint_states");
    assert_eq!(joints["wheel_source"]["values"], "positions");
    let ws = &ticks["wheel_source"];
    assert_eq!(ws["kind"], "ticks", "{ws}");
    assert_eq!(ws["topic"], "/wheel_ticks");
    assert_eq!(ws["type"], "std_msgs/msg/Int32MultiArray");
    assert_eq!(ws["values"], "ticks");
    // Each run states the wheel keys its source uses: the tick counts per
    // revolution for the counters, the joint names for the JointStates.
    let (ta, ja) = (&ticks["assumptions"], &joints["assumptions"]);
    assert_eq!(ta["ticks_per_rev"]["source"], "robot_file", "{ta}");
    assert!(ta.get("left_joint").is_none(), "{ta}");
    assert!(ja.get("ticks_per_rev").is_none(), "{ja}");
    assert_eq!(ja["left_joint"]["value"], "left_wheel", "{ja}");
    for key in ["r_right", "r_left", "wheel_base"] {
        let (a, b) = (num(&ticks["final"][key]), num(&joints["final"][key]));
        assert!((a - b).abs() < 1e-5, "{key}: ticks {a}, JointState {b}");
    }
    // diagnose says where its wheels came from too.
    let d = odocal(&[
        "diagnose",
        "--measured",
        path(&bag),
        "--robot",
        path(&robot),
        "--json",
    ]);
    assert!(d.status.success(), "{}", String::from_utf8_lossy(&d.stderr));
    let d: serde_json::Value = serde_json::from_slice(&d.stdout).unwrap();
    assert_eq!(d["wheel_source"]["kind"], "ticks", "{}", d["wheel_source"]);
    assert_eq!(d["wheel_source"]["messages"], 7501);
    // The counters did wrap: the wheels turned through far more than 2^15
    // ticks of 2π/8800 rad.
    let rec = read(
        &bag,
        &ReadOptions::for_robot(&RobotConfig::from_toml(TICKS_ROBOT).unwrap()),
    );
    let turned = rec.wheels.last().unwrap().right - rec.wheels[0].right;
    assert!(
        turned * 8800.0 / std::f64::consts::TAU > 4.0 * 32768.0,
        "{turned} rad"
    );
}

#[test]
fn wheels_that_cannot_be_read_exit_2_naming_the_robot_file_keys() {
    let test = "wheels_that_cannot_be_read_exit_2_naming_the_robot_file_keys";
    let dir = scratch(test);
    let renamed = dir.join("renamed.mcap");
    if wheel_sources(
        test,
        Path::new(BUNDLED),
        &renamed,
        &["rename", "--until", "5"],
    )
    .is_none()
    {
        return;
    }
    let run = |input: &Path, robot: &str, name: &str| {
        let r = dir.join(name);
        std::fs::write(&r, robot).unwrap();
        let o = odocal(&[
            "calibrate",
            "--input",
            path(input),
            "--robot",
            path(&r),
            "--method",
            "dkf",
            "--out",
            path(&dir.join("out")),
        ]);
        assert_eq!(o.status.code(), Some(2), "{name}");
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let wheelchair = TICKS_ROBOT.split("[wheels]").next().unwrap().to_string()
        + "[laser]\nx = -0.45\ny = 0.0\nyaw = 3.141592653589793\n";
    let e = run(&renamed, &wheelchair, "wheelchair.toml");
    for word in [
        "renamed.mcap",
        "/joint_states",
        "message 0",
        "'left_wheel'",
        "wheel_l_joint",
        "wheel_r_joint",
        "left_joint",
        "right_joint",
    ] {
        assert!(e.contains(word), "{word}: {e}");
    }
    // The robot file asks for a twist the recording does not have.
    let e = run(Path::new(BUNDLED), ODOM_ROBOT, "odom.toml");
    for word in [
        "wheelchair-corridor.mcap",
        "0 nav_msgs/msg/Odometry messages on /odom",
        "[wheels] source",
        "topic",
        "odocal inspect",
    ] {
        assert!(e.contains(word), "{word}: {e}");
    }
    // No [wheels]: the JointState default, on a bag whose wheels are ticks.
    let Some(ticks) = ticks_bag(test, &dir, &["--until", "5"]) else {
        return;
    };
    let e = run(&ticks, &wheelchair, "wheelchair2.toml");
    for word in [
        "/joint_states",
        "no [wheels] table",
        "[wheels] source and topic",
    ] {
        assert!(e.contains(word), "{word}: {e}");
    }
    // A twist that is zero throughout (an odometry of poses only).
    let still = dir.join("still.mcap");
    let args = [
        "odometry",
        "--radius",
        "0",
        "--separation",
        "1",
        "--until",
        "5",
    ];
    wheel_sources(test, Path::new(BUNDLED), &still, &args).unwrap();
    let e = run(&still, ODOM_ROBOT, "odom2.toml");
    assert!(e.contains("/odom") && e.contains("twist is zero"), "{e}");
}

fn read(path: &Path, opts: &ReadOptions) -> Recording {
    let mut source = open(path, opts).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    collect(&mut *source).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Converts `src` with `tools/bag_convert.py` into a ROS 1 bag and rosbag2
/// folders (SQLite, MCAP); the paths of each form.
fn every_form(test: &str, src: &Path, out: &Path) -> Option<Vec<PathBuf>> {
    let py = python_with(test, &["rosbags", "mcap"])?;
    python_tool(&py, "bag_convert.py", &[src, out]);
    let db3 = out.join("db3/db3.db3");
    Some(vec![
        src.to_path_buf(),
        out.join("bag.bag"),
        db3,
        out.join("db3"),
        out.join("mcap"),
    ])
}

#[test]
fn every_bag_reader_reads_twist_and_ticks_into_the_same_wheel_angles() {
    let test = "every_bag_reader_reads_twist_and_ticks_into_the_same_wheel_angles";
    let dir = scratch(test);
    let short = ["--until", "10", "--drop", "/scan", "--drop", "/imu"];
    let Some(odom) = odometry_bag(test, &dir, &short) else {
        return;
    };
    let ticks = ticks_bag(test, &dir, &short).unwrap();
    let joints = read(Path::new(BUNDLED), &ReadOptions::default()).wheels;
    let odom_opts = ReadOptions::for_robot(&RobotConfig::from_toml(ODOM_ROBOT).unwrap());
    let ticks_opts = ReadOptions::for_robot(&RobotConfig::from_toml(TICKS_ROBOT).unwrap());
    for (bag, opts, values, form) in [
        (&odom, &odom_opts, WheelValues::Twist, "odom"),
        (&ticks, &ticks_opts, WheelValues::Ticks, "ticks"),
    ] {
        let forms = every_form(test, bag, &dir.join(form)).unwrap();
        let first = read(&forms[0], opts);
        assert_eq!(first.wheel_values, Some(values));
        assert!(first.wheels.len() > 900, "{form}: {}", first.wheels.len());
        for p in &forms[1..] {
            let r = read(p, opts);
            assert_eq!(r.wheels, first.wheels, "{}", p.display());
            assert_eq!(r.wheel_values, Some(values), "{}", p.display());
        }
        expect_from_joints(&first, &joints, values);
    }
}

/// The wheel angles against the JointState positions φ they came from,
/// relative to the first: ticks give φ_k − φ_0 (to the tick); the twist of
/// backward differences, integrated by the trapezoidal rule from a zero
/// first twist, gives the mean of φ_k and φ_(k−1), minus φ_0.
fn expect_from_joints(rec: &Recording, joints: &[odocal::recording::WheelSample], v: WheelValues) {
    for (k, w) in rec.wheels.iter().enumerate() {
        let j = &joints[k];
        assert!((w.stamp - j.stamp).abs() < 1e-9, "sample {k}");
        let prev = &joints[k.saturating_sub(1)];
        let expect = |now: f64, before: f64, first: f64| match v {
            WheelValues::Ticks => now - first,
            _ => 0.5 * (now + before) - first,
        };
        let l = expect(j.left, prev.left, joints[0].left);
        let r = expect(j.right, prev.right, joints[0].right);
        assert!(
            (w.left - l).abs() < 1e-6 && (w.right - r).abs() < 1e-6,
            "{v:?} sample {k}: ({}, {}) vs ({l}, {r})",
            w.left,
            w.right
        );
    }
}
