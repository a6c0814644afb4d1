//! The prior's clock check through the whole chain: a simulated wheelchair
//! whose encoder stream is stamped late by a known delay (the `latency`
//! effect), written to a bag and read back, then scan matching with the
//! wheel-odometry prior. The check must find that delay from the turns
//! alone, say nothing against a prior read at it, and find no offset where
//! there is none.

use crate::support::{assert_recovered, scratch};
use odocal::effects::Effect;
use odocal::icp::{IcpParams, TimeOffsetFit};
use odocal::io::{read_recording, write_mcap, ReadOptions, WriteOptions};
use odocal::recording::Recording;
use odocal::robot::RobotConfig;
use odocal::sim::{self, SimConfig};

/// 40 s of the random walk (turns started and stopped often: a time shift
/// shows in every one) with the encoders stamped `delay` s late, through a
/// bag.
fn random_walk_bag(test: &str, delay: f64) -> (Recording, RobotConfig) {
    let mut cfg = SimConfig {
        duration_s: 40.0,
        seed: 3,
        ..SimConfig::default()
    };
    cfg.scenario.name = "random-walk".into();
    let robot = RobotConfig::default();
    let effects: Vec<Effect> = if delay > 0.0 {
        vec![Effect::Latency { delay }]
    } else {
        Vec::new()
    };
    let (rec, _) = sim::simulate(&cfg, &robot, &effects, &mut |_| {}).unwrap();
    let path = scratch(test).join("walk.mcap");
    write_mcap(&path, &rec, &WriteOptions::default()).unwrap();
    (
        read_recording(&path, &ReadOptions::default()).unwrap(),
        robot,
    )
}

fn fit(rec: &Recording, robot: &RobotConfig, time_offset: f64) -> TimeOffsetFit {
    let params = IcpParams {
        time_offset,
        ..Default::default()
    };
    let out = odocal::pipeline::icp::match_recording(rec, robot, &params).unwrap();
    let f = out
        .stats
        .prior_time_offset
        .expect("a prior and matched pairs");
    eprintln!("offset in use {time_offset:+.3} s: {f:?}");
    f
}

#[test]
fn icp_finds_the_encoders_latency_and_accepts_a_prior_read_at_it() {
    // `latency:delay=0.1`: the encoder reading of an instant is stamped
    // 0.1 s after it, i.e. odometry stamp − laser stamp = +0.1 s.
    let (rec, robot) = random_walk_bag("icp_time_offset_latency", 0.1);
    // The check's resolution on simulated turns is a few hundredths of a
    // second (without a latency it finds +0.001 s here, +0.04 s on the
    // smoother figure eight, where a shift of the odometry changes little).
    // A check that finds nothing answers the offset in use (0), which is
    // over three tolerances from the delay and must fail the same check.
    let at_zero = fit(&rec, &robot, 0.0);
    let what = format!("best offset read at 0: {at_zero:?}");
    assert_recovered(&what, at_zero.best_s, 0.1, at_zero.used_s, 0.03);
    assert!(at_zero.contradicts_used(), "{at_zero:?}");
    let at_delay = fit(&rec, &robot, 0.1);
    assert!((at_delay.best_s - 0.1).abs() < 0.03, "{at_delay:?}");
    assert!(!at_delay.contradicts_used(), "{at_delay:?}");
    // Read at the delay, the prior's turns are the matched ones' to within
    // the matching noise: the difference at 0 was the delay's.
    assert!(
        at_delay.rms_used_rad < 0.5 * at_zero.rms_used_rad,
        "{at_delay:?} vs {at_zero:?}"
    );
}

#[test]
fn icp_finds_no_offset_where_the_clocks_agree() {
    let (rec, robot) = random_walk_bag("icp_time_offset_none", 0.0);
    let f = fit(&rec, &robot, 0.0);
    // Within 30 ms of no offset; an answer at the 0.1 s latency the test
    // above hides fails the same check, so the check tells one apart.
    let agrees = |s: f64| s.abs() < 0.03;
    assert!(agrees(f.best_s), "{f:?}");
    assert!(!agrees(0.1), "the latency passes the check");
    assert!(!f.contradicts_used(), "{f:?}");
}

/// The Mines rover stamps its scans 0.18 s late (the batch calibration's
/// `time_offset`, a maximum-likelihood fit of the wheel rates to the scans'
/// speeds): the scan matcher's check, from the turns alone, finds the same
/// offset, and a calibration that pairs the two streams at equal stamps
/// says so in its assumptions.
#[test]
fn mines_rover_clock_check_agrees_with_the_batch_and_calibrate_states_it() {
    let Some(data) = crate::support::shared_data("mines_rover_clock_check") else {
        return;
    };
    let bag = data.join("mines-rover/exp2.mcap");
    let robot = concat!(env!("CARGO_MANIFEST_DIR"), "/scans/robots/mines-rover.toml");
    let dir = scratch("mines_rover_clock_check");
    let json = |args: &[&str]| -> serde_json::Value {
        let out = crate::support::odocal(args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let (bag, out) = (bag.to_str().unwrap(), |name: &str| dir.join(name));
    let run = |cmd: &str, method: &[&str], to: &std::path::Path| {
        let to = to.to_str().unwrap();
        let args = [&[cmd, "--input", bag, "--robot", robot], method].concat();
        json(&[&args[..], &["--out", to, "--json"]].concat())
    };
    let icp = run("icp", &[], &out("exp2.tum"));
    let best = icp["prior_time_offset"]["best_s"].as_f64().unwrap();
    let batch = run("calibrate", &["--method", "batch"], &out("batch"));
    let delta = batch["time_offset"]["value"].as_f64().unwrap();
    eprintln!("clock check {best:+.4} s, batch {delta:+.4} s");
    // The check's offset in use is 0, which misses the batch's by six
    // tolerances and must fail the same check.
    let used = icp["prior_time_offset"]["used_s"].as_f64().unwrap();
    assert_recovered("clock check vs batch", best, delta, used, 0.03);
    // The filters estimate the offset on the stream themselves: within 25 ms
    // (a quarter of a wheel period) of the batch's, where 0 is 180 ms off.
    let dkf = run("calibrate", &["--method", "dkf"], &out("dkf"));
    let a = &dkf["assumptions"]["time_offset"];
    assert_eq!(a["source"], "estimated", "{a}");
    let online = a["value"].as_f64().unwrap();
    crate::support::assert_recovered("time_offset", online, delta, 0.0, 0.025);
    // With the scan matcher's prior read at another offset, the filters'
    // own estimate does not follow it.
    let cfg = out("prior_offset.toml");
    std::fs::write(&cfg, "[icp]\ntime_offset = -0.05\n").unwrap();
    let cfg = ["--method", "dkf", "--config", cfg.to_str().unwrap()];
    let shifted = run("calibrate", &cfg, &out("dkf_shifted"));
    let a = &shifted["assumptions"]["time_offset"];
    let v = a["value"].as_f64().unwrap();
    crate::support::assert_recovered("time_offset, prior shifted", v, delta, 0.0, 0.025);
}
