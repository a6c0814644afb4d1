//! ICP on the Freiburg SLAM benchmark logs (shared real data), judged by the
//! relation metric of Kümmerle et al. 2009 like the `odocal icp` + `odocal
//! eval --relations` commands, against Censi's CSM (PL-ICP, scan to scan,
//! odometry as initial guess) and the raw odometry as measured on the same
//! bags (/work/shared/data/slam-benchmark/reference.md): on the local
//! relations (< 10 s apart) in translation and rotation, and on all of them.

use crate::support::shared_data;
use odocal::eval::{self, RelationStats};
use odocal::icp::IcpParams;
use odocal::io::relations::read_relations;
use odocal::io::{read_recording, ReadOptions};
use odocal::pipeline::icp::match_recording as run;
use odocal::robot::RobotConfig;

/// Relation figures of one log: default parameters, the recording's own
/// odometry as prior, as `odocal icp` runs it.
fn icp_relations(test: &str, name: &str) -> Option<RelationStats> {
    let dir = shared_data(test)?.join("slam-benchmark");
    let rec = read_recording(&dir.join(format!("{name}.mcap")), &ReadOptions::default()).unwrap();
    let out = run(&rec, &RobotConfig::default(), &IcpParams::default()).unwrap();
    let rels = read_relations(&dir.join(format!("{name}.relations"))).unwrap();
    let s = eval::relations(&out.trajectory, &rels).unwrap();
    let l = s.local.unwrap();
    eprintln!(
        "{name}: local {} rel {:.4} ± {:.4} m {:.3}°; all {} rel {:.3} ± {:.3} m {:.2}°; failed pairs {:?}",
        l.count, l.trans_mean, l.trans_std, l.rot_mean_deg,
        s.all.count, s.all.trans_mean, s.all.trans_std, s.all.rot_mean_deg, out.stats.failures
    );
    assert_eq!(s.skipped, 0, "{name}: relations outside the trajectory");
    Some(s)
}

/// Asserts the figures are below the anchors (local m, local deg, all m).
fn beats(name: &str, s: &RelationStats, local_m: f64, local_deg: f64, all_m: f64) {
    let l = s.local.unwrap();
    assert!(l.trans_mean < local_m, "{name} local {} m", l.trans_mean);
    assert!(
        l.rot_mean_deg < local_deg,
        "{name} local {}°",
        l.rot_mean_deg
    );
    assert!(
        s.all.trans_mean < all_m,
        "{name} all {} m",
        s.all.trans_mean
    );
}

#[test]
fn icp_relations_intel_beat_csm() {
    let Some(s) = icp_relations("icp_relations_intel_beat_csm", "intel") else {
        return;
    };
    // CSM on intel: local 0.023 ± 0.098 m, 0.40°; all 3.38 ± 7.12 m.
    beats("intel", &s, 0.023, 0.40, 3.38);
}

#[test]
fn icp_relations_mit_csail_beat_csm_on_all_relations_and_rotation() {
    let Some(s) = icp_relations(
        "icp_relations_mit_csail_beat_csm_on_all_relations_and_rotation",
        "mit-csail",
    ) else {
        return;
    };
    // Raw odometry on mit-csail: local 0.033 ± 0.039 m, all 1.68 ± 5.29 m;
    // CSM: local 0.028 ± 0.029 m, rotation 0.3–0.5° over the logs (0.40° on
    // intel), all 0.26 ± 0.75 m. The odometry freezes for about a second
    // three times and then jumps; detected, the freezes no longer cost the
    // long relations their heading (all: 0.35 m before, 0.20 m now). Local
    // translation: 0.0282 m with the prior term centred on the odometry,
    // 0.0274 m centred on its blend with the constant-velocity guess (half
    // of the short relations carry the odometry's own translation, to
    // < 1 mm, so the odometry cannot simply be dropped).
    beats("mit-csail", &s, 0.028, 0.40, 0.26);
}

#[test]
fn icp_relations_aces_beat_csm() {
    let Some(s) = icp_relations("icp_relations_aces_beat_csm", "aces") else {
        return;
    };
    // Not used for tuning. CSM on aces: local 0.040 ± 0.034 m, all
    // 0.36 ± 1.44 m; rotation 0.3–0.5° over the logs.
    beats("aces", &s, 0.040, 0.40, 0.36);
}

#[test]
fn icp_relations_fr079_beat_csm_on_all_relations() {
    let Some(s) = icp_relations("icp_relations_fr079_beat_csm_on_all_relations", "fr079") else {
        return;
    };
    // Not used for tuning. CSM on fr079: local 0.033 ± 0.022 m, 0.40°; all
    // 0.46 ± 0.88 m. odocal stays 1 mm behind on the local mean. A single
    // wrong match (484.6 s) whose speed the prior's centre carried over to
    // the next four scans made it 0.036 ± 0.040 m local, 0.53 m all.
    let l = s.local.unwrap();
    assert!(s.all.trans_mean < 0.46, "fr079 all {} m", s.all.trans_mean);
    assert!(
        l.trans_mean < 0.035 && l.trans_std < 0.030,
        "fr079 local {} ± {} m",
        l.trans_mean,
        l.trans_std
    );
    assert!(l.rot_mean_deg < 0.40, "fr079 local {}°", l.rot_mean_deg);
}
