//! The relation metric \[Kummerle2009\] on the raw odometry of the
//! Freiburg SLAM benchmark logs reproduces the figures measured for it
//! (/work/shared/data/slam-benchmark/reference.md, "raw odometry"), to the
//! precision they are reported with.

use crate::support;
use odocal::eval::{self, trajectory_from_stamped};
use odocal::io::relations::read_relations;
use odocal::io::{read_recording, ReadOptions};

/// `value` rounds to `reported` at `decimals` decimals (half a unit of the last digit).
fn rounds_to(value: f64, reported: f64, decimals: i32) -> bool {
    (value - reported).abs() <= 0.5 * 10f64.powi(-decimals) + 1e-12
}

fn check_log(test: &str, name: &str, local: (f64, f64), all: (f64, f64), all_decimals: i32) {
    let Some(data) = support::shared_data(test) else {
        return;
    };
    let dir = data.join("slam-benchmark");
    let mut opts = ReadOptions::default();
    // Only the odometry is needed; no topic of this name exists, so scans are skipped.
    opts.topics.scan = "/unused".into();
    let rec = read_recording(&dir.join(format!("{name}.mcap")), &opts).unwrap();
    let (odom, dropped) = trajectory_from_stamped(&rec.odom);
    assert!(
        odom.len() > 1000 && dropped <= 1,
        "{name}: {} odometry poses",
        odom.len()
    );
    let rels = read_relations(&dir.join(format!("{name}.relations"))).unwrap();
    let s = eval::relations(&odom, &rels).unwrap();
    let l = s.local.unwrap();
    eprintln!(
        "{name}: local {} rel {:.4} ± {:.4} m {:.2} ± {:.2} deg; all {} rel {:.3} ± {:.3} m {:.2} ± {:.2} deg; skipped {}",
        l.count, l.trans_mean, l.trans_std, l.rot_mean_deg, l.rot_std_deg,
        s.all.count, s.all.trans_mean, s.all.trans_std, s.all.rot_mean_deg, s.all.rot_std_deg, s.skipped
    );
    assert_eq!(s.all.count + s.skipped, rels.len());
    assert!(
        rounds_to(l.trans_mean, local.0, 3),
        "{name} local mean {}",
        l.trans_mean
    );
    assert!(
        rounds_to(l.trans_std, local.1, 3),
        "{name} local std {}",
        l.trans_std
    );
    assert!(
        rounds_to(s.all.trans_mean, all.0, all_decimals),
        "{name} all mean {}",
        s.all.trans_mean
    );
    assert!(
        rounds_to(s.all.trans_std, all.1, all_decimals),
        "{name} all std {}",
        s.all.trans_std
    );
}

#[test]
fn eval_relations_intel_raw_odometry_matches_reference() {
    check_log(
        "eval_relations_intel_raw_odometry_matches_reference",
        "intel",
        (0.035, 0.042),
        (7.38, 14.35),
        2,
    );
}

#[test]
fn eval_relations_mit_csail_raw_odometry_matches_reference() {
    check_log(
        "eval_relations_mit_csail_raw_odometry_matches_reference",
        "mit-csail",
        (0.033, 0.039),
        (1.68, 5.29),
        2,
    );
}

#[test]
fn eval_relations_aces_and_fr079_raw_odometry_match_reference() {
    let test = "eval_relations_aces_and_fr079_raw_odometry_match_reference";
    check_log(test, "aces", (0.034, 0.032), (0.55, 2.68), 2);
    check_log(test, "fr079", (0.058, 0.113), (6.50, 13.66), 2);
}
