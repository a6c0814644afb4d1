//! The streamed recording of `calibrate --input BAG --rrd` against the
//! in-memory one: the same scans at the same poses, the same ICP rows,
//! estimates, particle clouds and trajectories; and on a long run the
//! announced thinning (clouds, polylines) with memory that stays bounded.

use nalgebra::Point2;
use odocal::geom::{self, Pose2};
use odocal::io::{read_recording, ReadOptions};
use odocal::pipeline::calibrate::{run_file, run_observed, CalibInput};
use odocal::pipeline::record::{particle_logger, record, RunRecord};
use odocal::pipeline::record_stream::{RecorderOptions, StreamRecorder};
use odocal::pipeline::{self, Config};
use odocal::robot::RobotConfig;
use odocal::viz::{CalibEstimate, Logger, Stamp, TrajectoryKind, VizError};
use std::path::Path;

use crate::support::scratch;

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

/// Everything a logger was handed, per entity.
#[derive(Default, Debug)]
struct Tape {
    scans: Vec<(i64, f64, [f64; 3], usize)>,
    icp: Vec<(i64, f64, u32, f64)>,
    particles: Vec<(i64, f64, usize)>,
    estimates: Vec<(i64, f64, [f64; 3])>,
    trajectories: Vec<(TrajectoryKind, Vec<Pose2>)>,
    finished: usize,
}

impl Logger for Tape {
    fn map(&mut self, _: &[[Point2<f64>; 2]]) -> Result<(), VizError> {
        Ok(())
    }
    fn scan(&mut self, at: Stamp, p: &Pose2, pts: &[Point2<f64>]) -> Result<(), VizError> {
        self.scans.push((at.scan, at.time, geom::xyt(p), pts.len()));
        Ok(())
    }
    fn trajectory(&mut self, kind: TrajectoryKind, poses: &[Pose2]) -> Result<(), VizError> {
        self.trajectories.push((kind, poses.to_vec()));
        Ok(())
    }
    fn particles(&mut self, at: Stamp, rr: &[f64], _: &[f64], _: &[f64]) -> Result<(), VizError> {
        self.particles.push((at.scan, at.time, rr.len()));
        Ok(())
    }
    fn estimate(&mut self, at: Stamp, e: &CalibEstimate) -> Result<(), VizError> {
        self.estimates.push((at.scan, at.time, e.params));
        Ok(())
    }
    fn icp(&mut self, at: Stamp, iterations: u32, trace: f64) -> Result<(), VizError> {
        self.icp.push((at.scan, at.time, iterations, trace));
        Ok(())
    }
    fn finish(&mut self) -> Result<(), VizError> {
        self.finished += 1;
        Ok(())
    }
}

fn setup() -> (Config, RobotConfig, ReadOptions) {
    let cfg = Config::load(None).unwrap();
    let robot = RobotConfig::default();
    let mut read = ReadOptions::for_robot(&robot);
    read.topics = cfg.topics.clone();
    (cfg, robot, read)
}

/// The recording `calibrate --rrd` made before it streamed: read whole, then logged.
fn in_memory(cfg: &Config, robot: &RobotConfig, read: &ReadOptions) -> Tape {
    let rec = read_recording(Path::new(BUNDLED), read).unwrap();
    let out = pipeline::icp::run(&rec, robot, &cfg.icp).unwrap();
    let input = CalibInput {
        observations: out.observations(),
        wheels: rec.wheels.clone(),
        gyro: rec.gyro.clone(),
    };
    let scan_stamps: Vec<f64> = rec.scans.iter().map(|s| s.stamp).collect();
    let t_start = rec.time_span().unwrap().0;
    let mut tape = Tape::default();
    let mut err = None;
    let run = {
        let mut on_step = particle_logger(&mut tape, &scan_stamps, t_start, &mut err);
        run_observed(&input, robot, &cfg.calib, &cfg.measurements, &mut on_step).unwrap()
    };
    assert!(err.is_none());
    let raw = odocal::robot::wheel_odometry(&robot.diff_drive(), &rec.wheels, Pose2::identity());
    let reference = odocal::eval::trajectory_from_stamped(&rec.reference).0;
    record(
        &RunRecord {
            recording: Some(&rec),
            robot,
            walls: None,
            icp: Some(&out),
            raw: Some(&raw),
            calibrated: &run,
            reference: Some(&reference),
            t_start,
            scan_stamps: &scan_stamps,
        },
        &mut tape,
    )
    .unwrap();
    tape
}

fn streamed(opts: RecorderOptions, dir: &Path) -> (Tape, Vec<String>, usize) {
    let (cfg, robot, read) = setup();
    let mut tape = Tape::default();
    let mut rec = StreamRecorder::new(&mut tape, opts, robot.diff_drive(), robot.laser.pose());
    let summary = run_file(
        Path::new(BUNDLED),
        &read,
        &robot,
        &cfg.icp,
        &cfg.calib,
        &cfg.measurements,
        dir,
        &mut |_| {},
        &mut rec,
    )
    .unwrap();
    let every = rec.cloud_every();
    let notes = rec.finish().unwrap();
    assert_eq!(tape.estimates.len(), summary.iterations);
    (tape, notes, every)
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn streamed_recording_logs_what_the_in_memory_one_logs() {
    let (cfg, robot, read) = setup();
    let mem = in_memory(&cfg, &robot, &read);
    let (st, notes, every) = streamed(RecorderOptions::default(), &scratch("rec_stream_same"));
    assert!(notes.is_empty(), "{notes:?}");
    assert_eq!(every, 1);
    assert_eq!(st.finished, 1);
    // One scan row per scan, at the same index, time and pose.
    assert_eq!(st.scans.len(), mem.scans.len());
    assert!(st.scans.len() > 1000);
    for (a, b) in st.scans.iter().zip(&mem.scans) {
        assert_eq!((a.0, a.3), (b.0, b.3));
        assert!(
            (a.1 - b.1).abs() < 1e-9 && close(&a.2, &b.2, 1e-9),
            "{a:?} vs {b:?}"
        );
    }
    assert_eq!(st.icp.len(), mem.icp.len());
    for (a, b) in st.icp.iter().zip(&mem.icp) {
        assert_eq!((a.0, a.2), (b.0, b.2));
        assert!((a.1 - b.1).abs() < 1e-9 && (a.3 - b.3).abs() <= 1e-12 * b.3.abs().max(1.0));
    }
    assert_eq!(st.particles, mem.particles);
    assert_eq!(st.estimates.len(), mem.estimates.len());
    for (a, b) in st.estimates.iter().zip(&mem.estimates) {
        assert_eq!(a.0, b.0);
        assert!(
            (a.1 - b.1).abs() < 1e-9 && close(&a.2, &b.2, 1e-12),
            "{a:?} vs {b:?}"
        );
    }
    // The four trajectories, pose for pose.
    assert_eq!(st.trajectories.len(), 4);
    for (kind, poses) in &st.trajectories {
        let (_, m) = mem.trajectories.iter().find(|(k, _)| k == kind).unwrap();
        assert_eq!(poses.len(), m.len(), "{kind:?}");
        for (a, b) in poses.iter().zip(m) {
            assert!(close(&geom::xyt(a), &geom::xyt(b), 1e-9), "{kind:?}");
        }
    }
}

#[test]
fn long_runs_thin_clouds_and_polylines_and_say_so() {
    let opts = RecorderOptions {
        max_clouds: 100,
        max_polyline: 64,
    };
    let (st, notes, every) = streamed(opts, &scratch("rec_stream_thin"));
    let steps = st.estimates.len();
    assert!(every > 1);
    // Every step's estimate, one cloud in `every`.
    assert_eq!(st.particles.len(), steps.div_ceil(every));
    assert!(st.particles.len() <= 100 + 1);
    for (kind, poses) in &st.trajectories {
        assert!(
            poses.len() <= 65 && poses.len() >= 32,
            "{kind:?}: {}",
            poses.len()
        );
    }
    assert_eq!(notes.len(), 2, "{notes:?}");
    assert!(notes[0].contains(&format!("one filter step in {every}")));
    assert!(notes[1].contains("at most 64 poses"));
    // Scans and ICP rows are never thinned.
    assert_eq!(st.icp.len() + 1, st.scans.len());
}
