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
