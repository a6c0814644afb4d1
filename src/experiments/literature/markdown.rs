//! The literature comparison as markdown: its setup, the tables of medians
//! and the findings.

use super::{LiteratureRow, LiteratureTable};
use crate::experiments::compare::side_by_side_table;
use std::fmt::Write;

impl LiteratureTable {
    /// The comparison as markdown: setup, the table of medians, findings.
    pub fn markdown(&self) -> String {
        let p = &self.params;
        let c = &p.compare;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} repetitions, each with its own hidden errors (radii ± {:.1} %, wheel base ± {:.1} %). \
             Calibration data for every method: {} clockwise and {} counter-clockwise {} m squares \
             driven by the nominal model (speed {} m/s, wheel slip σ {} per step, {} ticks/rev); \
             their poses measured with σ {:.1} mm and {:.2}° at the corners (GA{}) and ends \
             (UMBmark, heading gain); the Adaptive-PF and the DKF instead see laser velocities \
             (σ {:.1} mm, {:.2} mrad per scan pair × [{}, {}]) and a gyro on the same squares. \
             Paryanto et al.'s rpm correction is fitted to a tachometer session on the same chair: \
             the wheels spun at {} steady speeds from 0.8 × an in-place turn's wheel rate to \
             1.2 × a straight's, the encoders read over 1 s beside a laser tachometer with its \
             own errors (scale σ {:.2} %, noise σ {:.2} rpm, {:.1} rpm digit); these encoders \
             count true wheel rotation (no rate-dependent gain), so what the correction removes \
             is the tachometer's own error. Evaluation: {} irregular {} m paths per repetition, odometry with each method's final \
             parameters (heading-pf: GA parameters fused with a heading source). Medians over the \
             repetitions; parameter errors in mm.\n",
            self.runs,
            100.0 * p.radius_error,
            100.0 * p.wheel_base_error,
            c.runs_per_direction,
            c.runs_per_direction,
            c.square_side,
            p.drive.speed,
            p.drive.slip_sigma,
            p.drive.ticks_per_rev,
            1e3 * c.end_pose_sigma[0],
            c.end_pose_sigma[1].to_degrees(),
            if c.ga_corners { "" } else { ": random 1.5–3 m pieces" },
            1e3 * p.laser.sigma_dx,
            1e3 * p.laser.sigma_dtheta,
            p.laser.sigma_factor[0],
            p.laser.sigma_factor[1],
            p.tachometer_speeds,
            100.0 * p.tachometer.scale_sigma,
            p.tachometer.reading_sigma_rpm,
            p.tachometer.resolution_rpm,
            c.evaluation_runs,
            p.evaluation_length_m
        );
        s.push_str(&table(&self.rows));
        if !self.changed_rows.is_empty() {
            let _ = writeln!(
                s,
                "\n## After a new user boards (R_R + {:.1} mm, R_L + {:.1} mm)\n\n\
                 Fresh evaluation paths with the changed radii. The classic methods keep the \
                 parameters of their calibration runs (heading-pf is left out: its heading source \
                 hides the change); adaptive-pf and dkf keep calibrating online on these paths \
                 (compute = filtering time over them). Parameter errors against the new truth.\n",
                1e3 * p.load_change[0],
                1e3 * p.load_change[1]
            );
            s.push_str(&table(&self.changed_rows));
        }
        s.push_str("\n## Findings\n\n");
        for f in &self.findings {
            let _ = writeln!(s, "- {f}");
        }
        s
    }
}

/// Markdown table of summary rows (medians; parameter errors in mm).
fn table(rows: &[LiteratureRow]) -> String {
    side_by_side_table(rows.iter().map(|r| {
        let errors = [r.err_r_right, r.err_r_left, r.err_wheel_base].map(|e| e.median);
        let figures = [r.rmse_xy, r.rmse_theta, r.path_error_percent, r.compute_ms];
        (r.method, Some(errors), figures.map(|f| f.median))
    }))
}
