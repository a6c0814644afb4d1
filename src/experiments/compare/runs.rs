//! The runs every method of a comparison sees: square runs in both
//! directions (the calibration data) and held-out evaluation runs, and the
//! pieces the GA is given of the squares.

use super::{CompareParams, CompareScenario};
use crate::classic::{ClassicError, GaRun, SimRun, Turn};
use crate::recording::WheelSample;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// The simulated runs of one comparison.
#[derive(Debug, Clone)]
pub struct ComparisonRuns {
    /// `runs_per_direction` clockwise runs, then as many counter-clockwise.
    pub squares: Vec<(Turn, SimRun)>,
    /// Held-out evaluation runs.
    pub evals: Vec<SimRun>,
}

impl ComparisonRuns {
    /// Asks `simulate(scenario, seed)` for the square runs of both
    /// directions, then for the evaluation runs; a failing run is an error
    /// naming its scenario and seed.
    pub fn simulate<F, E>(p: &CompareParams, mut simulate: F) -> Result<Self, ClassicError>
    where
        F: FnMut(CompareScenario, u64) -> Result<SimRun, E>,
        E: std::fmt::Display,
    {
        let mut simulate = |sc, seed| {
            simulate(sc, seed).map_err(|e| {
                ClassicError::invalid("comparison runs", format!("{sc:?} (seed {seed}): {e}"))
            })
        };
        let mut squares = Vec::new();
        for (k, (sc, dir)) in [
            (CompareScenario::Square, Turn::Cw),
            (CompareScenario::SquareCcw, Turn::Ccw),
        ]
        .into_iter()
        .enumerate()
        {
            for i in 0..p.runs_per_direction {
                let seed = p
                    .seed
                    .wrapping_mul(7919)
                    .wrapping_add((k * p.runs_per_direction + i) as u64);
                squares.push((dir, simulate(sc, seed)?));
            }
        }
        let evals: Vec<SimRun> = (0..p.evaluation_runs)
            .map(|i| {
                simulate(
                    CompareScenario::Evaluation,
                    p.seed.wrapping_mul(104_729).wrapping_add(i as u64),
                )
            })
            .collect::<Result<_, _>>()?;
        Ok(Self { squares, evals })
    }

    /// The square runs in order, without their directions.
    pub fn square_runs(&self) -> Vec<&SimRun> {
        self.squares.iter().map(|(_, r)| r).collect()
    }

    /// The GA's pieces of the square runs: cut at their corners when
    /// `ga_corners` (and the run has segment ends), else into random pieces
    /// of `short_run_m` (square i cut with seed `seed + i`).
    pub fn ga_pieces(&self, p: &CompareParams) -> Vec<GaRun> {
        self.squares
            .iter()
            .enumerate()
            .flat_map(|(i, (_, run))| {
                if p.ga_corners && !run.segment_ends.is_empty() {
                    return corner_pieces(run, p.ticks_per_rev);
                }
                split_short_runs(
                    run,
                    p.ticks_per_rev,
                    p.short_run_m.0,
                    p.short_run_m.1,
                    p.seed.wrapping_add(i as u64),
                )
            })
            .collect()
    }
}

/// Cuts a run into consecutive pieces whose true path length is drawn in
/// [min, max] (m), each with its true start and end pose, as GA runs.
pub fn split_short_runs(
    run: &SimRun,
    ticks_per_rev: f64,
    min: f64,
    max: f64,
    seed: u64,
) -> Vec<GaRun> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut out = Vec::new();
    let w = &run.wheels;
    let pose = |s: &WheelSample| run.truth.pose_at(s.stamp);
    let mut i0 = 0;
    let mut target = rng.random_range(min..max.max(min + 1e-9));
    let mut len = 0.0;
    for i in 1..w.len() {
        let (Some(a), Some(b)) = (pose(&w[i - 1]), pose(&w[i])) else {
            continue;
        };
        len += (b.translation.vector - a.translation.vector).norm();
        if len >= target {
            if let Some(start) = pose(&w[i0]) {
                out.push(GaRun::from_wheels(&w[i0..=i], ticks_per_rev, start, b));
            }
            i0 = i;
            len = 0.0;
            target = rng.random_range(min..max.max(min + 1e-9));
        }
    }
    out
}

/// Cuts a run at every second segment end (a square's corners, after each
/// turn) into GA runs with the true poses there.
fn corner_pieces(run: &SimRun, ticks_per_rev: f64) -> Vec<GaRun> {
    let w = &run.wheels;
    let mut cuts = vec![0usize];
    for &t in run.segment_ends.iter().skip(1).step_by(2) {
        let i = w.partition_point(|s| s.stamp < t - 1e-9).min(w.len() - 1);
        if i > *cuts.last().unwrap_or(&0) {
            cuts.push(i);
        }
    }
    cuts.windows(2)
        .filter_map(|c| {
            let a = run.truth.pose_at(w[c[0]].stamp)?;
            let b = run.truth.pose_at(w[c[1]].stamp)?;
            Some(GaRun::from_wheels(&w[c[0]..=c[1]], ticks_per_rev, a, b))
        })
        .collect()
}
