//! ICP on the Freiburg SLAM benchmark logs (shared real data), judged by the
//! relation metric of \[Kummerle2009\] like the `odocal icp` + `odocal
//! eval --relations` commands, against Censi's CSM (PL-ICP \[Censi2008\], scan to scan,
//! odometry as initial guess) and the raw odometry as measured on the same
//! bags (/work/shared/data/slam-benchmark/reference.md): on the local
//! relations (< 10 s apart) in translation and rotation, and on all of them.
//! Every figure is taken over the convergence ensemble
//! (`support::convergence_ensemble`): the long relations move by up to a
//! factor of two between its members.

use crate::support::{convergence_ensemble, shared_data};
use odocal::diagnose::stats::median;
use odocal::eval::{self, RelationStats};
use odocal::io::relations::read_relations;
use odocal::io::{read_recording, ReadOptions};
use odocal::pipeline::icp::match_recording as run;
use odocal::robot::RobotConfig;

/// Relation figures of one log over the convergence ensemble (default
/// parameters but the convergence bound, the recording's own odometry as
/// prior, as `odocal icp` runs it): one `RelationStats` per member.
fn icp_relations(test: &str, name: &str) -> Option<Vec<RelationStats>> {
    let dir = shared_data(test)?.join("slam-benchmark");
    let rec = read_recording(&dir.join(format!("{name}.mcap")), &ReadOptions::default()).unwrap();
    let rels = read_relations(&dir.join(format!("{name}.relations"))).unwrap();
    let mut out = Vec::new();
    for params in convergence_ensemble() {
        let m = run(&rec, &RobotConfig::default(), &params).unwrap();
        let s = eval::relations(&m.trajectory, &rels).unwrap();
        let l = s.local.unwrap();
        eprintln!(
            "{name} (convergence {:.1e}): local {} rel {:.4} ± {:.4} m {:.3}°; all {} rel {:.3} ± {:.3} m {:.2}°; failed pairs {:?}",
            params.convergence, l.count, l.trans_mean, l.trans_std, l.rot_mean_deg,
            s.all.count, s.all.trans_mean, s.all.trans_std, s.all.rot_mean_deg, m.stats.failures
        );
        assert_eq!(s.skipped, 0, "{name}: relations outside the trajectory");
        out.push(s);
    }
    Some(out)
}

/// The ensemble's medians: local translation mean (m), its std (m), local
/// rotation mean (deg), all relations' translation mean (m). The last falls
/// into two groups by which way a few places go; a run of the far group
/// moves the median of five by little, the mean by a fifth of the gap.
struct Ensemble {
    local: f64,
    local_std: f64,
    local_deg: f64,
    all: f64,
}

fn ensemble(runs: &[RelationStats]) -> Ensemble {
    let of = |f: fn(&RelationStats) -> f64| median(&mut runs.iter().map(f).collect::<Vec<_>>());
    Ensemble {
        local: of(|s| s.local.unwrap().trans_mean),
        local_std: of(|s| s.local.unwrap().trans_std),
        local_deg: of(|s| s.local.unwrap().rot_mean_deg),
        all: of(|s| s.all.trans_mean),
    }
}

/// Asserts the ensemble's figures are below the anchors (local m, local
/// deg, all m).
fn beats(name: &str, runs: &[RelationStats], local_m: f64, local_deg: f64, all_m: f64) {
    let m = ensemble(runs);
    assert!(m.local < local_m, "{name} local {} m", m.local);
    assert!(m.local_deg < local_deg, "{name} local {}°", m.local_deg);
    assert!(m.all < all_m, "{name} all {} m", m.all);
}

#[test]
fn icp_relations_intel_beat_csm() {
    let Some(s) = icp_relations("icp_relations_intel_beat_csm", "intel") else {
        return;
    };
    // CSM on intel: local 0.023 ± 0.098 m, 0.40°; all 3.38 ± 7.12 m
    // (published; measured here 0.024 ± 0.109 m, 0.354°, all 3.38 m).
    // odocal over the ensemble: local 0.0176–0.0180 m, 0.292–0.314°, all
    // 2.11–2.30 m.
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
    // CSM (measured here, the same over its own ensemble of convergence
    // bounds): local 0.028 ± 0.029 m, 0.408°, all 0.254–0.266 m. The
    // odometry freezes for about a second three times and then jumps;
    // detected, the freezes no longer cost the long relations their heading.
    // Local translation: 0.0282 m with the prior term centred on the
    // odometry, 0.0274 m centred on its blend with the constant-velocity
    // guess (half of the short relations carry the odometry's own
    // translation, to < 1 mm, so the odometry cannot simply be dropped).
    // Over the ensemble: local 0.0270–0.0272 m, 0.374–0.411° (median 0.398°),
    // all 0.115–0.252 m (median 0.20 m). Over 25 bounds from 0.7 to
    // 1.3·10⁻⁵: 21 runs ahead of CSM, four at 0.48–0.58 m (median 0.20,
    // mean 0.25 m): the long relations follow a fast turn at 999 s under a
    // late odometry, matched or not by a micrometre's difference.
    beats("mit-csail", &s, 0.028, 0.408, 0.26);
}

#[test]
fn icp_relations_aces_beat_csm() {
    let Some(s) = icp_relations("icp_relations_aces_beat_csm", "aces") else {
        return;
    };
    // Not used for tuning. CSM on aces: local 0.040 ± 0.034 m, all
    // 0.36 ± 1.44 m (published; measured here 0.0405 ± 0.035 m, 0.324°, all
    // 0.415–0.418 m); rotation 0.3–0.5° over the logs. odocal over the
    // ensemble: local 0.0334–0.0341 m, 0.317–0.328°, all 0.125–0.141 m.
    beats("aces", &s, 0.040, 0.40, 0.36);
}

#[test]
fn icp_relations_fr079_long_relations_on_par_with_csm() {
    let Some(s) = icp_relations(
        "icp_relations_fr079_long_relations_on_par_with_csm",
        "fr079",
    ) else {
        return;
    };
    // Not used for tuning. CSM on fr079 (measured here, the same over its
    // own ensemble): local 0.033 ± 0.022 m, 0.396°; all 0.444–0.470 m.
    // odocal stays 1 mm behind on the local mean (0.0335–0.0344 m over 15
    // convergence bounds from 0.7 to 1.4·10⁻⁵). Its long relations are not
    // ahead of CSM's: 0.39–0.60 m over 25 bounds from 0.7 to 1.3·10⁻⁵
    // (median 0.44, mean 0.46 m; 17 below CSM's), in two groups (0.39–0.46
    // and 0.49–0.60 m) by which way a few places go — a reversal the odometry missed (1587–1589 s), where the
    // forward information of four pairs counts as measured in some runs
    // (the scans place them, backwards, as the relations say) and not in
    // others (the odometry does, forwards), and few inliers at 1768–1773 s.
    // Asserted: the median within 20 % of CSM's (3 runs in 25 are beyond,
    // and a median of five only when three of its runs are).
    let m = ensemble(&s);
    assert!(m.all < 0.55, "fr079 all {} m", m.all);
    assert!(
        m.local < 0.035 && m.local_std < 0.030,
        "fr079 local {} ± {} m",
        m.local,
        m.local_std
    );
    assert!(m.local_deg < 0.40, "fr079 local {}°", m.local_deg);
}
