//! The diagnosis on real measured data (shared data folder, see its README):
//! a tracked LEGO robot with an overhead-tracked reference, the Paris Mines
//! rover, Censi et al.'s Khepera calibration tuples and the Intel lab's
//! integrated odometry. Each test asserts a finding that an independent
//! source supports (the data README's checks, the authors' published
//! calibration), with bounds wide enough for the noise of the data.

use crate::support::shared_data;
use odocal::diagnose::{diagnose, Cause, DiagnoseParams, Diagnosis, Measured, Verdict};
use odocal::icp::IcpParams;
use odocal::io::{censi, read_recording, ReadOptions};
use odocal::motion::Motion;
use odocal::pipeline::{self, load_robot};
use odocal::recording::Recording;
use odocal::robot::RobotConfig;
use std::path::{Path, PathBuf};

fn robot_file(name: &str) -> RobotConfig {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scans/robots/{name}.toml"));
    load_robot(Some(&p)).unwrap()
}

fn read(path: &Path, robot: &RobotConfig, reference: &str) -> Recording {
    let mut opts = ReadOptions::for_robot(robot);
    opts.topics.reference = reference.into();
    read_recording(path, &opts).unwrap()
}

/// ICP of the recording with every `stride`-th beam (keeps debug runs short).
fn motions(rec: &Recording, robot: &RobotConfig, stride: usize) -> Vec<Motion> {
    let icp = IcpParams {
        beam_stride: stride,
        ..IcpParams::default()
    };
    let icp = pipeline::diagnose::icp_for_diagnosis(&icp);
    pipeline::icp::match_recording(rec, robot, &icp)
        .unwrap()
        .motions
}

fn cause<'a>(d: &'a Diagnosis, effect: &str) -> Option<&'a Cause> {
    d.causes.iter().find(|c| c.effect == effect)
}

fn show(what: &str, d: &Diagnosis) {
    eprintln!(
        "{what}: {:?}\n  causes {:?}\n  held-out rejected {:?}\n  gain {:?}\n  noise {:?} rows {:?}",
        d.verdict, d.causes, d.heldout_rejected, d.gain, d.noise_scale, d.rows
    );
}

fn candidates(names: &[&str]) -> DiagnoseParams {
    DiagnoseParams {
        candidates: names.iter().map(|s| s.to_string()).collect(),
        ..DiagnoseParams::default()
    }
}

/// LEGO NXT tracked robot: the scans are stamped late relative to the
/// encoders (and to the overhead tracker, which is in step with the
/// encoders: data README), and the tracks turn the robot less than a 150 mm
/// wheel base predicts (a tracked vehicle's effective track is wider; the
/// README's dead reckoning against the tracker fits ≈ 172 mm).
#[test]
fn lego_robot_scans_lag_and_the_effective_track_is_wider_than_nominal() {
    let Some(data) = shared_data("lego_robot_diagnosis") else {
        return;
    };
    let robot = robot_file("lego-robot");
    let rec = read(
        &data.join("lego-robot/lego-robot.mcap"),
        &robot,
        "/reference",
    );
    assert!(rec.reference.len() > 200 && rec.reference.iter().all(|r| !r.has_heading));
    let m = motions(&rec, &robot, 2);
    let measured = Measured::new(&rec, &m);

    let d = diagnose(&robot, &measured, &DiagnoseParams::default()).unwrap();
    show("lego, every candidate", &d);
    assert!(
        matches!(d.verdict, Verdict::Explained | Verdict::PartlyExplained),
        "{:?}",
        d.verdict
    );
    let lat = cause(&d, "latency").expect("latency named");
    let delay = lat.parameters["delay"];
    assert!((-0.5..-0.3).contains(&delay), "delay {delay}");
    assert!(lat.stderr["delay"] < 0.05);
    assert!(d.gain.relative > 0.15, "{:?}", d.gain);
    // With every candidate, what the tracker supports: a track that turns
    // the robot less than the nominal 150 mm (a wider base, or one that
    // widens in turns as tracks skid), never an encoder gain that makes the
    // tracker's error worse; and both errors against it shrink.
    assert!(cause(&d, "encoder_gain").is_none(), "{:?}", d.causes);
    let wider = cause(&d, "wheel_base_scale").is_some_and(|c| c.parameters["scale"] > 0.0)
        || cause(&d, "turn_slip").is_some_and(|c| c.parameters["k"] > 0.0);
    assert!(wider, "{:?}", d.causes);
    let t = d.gain.trajectory.expect("tracker covers the held-out part");
    assert!(t.rpe_after < t.rpe_before, "{t:?}");
    assert!(t.ate_after.unwrap() < t.ate_before.unwrap(), "{t:?}");

    // The calibration family (latency, radii, wheel base): the wheel base
    // is what the data asks for, and it is wider than nominal.
    let p = candidates(&["latency", "radius_scale", "wheel_base_scale"]);
    let d = diagnose(&robot, &measured, &p).unwrap();
    show("lego, latency + radii + wheel base", &d);
    let wb = cause(&d, "wheel_base_scale").expect("wheel base named");
    let width = robot.wheel_base * (1.0 + wb.parameters["scale"]);
    eprintln!(
        "lego effective track width {:.1} ± {:.1} mm",
        width * 1e3,
        robot.wheel_base * wb.stderr["scale"] * 1e3
    );
    assert!((0.160..0.200).contains(&width), "width {width}");
    assert!(wb.parameters["scale"] > 3.0 * wb.stderr["scale"]);
    assert!(d.gain.relative > 0.15, "{:?}", d.gain);
    let traj = d
        .gain
        .trajectory
        .expect("reference overlaps the held-out part");
    let (before, after) = (traj.ate_before.unwrap(), traj.ate_after.unwrap());
    assert!(after < before, "held-out ATE {before} -> {after}");
}

/// Paris Mines rover, no reference: against ICP the encoder stream leads the
/// scans by about 0.16 s in both recordings (the scan is older than its
/// stamp), and that alone removes most of the turn-rate residual.
#[test]
fn mines_rover_scans_lag_the_encoders_in_both_recordings() {
    let Some(data) = shared_data("mines_rover_diagnosis") else {
        return;
    };
    let robot = robot_file("mines-rover");
    let mut delays = Vec::new();
    for name in ["exp1", "exp2"] {
        let rec = read(
            &data.join(format!("mines-rover/{name}.mcap")),
            &robot,
            "/ground_truth",
        );
        let m = motions(&rec, &robot, 3);
        let d = diagnose(&robot, &Measured::new(&rec, &m), &DiagnoseParams::default()).unwrap();
        show(name, &d);
        // The verdict sits at the border on these runs: what the latency
        // and mounting leave (a forward-speed or turn-rate structure of a
        // few per cent) crosses the null runs' floors or not with small
        // changes of the scan matching; what is left must then be named.
        match d.verdict {
            Verdict::Explained => assert!(!d.remaining.iter().any(|r| r.is_robot())),
            Verdict::PartlyExplained => assert!(d.remaining.iter().any(|r| r.is_robot())),
            v => panic!("{name}: verdict {v:?}"),
        }
        // The strongest cause by far is the latency.
        let first = &d.causes[0];
        assert_eq!(first.effect, "latency", "{:?}", d.causes);
        assert!(first.delta_bic > 300.0, "{first:?}");
        delays.push(first.parameters["delay"]);
        let w = d.gain.streams["icp_w"];
        assert!(w.after < 0.7 * w.before, "{w:?}");
        assert!(d.gain.relative > 0.3, "{:?}", d.gain);
    }
    for d in &delays {
        assert!((-0.2..-0.1).contains(d), "{delays:?}");
    }
    assert!((delays[0] - delays[1]).abs() < 0.03, "{delays:?}");
}

/// Censi et al.'s Khepera tuples: the diagnosis names the laser mount as
/// the dominant cause and its estimate agrees with the authors' maximum-
/// likelihood calibration (data README) in all three configurations; the
/// turn-rate scale R/D agrees with theirs to 0.15 %.
///
/// Each figure is judged against how far the authors' value lies from the
/// nominal robot (laser at the origin, R/D as in khepera.toml): where that
/// departure is at least three times the tolerance, the nominal value is
/// put through the same check and must fail it (`assert_recovered`). The
/// authors' R/D is 0.58–0.66 % above nominal on every set (a tolerance of
/// 1 % used to pass a diagnosis that named nothing); their lstraight mount
/// is 0.19 mm and 0.54° from the origin in y and yaw, which the tolerances
/// (0.6 mm, 0.02 rad) cannot tell from zero: those two only agree.
#[test]
fn censi_tuples_laser_mount_matches_the_authors_calibration() {
    let Some(data) = shared_data("censi_diagnosis") else {
        return;
    };
    let robot = robot_file("khepera");
    let mount = robot.laser.unwrap_or_default();
    let p = candidates(&["radius_scale", "wheel_base_scale", "laser_offset"]);
    let mut discriminating = Vec::new();
    for set in ["lstraight", "l90", "lmov"] {
        let dir = data.join("censi-calibration");
        let tuples = censi::read(&dir.join(format!("{set}.tuple"))).unwrap();
        let authors = censi::read_results(&dir.join(format!("{set}_results.json"))).unwrap();
        let d = pipeline::diagnose::run_tuples(&tuples, &robot, &p).unwrap();
        show(set, &d);
        // A turn-magnitude-dependent turn-rate residual of about 0.35 % is
        // left on these sets (no table effect has that sign: a negative turn
        // slip is unphysical), so "partly" is the honest verdict.
        assert!(
            matches!(d.verdict, Verdict::Explained | Verdict::PartlyExplained),
            "{:?}",
            d.verdict
        );
        assert!(cause(&d, "turn_slip").is_none(), "{:?}", d.causes);
        let l = cause(&d, "laser_offset").expect("laser mount named");
        assert_eq!(d.causes[0].effect, "laser_offset");
        // Measured: within 0.2 mm and 0.005 rad of the authors.
        for (k, want, nominal, tol) in [
            ("x", authors.l_x, mount.x, 0.6e-3),
            ("y", authors.l_y, mount.y, 0.6e-3),
            ("yaw", authors.l_theta, mount.yaw, 0.02),
        ] {
            let got = l.parameters[k];
            let what = format!("{set} laser {k}");
            eprintln!("{what}: {got:.5} authors {want:.5}");
            if (want - nominal).abs() >= 3.0 * tol {
                crate::support::assert_recovered(&what, got, want, nominal, tol);
                discriminating.push(what);
            } else {
                // The nominal already lies within the tolerance here (the
                // authors' lstraight y is 0.19 mm): not an accuracy claim,
                // only that the diagnosis did not move the value off.
                assert!((got - want).abs() < tol, "{what}: {got} vs {want}");
            }
        }
        // Turn-rate scale mean(R)/D relative to nominal, both calibrations
        // (measured: within 0.05 % of the authors').
        let x = odocal::effects::Departures::of(&odocal::diagnose::fitted_effects(&d));
        let ours =
            (1.0 + 0.5 * (x.radius_scale[0] + x.radius_scale[1])) / (1.0 + x.wheel_base_scale);
        let theirs = 0.25 * (authors.r_diam + authors.l_diam)
            / authors.axle
            / (robot.r_right / robot.wheel_base);
        eprintln!("{set}: R/D scale ours {ours:.5} authors {theirs:.5}");
        crate::support::assert_recovered(&format!("{set} R/D"), ours, theirs, 1.0, 1.5e-3);
        assert!(d.gain.relative > 0.1, "{:?}", d.gain);
    }
    assert_eq!(
        discriminating,
        [
            "lstraight laser x",
            "l90 laser x",
            "l90 laser y",
            "l90 laser yaw",
            "lmov laser x",
            "lmov laser y",
            "lmov laser yaw"
        ]
    );
}

/// Intel lab (CARMEN ODOM = integrated odometry, replayed as virtual
/// wheels): against ICP the logged odometry over-states distance by a few
/// per cent (more on the left wheel), and the laser does not sit at the
/// odometry's reference point (the log gives them as one pose) but about
/// 0.1 m ahead of it.
#[test]
fn intel_odometry_is_diagnosed_against_icp() {
    let Some(data) = shared_data("intel_diagnosis") else {
        return;
    };
    let robot = RobotConfig {
        name: "intel-virtual".into(),
        r_right: 0.1,
        r_left: 0.1,
        wheel_base: 0.4,
        ..RobotConfig::default()
    };
    let mut rec = read(
        &data.join("slam-benchmark/intel.mcap"),
        &robot,
        "/ground_truth",
    );
    assert!(rec.wheels.is_empty() && rec.odom.len() > 1000);
    // The first 400 s keep the test short.
    let t0 = rec.scans[0].stamp;
    rec.scans.retain(|s| s.stamp < t0 + 400.0);
    rec.odom.retain(|o| o.stamp < t0 + 400.0);
    // The odometry arrives in bursts (median gap 1 ms, mean 0.1 s): compare
    // over intervals of at least 1 s.
    let p = DiagnoseParams {
        min_interval: 1.0,
        ..DiagnoseParams::default()
    };
    let d = pipeline::diagnose::run_recording(&rec, &robot, &IcpParams::default(), &p).unwrap();
    show("intel", &d);
    assert_eq!(d.verdict, Verdict::Explained);
    let l = cause(&d, "laser_offset").expect("laser mount named");
    assert!((0.05..0.15).contains(&l.parameters["x"]), "{l:?}");
    assert!(l.parameters["x"] > 5.0 * l.stderr["x"]);
    assert!(d.gain.relative > 0.1, "{:?}", d.gain);
}

/// The command line reads Censi's tuple files directly and prints the
/// design.md JSON keys; the laser mount it names is the authors' one.
#[test]
fn cli_diagnoses_censi_tuples_with_json_keys() {
    let Some(data) = shared_data("cli_censi_diagnosis") else {
        return;
    };
    let dir = data.join("censi-calibration");
    let robot = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scans/robots/khepera.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(["diagnose", "--measured"])
        .arg(dir.join("lstraight.tuple"))
        .arg("--robot")
        .arg(&robot)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        v["verdict"] == "explained" || v["verdict"] == "partly-explained",
        "{}",
        v["verdict"]
    );
    // The shorter axle the authors measure is named as such, not as a
    // negative turn slip.
    let names: Vec<&str> = v["causes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["effect"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"wheel_base_scale") && !names.contains(&"turn_slip"),
        "{names:?}"
    );
    let wb = v["causes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["effect"] == "wheel_base_scale")
        .unwrap();
    assert!(wb["parameters"]["scale"].as_f64().unwrap() < 0.0, "{wb}");
    for r in v["remaining"].as_array().unwrap() {
        assert!(r["stream"].is_string() && r["structure"].is_string() && r["unit"].is_string());
        assert!(
            r["source"] == "robot" || r["source"] == "scan_matching",
            "{r}"
        );
    }
    let first = &v["causes"][0];
    assert_eq!(first["effect"], "laser_offset");
    let authors = censi::read_results(&dir.join("lstraight_results.json")).unwrap();
    let x = first["parameters"]["x"].as_f64().unwrap();
    // Within 0.6 mm of the authors' −5.8 mm (the laser at the base's
    // origin, the robot file's, misses by 9 tolerances).
    crate::support::assert_recovered("lstraight laser x", x, authors.l_x, 0.0, 0.6e-3);
    assert!(first["stderr"]["x"].as_f64().unwrap() > 0.0);
    assert!(first["delta_bic"].as_f64().unwrap() > 100.0);
    for k in ["heldout_rmse_before", "heldout_rmse_after", "relative"] {
        assert!(v["gain"][k].is_number(), "{k}");
    }
    // A broken tuple file is bad input (exit code 2) naming the file.
    let bad = crate::support::scratch("cli_censi_bad").join("bad.tuple");
    std::fs::write(&bad, "{ \"T\": 0.8, \"phi_l\": 0.5 }").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_odocal"))
        .args(["diagnose", "--measured"])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.tuple"));
}
