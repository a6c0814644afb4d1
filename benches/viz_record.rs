//! Cost of recording a whole run to `.rrd`: 6,000 scans × 541 points and
//! 6,000 filter steps of 8,000 particles (subsampled to 256 for display),
//! with estimates, ICP quality and its covariance ellipse (and their trail),
//! and four 6,000-pose trajectories grown along both timelines.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Point2;
use odocal::geom::pose;
use odocal::viz::{CalibEstimate, Logger, RerunLogger, Stamp, TrajectoryKind};

const SCANS: usize = 6_000;
const BEAMS: usize = 541;
const PARTICLES: usize = 8_000;

struct Run {
    points: Vec<Point2<f64>>,
    rr: Vec<f64>,
    rl: Vec<f64>,
    w: Vec<f64>,
}

fn run() -> Run {
    let points = (0..BEAMS)
        .map(|b| {
            let a = -2.356 + 4.712 * b as f64 / BEAMS as f64;
            Point2::new(4.0 * a.cos(), 4.0 * a.sin())
        })
        .collect();
    let mut rr = Vec::with_capacity(PARTICLES);
    let mut rl = Vec::with_capacity(PARTICLES);
    let mut w = Vec::with_capacity(PARTICLES);
    for k in 0..PARTICLES {
        let u = (k as f64 * 0.618_033_988_75).fract() - 0.5;
        let v = (k as f64 * 0.754_877_666_2).fract() - 0.5;
        rr.push(0.32 + 0.004 * u);
        rl.push(0.32 + 0.004 * v);
        w.push((-(u * u + v * v) * 20.0).exp());
    }
    Run { points, rr, rl, w }
}

fn record(dir: &std::path::Path, r: &Run) {
    let mut log = RerunLogger::to_file(dir.join("bench.rrd")).unwrap();
    let mut poses = Vec::with_capacity(SCANS);
    let mut times = Vec::with_capacity(SCANS);
    let mount = pose(-0.45, 0.0, std::f64::consts::PI);
    for i in 0..SCANS {
        let at = Stamp::new(i as i64, 0.1 * i as f64);
        let p = pose(0.01 * i as f64, 0.0, 0.001 * i as f64);
        poses.push(p);
        times.push(at.time);
        log.scan(at, &p, &mount, &r.points).unwrap();
        log.particles(at, &r.rr, &r.rl, &r.w).unwrap();
        let e = CalibEstimate {
            params: [0.32, 0.32, 0.65],
            std: [1e-3; 3],
            particles: PARTICLES,
            process_sigma: 1e-4,
        };
        log.estimate(at, &e).unwrap();
        log.icp(at, 6, 1e-4).unwrap();
        log.icp_covariance(at, &p, [[4e-6, 1e-6], [1e-6, 2e-6]])
            .unwrap();
    }
    for k in TrajectoryKind::ALL {
        log.trajectory(k, &times, &poses).unwrap();
    }
    log.finish().unwrap();
}

fn bench(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("odocal-bench-viz-{}", std::process::id()));
    let r = run();
    let mut g = c.benchmark_group("viz");
    g.sample_size(10);
    g.bench_function("record_6000_scans_541_beams_6000_pf_steps", |b| {
        b.iter(|| record(&dir, &r))
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
