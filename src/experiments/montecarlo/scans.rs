//! [Farina, Table II] end to end: every run is a simulated wheelchair with
//! its own true radii and wheel base, whose LMS111 scans go through ICP; the
//! calibrators see what they would see on a real chair (ICP motions with
//! their own σ, quantised encoders, the gyro), not ICP-like synthetic noise.

use super::{montecarlo_with, MonteCarloRuns, MonteCarloTable, RunTruth};
use crate::calib::{self, synth::draw_truth, CalibParams};
use crate::geom::{self, Pose2};
use crate::icp::IcpParams;
use crate::motion::arc_along_chord;
use crate::pipeline::PipelineError;
use crate::robot::{DiffDrive, RobotConfig};
use crate::sim::{self, SimConfig, Truth};
use crate::traj::Trajectory;
use serde::{Deserialize, Serialize};

/// Settings of the end-to-end Monte Carlo (`[scans]` of `--settings`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScanMonteCarloParams {
    /// Length of each run (s).
    pub duration_s: f64,
    /// Built-in scenarios, taken in turn (run k drives `scenarios[k % len]`).
    pub scenarios: Vec<String>,
    /// σ of one gyro sample the calibrators are told (rad/s).
    pub gyro_sigma: f64,
    /// Convergence: radius error below this fraction of the truth.
    pub convergence_fraction: f64,
}

impl Default for ScanMonteCarloParams {
    fn default() -> Self {
        Self {
            duration_s: 120.0,
            scenarios: [
                "corridor-loop",
                "figure-eight",
                "hall",
                "random-walk",
                "square",
            ]
            .map(String::from)
            .to_vec(),
            gyro_sigma: 0.003,
            convergence_fraction: 0.005,
        }
    }
}

/// The simulator's truth seen by the scorer.
struct SimTruth {
    truth: Truth,
    trajectory: Trajectory,
    /// Stamps (s) and unwrapped headings (rad) of the true trajectory.
    stamps: Vec<f64>,
    heading: Vec<f64>,
}

impl SimTruth {
    fn new(truth: Truth) -> Self {
        let trajectory = truth.trajectory();
        let stamps = truth.trajectory.iter().map(|p| p.t).collect();
        let mut heading = Vec::with_capacity(truth.trajectory.len());
        for (k, p) in truth.trajectory.iter().enumerate() {
            heading.push(match k {
                0 => p.theta,
                _ => heading[k - 1] + geom::wrap_angle(p.theta - truth.trajectory[k - 1].theta),
            });
        }
        Self {
            truth,
            trajectory,
            stamps,
            heading,
        }
    }

    /// The true heading at `t` (rad), unwrapped and interpolated, so that
    /// a turn of more than π within a velocity window counts in full.
    fn heading_at(&self, t: f64) -> f64 {
        let (s, h) = (&self.stamps, &self.heading);
        if s.len() < 2 {
            return h.first().copied().unwrap_or(0.0);
        }
        let k = s.partition_point(|&x| x <= t).clamp(1, s.len() - 1);
        let f = ((t - s[k - 1]) / (s[k] - s[k - 1])).clamp(0.0, 1.0);
        h[k - 1] + (h[k] - h[k - 1]) * f
    }
}

impl RunTruth for SimTruth {
    fn params_at(&self, t: f64) -> DiffDrive {
        self.truth
            .parameters_at(t)
            .unwrap_or(self.truth.nominal.diff_drive())
    }

    fn mean_velocity(&self, t0: f64, t1: f64) -> (f64, f64) {
        match (self.trajectory.pose_at(t0), self.trajectory.pose_at(t1)) {
            (Some(a), Some(b)) if t1 > t0 => {
                let [dx, dy, _] = geom::xyt(&geom::between(&a, &b));
                let dth = self.heading_at(t1) - self.heading_at(t0);
                let (s, th) = arc_along_chord(dx, dy, dth);
                (s / (t1 - t0), th / (t1 - t0))
            }
            _ => (0.0, 0.0),
        }
    }

    fn pose_at(&self, t: f64) -> Option<Pose2> {
        self.trajectory.pose_at(t)
    }

    fn change_time(&self) -> Option<f64> {
        None
    }
}

/// One run: simulate a chair with parameters `draw_truth(seed)`, match its
/// scans, and build the calibrator steps from ICP, encoders and gyro.
fn prepare_run(
    seed: u64,
    k: usize,
    settings: &ScanMonteCarloParams,
    nominal: &RobotConfig,
    icp: &IcpParams,
) -> Result<(Vec<calib::CalibStep>, SimTruth), PipelineError> {
    let t = draw_truth(seed);
    let truth_robot = RobotConfig {
        r_right: t.r_right,
        r_left: t.r_left,
        wheel_base: t.wheel_base,
        ..nominal.clone()
    };
    let mut cfg = SimConfig {
        duration_s: settings.duration_s,
        seed,
        ..SimConfig::default()
    };
    cfg.scenario.name = settings.scenarios[k % settings.scenarios.len()].clone();
    let (rec, truth) = sim::simulate(&cfg, &truth_robot, &[], &mut |_| {})
        .map_err(|e| PipelineError::BadArgument(e.to_string()))?;
    // ICP's prior is the wheel odometry of the nominal chair, as on a real one.
    let out = crate::pipeline::icp::match_recording(&rec, nominal, icp)?;
    let steps = calib::steps(
        &out.observations(),
        &rec.wheels,
        &rec.gyro,
        settings.gyro_sigma,
    );
    Ok((steps, SimTruth::new(truth)))
}

/// Runs every configuration over `runs` simulated chairs (run k: true
/// parameters `draw_truth(seed + k)`, simulator seed `seed + k`).
pub fn scan_montecarlo(
    runs: usize,
    seed: u64,
    settings: &ScanMonteCarloParams,
    nominal: &RobotConfig,
    icp: &IcpParams,
    configs: &[(String, CalibParams)],
) -> Result<MonteCarloTable, PipelineError> {
    if settings.scenarios.is_empty() || !(settings.duration_s > 0.0) {
        return Err(PipelineError::BadArgument(
            "scans: at least one scenario and a positive duration_s".into(),
        ));
    }
    let mc = MonteCarloRuns {
        runs,
        seed,
        nominal: [nominal.r_right, nominal.r_left, nominal.wheel_base],
        convergence_fraction: settings.convergence_fraction,
        parallel: false,
        span: settings.duration_s,
    };
    let make = |s: u64| prepare_run(s, s.wrapping_sub(seed) as usize, settings, nominal, icp);
    montecarlo_with(&mc, configs, &make)
}
