//! The live input without a network: a recording's stored messages pushed
//! through the inlet one by one, as the DDS listener does, come out of
//! [`LiveSource`] as the same samples the bag reader gives; malformed,
//! oversized and out-of-order messages are refused and counted, never
//! fatal; silent streams stay bounded.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

use odocal::io::stored::stored_messages;
use odocal::io::{Item, ReadOptions, SampleSource};
use odocal::live::{Incoming, Inlet, LiveParams, LiveSource};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

/// The topics a live run subscribes to for the default robot.
fn topics() -> Vec<(String, String)> {
    [
        ("/scan", "sensor_msgs/msg/LaserScan"),
        ("/joint_states", "sensor_msgs/msg/JointState"),
        ("/imu", "sensor_msgs/msg/Imu"),
        ("/tf_static", "tf2_msgs/msg/TFMessage"),
    ]
    .iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect()
}

/// Every stored message of the bundled recording, in file order.
fn messages(opts: &ReadOptions) -> Vec<Incoming> {
    let mut s = stored_messages(BUNDLED.as_ref(), opts).unwrap().unwrap();
    let mut out = Vec::new();
    while let Some(m) = s.next_message().unwrap() {
        out.push(Incoming {
            topic: m.topic,
            data: m.data,
            log_time_ns: m.log_time_ns,
            arrived: Instant::now(),
        });
    }
    out
}

fn live_opts() -> ReadOptions {
    ReadOptions {
        reorder_tolerance: 0.0,
        log_time_for_unset: false,
        ..ReadOptions::default()
    }
}

fn params() -> LiveParams {
    LiveParams {
        settle_s: 0.0,
        wait_s: 10.0,
        ..LiveParams::default()
    }
}

/// A live source over `msgs`, queued whole and the inlet closed after them;
/// the inlet's counts.
fn source<'o>(
    msgs: Vec<Incoming>,
    opts: &'o ReadOptions,
    p: &LiveParams,
) -> (LiveSource<'o>, Arc<odocal::live::InletStats>) {
    let (inlet, rx, stats) = Inlet::new(msgs.len() + 1, p.max_message_bytes);
    for m in msgs {
        assert!(inlet.offer(m));
    }
    drop(inlet);
    let stop = Arc::new(AtomicBool::new(false));
    let topics = topics();
    let src = LiveSource::start(
        "test",
        rx,
        &topics,
        opts,
        p,
        stop,
        stats.clone(),
        Box::new(|_| {}),
    )
    .unwrap();
    (src, stats)
}

/// Items of a live source fed `msgs`, and the inlet's counts.
fn drain(msgs: Vec<Incoming>, opts: &ReadOptions, p: &LiveParams) -> (Vec<Item>, [u64; 4]) {
    let (mut src, stats) = source(msgs, opts, p);
    assert_eq!(
        src.info().gyro,
        usize::MAX,
        "the gyro was heard at the start"
    );
    assert!(
        src.info().base_from_laser.is_some(),
        "/tf_static states the mounting"
    );
    let mut items = Vec::new();
    while let Some(i) = src.next_item().unwrap() {
        items.push(i);
    }
    (items, stats.counts())
}

fn stamps(items: &[Item], stream: fn(&Item) -> bool) -> Vec<f64> {
    items
        .iter()
        .filter(|i| stream(i))
        .map(Item::stamp)
        .collect()
}

#[test]
fn stored_messages_come_out_as_the_bag_readers_samples() {
    let opts = live_opts();
    let (live, counts) = drain(messages(&opts), &opts, &params());
    let rec = odocal::io::read_recording(BUNDLED.as_ref(), &ReadOptions::default()).unwrap();
    let is_scan: fn(&Item) -> bool = |i| matches!(i, Item::Scan(_));
    let is_wheel: fn(&Item) -> bool = |i| matches!(i, Item::Wheel(_));
    let is_gyro: fn(&Item) -> bool = |i| matches!(i, Item::Gyro(_));
    // A live stream's unset (zero) header stamps are refused: the
    // simulated recording starts its clock at 0 s.
    let set = |t: &f64| *t != 0.0;
    let want_scans: Vec<f64> = rec.scans.iter().map(|s| s.stamp).filter(set).collect();
    let want_wheels: Vec<f64> = rec.wheels.iter().map(|s| s.stamp).filter(set).collect();
    let zero = rec.scans.len() - want_scans.len() + rec.wheels.len() - want_wheels.len()
        + rec.gyro.iter().filter(|g| g.stamp == 0.0).count();
    assert!(zero > 0 && zero < 5, "{zero} messages stamped 0");
    assert_eq!(stamps(&live, is_scan), want_scans);
    assert_eq!(stamps(&live, is_wheel), want_wheels);
    assert_eq!(
        stamps(&live, is_gyro).len(),
        rec.gyro.iter().filter(|g| g.stamp != 0.0).count()
    );
    // The wheel angles themselves, not only their stamps.
    let first_wheel = live.iter().find_map(|i| match i {
        Item::Wheel(w) => Some(*w),
        _ => None,
    });
    assert_eq!(
        first_wheel,
        rec.wheels.iter().find(|w| w.stamp != 0.0).copied()
    );
    assert_eq!(counts[3] as usize, zero, "only the unset stamps refused");
}

#[test]
fn malformed_and_backward_messages_are_refused_and_the_stream_goes_on() {
    let opts = live_opts();
    let mut msgs = messages(&opts);
    // Every scan but the one stamped 0 (unset) at the start.
    let n_scans = msgs.iter().filter(|m| m.topic == "/scan").count() - 1;
    // After the start: garbage under /scan, a scan cut short and a scan
    // from the past (time going back).
    let k = msgs.len() / 2;
    let scan_at = msgs[k..].iter().position(|m| m.topic == "/scan").unwrap() + k;
    let mut cut = msgs[scan_at].clone();
    cut.data.truncate(cut.data.len() / 2);
    let first_scan = msgs.iter().find(|m| m.topic == "/scan").unwrap().clone();
    let garbage = Incoming {
        data: vec![0, 1, 0, 0, 0xff, 0xff, 0xff, 0xff, 1, 2, 3],
        ..first_scan.clone()
    };
    for m in [garbage, cut, first_scan] {
        msgs.insert(scan_at, m);
    }
    let p = params();
    let (items, counts) = drain(msgs, &opts, &p);
    let scans = items.iter().filter(|i| matches!(i, Item::Scan(_))).count();
    assert_eq!(scans, n_scans, "every real scan still came through");
    let (_, clean) = drain(messages(&opts), &opts, &p);
    assert_eq!(
        counts[3] - clean[3],
        3,
        "garbage, the cut scan and the backward scan refused"
    );
}

#[test]
fn an_oversized_message_is_counted_not_queued() {
    let (inlet, rx, stats) = Inlet::new(4, 1_000);
    let m = Incoming {
        topic: "/scan".into(),
        data: vec![0; 1_001],
        log_time_ns: 0,
        arrived: Instant::now(),
    };
    assert!(inlet.offer(m));
    assert_eq!(stats.counts()[2], 1);
    assert!(rx.try_recv().is_err());
}

#[test]
fn silent_wheels_drop_scans_and_a_silent_gyro_leaves_the_run() {
    let opts = live_opts();
    let msgs = messages(&opts);
    // No gyro after 20 s of log time; no wheels from 40 to 50 s.
    let t0 = msgs[0].log_time_ns;
    let s = |m: &Incoming| (m.log_time_ns - t0) as f64 * 1e-9;
    let kept: Vec<Incoming> = msgs
        .into_iter()
        .filter(|m| {
            let t = s(m);
            let wheel_gap = m.topic == "/joint_states" && (40.0..50.0).contains(&t);
            let gyro_gone = m.topic == "/imu" && t > 20.0;
            !wheel_gap && !gyro_gone
        })
        .collect();
    let (mut src, _) = source(kept, &opts, &params());
    let mut ended_at = None;
    let mut scans_in_gap = 0;
    let mut gyro_after = 0;
    while let Some(i) = src.next_item().unwrap() {
        if src.gyro_ended() && ended_at.is_none() {
            ended_at = Some(i.stamp());
        }
        match &i {
            // The wheels' last sample is near 40 s; silence_s is 3 s.
            Item::Scan(sc) if (43.5..50.0).contains(&sc.stamp) => scans_in_gap += 1,
            Item::Gyro(_) if ended_at.is_some() => gyro_after += 1,
            _ => {}
        }
    }
    let ended = ended_at.expect("the silent gyro was ended");
    assert!((23.0..25.0).contains(&ended), "gyro ended at {ended} s");
    assert_eq!(gyro_after, 0);
    assert_eq!(
        scans_in_gap, 0,
        "scans beyond the wheels by > 3 s are dropped"
    );
    let t = src.traffic();
    let t = t.lock().unwrap();
    assert!(t.scans_dropped > 100, "{} dropped", t.scans_dropped);
    assert!(t.gyro_dropped);
}

#[test]
fn a_run_that_never_starts_says_what_came() {
    let opts = live_opts();
    let only_scans: Vec<Incoming> = messages(&opts)
        .into_iter()
        .filter(|m| m.topic == "/scan")
        .take(50)
        .collect();
    let (inlet, rx, stats) = Inlet::new(100, 8 << 20);
    for m in only_scans {
        inlet.offer(m);
    }
    let p = LiveParams {
        wait_s: 0.5,
        ..params()
    };
    let stop = Arc::new(AtomicBool::new(false));
    let e = LiveSource::start(
        "ROS 2 domain 9",
        rx,
        &topics(),
        &opts,
        &p,
        stop,
        stats,
        Box::new(|_| {}),
    )
    .err()
    .expect("no wheels: no start");
    let m = e.to_string();
    assert!(m.contains("ROS 2 domain 9"), "{m}");
    assert!(m.contains("49 scans on /scan"), "{m}");
    assert!(m.contains("1 refused"), "{m}");
    assert!(m.contains("0 wheel samples on /joint_states"), "{m}");
    drop(inlet);
}

#[test]
fn a_configured_topic_of_another_type_is_refused_by_name() {
    let opts = live_opts();
    let (_inlet, rx, stats) = Inlet::new(4, 1_000);
    let mut t = topics();
    t[0].1 = "sensor_msgs/msg/PointCloud2".into();
    let stop = Arc::new(AtomicBool::new(false));
    let e = LiveSource::start("d", rx, &t, &opts, &params(), stop, stats, Box::new(|_| {}))
        .err()
        .expect("wrong type refused");
    assert!(e.to_string().contains("/scan"), "{e}");
    assert!(e.to_string().contains("LaserScan"), "{e}");
}
