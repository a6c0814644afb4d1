//! Hidden effects in simulated recordings (ray-cast LMS111 scans, quantised
//! encoders, gyro), run blind: ICP on the scans, then the diagnosis of the
//! nominal robot. The simulator's truth never reaches `diagnose`.

use crate::support::assert_recovered;
use odocal::diagnose::{diagnose, DiagnoseParams, Measured, Verdict};
use odocal::effects::Effect;
use odocal::icp::{match_recording, IcpParams};
use odocal::robot::RobotConfig;
use odocal::sim::{simulate, SimConfig};

fn blind(effects: &[Effect], seed: u64) -> odocal::diagnose::Diagnosis {
    let mut cfg = SimConfig::default();
    cfg.scenario.name = "figure-eight".into();
    cfg.duration_s = 40.0;
    cfg.laser.rate_hz = 25.0;
    cfg.seed = seed;
    let robot = RobotConfig::default();
    let (rec, _truth) = simulate(&cfg, &robot, effects, &mut |_| {}).unwrap();
    // From here on only the recording and the nominal robot.
    let mount = rec
        .base_from_laser
        .unwrap_or_else(|| robot.laser.unwrap().pose());
    let (motions, _) = match_recording(&rec.scans, mount, None, &IcpParams::default()).unwrap();
    let m = Measured::new(&rec, &motions);
    diagnose(&robot, &m, &DiagnoseParams::default()).unwrap()
}

#[test]
fn simulated_hidden_effects_are_named_blind_through_icp() {
    for (e, seed) in [
        (Effect::WheelBaseScale { scale: 0.04 }, 11),
        (Effect::GyroBias { bias: -0.006 }, 12),
    ] {
        let d = blind(&[e], seed);
        eprintln!(
            "{e}: {:?} {:?} gain {:?} noise {:?}",
            d.verdict, d.causes, d.gain, d.noise_scale
        );
        assert_eq!(d.verdict, Verdict::Explained, "{e}: {:?}", d.candidates);
        let c = d
            .causes
            .iter()
            .find(|c| c.effect == e.name())
            .expect("named");
        // Each size within 20 % of the hidden one; the effect left out (a
        // size of 0) misses by five times that and must fail the same check.
        for (k, v) in e.params() {
            let what = format!("{e}: {k} {c:?}");
            assert_recovered(&what, c.parameters[k], v, 0.0, 0.2 * v.abs());
        }
        assert!(d.gain.relative > 0.0);
    }
}

#[test]
fn simulated_null_recording_blind_through_icp() {
    let d = blind(&[], 13);
    eprintln!(
        "null: {:?} {:?} {:?} {:?}",
        d.verdict, d.causes, d.noise_scale, d.structure_before
    );
    // Nothing hidden: the verdict must say the nominal model agrees, not
    // merely name no cause (an `unexplained` verdict names none either).
    assert_eq!(d.verdict, Verdict::NoDiscrepancy, "{:?}", d.candidates);
    assert!(d.causes.is_empty(), "{:?}", d.causes);
    assert!(d.faults.is_empty(), "{:?}", d.faults);
    assert_eq!(d.verdict, Verdict::NoDiscrepancy, "{:?}", d.remaining);
}
