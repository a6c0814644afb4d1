//! Reading every shared real bag: counts from the data README, the laser
//! mount from /tf_static, and CARMEN vs MCAP of the same log.

use crate::support::shared_data;
use odocal::io::{read_recording, ReadOptions};
use odocal::recording::Recording;

fn read(test: &str, rel: &str, opts: &ReadOptions) -> Option<Recording> {
    let dir = shared_data(test)?;
    Some(read_recording(&dir.join(rel), opts).unwrap_or_else(|e| panic!("{e}")))
}

fn lego_opts() -> ReadOptions {
    let mut o = ReadOptions::default();
    o.topics.reference = "/reference".into();
    o
}

fn assert_sorted(r: &Recording) {
    assert!(r.scans.windows(2).all(|w| w[0].stamp <= w[1].stamp));
    assert!(r.odom.windows(2).all(|w| w[0].stamp <= w[1].stamp));
    assert!(r.wheels.windows(2).all(|w| w[0].stamp <= w[1].stamp));
    assert!(r.reference.windows(2).all(|w| w[0].stamp <= w[1].stamp));
}

#[test]
fn benchmark_bags_have_readme_counts() {
    // (file, scans, beams, odom, range_min, range_max, laser x)
    let table = [
        (
            "slam-benchmark/intel.mcap",
            13631,
            180,
            26915,
            0.1,
            80.0,
            0.0,
        ),
        ("slam-benchmark/aces.mcap", 7374, 180, 7375, 0.3, 50.0, 0.0),
        (
            "slam-benchmark/fr079.mcap",
            4934,
            360,
            8951,
            0.1,
            80.0,
            0.04,
        ),
        (
            "slam-benchmark/mit-csail.mcap",
            1988,
            361,
            1988,
            0.1,
            80.0,
            0.0,
        ),
    ];
    for (rel, scans, beams, odom, rmin, rmax, lx) in table {
        let Some(r) = read(
            "benchmark_bags_have_readme_counts",
            rel,
            &ReadOptions::default(),
        ) else {
            return;
        };
        assert_eq!(r.scans.len(), scans, "{rel}");
        assert!(r.scans.iter().all(|s| s.ranges.len() == beams), "{rel}");
        assert_eq!(r.odom.len(), odom, "{rel}");
        assert!(r.wheels.is_empty() && r.gyro.is_empty() && r.reference.is_empty());
        let s = &r.scans[0];
        assert!(
            (s.angle_min + std::f64::consts::FRAC_PI_2).abs() < 1e-6,
            "{rel}"
        );
        let inc = if beams == 361 { 360.0 } else { beams as f64 };
        assert!((s.angle_increment - std::f64::consts::PI / inc).abs() < 1e-7);
        assert!((s.range_min - rmin).abs() < 1e-6 && (s.range_max - rmax).abs() < 1e-5);
        let b = r.base_from_laser.expect("tf_static base_link -> laser");
        assert!((b.translation.vector.x - lx).abs() < 1e-12, "{rel}");
        assert!(b.rotation.angle().abs() < 1e-12);
        assert_sorted(&r);
    }
}

#[test]
fn lego_bag_has_wheels_scans_and_point_reference() {
    let Some(r) = read(
        "lego_bag_has_wheels_scans_and_point_reference",
        "lego-robot/lego-robot.mcap",
        &lego_opts(),
    ) else {
        return;
    };
    assert_eq!(r.scans.len(), 278);
    assert_eq!(r.wheels.len(), 278);
    assert_eq!(r.reference.len(), 278);
    assert!(r.reference.iter().all(|p| !p.has_heading));
    assert!(r.scans.iter().all(|s| s.ranges.len() == 660));
    assert!((r.scans[0].angle_min + 2.024855).abs() < 1e-6);
    let b = r.base_from_laser.unwrap();
    assert!((b.translation.vector.x - 0.030).abs() < 1e-12);
    assert!((b.rotation.angle() + 0.06981317).abs() < 1e-7);
    // 41 Hokuyo error codes became NaN (REP 117), never points.
    let nan = r
        .scans
        .iter()
        .flat_map(|s| &s.ranges)
        .filter(|x| x.is_nan())
        .count();
    assert_eq!(nan, 41);
    assert_sorted(&r);
}

#[test]
fn mines_bags_have_one_joint_state_per_scan() {
    for (rel, n) in [
        ("mines-rover/exp1.mcap", 756),
        ("mines-rover/exp2.mcap", 641),
    ] {
        let Some(r) = read(
            "mines_bags_have_one_joint_state_per_scan",
            rel,
            &ReadOptions::default(),
        ) else {
            return;
        };
        assert_eq!(r.scans.len(), n, "{rel}");
        assert_eq!(r.wheels.len(), n, "{rel}");
        assert!(r.scans.iter().all(|s| s.ranges.len() == 682));
        assert!((r.scans[0].scan_time - 0.1).abs() < 1e-7);
        let b = r.base_from_laser.unwrap();
        assert!((b.translation.vector.x - 0.145).abs() < 1e-12);
        // Ticks · 2π/2000: every wheel angle is a whole number of ticks.
        for w in &r.wheels {
            let ticks = w.left * 2000.0 / std::f64::consts::TAU;
            assert!((ticks - ticks.round()).abs() < 1e-6);
        }
        assert_sorted(&r);
    }
}

#[test]
fn carmen_log_matches_its_mcap_conversion() {
    let test = "carmen_log_matches_its_mcap_conversion";
    let (Some(clf), Some(bag)) = (
        read(
            test,
            "slam-benchmark/mit-csail.clf",
            &ReadOptions::default(),
        ),
        read(
            test,
            "slam-benchmark/mit-csail.mcap",
            &ReadOptions::default(),
        ),
    ) else {
        return;
    };
    assert_eq!(clf.scans.len(), 1988);
    assert_eq!(bag.scans.len(), 1988);
    assert_eq!(clf.odom.len(), bag.odom.len());
    for (a, b) in clf.scans.iter().zip(&bag.scans) {
        // The bag stores stamps in ns and angles as float32.
        assert!((a.stamp - b.stamp).abs() < 1e-6);
        assert!((a.angle_min - b.angle_min).abs() < 1e-6);
        assert!((a.angle_increment - b.angle_increment).abs() < 1e-7);
        assert_eq!(a.range_min as f32, b.range_min as f32);
        assert_eq!(a.range_max as f32, b.range_max as f32);
        assert_eq!(a.ranges, b.ranges);
    }
    for (a, b) in clf.odom.iter().zip(&bag.odom) {
        assert!((a.stamp - b.stamp).abs() < 1e-6);
        assert!((a.pose.translation.vector - b.pose.translation.vector).norm() < 1e-9);
        let d = odocal::geom::wrap_angle(a.pose.rotation.angle() - b.pose.rotation.angle());
        assert!(d.abs() < 1e-9);
    }
}
