//! A bag streamed from disk against the same data in memory: the same samples
//! from the streaming and the whole-file bag readers (also for out-of-order
//! bags and rate-only wheels), and the same output files from `icp` and
//! `calibrate` on the bundled recording and on real data.

use crate::support::{scratch, shared_data};
use odocal::calib::{CalibSummary, Method};
use odocal::io::cdr::CdrWriter;
use odocal::io::ros_msgs::{Header, ImuMsg, JointStateMsg, RosMsg, Time, Vec3};
use odocal::io::{read_recording, McapStream, ReadOptions, RecordingSource, SampleSource};
use odocal::pipeline::calibrate::{CalibSource, CalibrateJob, CalibratorChoice};
use odocal::pipeline::icp::IcpJob;
use odocal::pipeline::outputs::{CalibFiles, IcpFiles};
use odocal::pipeline::{self, drive, Common, Config};
use odocal::recording::Recording;
use odocal::robot::RobotConfig;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

/// Every item of the streamed bag, gathered per stream.
fn streamed(path: &Path, opts: &ReadOptions) -> Recording {
    let mut s = McapStream::open(path, opts).unwrap();
    odocal::io::collect(&mut s).unwrap()
}

/// Equal streams (bit for bit: NaN ranges count as equal, so the Debug
/// texts are compared), or a short message naming the first difference.
fn same<T: std::fmt::Debug>(a: &[T], b: &[T], what: &str, stamp: impl Fn(&T) -> f64) {
    let first = a
        .iter()
        .zip(b)
        .position(|(x, y)| format!("{x:?}") != format!("{y:?}"));
    assert!(
        a.len() == b.len() && first.is_none(),
        "{what}: {} vs {} items, first difference at {:?} (stamps {:?} vs {:?})",
        a.len(),
        b.len(),
        first,
        first.map(|i| stamp(&a[i])),
        first.map(|i| stamp(&b[i])),
    );
}

fn assert_same_recording(a: &Recording, b: &Recording, what: &str) {
    same(&a.scans, &b.scans, &format!("{what}: scans"), |s| s.stamp);
    same(&a.wheels, &b.wheels, &format!("{what}: wheels"), |s| {
        s.stamp
    });
    same(&a.gyro, &b.gyro, &format!("{what}: gyro"), |s| s.stamp);
    same(&a.odom, &b.odom, &format!("{what}: odom"), |s| s.stamp);
    same(
        &a.reference,
        &b.reference,
        &format!("{what}: reference"),
        |s| s.stamp,
    );
    assert_eq!(a.base_from_laser, b.base_from_laser, "{what}: laser mount");
}

/// Real bags with their joint names (robot files beside the data).
fn real_bags(test: &str) -> Vec<(PathBuf, ReadOptions)> {
    let Some(data) = shared_data(test) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (bag, robot) in [
        ("lego-robot/lego-robot.mcap", "lego-robot.toml"),
        ("mines-rover/exp1.mcap", "mines-rover.toml"),
        ("slam-benchmark/mit-csail.mcap", ""),
    ] {
        if test == "streamed_icp_matches_on_real_bags" && robot.is_empty() {
            continue; // Too long for a debug-mode test; its reader is checked.
        }
        let robot_file = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scans/robots")
            .join(robot);
        let robot = if robot.is_empty() || !robot_file.is_file() {
            RobotConfig::default()
        } else {
            pipeline::load_robot(Some(&robot_file)).unwrap()
        };
        out.push((data.join(bag), ReadOptions::for_robot(&robot)));
    }
    out
}

#[test]
fn stream_yields_exactly_what_read_recording_reads() {
    let mut bags = vec![(PathBuf::from(BUNDLED), ReadOptions::default())];
    bags.extend(real_bags("stream_yields_exactly_what_read_recording_reads"));
    for (bag, opts) in bags {
        let whole = read_recording(&bag, &opts).unwrap();
        let s = streamed(&bag, &opts);
        assert!(whole.scans.len() > 100, "{}", bag.display());
        assert_same_recording(&s, &whole, &bag.display().to_string());
    }
}

/// A bag whose gyro and wheel (rates only) messages are written out of stamp
/// order, up to `jitter` seconds back.
fn shuffled_bag(path: &Path, jitter: f64) {
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .create(std::io::BufWriter::new(
            std::fs::File::create(path).unwrap(),
        ))
        .unwrap();
    let mut channel = BTreeMap::new();
    for (topic, ty) in [
        ("/imu", ImuMsg::TYPE),
        ("/joint_states", JointStateMsg::TYPE),
    ] {
        let text = odocal::io::ros_schema::schema_text(ty).unwrap();
        let schema = w.add_schema(ty, "ros2msg", text.as_bytes()).unwrap();
        channel.insert(
            topic,
            w.add_channel(schema, topic, "cdr", &BTreeMap::new())
                .unwrap(),
        );
    }
    let robot = RobotConfig::default();
    let mut cdr = CdrWriter::new();
    let mut seq = 0u32;
    // Stamps at 100 Hz, written in blocks of 37 reversed (0.36 s back).
    assert!(0.36 < jitter);
    let order = (0..2000u32)
        .collect::<Vec<_>>()
        .chunks(37)
        .flat_map(|c| c.iter().rev().copied().collect::<Vec<_>>())
        .collect::<Vec<_>>();
    for j in order {
        let t = 10.0 + j as f64 * 0.01;
        let header = Header {
            stamp: Time::from_seconds(t),
            frame_id: "base_link".into(),
        };
        for topic in ["/imu", "/joint_states"] {
            cdr.clear();
            if topic == "/imu" {
                ImuMsg {
                    header: header.clone(),
                    angular_velocity: Vec3 {
                        x: 0.0,
                        y: 0.0,
                        z: (t * 0.7).sin(),
                    },
                    ..Default::default()
                }
                .write(&mut cdr);
            } else {
                JointStateMsg {
                    header: header.clone(),
                    name: vec![robot.left_joint.clone(), robot.right_joint.clone()],
                    position: Vec::new(),
                    velocity: vec![1.0 + (t * 0.3).cos(), 2.0 + (t * 0.2).sin()],
                    effort: Vec::new(),
                }
                .write(&mut cdr);
            }
            seq += 1;
            let log_time = (t * 1e9) as u64;
            w.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel[topic],
                    sequence: seq,
                    log_time,
                    publish_time: log_time,
                },
                cdr.bytes(),
            )
            .unwrap();
        }
    }
    w.finish().unwrap();
}

#[test]
fn stream_sorts_out_of_order_bags_like_the_whole_file_reader() {
    let d = scratch("stream_sorts_out_of_order");
    let bag = d.join("shuffled.mcap");
    shuffled_bag(&bag, 0.5);
    let opts = ReadOptions::default();
    let whole = read_recording(&bag, &opts).unwrap();
    assert_eq!(whole.gyro.len(), 2000);
    assert!(whole.gyro.windows(2).all(|w| w[1].stamp > w[0].stamp));
    // Rates were integrated into angles after sorting.
    assert!(whole.wheels.last().unwrap().right > 30.0);
    let s = streamed(&bag, &opts);
    assert_same_recording(&s, &whole, "shuffled");
    // A window shorter than the disorder is refused by both readers alike.
    let tight = ReadOptions {
        reorder_tolerance: 0.1,
        ..ReadOptions::default()
    };
    let e1 = read_recording(&bag, &tight).unwrap_err();
    let e2 = McapStream::open(&bag, &tight)
        .and_then(|mut s| {
            while s.next_item()?.is_some() {}
            Ok(())
        })
        .unwrap_err();
    assert_eq!(e1.to_string(), e2.to_string());
    assert!(e1.to_string().contains("backwards"), "{e1}");
}

fn config() -> (Config, RobotConfig) {
    let cfg = Config::load(None).unwrap();
    (cfg, RobotConfig::default())
}

fn read_opts(cfg: &Config, robot: &RobotConfig) -> ReadOptions {
    let mut r = ReadOptions::for_robot(robot);
    r.topics = cfg.topics.clone();
    r
}

fn same_file(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x.len() > 100, "{} is empty", a.display());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

/// `odocal calibrate` on a file with `particles` particles and `method`.
fn calibrate_command(
    input: &Path,
    out: &Path,
    method: Method,
    particles: Option<usize>,
    config: Option<&Path>,
) -> CalibSummary {
    let job = CalibrateJob {
        input: CalibSource::Recording(input.to_path_buf()),
        out: out.to_path_buf(),
        choice: CalibratorChoice {
            method: Some(method),
            particles,
            ..Default::default()
        },
        viewer: None,
        common: Common {
            config: config.map(Path::to_path_buf),
            robot: None,
        },
        init: Default::default(),
    };
    pipeline::calibrate::run(&job, &mut pipeline::NoObserver)
        .unwrap()
        .summary
}

/// The same recording in memory through the same driver, written by the
/// same observers.
fn icp_in_memory(rec: &Recording, robot: &RobotConfig, cfg: &Config, tum: &Path, csv: &Path) {
    let mut files = IcpFiles::create(tum, Some(csv)).unwrap();
    drive::run_icp(&mut RecordingSource::new(rec), robot, &cfg.icp, &mut files).unwrap();
    files.commit().unwrap();
}

#[test]
fn a_bag_and_the_same_recording_in_memory_give_the_same_files() {
    let (cfg, robot) = config();
    let read = read_opts(&cfg, &robot);
    let d = scratch("bag_and_memory_same_files");
    let bag = Path::new(BUNDLED);
    let rec = read_recording(bag, &read).unwrap();
    icp_in_memory(&rec, &robot, &cfg, &d.join("a.tum"), &d.join("a.csv"));
    // Progress is the fraction of scans read: rising, ending at 1.
    let mut fractions = Vec::new();
    let job = IcpJob {
        input: bag.to_path_buf(),
        out: d.join("b.tum"),
        motions: Some(d.join("b.csv")),
        common: Common::default(),
    };
    let s = pipeline::icp::run(&job, &mut pipeline::Progress::new(|f| fractions.push(f))).unwrap();
    assert_eq!(fractions.len(), rec.scans.len());
    assert!(fractions.windows(2).all(|w| w[1] > w[0]) && fractions.last() == Some(&1.0));
    same_file(&d.join("a.tum"), &d.join("b.tum"));
    same_file(&d.join("a.csv"), &d.join("b.csv"));
    // The in-memory ICP of the library gives the same motions and trajectory.
    let whole = pipeline::icp::match_recording(&rec, &robot, &cfg.icp).unwrap();
    assert_eq!(s.stats.pairs, whole.stats.pairs);
    assert_eq!(s.stats.failures, whole.stats.failures);
    assert_eq!(s.stats.mean_iterations, whole.stats.mean_iterations);
    assert_eq!(s.path_length, whole.trajectory.path_length());
    odocal::io::csv::write_motions(&d.join("c.csv"), &whole.motions).unwrap();
    same_file(&d.join("b.csv"), &d.join("c.csv"));
    assert!(whole.stats.pairs > 500);

    // The adaptive particle filter (fewer particles to keep the test short):
    // the command on the bag, and the same driver over the recording in
    // memory, written by the same observers.
    let mut params = cfg.calib.clone();
    params.particles = Some(300);
    let a = d.join("cal-a");
    let mem = calibrate_in_memory(&rec, &robot, &cfg, &params, &cfg.measurements, &a);
    let b = d.join("cal-b");
    let s = calibrate_command(bag, &b, Method::AdaptivePf, Some(300), None);
    same_file(&a.join("calibration.csv"), &b.join("calibration.csv"));
    same_file(&a.join("trajectory.tum"), &b.join("trajectory.tum"));
    assert_eq!(s.final_params, mem.summary.final_params);
    assert_eq!(s.online, mem.summary.online);
    assert_eq!(
        s.assumptions.source("laser"),
        Some(odocal::assumptions::Origin::TfStatic)
    );
    assert!(s.iterations > 50);
}

/// The calibration of `rec` in memory through the command's driver, its
/// history and trajectory written into `out` as the command writes them.
fn calibrate_in_memory(
    rec: &Recording,
    robot: &RobotConfig,
    cfg: &Config,
    params: &odocal::calib::CalibParams,
    meas: &pipeline::calibrate::MeasurementConfig,
    out: &Path,
) -> drive::CalibRunSummary {
    let mut files = CalibFiles::create(out).unwrap();
    if params.change.naming.enabled {
        files = files.naming_changes(robot, &params.change.naming);
    }
    let mut source = RecordingSource::new(rec);
    let info = odocal::io::SampleSource::info(&source).clone();
    let nominal = pipeline::Nominal::load(None).unwrap();
    let icp = nominal.icp_params(&cfg.icp, &info);
    let (_, mut done) =
        drive::run_calibration(&mut source, robot, &icp, params, meas, &mut files).unwrap();
    done.summary.changes = files.changes();
    files.commit(&done.summary).unwrap();
    done
}

/// A short simulated bag (library simulator, written as `odocal simulate` does).
fn short_bag(d: &Path, seconds: f64) -> PathBuf {
    let (mut cfg, robot) = config();
    cfg.sim.duration_s = seconds;
    cfg.sim.scenario.name = "square".into();
    let out = d.join("short.mcap");
    pipeline::simulate::simulate(&cfg.sim, &cfg.topics, &robot, &[], &out, None, &mut |_| {})
        .unwrap();
    out
}

#[test]
fn kalman_calibration_of_a_bag_matches_the_in_memory_run_without_and_with_gyro() {
    let (cfg, robot) = config();
    let read = read_opts(&cfg, &robot);
    let d = scratch("bag_kalman_calibration");
    let bag = short_bag(&d, 8.0);
    let rec = read_recording(&bag, &read).unwrap();
    for (k, use_gyro) in [false, true].into_iter().enumerate() {
        let meas = pipeline::calibrate::MeasurementConfig {
            use_gyro,
            ..cfg.measurements
        };
        let mut params = cfg.calib.clone();
        params.method = Method::Dkf;
        // 8 s of corridor without a turn: the command would refuse the wheel
        // base (tested in `calib_checks`) and the radii on 7 intervals of a
        // second; its checks are off to compare paths.
        params.checks.min_rotation_rad = 0.0;
        params.checks.min_steps = 5;
        let a = d.join(format!("a{k}"));
        let mem = calibrate_in_memory(&rec, &robot, &cfg, &params, &meas, &a);
        let toml = d.join(format!("gyro{k}.toml"));
        std::fs::write(
            &toml,
            format!(
                "[measurements]\nuse_gyro = {use_gyro}\n[calib.checks]\nmin_rotation_rad = 0.0\n\
                 min_steps = 5\n"
            ),
        )
        .unwrap();
        let b = d.join(format!("b{k}"));
        let s = calibrate_command(&bag, &b, Method::Dkf, None, Some(&toml));
        same_file(&a.join("calibration.csv"), &b.join("calibration.csv"));
        assert_eq!(s.final_params, mem.summary.final_params);
        assert_eq!(s.iterations, mem.summary.iterations);
    }
}

#[test]
fn icp_of_real_bags_matches_the_in_memory_run() {
    let (cfg, _) = config();
    let d = scratch("real_bags_icp");
    for (k, (bag, read)) in real_bags("icp_of_real_bags_matches_the_in_memory_run")
        .into_iter()
        .enumerate()
    {
        let robot = RobotConfig {
            left_joint: read.left_joint.clone(),
            right_joint: read.right_joint.clone(),
            ..RobotConfig::default()
        };
        let rec = read_recording(&bag, &read).unwrap();
        let (a, b) = (d.join(format!("a{k}.csv")), d.join(format!("b{k}.csv")));
        icp_in_memory(&rec, &robot, &cfg, &d.join(format!("a{k}.tum")), &a);
        let robot_toml = d.join(format!("robot{k}.toml"));
        std::fs::write(
            &robot_toml,
            format!(
                "r_right = {}\nr_left = {}\nwheel_base = {}\n\
                 left_joint = \"{}\"\nright_joint = \"{}\"\n",
                robot.r_right, robot.r_left, robot.wheel_base, read.left_joint, read.right_joint
            ),
        )
        .unwrap();
        let job = IcpJob {
            input: bag.clone(),
            out: d.join(format!("b{k}.tum")),
            motions: Some(b.clone()),
            common: Common {
                config: None,
                robot: Some(robot_toml),
            },
        };
        pipeline::icp::run(&job, &mut pipeline::NoObserver).unwrap();
        same_file(&a, &b);
        same_file(&d.join(format!("a{k}.tum")), &d.join(format!("b{k}.tum")));
    }
}

#[test]
fn simulate_writes_scans_as_it_casts_them_with_the_in_memory_bytes() {
    // The streaming writer (scans cast block by block, summary patched in
    // the file) must give the bytes of the whole-recording encoder, also when
    // the run is not a whole number of blocks and has an effect.
    let d = scratch("sim_stream_bytes");
    let (mut cfg, robot) = config();
    cfg.sim.duration_s = 11.3;
    cfg.sim.scenario.name = "square".into();
    let effects = [odocal::effects::Effect::parse("gyro_bias:bias=0.01").unwrap()];
    let out = d.join("streamed.mcap");
    let truth_file = d.join("streamed.json");
    let mut fractions = Vec::new();
    let summary = pipeline::simulate::simulate(
        &cfg.sim,
        &cfg.topics,
        &robot,
        &effects,
        &out,
        Some(&truth_file),
        &mut |f| fractions.push(f),
    )
    .unwrap();
    let (rec, truth) = odocal::sim::simulate(&cfg.sim, &robot, &effects, &mut |_| {}).unwrap();
    assert_eq!(summary.scans, rec.scans.len());
    // The truth file, its series written as they are drawn, is the text of
    // the whole truth serialised at once.
    assert!(
        std::fs::read_to_string(&truth_file).unwrap() == truth.to_json(),
        "streamed truth file differs"
    );
    assert_eq!(summary.path_length_m, truth.trajectory().path_length());
    assert!(rec.scans.len() > odocal::sim::LaserSim::BLOCK * 2);
    let mut opts = odocal::io::WriteOptions::for_robot(&robot);
    opts.topics = cfg.topics.clone();
    let bytes = odocal::io::encode_mcap(&rec, &opts).unwrap();
    assert!(
        std::fs::read(&out).unwrap() == bytes,
        "streamed bag differs"
    );
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(fractions.last(), Some(&1.0));
    // The summary section still reads with the official reader's index.
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    assert_eq!(summary.channels.len(), 5);
}
