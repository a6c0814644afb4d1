//! The classic methods on a comparison's runs: each calibrates from the
//! square runs (and their measured end poses) and is scored on the
//! evaluation runs.

use super::runs::ComparisonRuns;
use super::score::{start_of, Calibrated, Evaluation};
use super::{ClassicMethod, ClassicResult, CompareParams};
use crate::classic::{
    fit_heading_gain, fit_tachometer, ga_calibrate, heading_pf, simulate_heading, umbmark,
    ClassicError, GaBounds, GaParams, GaRun, HeadingPfParams, HeadingTrial, TickParams, UmbmarkRun,
};
use crate::geom::{self, Pose2};
use crate::recording::WheelSample;
use crate::robot::{wheel_odometry, DiffDrive};
use crate::traj::Trajectory;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use std::time::Instant;

/// No calibration, the tachometer and heading gain of \[Paryanto\], UMBmark, the
/// GA of \[GAHeading\] and its heading fusion, in this order, scored by `eval`.
pub(crate) fn classic_methods(
    nominal: &DiffDrive,
    p: &CompareParams,
    runs: &ComparisonRuns,
    eval: &Evaluation<'_>,
) -> Result<Vec<ClassicResult>, ClassicError> {
    let none = eval.odometry(Calibrated {
        method: ClassicMethod::None,
        params: *nominal,
        ms: 0.0,
        details: serde_json::Value::Null,
    })?;
    let mut c = Calibrations {
        nominal,
        p,
        runs,
        noise: PoseNoise::new(p.end_pose_sigma, p.seed),
    };
    let tacho = c.tacho_heading(eval)?;
    let um = c.umbmark_correction(eval)?;
    let ga = c.ga_calibration()?;
    let (k_ga, ms_ga) = (ga.params, ga.ms);
    let ga_row = eval.odometry(ga)?;
    let pf = heading_fusion(&k_ga, ms_ga, p, eval)?;
    Ok(vec![none, tacho, um, ga_row, pf])
}

/// The classic calibrations from the square runs, whose measured end poses
/// all draw from one noise stream (in this order: heading trials, UMBmark
/// ends, GA pieces).
struct Calibrations<'a> {
    nominal: &'a DiffDrive,
    p: &'a CompareParams,
    runs: &'a ComparisonRuns,
    noise: PoseNoise,
}

impl Calibrations<'_> {
    /// \[Paryanto\]: tachometer correction (if a table is given) and heading gain
    /// from the square runs' total turns (actual vs estimated).
    fn tacho_heading(&mut self, eval: &Evaluation<'_>) -> Result<ClassicResult, ClassicError> {
        let t0 = Instant::now();
        let tacho = self
            .p
            .tachometer
            .as_deref()
            .map(fit_tachometer)
            .transpose()?;
        let correct = |w: &[WheelSample]| {
            tacho
                .as_ref()
                .map_or_else(|| w.to_vec(), |c| c.correct_wheels(w))
        };
        let trials: Vec<HeadingTrial> = self
            .runs
            .squares
            .iter()
            .map(|(_, run)| {
                let est = wheel_odometry(self.nominal, &correct(&run.wheels), Pose2::identity());
                HeadingTrial {
                    actual_deg: (total_turn(&run.truth).abs() + self.noise.angle()).to_degrees(),
                    estimated_deg: total_turn(&est).abs().to_degrees(),
                }
            })
            .collect();
        let gain = fit_heading_gain(&trials)?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let scale = |s: Option<f64>| s.unwrap_or(1.0);
        let k_th = DiffDrive {
            r_right: self.nominal.r_right
                * scale(tacho.as_ref().map(|c| c.right.slope_through_origin)),
            r_left: self.nominal.r_left
                * scale(tacho.as_ref().map(|c| c.left.slope_through_origin)),
            wheel_base: gain.effective_wheel_base(self.nominal.wheel_base),
        };
        let k_gain = DiffDrive {
            wheel_base: gain.effective_wheel_base(self.nominal.wheel_base),
            ..*self.nominal
        };
        let details = serde_json::json!({ "tachometer": tacho, "heading_gain": gain });
        let c = Calibrated {
            method: ClassicMethod::TachoHeading,
            params: k_th,
            ms,
            details,
        };
        eval.estimates(
            c,
            eval.runs.iter().map(|run| {
                Ok(wheel_odometry(
                    &k_gain,
                    &correct(&run.wheels),
                    start_of(run),
                ))
            }),
        )
    }

    /// UMBmark on the square runs, their end positions measured with noise.
    fn umbmark_correction(&mut self, eval: &Evaluation<'_>) -> Result<ClassicResult, ClassicError> {
        let t0 = Instant::now();
        let errors: Vec<UmbmarkRun> = self
            .runs
            .squares
            .iter()
            .map(|(dir, run)| {
                let mut r = UmbmarkRun::from_sim(run, self.nominal, *dir);
                let (dx, dy) = self.noise.xy();
                r.eps_x += dx;
                r.eps_y += dy;
                r
            })
            .collect();
        let um = umbmark(&errors, self.p.square_side, self.nominal)?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        eval.odometry(Calibrated {
            method: ClassicMethod::Umbmark,
            params: um.corrected(),
            ms,
            details: serde_json::to_value(&um).unwrap_or_default(),
        })
    }

    /// The GA on pieces of the square runs (corners or 1.5–3 m pieces), their
    /// start and end poses measured with noise, in a box around nominal.
    fn ga_calibration(&mut self) -> Result<Calibrated, ClassicError> {
        let t0 = Instant::now();
        let pieces: Vec<GaRun> = self
            .runs
            .ga_pieces(self.p)
            .into_iter()
            .map(|g| GaRun {
                start: self.noise.pose(&g.start),
                end: self.noise.pose(&g.end),
                ..g
            })
            .collect();
        let nominal_ticks = TickParams::from_diff_drive(self.nominal, self.p.ticks_per_rev);
        let ga = ga_calibrate(
            &pieces,
            &GaParams {
                bounds: GaBounds::around(&nominal_ticks, self.p.ga_bounds_rel),
                ..self.p.ga
            },
        )?;
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let details = serde_json::json!({ "params": ga.params, "cost": ga.cost, "pieces": pieces.len(), "evaluations": ga.evaluations });
        Ok(Calibrated {
            method: ClassicMethod::Ga,
            params: ga.params.to_diff_drive(self.p.ticks_per_rev),
            ms,
            details,
        })
    }
}

/// The GA-calibrated odometry `k_ga` fused with the heading source on each
/// evaluation run; compute time is the GA's `ms_ga` plus the filtering.
fn heading_fusion(
    k_ga: &DiffDrive,
    ms_ga: f64,
    p: &CompareParams,
    eval: &Evaluation<'_>,
) -> Result<ClassicResult, ClassicError> {
    let t0 = Instant::now();
    let estimates: Vec<Trajectory> = eval
        .runs
        .iter()
        .enumerate()
        .map(|(i, run)| {
            let h = simulate_heading(
                &run.truth,
                &p.heading,
                p.seed.wrapping_add(31 * i as u64 + 7),
            );
            heading_pf(
                k_ga,
                &run.wheels,
                &h,
                &start_of(run),
                &HeadingPfParams {
                    seed: p.seed.wrapping_add(i as u64),
                    ..p.pf
                },
            )
        })
        .collect::<Result<_, _>>()?;
    let pf_ms = t0.elapsed().as_secs_f64() * 1e3;
    let details = serde_json::json!({ "particles": p.pf.particles, "heading_sigma": p.heading.sigma, "filter_ms": pf_ms });
    let c = Calibrated {
        method: ClassicMethod::HeadingPf,
        params: *k_ga,
        ms: ms_ga + pf_ms,
        details,
    };
    eval.estimates(c, estimates.iter().map(Ok))
}

/// Measurement noise of end poses: N(0, σ²) per coordinate, seeded.
struct PoseNoise {
    rng: StdRng,
    sigma: [f64; 2],
}

impl PoseNoise {
    fn new(sigma: [f64; 2], seed: u64) -> Self {
        Self {
            rng: StdRng::seed_from_u64(seed ^ 0x656e_6470_6f73),
            sigma,
        }
    }
    fn draw(&mut self, s: f64) -> f64 {
        if s > 0.0 {
            let z: f64 = self.rng.sample(rand_distr::StandardNormal);
            s * z
        } else {
            0.0
        }
    }
    fn xy(&mut self) -> (f64, f64) {
        (self.draw(self.sigma[0]), self.draw(self.sigma[0]))
    }
    fn angle(&mut self) -> f64 {
        self.draw(self.sigma[1])
    }
    fn pose(&mut self, p: &Pose2) -> Pose2 {
        let [x, y, t] = geom::xyt(p);
        let (dx, dy) = self.xy();
        geom::pose(x + dx, y + dy, t + self.angle())
    }
}

/// Total unwrapped heading change of a trajectory (rad).
fn total_turn(t: &Trajectory) -> f64 {
    t.poses
        .windows(2)
        .map(|w| geom::wrap_angle(geom::heading(&w[1]) - geom::heading(&w[0])))
        .sum()
}
