//! Checks shared by the fuzz targets: what a reader returns must be finite
//! wherever a number reaches the pipeline (scan ranges excepted: REP 117 lets
//! them be NaN or ±inf, and the scan code treats those as invalid beams).

use odocal::geom::Pose2;
use odocal::recording::Recording;

/// Panics (a fuzz finding) if a pose has a non-finite or non-unit part.
pub fn check_pose(what: &str, p: &Pose2) {
    let v = p.translation.vector;
    let (c, s) = (p.rotation.re, p.rotation.im);
    assert!(
        v.x.is_finite() && v.y.is_finite() && c.is_finite() && s.is_finite(),
        "{what}: non-finite pose {p:?}"
    );
    assert!(
        ((c * c + s * s) - 1.0).abs() < 1e-6,
        "{what}: rotation is not unit {p:?}"
    );
}

/// Panics if any stamp, wheel angle, rate, pose or scan geometry read is not
/// finite, or a stream is not sorted by stamp.
pub fn check_recording(r: &Recording) {
    let sorted = |name: &str, t: &[f64]| {
        assert!(t.iter().all(|x| x.is_finite()), "{name}: non-finite stamp");
        assert!(t.windows(2).all(|w| w[0] <= w[1]), "{name}: not sorted");
    };
    sorted(
        "scans",
        &r.scans.iter().map(|s| s.stamp).collect::<Vec<_>>(),
    );
    sorted(
        "wheels",
        &r.wheels.iter().map(|s| s.stamp).collect::<Vec<_>>(),
    );
    sorted("gyro", &r.gyro.iter().map(|s| s.stamp).collect::<Vec<_>>());
    sorted("odom", &r.odom.iter().map(|s| s.stamp).collect::<Vec<_>>());
    sorted(
        "reference",
        &r.reference.iter().map(|s| s.stamp).collect::<Vec<_>>(),
    );
    for s in &r.scans {
        for v in [
            s.angle_min,
            s.angle_increment,
            s.time_increment,
            s.scan_time,
            s.range_min,
            s.range_max,
        ] {
            assert!(v.is_finite(), "scan geometry not finite: {v}");
        }
        assert!(!s.ranges.is_empty(), "scan with no beams");
    }
    for w in &r.wheels {
        assert!(w.left.is_finite() && w.right.is_finite(), "wheel {w:?}");
    }
    for g in &r.gyro {
        assert!(g.wz.is_finite(), "gyro {g:?}");
    }
    for p in r.odom.iter().chain(&r.reference) {
        check_pose("odom/reference", &p.pose);
    }
    if let Some(p) = &r.base_from_laser {
        check_pose("base_from_laser", p);
    }
}

/// Read options that also take the LEGO and Mines bags' `/reference` topic.
pub fn with_reference() -> odocal::io::ReadOptions {
    odocal::io::ReadOptions {
        topics: odocal::io::TopicConfig {
            reference: "/reference".into(),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A folder of this fuzzing process for the readers that take a path (in
/// memory when `/dev/shm` exists).
fn scratch_root() -> std::path::PathBuf {
    let base = std::path::Path::new("/dev/shm");
    let base = if base.is_dir() {
        base.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    let dir = base.join(format!("odocal-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    dir
}

/// Writes `data` into this process's scratch file `input.EXT` and returns
/// its path.
pub fn scratch_file(ext: &str, data: &[u8]) -> std::path::PathBuf {
    let path = scratch_root().join(format!("input.{ext}"));
    std::fs::write(&path, data).expect("writing the scratch file");
    path
}

/// Writes `files` (name, bytes) into this process's scratch folder `bag/`,
/// emptied first, and returns it.
pub fn scratch_dir(files: &[(&str, &[u8])]) -> std::path::PathBuf {
    let dir = scratch_root().join("bag");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    for (name, data) in files {
        std::fs::write(dir.join(name), data).expect("writing a scratch file");
    }
    dir
}
