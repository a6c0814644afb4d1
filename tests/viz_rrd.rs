//! A Rerun recording written through `RerunLogger`, read back with the
//! official rerun-sdk (tools/rrd_check.py): entity paths, timelines, row and
//! point counts are what was logged.
#![cfg(feature = "rerun")]

use crate::support::{python_with, scratch};
use crate::viz_logger::{feed, RunShape};
use odocal::viz::{
    entity, systematic_subsample, Logger, RerunLogger, RerunOptions, RerunSink, Stamp,
    TrajectoryKind,
};
use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;

pub fn run_check(test: &str, rrd: &Path, expect: &Value) -> bool {
    let Some(py) = python_with(test, &["rerun", "pyarrow"]) else {
        return false;
    };
    let exp = rrd.with_extension("expect.json");
    std::fs::write(&exp, serde_json::to_vec_pretty(expect).unwrap()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/rrd_check.py");
    let out = Command::new(py)
        .arg(script)
        .arg(rrd)
        .arg(&exp)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "rrd_check failed:\n{stderr}\n{}",
        String::from_utf8_lossy(&out.stdout)
    );
    true
}

#[test]
fn rerun_recording_matches_what_was_logged() {
    let dir = scratch("rerun_rrd");
    let rrd = dir.join("run.rrd");
    let shape = RunShape {
        scans: 23,
        beams: 541,
        particles: 2000,
        map_segments: 5,
    };
    let options = RerunOptions {
        max_particles: 100,
        // Small batches: several chunks per entity must add up.
        batch_rows: 4,
        ..RerunOptions::default()
    };
    let mut log = RerunLogger::new(RerunSink::File(rrd.clone()), options).unwrap();
    feed(&mut log, &shape).unwrap();
    assert!(rrd.is_file());

    // The subsample the logger must have drawn at each step.
    let steps = shape.scans - 1;
    let w: Vec<f64> = (0..shape.particles)
        .map(|k| {
            let u = (k as f64 * 0.618_033_988_75).fract() - 0.5;
            let v = (k as f64 * 0.754_877_666_2).fract() - 0.5;
            (-(u * u + v * v) * 20.0).exp()
        })
        .collect();
    let shown = systematic_subsample(&w, 100).len();
    assert!(shown > 50 && shown <= 100, "shown {shown}");

    let last_t = 10.0 + 0.1 * (shape.scans - 1) as f64;
    let temporal = |rows: usize, first_scan: i64| json!({"rows": rows, "first": {"scan": first_scan}, "last": {"scan": shape.scans as i64 - 1, "time": last_t}});
    let mut entities = serde_json::Map::new();
    entities.insert(
        entity::MAP.into(),
        json!({"static": true, "rows": 1,
        "instances": {"LineStrips2D:strips": shape.map_segments}}),
    );
    // Each trajectory: the whole line (static) and the line grown to each
    // pose (23 poses: one row each), on both timelines: pose i is at scan i.
    for kind in TrajectoryKind::ALL {
        entities.insert(
            kind.full_entity().into(),
            json!({"static": true, "rows": 1,
            "instances": {"LineStrips2D:strips": 1}}),
        );
        let mut grown = temporal(shape.scans, 0);
        grown["instances"] =
            json!({"LineStrips2D:strips": shape.scans, "LineStrips2D:colors": shape.scans});
        grown["first"]["time"] = json!(10.0);
        entities.insert(kind.entity().into(), grown);
    }
    // The robot moves under its transform; laser and heading hang on it.
    let mut robot = temporal(shape.scans, 0);
    robot["instances"] = json!({"Transform3D:translation": shape.scans,
        "Transform3D:rotation_axis_angle": shape.scans});
    robot["first"]["time"] = json!(10.0);
    entities.insert(entity::ROBOT.into(), robot);
    for e in [entity::LASER, entity::ROBOT_HEADING] {
        entities.insert(e.into(), json!({"static": true, "rows": 1}));
    }
    let mut scan = temporal(shape.scans, 0);
    scan["instances"] = json!({"Points2D:positions": shape.scans * shape.beams});
    scan["first"]["time"] = json!(10.0);
    entities.insert(entity::SCAN_POINTS.into(), scan);
    // One ellipse per scan match, 33 points (closed); its colour static.
    let mut ell = temporal(steps, 1);
    ell["instances"] = json!({"LineStrips2D:strips": steps, "LineStrips2D:colors": 1});
    entities.insert(entity::ICP_COVARIANCE.into(), ell);
    // The trail: levels of 1, 2, 4, 8 and 16 ellipses for 22 matches. What
    // they show is pinned by the cursors below, not how they store it.
    for level in 0..5 {
        entities.insert(
            entity::trail_level(level),
            json!({"first": {"scan": (1 << level) as i64}}),
        );
    }
    let mut parts = temporal(steps, 1);
    parts["instances"] = json!({"Points2D:positions": steps * shown,
        "Points2D:colors": steps * shown, "Points2D:radii": steps * shown});
    entities.insert(entity::PARTICLES.into(), parts);
    for s in [
        entity::PARTICLES_SHOWN,
        entity::EST_R_RIGHT,
        entity::EST_R_LEFT,
        entity::EST_WHEEL_BASE,
        entity::STD_R_RIGHT,
        entity::STD_R_LEFT,
        entity::STD_WHEEL_BASE,
        entity::PARTICLES_COUNT,
        entity::PROCESS_SIGMA,
        entity::ICP_ITERATIONS,
        entity::ICP_COV_TRACE,
    ] {
        let mut e = temporal(steps, 1);
        e["instances"] = json!({"Scalars:scalars": steps});
        entities.insert(s.into(), e);
    }
    // What the viewer draws with the cursor at scan k: the ellipses of the
    // k matches so far (the k-th ends at scan k), 33 points each, on either
    // timeline; the latest one alone on its own entity; each grown line
    // through poses 0..=k, ending at the robot.
    let mut cursors = Vec::new();
    for k in 0..shape.scans as i64 {
        let t = 10.0 + 0.1 * k as f64 + 1e-6;
        for (tl, at) in [(entity::SCAN, json!(k)), (entity::TIME, json!(t))] {
            cursors.push(
                json!({"prefix": entity::ICP_COVARIANCE_TRAIL, "timeline": tl,
                "at": at, "component": "LineStrips2D:strips", "want": k}),
            );
        }
        cursors.push(
            json!({"prefix": entity::ICP_COVARIANCE_TRAIL, "timeline": entity::SCAN,
            "at": k, "component": "LineStrips2D:strips", "depth": 2, "want": 33 * k}),
        );
        for kind in [TrajectoryKind::Icp, TrajectoryKind::Reference] {
            cursors.push(
                json!({"prefix": kind.entity(), "timeline": entity::SCAN, "at": k,
                "component": "LineStrips2D:strips", "depth": 2, "want": k + 1}),
            );
        }
    }
    let expect = json!({
        "version": "0.36.3",
        "timelines": [entity::SCAN, entity::TIME],
        "exact": true,
        "entities": entities,
        "cursors": cursors,
        // The layout it opens on: the world, the estimates, the cloud, ICP.
        "blueprint": ["/world", "/", "/calib/particles", "/icp"],
    });
    if !run_check("rerun_recording_matches_what_was_logged", &rrd, &expect) {
        return;
    }
    // The checker is not vacuous: a wrong row count is reported.
    let mut wrong = expect.clone();
    wrong["entities"][entity::SCAN_POINTS]["rows"] = json!(shape.scans + 1);
    let exp = rrd.with_extension("wrong.json");
    std::fs::write(&exp, serde_json::to_vec(&wrong).unwrap()).unwrap();
    let py = python_with("rrd_wrong", &["rerun"]).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/rrd_check.py");
    let out = Command::new(py)
        .arg(script)
        .arg(&rrd)
        .arg(&exp)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("world/robot/laser/scan: 23 rows, want 24")
    );
}

#[test]
fn unfinished_recording_leaves_no_file() {
    let dir = scratch("rerun_unfinished");
    let rrd = dir.join("partial.rrd");
    {
        let mut log = RerunLogger::to_file(&rrd).unwrap();
        log.icp(Stamp::new(1, 0.1), 4, 1e-3).unwrap();
        // dropped without finish
    }
    assert!(!rrd.exists());
    let leftovers = std::fs::read_dir(&dir).unwrap().count();
    assert_eq!(leftovers, 0, "temporary file left behind");
}

#[test]
fn rerun_logger_rejects_bad_input() {
    let dir = scratch("rerun_bad_input");
    let mut log = RerunLogger::to_file(dir.join("bad.rrd")).unwrap();
    assert!(log
        .particles(Stamp::new(0, 0.0), &[0.3], &[0.3, 0.31], &[1.0])
        .is_err());
    assert!(log.icp(Stamp::new(0, f64::NAN), 3, 0.1).is_err());
    assert!(log.icp(Stamp::new(0, 0.0), 3, f64::INFINITY).is_err());
    log.finish().unwrap();
    log.finish().unwrap();
    assert!(dir.join("bad.rrd").is_file());
}
