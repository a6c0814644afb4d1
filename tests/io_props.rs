//! Property tests on damaged real files: truncated, bit-flipped and spliced
//! versions of real bags (SLAM benchmark, LEGO, Mines), of the real CARMEN log
//! and of TUM trajectories fed to the readers. Each gives an error value or a
//! correct partial read — never a panic, never a NaN in what was read.

use std::path::PathBuf;
use std::sync::OnceLock;

use odocal::eval::traj3::Trajectory3;
use odocal::geom::Pose2;
use odocal::io::carmen::read_carmen_bytes;
use odocal::io::tum::parse_tum;
use odocal::io::{read_mcap_bytes, ReadOptions, TopicConfig};
use odocal::recording::Recording;
use proptest::prelude::*;

use crate::support::shared_data;

fn pose_ok(p: &Pose2) -> bool {
    let v = p.translation.vector;
    let (c, s) = (p.rotation.re, p.rotation.im);
    [v.x, v.y, c, s].iter().all(|x| x.is_finite()) && ((c * c + s * s) - 1.0).abs() < 1e-9
}

/// Every float a reader returns is finite (scan ranges excepted: REP 117 lets
/// them be NaN/±inf, marking invalid beams), every stream sorted, no empty scan.
pub(crate) fn assert_sound(r: &Recording) {
    let streams: [(&str, Vec<f64>); 5] = [
        ("scans", r.scans.iter().map(|s| s.stamp).collect()),
        ("wheels", r.wheels.iter().map(|s| s.stamp).collect()),
        ("gyro", r.gyro.iter().map(|s| s.stamp).collect()),
        ("odom", r.odom.iter().map(|s| s.stamp).collect()),
        ("reference", r.reference.iter().map(|s| s.stamp).collect()),
    ];
    for (name, t) in &streams {
        assert!(t.iter().all(|x| x.is_finite()), "{name}: non-finite stamp");
        assert!(t.windows(2).all(|w| w[0] <= w[1]), "{name}: not sorted");
    }
    for s in &r.scans {
        let geometry = [
            s.angle_min,
            s.angle_increment,
            s.time_increment,
            s.scan_time,
            s.range_min,
            s.range_max,
        ];
        assert!(
            geometry.iter().all(|v| v.is_finite()),
            "scan geometry {geometry:?}"
        );
        assert!(!s.ranges.is_empty());
    }
    for w in &r.wheels {
        assert!(w.left.is_finite() && w.right.is_finite(), "{w:?}");
    }
    for g in &r.gyro {
        assert!(g.wz.is_finite(), "{g:?}");
    }
    for p in r.odom.iter().chain(&r.reference) {
        assert!(pose_ok(&p.pose), "{p:?}");
    }
    if let Some(p) = &r.base_from_laser {
        assert!(pose_ok(p), "{p:?}");
    }
}

/// A TUM trajectory is sound: ≥ 2 poses, stamps strictly increasing, finite,
/// unit quaternions.
fn assert_sound_tum(t: &Trajectory3) {
    assert!(t.stamps.len() >= 2 && t.stamps.len() == t.poses.len());
    assert!(t.stamps.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(t.first_non_finite(), None);
    for p in &t.poses {
        assert!((p.rotation.coords.norm() - 1.0).abs() < 1e-9);
    }
}

fn opts() -> ReadOptions {
    // LEGO and Mines publish their reference on /reference.
    ReadOptions {
        topics: TopicConfig {
            reference: "/reference".into(),
            ..Default::default()
        },
        ..Default::default()
    }
}

const BAGS: [&str; 3] = [
    "slam-benchmark/mit-csail.mcap",
    "lego-robot/lego-robot.mcap",
    "mines-rover/exp2.mcap",
];

/// A real bag's bytes and its full read.
type Bag = (Vec<u8>, Recording);

/// The real bags, loaded once; `None` without shared data.
fn bags() -> Option<&'static Vec<Bag>> {
    static B: OnceLock<Option<Vec<Bag>>> = OnceLock::new();
    B.get_or_init(|| {
        let dir: PathBuf = shared_data("io_props (real bags)")?;
        Some(
            BAGS.iter()
                .map(|f| {
                    let b = std::fs::read(dir.join(f)).unwrap();
                    let r = read_mcap_bytes(&b, f, &opts()).expect("the intact bag reads");
                    (b, r)
                })
                .collect(),
        )
    })
    .as_ref()
}

/// The first 120 lines of the real CARMEN log (117 FLASER records) and their read.
fn carmen() -> Option<&'static (String, Recording)> {
    static C: OnceLock<Option<(String, Recording)>> = OnceLock::new();
    C.get_or_init(|| {
        let dir = shared_data("io_props (CARMEN log)")?;
        let text = std::fs::read_to_string(dir.join("slam-benchmark/mit-csail.clf")).unwrap();
        let head: String = text.lines().take(120).map(|l| format!("{l}\n")).collect();
        let r = read_carmen_bytes(head.as_bytes(), "head.clf", &ReadOptions::default()).unwrap();
        assert!(r.scans.len() > 100, "{} scans", r.scans.len());
        Some((head, r))
    })
    .as_ref()
}

/// A TUM text of the real log's odometry (as `odocal` writes TUM files).
fn tum() -> Option<&'static (String, Trajectory3)> {
    static T: OnceLock<Option<(String, Trajectory3)>> = OnceLock::new();
    T.get_or_init(|| {
        let (_, r) = carmen()?;
        let mut text = String::from("# timestamp tx ty tz qx qy qz qw\n");
        for p in &r.odom {
            let v = p.pose.translation.vector;
            let h = p.pose.rotation.angle();
            text.push_str(&format!(
                "{} {} {} 0 0 0 {} {}\n",
                p.stamp,
                v.x,
                v.y,
                (h / 2.0).sin(),
                (h / 2.0).cos()
            ));
        }
        let t = parse_tum(&text, "odom.tum").unwrap();
        Some((text, t))
    })
    .as_ref()
}

/// Applies bit flips at fractional positions (position fraction, bit).
fn flip(bytes: &mut [u8], flips: &[(f64, u8)]) {
    let n = bytes.len();
    for &(f, bit) in flips {
        let at = ((f * n as f64) as usize).min(n - 1);
        bytes[at] ^= 1 << bit;
    }
}

fn cut_at(n: usize, f: f64) -> usize {
    ((f * n as f64) as usize).min(n.saturating_sub(1))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// A bag cut anywhere is always detected (the footer is gone).
    #[test]
    fn truncated_real_bag_is_an_error(which in 0usize..3, f in 0.0f64..1.0) {
        let Some(bags) = bags() else { return Ok(()) };
        let (b, _) = &bags[which];
        let e = read_mcap_bytes(&b[..cut_at(b.len(), f)], "cut.mcap", &opts());
        let e = e.expect_err("a truncated bag must not read as complete");
        prop_assert_eq!(e.file.as_str(), "cut.mcap");
    }

    /// Flipped bits: an error, or a sound recording.
    #[test]
    fn bit_flipped_real_bag_is_an_error_or_sound(
        which in 0usize..3,
        flips in proptest::collection::vec((0.0f64..1.0, 0u8..8), 1..6),
    ) {
        let Some(bags) = bags() else { return Ok(()) };
        let mut b = bags[which].0.clone();
        flip(&mut b, &flips);
        if let Ok(r) = read_mcap_bytes(&b, "flipped.mcap", &opts()) {
            assert_sound(&r);
        }
    }

    /// A spliced bag (the head of one bag, the tail of another or the same):
    /// an error, or a sound recording.
    #[test]
    fn spliced_real_bags_are_an_error_or_sound(
        a in 0usize..3, b in 0usize..3, fa in 0.0f64..1.0, fb in 0.0f64..1.0,
    ) {
        let Some(bags) = bags() else { return Ok(()) };
        let (x, y) = (&bags[a].0, &bags[b].0);
        let mut s = x[..cut_at(x.len(), fa)].to_vec();
        s.extend_from_slice(&y[cut_at(y.len(), fb)..]);
        if let Ok(r) = read_mcap_bytes(&s, "spliced.mcap", &opts()) {
            assert_sound(&r);
        }
    }

    /// A CARMEN log cut anywhere: an error naming a line, or a read whose
    /// records equal the full read's, all but the last record (whose final
    /// number may itself have been cut).
    #[test]
    fn truncated_carmen_log_reads_a_correct_prefix(f in 0.0f64..1.0) {
        let Some((text, full)) = carmen() else { return Ok(()) };
        let cut = &text.as_bytes()[..cut_at(text.len(), f)];
        match read_carmen_bytes(cut, "cut.clf", &ReadOptions::default()) {
            Ok(r) => {
                assert_sound(&r);
                let n = r.scans.len();
                prop_assert!(n <= full.scans.len());
                prop_assert_eq!(&r.scans[..n.saturating_sub(1)], &full.scans[..n.saturating_sub(1)]);
                prop_assert_eq!(&r.odom[..n.saturating_sub(1)], &full.odom[..n.saturating_sub(1)]);
            }
            Err(e) => {
                prop_assert_eq!(e.file.as_str(), "cut.clf");
                let pos = e.position.clone().unwrap_or_default();
                prop_assert!(pos.starts_with("line ") || e.message.contains("neither"), "{}", e);
            }
        }
    }

    /// Flipped bits and spliced lines in a CARMEN log: an error or sound.
    #[test]
    fn damaged_carmen_log_is_an_error_or_sound(
        flips in proptest::collection::vec((0.0f64..1.0, 0u8..8), 1..6),
        fa in 0.0f64..1.0, fb in 0.0f64..1.0,
    ) {
        let Some((text, _)) = carmen() else { return Ok(()) };
        let mut b = text.as_bytes().to_vec();
        flip(&mut b, &flips);
        if let Ok(r) = read_carmen_bytes(&b, "flipped.clf", &ReadOptions::default()) {
            assert_sound(&r);
        }
        let t = text.as_bytes();
        let mut s = t[..cut_at(t.len(), fa)].to_vec();
        s.extend_from_slice(&t[cut_at(t.len(), fb)..]);
        if let Ok(r) = read_carmen_bytes(&s, "spliced.clf", &ReadOptions::default()) {
            assert_sound(&r);
        }
    }

    /// TUM text cut, flipped or spliced: an error, or a sound trajectory; a
    /// cut one keeps the intact poses but the last.
    #[test]
    fn damaged_tum_is_an_error_or_sound(
        f in 0.0f64..1.0,
        flips in proptest::collection::vec((0.0f64..1.0, 0u8..7), 1..6),
        fa in 0.0f64..1.0, fb in 0.0f64..1.0,
    ) {
        let Some((text, full)) = tum() else { return Ok(()) };
        if let Ok(t) = parse_tum(&text[..cut_at(text.len(), f)], "cut.tum") {
            assert_sound_tum(&t);
            let n = t.len() - 1;
            prop_assert_eq!(&t.stamps[..n], &full.stamps[..n]);
            prop_assert_eq!(&t.poses[..n], &full.poses[..n]);
        }
        // Bits 0..7 keep the text ASCII, so it stays a str.
        let mut b = text.as_bytes().to_vec();
        flip(&mut b, &flips);
        if let Ok(t) = parse_tum(std::str::from_utf8(&b).unwrap(), "flipped.tum") {
            assert_sound_tum(&t);
        }
        let mut s = text[..cut_at(text.len(), fa)].to_string();
        s.push_str(&text[cut_at(text.len(), fb)..]);
        if let Ok(t) = parse_tum(&s, "spliced.tum") {
            assert_sound_tum(&t);
        }
    }
}
