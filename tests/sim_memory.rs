//! The simulator in flat memory: a streamed run's sensors read the motion
//! through windows bounded by what one sample (or one block of scans) reads,
//! whatever the run's length; they give, bit for bit, the samples of the
//! whole drive kept in memory; and `odocal simulate`'s peak resident memory,
//! as the kernel accounts it for the process, does not grow with the run.

use crate::support::{python_with, scratch};
use odocal::effects::Effect;
use odocal::robot::RobotConfig;
use odocal::sim::{self, SimConfig, TrueRobot, WheelTrack};
use std::process::Command;

fn config(duration: f64) -> SimConfig {
    SimConfig {
        duration_s: duration,
        ..Default::default()
    }
}

/// The most drive poses a stream's tape held at once over the whole stream.
fn most_held<S: sim::Sensor>(mut s: sim::SensorStream<S>) -> usize {
    let mut most = s.held();
    while s.next().is_some() {
        most = most.max(s.held());
    }
    most
}

#[test]
fn sensor_windows_are_bounded_by_one_sample_whatever_the_run_length() {
    let robot = RobotConfig::default();
    let effects = [Effect::parse("latency:delay=0.3").unwrap()];
    let mut held = Vec::new();
    for duration in [20.0, 200.0] {
        let run = sim::prepare(&config(duration), &robot, &effects).unwrap();
        held.push([
            most_held(run.encoders()),
            most_held(run.gyro()),
            most_held(run.reference()),
            most_held(run.trajectory()),
        ]);
    }
    assert_eq!(held[0], held[1], "windows grew with the run: {held:?}");
    // A sample reads one instant (encoders: the latency earlier; reference,
    // truth), or the gyro's interval of 1/100 s = 10 steps of 1 ms: the pose
    // before and after each end, and nothing older.
    let [enc, gyro, reference, truth] = held[1];
    assert!(enc <= 3 && reference <= 3 && truth <= 3, "{:?}", held[1]);
    assert!(gyro <= 10 + 3, "{gyro}");
}

#[test]
fn laser_window_is_one_block_of_scans() {
    let run = sim::prepare(&config(12.0), &RobotConfig::default(), &[]).unwrap();
    let mut laser = run.laser();
    let n = laser.len();
    assert_eq!(n, 600);
    let mut most = 0;
    let mut start = 0;
    while start < n {
        let end = (start + sim::LaserSim::BLOCK).min(n);
        assert_eq!(laser.scans(start..end).len(), end - start);
        most = most.max(laser.held());
        start = end;
    }
    // 250 scans at 50 Hz span 4.98 s, plus a sweep of 15 ms: 4,995 steps of 1 ms.
    assert!((4990..=5000).contains(&most), "{most}");
}

#[test]
fn streams_equal_the_whole_drive_kept_in_memory() {
    // The same run through the whole `drive` (every step kept), its wheel
    // track and the encoder model over it, against the streams' windows.
    let cfg = config(30.0);
    let robot = RobotConfig::default();
    let effects = [
        Effect::parse("latency:delay=0.25").unwrap(),
        Effect::parse("radius_step:time=7,right=0.004").unwrap(),
        Effect::parse("turn_slip:k=0.05").unwrap(),
    ];
    let run = sim::prepare(&cfg, &robot, &effects).unwrap();
    let scn = sim::Scenario::from_config(&cfg).unwrap();
    let whole = sim::drive(&scn, &cfg.scenario, cfg.duration_s, 1e-3);
    let truth = TrueRobot::new(&robot, &effects);
    let wheels = sim::encoder_samples(
        &cfg.encoder,
        robot.ticks_per_rev,
        &WheelTrack::new(&whole, &truth),
        &truth,
        cfg.seed,
        cfg.duration_s,
    );
    let streamed: Vec<_> = run.encoders().collect();
    assert_eq!(streamed.len(), 3001);
    assert!(streamed == wheels, "encoder samples differ");
    let poses: Vec<_> = run.trajectory().collect();
    assert_eq!(poses.len(), 3001);
    for p in &poses {
        let [x, y, _] = whole.pose_at(p.t);
        assert!(p.x == x && p.y == y, "pose at {} s differs", p.t);
    }
    // Parameters: 10 Hz plus the step at 7 s, which is also a sample time.
    let params: Vec<_> = run.parameters().collect();
    assert_eq!(params.len(), 301);
    assert!(params.windows(2).all(|w| w[0].t < w[1].t));
    let at7 = params.iter().find(|p| p.t == 7.0).unwrap();
    assert!((at7.r_right - 0.324).abs() < 1e-12, "{at7:?}");
}

/// Peak resident memory (kB) of `odocal simulate` over a run of `seconds`
/// s, bag and truth file written, as the kernel accounts it for the child
/// (`ru_maxrss` of the reaped children). A process's `ru_maxrss` also holds
/// the resident size of the process that started it, at the moment it
/// started it (exec keeps that high-water mark): started from this test
/// binary, whose size depends on the tests running beside it, the figure
/// would be that binary's. A small Python process starts it instead, so the
/// figure is odocal's own or Python's (about 14 MB), whichever is larger:
/// the comparison below holds either way.
fn peak_rss_kb(python: &str, dir: &std::path::Path, seconds: u32) -> i64 {
    let measure = "import resource, subprocess, sys\n\
        subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)\n\
        print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)";
    let path = |name: String| dir.join(name).to_str().unwrap().to_string();
    let out = Command::new(python)
        .args(["-c", measure, env!("CARGO_BIN_EXE_odocal"), "simulate"])
        .args(["--config", &path("fast.toml".into())])
        .args(["--duration", &seconds.to_string()])
        .args(["--out", &path(format!("r{seconds}.mcap"))])
        .args(["--truth", &path(format!("r{seconds}.json"))])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().parse().unwrap()
}

#[test]
fn simulate_peak_memory_does_not_grow_with_the_run() {
    // Ten times longer, same peak: a run held in memory would grow by some
    // 30 kB per simulated second at these rates (drive at 200 Hz, poses and
    // truth text at 100 Hz), 54 MB over the extra 1,800 s. A slow laser
    // keeps the test fast; its block of 250 scans spans 125 s, inside both runs.
    let Some(python) = python_with("sim_memory_rss", &["resource"]) else {
        return;
    };
    let d = scratch("sim_memory_rss");
    std::fs::write(
        d.join("fast.toml"),
        "[sim]\nintegration_hz = 200.0\n[sim.laser]\nrate_hz = 2.0\n",
    )
    .unwrap();
    let short = peak_rss_kb(&python, &d, 200);
    let long = peak_rss_kb(&python, &d, 2000);
    let truth_mb = std::fs::metadata(d.join("r2000.json")).unwrap().len() as f64 / 1e6;
    assert!(truth_mb > 20.0, "the long truth file is {truth_mb} MB");
    assert!(
        long < short + 8_000,
        "peak memory grew with the run: {short} kB for 200 s, {long} kB for 2000 s"
    );
    let _ = std::fs::remove_dir_all(&d);
}
