//! The Rerun recording of `calibrate --input BAG --rrd`: the same for a bag
//! streamed from disk and for the same recording in memory, every scan, ICP
//! row, estimate and particle cloud logged, the raw odometry and reference
//! as integrated and read; and on a long run the announced thinning (clouds,
//! polylines) with memory that stays bounded.

use nalgebra::Point2;
use odocal::geom::{self, Pose2};
use odocal::io::{read_recording, McapStream, ReadOptions, RecordingSource, SampleSource};
use odocal::pipeline::recorder::{RecorderOptions, StreamRecorder};
use odocal::pipeline::{self, drive, Config};
use odocal::robot::RobotConfig;
use odocal::viz::{CalibEstimate, Logger, Stamp, TrajectoryKind, VizError};
use std::path::Path;

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

/// A scan-match ellipse handed to the logger: row, time, matched pose, covariance.
type Ellipse = (i64, f64, [f64; 3], [[f64; 2]; 2]);

/// Everything a logger was handed, per entity.
#[derive(Default, Debug)]
struct Tape {
    scans: Vec<(i64, f64, [f64; 3], usize)>,
    icp: Vec<(i64, f64, u32, f64)>,
    particles: Vec<(i64, f64, usize)>,
    estimates: Vec<(i64, f64, [f64; 3])>,
    trajectories: Vec<(TrajectoryKind, Vec<Pose2>)>,
    /// Scan-match ellipses.
    ellipses: Vec<Ellipse>,
    finished: usize,
}

impl Logger for Tape {
    fn map(&mut self, _: &[[Point2<f64>; 2]]) -> Result<(), VizError> {
        Ok(())
    }
    fn scan(
        &mut self,
        at: Stamp,
        base: &Pose2,
        laser: &Pose2,
        pts: &[Point2<f64>],
    ) -> Result<(), VizError> {
        self.scans
            .push((at.scan, at.time, geom::xyt(&(base * laser)), pts.len()));
        Ok(())
    }
    fn trajectory(
        &mut self,
        kind: TrajectoryKind,
        times: &[f64],
        poses: &[Pose2],
    ) -> Result<(), VizError> {
        assert_eq!(times.len(), poses.len());
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
    fn icp_covariance(
        &mut self,
        at: Stamp,
        pose: &Pose2,
        cov: [[f64; 2]; 2],
    ) -> Result<(), VizError> {
        self.ellipses.push((at.scan, at.time, geom::xyt(pose), cov));
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

/// The recording of a calibration run over `source` (the command's driver).
fn record(
    source: &mut dyn SampleSource,
    opts: RecorderOptions,
) -> (Tape, Vec<String>, usize, usize) {
    let (cfg, robot, _) = setup();
    let params = pipeline::calibrate::params_for_robot(&cfg.calib, &robot);
    let mut tape = Tape::default();
    let mut rec = StreamRecorder::new(
        &mut tape,
        opts,
        robot.diff_drive(),
        robot.laser.unwrap().pose(),
    );
    let (icp, done) = drive::run_calibration(
        source,
        &robot,
        &cfg.icp,
        &params,
        &cfg.measurements,
        &mut rec,
    )
    .unwrap();
    let every = rec.cloud_every();
    let notes = rec.finish().unwrap();
    assert_eq!(tape.estimates.len(), done.summary.iterations);
    (tape, notes, every, icp.stats.pairs)
}

fn streamed(opts: RecorderOptions) -> (Tape, Vec<String>, usize) {
    let (_, _, read) = setup();
    let mut bag = McapStream::open(Path::new(BUNDLED), &read).unwrap();
    let (tape, notes, every, _) = record(&mut bag, opts);
    (tape, notes, every)
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// `b`'s poses relative to its first, against `a`'s.
fn same_shape(a: &[Pose2], b: &[Pose2], tol: f64) -> bool {
    let (a0, b0) = (a[0].inverse(), b[0].inverse());
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| close(&geom::xyt(&(a0 * x)), &geom::xyt(&(b0 * y)), tol))
}

#[test]
fn a_bag_and_the_same_recording_in_memory_are_recorded_alike_and_whole() {
    let (_, robot, read) = setup();
    let (st, notes, every) = streamed(RecorderOptions::default());
    let rec = read_recording(Path::new(BUNDLED), &read).unwrap();
    let (mem, _, _, pairs) = record(&mut RecordingSource::new(&rec), RecorderOptions::default());
    // The same rows; where a pose is put on the reference depends on how
    // far the reference has been read when ICP starts, so poses are compared
    // up to that anchor.
    assert_eq!(st.icp, mem.icp);
    assert_eq!(st.particles, mem.particles);
    assert_eq!(st.estimates, mem.estimates);
    // A scan is drawn at the ICP pose known when it is placed, which depends
    // on how the streams interleave; which scans, when and with how many
    // points does not.
    for (a, b) in st.scans.iter().zip(&mem.scans) {
        assert_eq!((a.0, a.1, a.3), (b.0, b.1, b.3));
    }
    for ((k, a), (l, b)) in st.trajectories.iter().zip(&mem.trajectories) {
        assert_eq!(k, l);
        assert!(same_shape(a, b, 1e-9), "{k:?}");
    }
    assert!(notes.is_empty(), "{notes:?}");
    assert_eq!(every, 1);
    assert_eq!(st.finished, 1);
    // One scan row per scan, one ICP row per pair, a cloud at every step.
    assert_eq!(st.scans.len(), rec.scans.len());
    assert!(st.scans.len() > 1000);
    assert_eq!(st.icp.len(), pairs);
    assert_eq!(pairs + 1, rec.scans.len());
    assert_eq!(st.particles.len(), st.estimates.len());
    // An ellipse for every scan match that succeeded (the bundled run has no
    // failed pair), on the ICP row of its pair, with the pair's covariance.
    assert_eq!(st.ellipses.len(), pairs);
    for (e, i) in st.ellipses.iter().zip(&st.icp) {
        assert_eq!((e.0, e.1), (i.0, i.1));
        // Its x, y block: part of the covariance whose trace ICP logged.
        let xy = e.3[0][0] + e.3[1][1];
        assert!(xy > 0.0 && xy <= i.3 * (1.0 + 1e-12), "{e:?} {i:?}");
    }
    // The four trajectories; raw odometry and reference as integrated and read.
    assert_eq!(st.trajectories.len(), 4);
    let get = |k: TrajectoryKind| &st.trajectories.iter().find(|(x, _)| *x == k).unwrap().1;
    let raw = odocal::robot::wheel_odometry(&robot.diff_drive(), &rec.wheels, Pose2::identity());
    assert!(same_shape(
        get(TrajectoryKind::RawOdometry),
        &raw.poses,
        1e-9
    ));
    let reference: Vec<Pose2> = rec.reference.iter().map(|p| p.pose).collect();
    assert!(same_shape(
        get(TrajectoryKind::Reference),
        &reference,
        1e-12
    ));
}

#[test]
fn long_runs_thin_clouds_and_polylines_and_say_so() {
    let opts = RecorderOptions {
        max_clouds: 100,
        max_polyline: 64,
    };
    let (st, notes, every) = streamed(opts);
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
