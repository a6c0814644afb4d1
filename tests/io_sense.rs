//! The sense checks after parsing: scan geometry that contradicts itself
//! (beam count against angles, increment sign, range limits, too few beams),
//! CARMEN lines whose value count disagrees with their count or that are cut
//! off, are refused naming file, topic and position; every real recording
//! in the shared data (CARMEN-converted logs with increment = π/n included)
//! still reads.

use crate::support::{scratch, shared_data};
use odocal::io::ros_msgs::{Header, LaserScanMsg, RosMsg, Time};
use odocal::io::{read_mcap_bytes, read_recording, ReadOptions};

const SCAN: &str = "sensor_msgs/msg/LaserScan";

/// A 181-beam scan from −90° to +90°, consistent unless changed.
fn scan(stamp: f64) -> LaserScanMsg {
    let inc = std::f32::consts::PI / 180.0;
    LaserScanMsg {
        header: Header {
            stamp: Time::from_seconds(stamp),
            frame_id: "laser".into(),
        },
        angle_min: -90.0 * inc,
        angle_max: 90.0 * inc,
        angle_increment: inc,
        range_min: 0.1,
        range_max: 30.0,
        ranges: (0..181).map(|i| 2.0 + (i as f32 * 0.1).sin()).collect(),
        ..Default::default()
    }
}

/// A bag with three scans, the last one `bad`; the read's error.
fn third_refused(bad: LaserScanMsg) -> odocal::InputError {
    let msgs: Vec<crate::io_time::Msg> = [scan(1.0), scan(1.1), bad]
        .iter()
        .enumerate()
        .map(|(i, m)| crate::io_time::Msg {
            log_ns: 1_000_000 * (i as u64 + 1),
            data: m.encode(),
        })
        .collect();
    let bytes = crate::io_time::bag(&[("/scan", SCAN, msgs)]);
    let e = read_mcap_bytes(&bytes, "geometry.mcap", &ReadOptions::default())
        .expect_err("inconsistent geometry must be refused");
    assert_eq!(e.file, "geometry.mcap");
    assert_eq!(e.topic.as_deref(), Some("/scan"), "{e}");
    assert_eq!(e.position.as_deref(), Some("message 2"), "{e}");
    e
}

#[test]
fn scan_geometry_that_contradicts_itself_is_refused() {
    // 181 ranges but angles for 91: angle_max says +90° with a 2° increment
    // from −90° would need 91 beams.
    let mut s = scan(1.2);
    s.angle_increment *= 2.0;
    let e = third_refused(s);
    assert!(e.message.contains("disagree with its 181 ranges"), "{e}");
    // The increment points away from angle_max.
    let mut s = scan(1.2);
    s.angle_increment = -s.angle_increment;
    assert!(third_refused(s).message.contains("points away"));
    // range_max below range_min, and equal.
    let mut s = scan(1.2);
    s.range_max = 0.05;
    assert!(third_refused(s).message.contains("range_min < range_max"));
    let mut s = scan(1.2);
    s.range_max = s.range_min;
    assert!(third_refused(s).message.contains("range_min < range_max"));
    // One beam.
    let mut s = scan(1.2);
    s.ranges.truncate(1);
    s.angle_max = s.angle_min;
    assert!(third_refused(s).message.contains("1 beam"));
}

#[test]
fn carmen_convention_of_pi_over_n_passes() {
    // 180 beams at π/180 from −90°: the last at +89°, angle_max stated +90°
    // (one increment off) or +89° both read.
    for angle_max_deg in [89.0f32, 90.0] {
        let mut s = scan(1.2);
        s.ranges.truncate(180);
        s.angle_max = angle_max_deg.to_radians();
        let msgs: Vec<crate::io_time::Msg> = [s]
            .iter()
            .map(|m| crate::io_time::Msg {
                log_ns: 1_000_000,
                data: m.encode(),
            })
            .collect();
        let bytes = crate::io_time::bag(&[("/scan", SCAN, msgs)]);
        let r = read_mcap_bytes(&bytes, "carmen.mcap", &ReadOptions::default()).unwrap();
        assert_eq!(r.scans[0].ranges.len(), 180);
    }
}

#[test]
fn every_real_recording_passes_the_sense_checks() {
    let Some(dir) = shared_data("every_real_recording_passes_the_sense_checks") else {
        return;
    };
    let bags = [
        "slam-benchmark/intel.mcap",
        "slam-benchmark/aces.mcap",
        "slam-benchmark/fr079.mcap",
        "slam-benchmark/mit-csail.mcap",
        "slam-benchmark/mit-csail.clf",
        "lego-robot/lego-robot.mcap",
        "mines-rover/exp1.mcap",
        "mines-rover/exp2.mcap",
    ];
    for b in bags {
        let r = read_recording(&dir.join(b), &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{b}: {e}"));
        assert!(r.scans.len() > 100, "{b}");
    }
}

#[test]
fn carmen_lines_that_disagree_with_their_counts_or_are_cut_are_refused() {
    let d = scratch("sense_carmen");
    let odom = "ODOM 0 0 0 0 0 0 1.0 h 1.0\n";
    let flaser = |n: usize, values: usize, t: f64| {
        let r: Vec<String> = (0..values).map(|_| "1.5".to_string()).collect();
        format!("FLASER {n} {} 0 0 0 0 0 0 {t} h {t}\n", r.join(" "))
    };
    let cases = [
        // FLASER 3 followed by 5 readings: two values too many.
        (
            format!("{odom}{}", flaser(3, 5, 2.0)),
            "line 2",
            "FLASER 3 makes 13 values",
        ),
        // A count past the cap.
        (
            format!("{odom}FLASER 5000000 1 2 3\n"),
            "line 2",
            "over the cap",
        ),
        // The last line cut inside its record.
        (
            format!("{odom}{}", &flaser(181, 181, 3.0)[..700]),
            "line 2",
            "truncated",
        ),
        // An ODOM with one value more than the record has.
        (
            format!("{odom}ODOM 0 0 0 0 0 0 2.0 h 2.0 7\n"),
            "line 2",
            "longer than its counts",
        ),
    ];
    for (i, (text, line, needle)) in cases.iter().enumerate() {
        let p = d.join(format!("bad{i}.clf"));
        std::fs::write(&p, text).unwrap();
        let e = read_recording(&p, &ReadOptions::default()).expect_err(needle);
        assert_eq!(e.file, p.display().to_string());
        assert_eq!(e.position.as_deref(), Some(*line), "{e}");
        assert!(e.message.contains(needle), "'{needle}' not in {e}");
    }
    // The same records, consistent and whole, read.
    let p = d.join("good.clf");
    std::fs::write(&p, format!("{odom}{}", flaser(181, 181, 2.0))).unwrap();
    let r = read_recording(&p, &ReadOptions::default()).unwrap();
    assert_eq!(r.scans.len(), 1);
}
