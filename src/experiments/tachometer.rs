//! The calibration of \[Paryanto\] from its own tables: the per-wheel rpm correction
//! fitted to the tachometer table (Table I), the heading gain from the five
//! 90° turns, and the correction applied to the straight-driving wheel speed
//! pairs (Table II) to see whether it brings right and left together.

use super::inputs::{bad, ExperimentInputs};
use super::output::{comma_list, draw_lines, ExperimentOutput};
use super::square::SquareExperimentParams;
use crate::classic::{
    check_finite, fit_heading_gain, fit_tachometer, ClassicError, HeadingGain, HeadingTrial,
    TachoCalibration, TachoReading,
};
use crate::error::InputError;
use crate::io::seed_tables::{read_seed_table, SeedTable};
use crate::pipeline::PipelineError;
use crate::viz::plot::{LineChart, Series};
use serde::Serialize;
use std::fmt::Write;
use std::path::Path;

/// One straight-driving pair before and after the rpm correction (rad/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpeedPair {
    /// Right wheel as read (rad/s).
    pub right: f64,
    /// Left wheel as read (rad/s).
    pub left: f64,
    /// Right after correction (rad/s).
    pub right_corrected: f64,
    /// Left after correction (rad/s).
    pub left_corrected: f64,
}

/// The fitted corrections and what they do.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TachometerExperiment {
    /// Per-wheel rpm correction.
    pub tachometer: TachoCalibration,
    /// Heading gain from the turn trials.
    pub heading_gain: HeadingGain,
    /// Wheel base (m) that applies the gain, for a nominal wheel base.
    pub effective_wheel_base: Option<[f64; 2]>,
    /// Table II pairs before and after, when given.
    pub speed_pairs: Vec<SpeedPair>,
    /// RMS of right − left before and after correction (rad/s).
    pub pair_rms: Option<[f64; 2]>,
}

/// Fits both corrections; `pairs` (right, left rad/s) and `nominal_wheel_base`
/// (m) are optional extras.
pub fn tachometer_experiment(
    table: &[TachoReading],
    trials: &[HeadingTrial],
    pairs: &[(f64, f64)],
    nominal_wheel_base: Option<f64>,
) -> Result<TachometerExperiment, ClassicError> {
    let tachometer = fit_tachometer(table)?;
    let heading_gain = fit_heading_gain(trials)?;
    check_finite("tachometer", "speed", pairs.iter().flat_map(|p| [p.0, p.1]))?;
    let speed_pairs: Vec<SpeedPair> = pairs
        .iter()
        .map(|&(r, l)| {
            let (rc, lc) = tachometer.correct_rates(r, l);
            SpeedPair {
                right: r,
                left: l,
                right_corrected: rc,
                left_corrected: lc,
            }
        })
        .collect();
    let rms = |f: &dyn Fn(&SpeedPair) -> f64| {
        (speed_pairs.iter().map(|p| f(p).powi(2)).sum::<f64>() / speed_pairs.len() as f64).sqrt()
    };
    let pair_rms = (!speed_pairs.is_empty()).then(|| {
        [
            rms(&|p| p.right - p.left),
            rms(&|p| p.right_corrected - p.left_corrected),
        ]
    });
    Ok(TachometerExperiment {
        effective_wheel_base: nominal_wheel_base.map(|d| [d, heading_gain.effective_wheel_base(d)]),
        tachometer,
        heading_gain,
        speed_pairs,
        pair_rms,
    })
}

impl TachometerExperiment {
    /// Markdown: the fits, the corrected table, the gain.
    pub fn markdown(&self, table: &[TachoReading]) -> String {
        let (r, l) = (&self.tachometer.right, &self.tachometer.left);
        let mut s = String::from("## rpm correction (Paryanto et al., Table I)\n\n");
        let _ = writeln!(
            s,
            "tachometer rpm = slope · encoder rpm + intercept, least squares per wheel.\n\n\
             | wheel | slope | intercept (rpm) | through origin | RMS before (rpm) | RMS after (rpm) |\n|---|---|---|---|---|---|\n\
             | right | {:.5} | {:+.3} | {:.5} | {:.3} | {:.3} |\n| left | {:.5} | {:+.3} | {:.5} | {:.3} | {:.3} |\n",
            r.slope, r.intercept, r.slope_through_origin, r.rms_before, r.rms_residual,
            l.slope, l.intercept, l.slope_through_origin, l.rms_before, l.rms_residual
        );
        s.push_str("| tachometer (rpm) | right encoder | right corrected | left encoder | left corrected |\n|---|---|---|---|---|\n");
        for t in table {
            let _ = writeln!(
                s,
                "| {} | {} | {:.2} | {} | {:.2} |",
                t.tachometer_rpm,
                t.right_encoder_rpm,
                r.apply(t.right_encoder_rpm),
                t.left_encoder_rpm,
                l.apply(t.left_encoder_rpm)
            );
        }
        let g = &self.heading_gain;
        let _ = writeln!(
            s,
            "\n## Heading gain (Paryanto et al., five 90° turns)\n\nGain {:.3} ± {:.3} (mean ratio, the paper's 3.2; \
             least squares {:.3}); per trial {}; largest residual after the gain {:.1}°.",
            g.gain,
            g.gain_stderr,
            g.gain_least_squares,
            comma_list(&g.per_trial, |v| format!("{v:.2}")),
            g.max_abs_residual_deg
        );
        if let Some([d, e]) = self.effective_wheel_base {
            let _ = write!(s, "As a wheel base: {d:.3} m nominal → {e:.3} m effective.");
            if !(0.67..1.5).contains(&g.gain) {
                let _ = write!(
                    s,
                    " A gain this far from 1 is not a geometric error: no real wheel base is off \
                     by a factor of {:.1}; the turns were under-read for another reason (slip of \
                     the belt-driven encoders, skidding casters).",
                    g.gain
                );
            }
            s.push('\n');
        }
        if let Some([a, b]) = self.pair_rms {
            let _ = writeln!(
                s,
                "\n## Straight driving (Paryanto et al., Table II)\n\nRMS of right − left wheel speed: \
                 {a:.4} rad/s as read, {b:.4} rad/s after the rpm correction{}.",
                if b < a {
                    ""
                } else {
                    " — the correction does not bring the wheels together: the difference \
                     while driving straight is not an encoder scale error"
                }
            );
            let _ = writeln!(s, "\n| right (rad/s) | left (rad/s) | right corrected | left corrected |\n|---|---|---|---|");
            for p in &self.speed_pairs {
                let _ = writeln!(
                    s,
                    "| {:.2} | {:.2} | {:.3} | {:.3} |",
                    p.right, p.left, p.right_corrected, p.left_corrected
                );
            }
        }
        s
    }
}

/// `encoder_vs_tachometer.csv`: tachometer_rpm,right_encoder_rpm,left_encoder_rpm.
pub fn tachometer_table(t: &SeedTable) -> Result<Vec<TachoReading>, InputError> {
    let (a, r, l) = (
        t.numbers("tachometer_rpm")?,
        t.numbers("right_encoder_rpm")?,
        t.numbers("left_encoder_rpm")?,
    );
    Ok((0..a.len())
        .map(|i| TachoReading {
            tachometer_rpm: a[i],
            right_encoder_rpm: r[i],
            left_encoder_rpm: l[i],
        })
        .collect())
}

/// `heading_trials.csv`: actual_deg,estimated_deg (a trial column is ignored).
pub fn heading_trials(t: &SeedTable) -> Result<Vec<HeadingTrial>, InputError> {
    let (a, e) = (t.numbers("actual_deg")?, t.numbers("estimated_deg")?);
    Ok(a.into_iter()
        .zip(e)
        .map(|(actual_deg, estimated_deg)| HeadingTrial {
            actual_deg,
            estimated_deg,
        })
        .collect())
}

/// `wheel_speed_pairs.csv`: right_rad_s,left_rad_s, as (right, left) pairs.
pub fn speed_pairs(t: &SeedTable) -> Result<Vec<(f64, f64)>, InputError> {
    let (r, l) = (t.numbers("right_rad_s")?, t.numbers("left_rad_s")?);
    Ok(r.into_iter().zip(l).collect())
}

/// The straight-driving pairs of the `--tables` folder, none without the file.
fn table_pairs(inp: &ExperimentInputs<'_>) -> Result<Vec<(f64, f64)>, PipelineError> {
    Ok(match inp.tables.map(|d| d.join("wheel_speed_pairs.csv")) {
        Some(p) if p.is_file() => speed_pairs(&read_seed_table(&p)?)?,
        _ => Vec::new(),
    })
}

/// `odocal experiment tachometer`: both corrections from the paper's published tables,
/// encoder − tachometer before and after drawn into `png`.
pub(super) fn tachometer_output(
    inp: &ExperimentInputs<'_>,
    square: &SquareExperimentParams,
    png: &Path,
) -> Result<ExperimentOutput, PipelineError> {
    let rows = tachometer_table(&inp.seed_table("encoder_vs_tachometer.csv")?)?;
    let trials = heading_trials(&inp.seed_table("heading_trials.csv")?)?;
    let pairs = table_pairs(inp)?;
    let e = tachometer_experiment(&rows, &trials, &pairs, Some(square.nominal.wheel_base))
        .map_err(bad)?;
    draw_lines(png, &correction_chart(&rows, &e.tachometer))?;
    let title = "Paryanto et al.: tachometer rpm correction and heading gain";
    Ok(ExperimentOutput::titled(title, e.markdown(&rows), &e))
}

/// Encoder − tachometer rpm per wheel, as read and after the correction `c`.
fn correction_chart(rows: &[TachoReading], c: &TachoCalibration) -> LineChart {
    let xs: Vec<f64> = rows.iter().map(|r| r.tachometer_rpm).collect();
    let err = |f: &dyn Fn(&TachoReading) -> f64| -> Vec<f64> {
        rows.iter().map(|r| f(r) - r.tachometer_rpm).collect()
    };
    let (fr, fl) = (&c.right, &c.left);
    LineChart::new(
        "Paryanto et al. Table I: encoder − tachometer before and after the rpm correction",
        "tachometer (rpm)",
    )
    .panel(
        "encoder − tachometer (rpm)",
        vec![
            Series::from_xy("right, as read", &xs, &err(&|r| r.right_encoder_rpm)),
            Series::from_xy("left, as read", &xs, &err(&|r| r.left_encoder_rpm)),
            Series::from_xy(
                "right, corrected",
                &xs,
                &err(&|r| fr.apply(r.right_encoder_rpm)),
            )
            .dashed(),
            Series::from_xy(
                "left, corrected",
                &xs,
                &err(&|r| fl.apply(r.left_encoder_rpm)),
            )
            .dashed(),
        ],
    )
}
