//! The time policy of the readers (documented in `odocal::io`): stamps that go
//! back, duplicate stamps, gaps of seconds, clocks that start at 0 or run on
//! Unix time, unset and invalid stamps — each case read from a bag (or a
//! CARMEN log) and followed to where the pipeline uses it.

use std::collections::BTreeMap;
use std::io::Cursor;

use odocal::calib::{steps, MAX_GAP_STEP};
use odocal::icp::{match_recording, IcpParams};
use odocal::io::carmen::read_carmen_bytes;
use odocal::io::ros_msgs::{Header, JointStateMsg, LaserScanMsg, RosMsg, Time};
use odocal::io::{read_mcap_bytes, ReadOptions};
use odocal::motion::{PairFailure, VelocityObs};
use odocal::recording::Recording;
use odocal::robot::wheel_rates;
use odocal::InputError;

const SCAN: &str = "sensor_msgs/msg/LaserScan";
const JS: &str = "sensor_msgs/msg/JointState";

/// One message: log time (ns) and CDR bytes.
pub(crate) struct Msg {
    pub(crate) log_ns: u64,
    pub(crate) data: Vec<u8>,
}

/// A bag with one channel per (topic, schema, messages), in file order.
pub(crate) fn bag(channels: &[(&str, &str, Vec<Msg>)]) -> Vec<u8> {
    let mut w = mcap::WriteOptions::new()
        .compression_threads(0)
        .create(Cursor::new(Vec::new()))
        .unwrap();
    for (topic, ty, msgs) in channels {
        let s = w.add_schema(ty, "ros2msg", b"").unwrap();
        let c = w.add_channel(s, topic, "cdr", &BTreeMap::new()).unwrap();
        for (i, m) in msgs.iter().enumerate() {
            let h = mcap::records::MessageHeader {
                channel_id: c,
                sequence: i as u32,
                log_time: m.log_ns,
                publish_time: m.log_ns,
            };
            w.write_to_known_channel(&h, &m.data).unwrap();
        }
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

fn header(stamp: Time) -> Header {
    Header {
        stamp,
        frame_id: "laser".into(),
    }
}

/// A 181-beam scan of a room (distinct ranges, so ICP has structure).
fn scan_msg(stamp: Time, log_ns: u64) -> Msg {
    let m = LaserScanMsg {
        header: header(stamp),
        angle_min: -1.5,
        angle_max: 1.5,
        angle_increment: 3.0 / 180.0,
        range_min: 0.1,
        range_max: 30.0,
        ranges: (0..181).map(|i| 3.0 + (i as f32 * 0.07).sin()).collect(),
        ..Default::default()
    };
    Msg {
        log_ns,
        data: m.encode(),
    }
}

fn joints_msg(stamp: Time, log_ns: u64, left: f64, right: f64, velocities: bool) -> Msg {
    let values = vec![left, right];
    let m = JointStateMsg {
        header: header(stamp),
        name: vec!["left_wheel".into(), "right_wheel".into()],
        position: if velocities { vec![] } else { values.clone() },
        velocity: if velocities { values } else { vec![] },
        effort: vec![],
    };
    Msg {
        log_ns,
        data: m.encode(),
    }
}

/// Stamp and log time both `t` (s), as our writer and the shared bags do.
fn same(t: f64) -> (Time, u64) {
    (Time::from_seconds(t), (t * 1e9).round() as u64)
}

fn scans_at(ts: &[f64]) -> Vec<Msg> {
    ts.iter()
        .map(|&t| {
            let (s, l) = same(t);
            scan_msg(s, l)
        })
        .collect()
}

fn read(b: &[u8]) -> Result<Recording, InputError> {
    read_mcap_bytes(b, "time.mcap", &ReadOptions::default())
}

fn scan_stamps(r: &Recording) -> Vec<f64> {
    r.scans.iter().map(|s| s.stamp).collect()
}

#[test]
fn backward_jumps_are_per_stream_and_name_the_message() {
    // Each stream is checked on its own: joint states 1.5 s behind the scans
    // are fine, and so is a 1.9 s step back within the scans (sorted).
    let joints: Vec<Msg> = (0..5)
        .map(|k| {
            let (s, l) = same(8.5 + 0.5 * k as f64);
            joints_msg(s, l, k as f64, k as f64, false)
        })
        .collect();
    let b = bag(&[
        ("/scan", SCAN, scans_at(&[10.0, 11.0, 12.0, 10.1, 12.5])),
        ("/joint_states", JS, joints),
    ]);
    let r = read(&b).unwrap();
    assert_eq!(scan_stamps(&r), [10.0, 10.1, 11.0, 12.0, 12.5]);
    assert_eq!(r.wheels.len(), 5);
    // Back by 2.5 s from the latest stamp (not from the previous message):
    // 10.0, 12.0, 11.0 (ok), 9.4 (2.6 s behind 12.0) is refused.
    let b = bag(&[("/scan", SCAN, scans_at(&[10.0, 12.0, 11.0, 9.4]))]);
    let e = read(&b).unwrap_err();
    assert_eq!(e.topic.as_deref(), Some("/scan"));
    assert_eq!(e.position.as_deref(), Some("message 3"));
    assert!(e.message.contains("backwards by 2.600 s"), "{e}");
}

#[test]
fn duplicate_stamps_are_kept_in_file_order_and_skipped_downstream() {
    // Two scans and two wheel samples share a stamp.
    let mut scans = scans_at(&[1.0, 1.1, 1.1, 1.2]);
    // The second copy differs (a re-sent, changed scan): file order is kept.
    let (s, l) = same(1.1);
    let mut changed = LaserScanMsg::decode(&scan_msg(s, l).data).unwrap();
    changed.ranges[0] = 9.0;
    scans[2].data = changed.encode();
    let joints: Vec<Msg> = [(1.0, 0.0), (1.1, 0.1), (1.1, 0.5), (1.2, 0.2)]
        .iter()
        .map(|&(t, a)| {
            let (s, l) = same(t);
            joints_msg(s, l, a, a, false)
        })
        .collect();
    let r = read(&bag(&[
        ("/scan", SCAN, scans),
        ("/joint_states", JS, joints),
    ]))
    .unwrap();
    assert_eq!(scan_stamps(&r), [1.0, 1.1, 1.1, 1.2]);
    assert_eq!(r.scans[1].ranges[0], r.scans[3].ranges[0]);
    assert_eq!(r.scans[2].ranges[0], 9.0);
    assert_eq!(
        r.wheels.iter().map(|w| w.left).collect::<Vec<_>>(),
        [0.0, 0.1, 0.5, 0.2]
    );
    // Wheel rates skip the zero-length step: every rate finite, dt > 0.
    let rates = wheel_rates(&r.wheels);
    assert_eq!(rates.len(), 2);
    for w in &rates {
        assert!(w.t1 > w.t0 && w.left.is_finite() && w.right.is_finite());
    }
    // ICP flags the pair with dt = 0 and goes on.
    let (motions, _) = match_recording(
        &r.scans,
        odocal::geom::Pose2::identity(),
        None,
        &IcpParams::default(),
    )
    .unwrap();
    assert_eq!(motions.len(), 3);
    assert_eq!(motions[1].failure, Some(PairFailure::BadTime));
    assert_ne!(motions[0].failure, Some(PairFailure::BadTime));
    assert_ne!(motions[2].failure, Some(PairFailure::BadTime));
}

#[test]
fn gaps_of_seconds_are_kept_and_calibration_steps_over_them() {
    // Wheel angles at 10 Hz with a 4 s hole; velocities 2 rad/s (left) and
    // 1 rad/s (right) throughout.
    let ts: Vec<f64> = (0..=10)
        .map(|k| k as f64 * 0.1)
        .chain((0..=10).map(|k| 5.0 + k as f64 * 0.1))
        .collect();
    let joints: Vec<Msg> = ts
        .iter()
        .map(|&t| {
            let (s, l) = same(100.0 + t);
            joints_msg(s, l, 2.0 * t, t, false)
        })
        .collect();
    let r = read(&bag(&[
        ("/scan", SCAN, scans_at(&[100.0, 100.5, 105.5, 106.0])),
        ("/joint_states", JS, joints),
    ]))
    .unwrap();
    assert_eq!(scan_stamps(&r), [100.0, 100.5, 105.5, 106.0]);
    assert_eq!(r.wheels.len(), 22);
    // Observations before and after the hole only.
    let obs = |t0: f64, t1: f64| VelocityObs {
        t0,
        t1,
        v: 0.3,
        w: 0.1,
        sigma_v: 0.01,
        sigma_w: 0.01,
    };
    let s = steps(
        &[obs(100.0, 100.5), obs(105.5, 106.0)],
        &r.wheels,
        &[],
        0.01,
    );
    // Contiguous from the first wheel sample to the last, predict-only steps
    // of at most MAX_GAP_STEP across the hole, true mean rates everywhere.
    assert!((s[0].t0 - 100.0).abs() < 1e-9);
    assert!((s.last().unwrap().t1 - 106.0).abs() < 1e-9);
    for w in s.windows(2) {
        assert!((w[0].t1 - w[1].t0).abs() < 1e-9);
    }
    let across: Vec<_> = s
        .iter()
        .filter(|c| c.t0 >= 100.5 - 1e-9 && c.t1 <= 105.5 + 1e-9)
        .collect();
    assert!(across.len() >= 40, "{} steps across the hole", across.len());
    for c in &s {
        assert!(c.t1 > c.t0);
        if c.measurements().is_empty() {
            assert!(c.t1 - c.t0 <= MAX_GAP_STEP + 1e-9);
        }
        assert!((c.omega_left - 2.0).abs() < 1e-6, "{}", c.omega_left);
        assert!((c.omega_right - 1.0).abs() < 1e-6, "{}", c.omega_right);
    }
}

#[test]
fn clock_starting_at_zero_reads_as_zero() {
    // Simulated time from 0 (stamp 0 is unset, so the log time, also 0, is used).
    let r = read(&bag(&[("/scan", SCAN, scans_at(&[0.0, 0.04, 0.08]))])).unwrap();
    assert_eq!(scan_stamps(&r), [0.0, 0.04, 0.08]);
}

#[test]
fn unset_stamps_take_the_log_time() {
    // A publisher that never fills the header: every stamp zero.
    let msgs: Vec<Msg> = (0..4)
        .map(|k| scan_msg(Time::default(), 1_700_000_000_000_000_000 + k * 25_000_000))
        .collect();
    let r = read(&bag(&[("/scan", SCAN, msgs)])).unwrap();
    let t = scan_stamps(&r);
    for (k, w) in t.windows(2).enumerate() {
        assert!((w[1] - w[0] - 0.025).abs() < 1e-6, "step {k}: {w:?}");
    }
    assert!((t[0] - 1.7e9).abs() < 1e-6);
}

#[test]
fn header_clock_at_zero_with_wall_clock_log_times_is_an_error_naming_the_cause() {
    // Header stamps from 0 (sim time), log times Unix: the first message's
    // zero stamp cannot be told from an unset one; the clash is reported.
    let wall = 1_700_000_000_000_000_000u64;
    let msgs: Vec<Msg> = [0.0, 0.04, 0.08]
        .iter()
        .enumerate()
        .map(|(k, &t)| scan_msg(Time::from_seconds(t), wall + k as u64 * 40_000_000))
        .collect();
    let e = read(&bag(&[("/scan", SCAN, msgs)])).unwrap_err();
    assert_eq!(e.position.as_deref(), Some("message 1"));
    assert!(e.message.contains("backwards"), "{e}");
    assert!(e.message.contains("log time"), "{e}");
}

#[test]
fn unix_time_stamps_keep_microseconds() {
    // 1 ms steps at Unix time (1.7e9 s): f64 keeps ~0.24 µs.
    let base = Time {
        sec: 1_700_000_000,
        nanosec: 123_456_789,
    };
    let msgs: Vec<Msg> = (0..50)
        .map(|k| {
            let ns = base.nanosec as u64 + k * 1_000_000;
            let stamp = Time {
                sec: base.sec + (ns / 1_000_000_000) as i32,
                nanosec: (ns % 1_000_000_000) as u32,
            };
            scan_msg(stamp, 0)
        })
        .collect();
    let r = read(&bag(&[("/scan", SCAN, msgs)])).unwrap();
    let t = scan_stamps(&r);
    assert!((t[0] - 1_700_000_000.0 - 0.123_456_789).abs() < 1e-6);
    for w in t.windows(2) {
        assert!((w[1] - w[0] - 0.001).abs() < 1e-6, "{w:?}");
    }
}

#[test]
fn negative_and_malformed_stamps_are_errors() {
    for (stamp, at) in [
        (
            Time {
                sec: -5,
                nanosec: 0,
            },
            "negative",
        ),
        (
            Time {
                sec: 3,
                nanosec: 1_500_000_000,
            },
            "nanosec",
        ),
    ] {
        let mut msgs = scans_at(&[1.0, 2.0]);
        msgs.push(scan_msg(stamp, 3_000_000_000));
        let e = read(&bag(&[("/scan", SCAN, msgs)])).unwrap_err();
        assert_eq!(e.position.as_deref(), Some("message 2"), "{e}");
        assert!(e.message.contains("invalid header stamp"), "{e}");
        assert!(e.message.contains(at), "{e}");
    }
}

#[test]
fn velocity_wheels_integrate_across_a_gap_at_the_mean_rate() {
    // Rates only (no angles): a 2 s hole is bridged by the trapezoid rule.
    let msgs: Vec<Msg> = [0.0, 0.1, 0.2, 2.2, 2.3]
        .iter()
        .map(|&t| {
            let (s, l) = same(50.0 + t);
            joints_msg(s, l, 1.0, -0.5, true)
        })
        .collect();
    let r = read(&bag(&[("/joint_states", JS, msgs)])).unwrap();
    let last = r.wheels.last().unwrap();
    assert!((last.left - 2.3).abs() < 1e-9, "{last:?}");
    assert!((last.right + 1.15).abs() < 1e-9, "{last:?}");
}

#[test]
fn carmen_time_policy_matches_the_bag_reader() {
    let opts = ReadOptions::default();
    let odom = |t: f64| format!("ODOM 0 0 0 0 0 0 {t} host {t}\n");
    // Within the tolerance: sorted; duplicates kept.
    let text: String = [10.0, 11.0, 10.5, 10.5, 12.0].map(odom).concat();
    let r = read_carmen_bytes(text.as_bytes(), "t.clf", &opts).unwrap();
    let t: Vec<f64> = r.odom.iter().map(|p| p.stamp).collect();
    assert_eq!(t, [10.0, 10.5, 10.5, 11.0, 12.0]);
    // Beyond it: an error naming the line.
    let text: String = [10.0, 11.0, 12.0, 9.5].map(odom).concat();
    let e = read_carmen_bytes(text.as_bytes(), "t.clf", &opts).unwrap_err();
    assert_eq!(e.position.as_deref(), Some("line 4"));
    assert!(e.message.contains("backwards"), "{e}");
    // Negative stamps are refused; 0 is a valid start.
    let text = format!("{}{}", odom(0.0), odom(-1.0));
    let e = read_carmen_bytes(text.as_bytes(), "t.clf", &opts).unwrap_err();
    assert_eq!(e.position.as_deref(), Some("line 2"));
    assert!(e.message.contains("negative"), "{e}");
    // Gaps are kept as they are.
    let text: String = [0.0, 0.1, 30.0].map(odom).concat();
    let r = read_carmen_bytes(text.as_bytes(), "t.clf", &opts).unwrap();
    assert_eq!(
        r.odom.iter().map(|p| p.stamp).collect::<Vec<_>>(),
        [0.0, 0.1, 30.0]
    );
}
