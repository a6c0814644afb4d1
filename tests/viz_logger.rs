//! The logger contract, independent of the sink: a synthetic run fed through
//! any `Logger`, and the do-nothing logger accepting it.

use nalgebra::Point2;
use odocal::geom::pose;
use odocal::viz::{CalibEstimate, Logger, NullLogger, Stamp, TrajectoryKind, VizError};

/// Sizes of a synthetic run fed by [`feed`].
pub struct RunShape {
    pub scans: usize,
    pub beams: usize,
    pub particles: usize,
    pub map_segments: usize,
}

/// Feeds a synthetic run: a square room map, `scans` scans of `beams` points
/// along a circle, one filter step per scan after the first with a Gaussian
/// blob of particles, the estimate, ICP quality, and the four trajectories.
/// Scan `i` is at time `10 + 0.1 i` s.
pub fn feed(log: &mut dyn Logger, shape: &RunShape) -> Result<(), VizError> {
    let segs: Vec<[Point2<f64>; 2]> = (0..shape.map_segments)
        .map(|k| {
            let a = k as f64;
            [Point2::new(a, 0.0), Point2::new(a + 1.0, 0.5)]
        })
        .collect();
    log.map(&segs)?;
    let pts: Vec<Point2<f64>> = (0..shape.beams)
        .map(|b| {
            let a = -2.356 + 4.712 * b as f64 / shape.beams.max(1) as f64;
            Point2::new(4.0 * a.cos(), 4.0 * a.sin())
        })
        .collect();
    let n = shape.particles;
    let mut rr = vec![0.0; n];
    let mut rl = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut poses = Vec::with_capacity(shape.scans);
    for i in 0..shape.scans {
        let at = Stamp::new(i as i64, 10.0 + 0.1 * i as f64);
        let p = pose(0.05 * i as f64, 0.01 * i as f64, 0.002 * i as f64);
        poses.push(p);
        log.scan(at, &p, &pose(-0.45, 0.0, std::f64::consts::PI), &pts)?;
        if i == 0 {
            continue;
        }
        for k in 0..n {
            // A deterministic spread around (0.32, 0.32) m.
            let u = (k as f64 * 0.618_033_988_75).fract() - 0.5;
            let v = (k as f64 * 0.754_877_666_2).fract() - 0.5;
            rr[k] = 0.32 + 0.004 * u;
            rl[k] = 0.32 + 0.004 * v;
            w[k] = (-(u * u + v * v) * 20.0).exp();
        }
        log.particles(at, &rr, &rl, &w)?;
        log.estimate(
            at,
            &CalibEstimate {
                params: [0.32, 0.321, 0.65],
                std: [1e-3, 1e-3, 2e-3],
                particles: n,
                process_sigma: 1e-4,
            },
        )?;
        log.icp(at, 5 + (i % 7) as u32, 1e-4)?;
        log.icp_covariance(at, &p, [[4e-6, 1e-6], [1e-6, 2e-6]])?;
    }
    let times: Vec<f64> = (0..shape.scans).map(|i| 10.0 + 0.1 * i as f64).collect();
    for kind in TrajectoryKind::ALL {
        log.trajectory(kind, &times, &poses)?;
    }
    log.finish()
}

#[test]
fn null_logger_accepts_a_whole_run() {
    let mut log = NullLogger;
    let shape = RunShape {
        scans: 20,
        beams: 541,
        particles: 500,
        map_segments: 4,
    };
    feed(&mut log, &shape).unwrap();
    // finish twice is harmless
    log.finish().unwrap();
}

#[test]
fn stamp_rejects_non_finite_time() {
    assert!(Stamp::new(3, f64::NAN).check().is_err());
    assert!(Stamp::new(3, 1.5).check().is_ok());
}
