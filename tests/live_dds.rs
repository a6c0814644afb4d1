//! `odocal live` on a DDS domain against an independent peer: Cyclone DDS
//! from PyPI (`tools/live_peer.py`, no ROS and nothing of odocal) plays the
//! bundled recording at 3× real time with ROS 2's type names and QoS, and
//! listens to what the node publishes; after SIGINT the node's summary
//! agrees with the offline `calibrate` of the same recording. Malformed and
//! oversized scans from a second publisher are refused and survived. Both
//! sides on 127.0.0.1, on a domain of their own.

use crate::support;
use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

/// A domain no other test run shares (ROS 2 allows 0–232; high ones are
/// rarely used by robots on the same host).
fn domain() -> u16 {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .subsec_nanos();
    150 + ((std::process::id() ^ t) % 80) as u16
}

fn summary(dir: &std::path::Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json"))
        .unwrap_or_else(|e| panic!("{}: {e}", dir.join("summary.json").display()));
    serde_json::from_str(&text).unwrap()
}

fn param(s: &serde_json::Value, k: &str) -> f64 {
    s["final"][k]
        .as_f64()
        .unwrap_or_else(|| panic!("{k} in {s}"))
}

#[test]
fn live_on_loopback_agrees_with_offline_calibrate_and_survives_bad_messages() {
    let Some(py) = support::python_with("live_on_loopback", &["cyclonedds", "mcap"]) else {
        return;
    };
    let dir = support::scratch("live_on_loopback");
    let (offline, live) = (dir.join("offline"), dir.join("live"));
    let o = support::odocal(&[
        "calibrate",
        "--input",
        BUNDLED,
        "--out",
        offline.to_str().unwrap(),
        "--json",
    ]);
    support::ok_json(&o);
    let cfg = dir.join("live.toml");
    // The oversized scan of the peer (200 000 beams, 800 kB) is above this.
    std::fs::write(
        &cfg,
        "[live]\nlocalhost_only = true\nwait_s = 60.0\nmax_message_bytes = 400000\n",
    )
    .unwrap();
    let d = domain();
    let rrd = dir.join("live.rrd");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_odocal"));
    cmd.args(["live", "--out", live.to_str().unwrap(), "--config"])
        .arg(&cfg);
    // The run recorded for the Rerun viewer as it goes (as `--connect`
    // streams it), when built with Rerun.
    if cfg!(feature = "rerun") {
        cmd.arg("--rrd").arg(&rrd);
    }
    let mut node = cmd
        .env("ROS_DOMAIN_ID", d.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start odocal live");
    let peer = Command::new(&py)
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/tools/live_peer.py"))
        .args(["publish", "--domain", &d.to_string(), "--mcap", BUNDLED])
        .args(["--rate", "3", "--malformed", "3", "--linger", "3"])
        .output()
        .expect("run the peer");
    // SIGINT, as Ctrl-C: the node writes its outputs and ends.
    unsafe { libc::kill(node.id() as i32, libc::SIGINT) };
    let begun = Instant::now();
    let status = loop {
        if let Some(s) = node.try_wait().unwrap() {
            break s;
        }
        if begun.elapsed() > Duration::from_secs(60) {
            let _ = node.kill();
            panic!("odocal live did not end within 60 s of SIGINT");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let mut err = String::new();
    node.stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert!(
        peer.status.success(),
        "peer: {}",
        String::from_utf8_lossy(&peer.stderr)
    );
    assert!(status.success(), "odocal live: {status:?}\n{err}");
    let heard: serde_json::Value = serde_json::from_slice(&peer.stdout).unwrap();
    assert_eq!(heard["matched"], true, "{heard}\n{err}");

    // What the peer heard: the odometry at the wheels' rate and in order,
    // the diagnostics with odocal's status and its values.
    let sent_wheels = heard["sent"]["/joint_states"].as_u64().unwrap();
    let odom = heard["odometry_received"].as_u64().unwrap();
    assert!(
        odom as f64 > 0.9 * sent_wheels as f64,
        "{odom} odometry messages for {sent_wheels} wheel messages\n{err}"
    );
    assert_eq!(heard["odometry_stamps_increase"], true);
    assert_eq!(heard["last_odometry"]["frame_id"], "odom");
    assert_eq!(heard["last_odometry"]["child_frame_id"], "base_link");
    // 25 s of play at 3×, diagnostics at 1 Hz.
    assert!(
        heard["diagnostics_received"].as_u64().unwrap() >= 15,
        "{heard}"
    );
    let values = &heard["last_status"]["values"];
    for k in [
        "r_right",
        "r_left",
        "wheel_base",
        "r_right_std",
        "time_offset",
    ] {
        assert!(values[k].is_string(), "{k} missing from {values}");
    }
    let levels = heard["levels_seen"].as_array().unwrap();
    assert!(
        levels.contains(&1.into()),
        "WARN while warming up: {levels:?}"
    );

    // The calibration agrees with the offline one; the nominal values (the
    // do-nothing answer) would not.
    let (a, b) = (summary(&offline), summary(&live));
    let nominal = [("r_right", 0.32), ("r_left", 0.32), ("wheel_base", 0.65)];
    for (k, tol) in [("r_right", 1e-3), ("r_left", 1e-3), ("wheel_base", 3e-3)] {
        let (off, on) = (param(&a, k), param(&b, k));
        assert!(
            (off - on).abs() < tol,
            "{k}: live {on} vs offline {off}\n{err}"
        );
    }
    // Negative control: the same 1 mm check on the nominal radii fails.
    let misses = nominal[..2]
        .iter()
        .filter(|(k, n)| (param(&a, k) - n).abs() >= 1e-3)
        .count();
    assert!(
        misses > 0,
        "the nominal radii pass the 1 mm check: it proves nothing"
    );
    // The status published matches the summary's estimate.
    let r: f64 = values["r_right"].as_str().unwrap().parse().unwrap();
    assert!((r - param(&b, "r_right")).abs() < 1e-3, "{values}");

    // The malformed scans and the oversized one: refused, counted, survived.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(live.join("live.json")).unwrap()).unwrap();
    let [_, _, oversized, refused] = [0, 1, 2, 3].map(|i| report["messages"][i].as_u64().unwrap());
    assert!(refused >= 3, "{report}\n{err}");
    assert!(oversized >= 1, "{report}\n{err}");
    assert!(err.contains("/scan: message refused: CDR"), "{err}");
    for f in ["calibration.csv", "trajectory.tum", "summary.json"] {
        assert!(live.join(f).is_file(), "{f} written");
    }
    if cfg!(feature = "rerun") {
        let n = std::fs::metadata(&rrd).map_or(0, |m| m.len());
        assert!(n > 100_000, "{}: {n} bytes", rrd.display());
    }
}

/// `odocal play` publishes the bundled recording as its robot did: an
/// independent Cyclone DDS subscriber with ROS 2's type names receives each
/// topic's messages (its own CDR decoding of odocal's payloads), in stamp
/// order, the static transform latched, the first scan as the bag has it.
#[test]
fn play_publishes_the_recording_to_an_independent_subscriber() {
    let Some(py) = support::python_with("play_to_peer", &["cyclonedds", "mcap"]) else {
        return;
    };
    let dir = support::scratch("play_to_peer");
    let cfg = dir.join("live.toml");
    std::fs::write(&cfg, "[live]\nlocalhost_only = true\n").unwrap();
    let d = domain();
    let listener = Command::new(&py)
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/tools/live_peer.py"))
        .args(["listen", "--domain", &d.to_string(), "--seconds", "25"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the listener");
    let played = Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args([
            "play", BUNDLED, "--rate", "5", "--delay", "4", "--json", "--config",
        ])
        .arg(&cfg)
        .env("ROS_DOMAIN_ID", d.to_string())
        .output()
        .expect("run odocal play");
    let played = support::ok_json(&played);
    let heard = listener.wait_with_output().unwrap();
    assert!(
        heard.status.success(),
        "{}",
        String::from_utf8_lossy(&heard.stderr)
    );
    let heard: serde_json::Value = serde_json::from_slice(&heard.stdout).unwrap();
    // The bag: 1875 scans, 7501 joint states and gyro samples, 1 transform
    // (and 751 ground-truth poses, which the listener does not read).
    assert_eq!(played["messages"], 1875 + 2 * 7501 + 1 + 751, "{played}");
    for (topic, n) in [("/scan", 1875), ("/joint_states", 7501), ("/imu", 7501)] {
        let got = heard["counts"][topic].as_u64().unwrap();
        assert!(
            got as f64 >= 0.99 * n as f64,
            "{topic}: {got} of {n}: {heard}"
        );
        assert_eq!(heard["ordered"][topic], true, "{topic} out of order");
    }
    assert_eq!(heard["counts"]["/tf_static"], 1, "{heard}");
    assert_eq!(heard["tf_static"]["child"], "laser");
    assert!((heard["tf_static"]["x"].as_f64().unwrap() + 0.45).abs() < 1e-12);
    let scan = &heard["first_scan"];
    assert_eq!(scan["frame_id"], "laser");
    assert_eq!(scan["beams"], 541);
    assert!(
        (scan["angle_min"].as_f64().unwrap() + 2.356194).abs() < 1e-5,
        "{scan}"
    );
    assert!(
        (heard["last_stamp"]["/scan"].as_f64().unwrap() - 74.96).abs() < 0.05,
        "{heard}"
    );
}
