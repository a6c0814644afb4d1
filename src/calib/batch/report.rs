//! The batch estimate as reported: each unknown with its std from the
//! inverse Fisher information (JᵀΣ⁻¹J)⁻¹ at the optimum, the correlation
//! matrix, per-unknown observability with the motion that is missing, and
//! the plausibility checks. Without given covariances the Σ's are the
//! residuals' own σ's (Censi's solver), which sets χ²/dof ≈ 1; with the scan
//! matcher's, a reduced χ² above 1 says they are too small for this
//! recording (a real scanner's range bias, scan skew, slip) and the
//! covariance is multiplied by it (the Birge ratio squared), with a note.

use super::model::Unknowns;
use super::solve::Fit;
use super::{BatchError, BatchParams, NAMES};
use crate::calib::{implausible, observability, CheckParams, Evidence, ParamObservability};
use crate::robot::DiffDrive;
use nalgebra::DMatrix;
use serde::Serialize;
use std::collections::BTreeMap;

/// A value with its standard deviation (same unit).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Valued {
    /// The estimate.
    pub value: f64,
    /// Its standard deviation.
    pub std: f64,
}

/// The laser mounting `base_from_laser` with std's (m, m, rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LaserValued {
    /// Forward offset (m).
    pub x: Valued,
    /// Left offset (m).
    pub y: Valued,
    /// Yaw (rad).
    pub yaw: Valued,
}

/// The correlation matrix with its row/column names.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Correlation {
    /// Unknown names, in row order.
    pub names: Vec<String>,
    /// Correlation coefficients.
    pub matrix: Vec<Vec<f64>>,
}

/// The result of the batch calibration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchEstimate {
    /// Right wheel radius (m).
    pub r_right: Valued,
    /// Left wheel radius (m).
    pub r_left: Valued,
    /// Wheel base (m).
    pub wheel_base: Valued,
    /// Laser mounting.
    pub laser: LaserValued,
    /// Wheel stamps minus laser stamps of one instant (s); `None` when not
    /// estimated (no wheel time, or switched off).
    pub time_offset: Option<Valued>,
    /// Correlations of the unknowns.
    pub correlation: Correlation,
    /// Per unknown: observable, weak, std and what motion is missing (in the
    /// summary under `observability`).
    #[serde(skip)]
    pub observability: BTreeMap<String, ParamObservability>,
    /// The closed-form start ([Censi2013, Sec. IV]), `[r_R, r_L, b, ℓx, ℓy, ℓθ]`.
    pub closed_form: [f64; 6],
    /// Intervals in the final fit.
    pub intervals: usize,
    /// Intervals dropped as outliers.
    pub dropped: usize,
    /// χ² of the final fit and its degrees of freedom.
    pub chi2: f64,
    /// 3·intervals − unknowns.
    pub dof: usize,
    /// The σ's estimated from the residuals `[x m, y m, θ rad]`, when the
    /// intervals carried no covariance.
    pub noise_sigma: Option<[f64; 3]>,
    /// The factor the std's were multiplied by (√(χ²/dof) when the given
    /// covariances explain the residuals too well; else 1).
    pub std_widening: f64,
    /// What a reader of the numbers must know: widened std's, a time
    /// offset of more than a wheel period.
    pub notes: Vec<String>,
    /// The motion the intervals showed.
    #[serde(skip)]
    pub excitation: Evidence,
    /// Covariance of the unknowns (in [`NAMES`] order).
    #[serde(skip)]
    pub covariance: DMatrix<f64>,
}

impl BatchEstimate {
    /// The estimated kinematics.
    pub fn drive(&self) -> DiffDrive {
        DiffDrive {
            r_right: self.r_right.value,
            r_left: self.r_left.value,
            wheel_base: self.wheel_base.value,
        }
    }

    /// The std's of the kinematics (m).
    pub fn drive_std(&self) -> DiffDrive {
        DiffDrive {
            r_right: self.r_right.std,
            r_left: self.r_left.std,
            wheel_base: self.wheel_base.std,
        }
    }

    /// The estimate as unknowns (time offset 0 when not estimated).
    pub fn unknowns(&self) -> Unknowns {
        Unknowns {
            r_right: self.r_right.value,
            r_left: self.r_left.value,
            wheel_base: self.wheel_base.value,
            laser: [self.laser.x.value, self.laser.y.value, self.laser.yaw.value],
            time_offset: self.time_offset.map_or(0.0, |v| v.value),
        }
    }
}

/// What [`build`] needs besides the fit.
pub struct Context<'a> {
    /// The nominal kinematics (scale and bounds).
    pub nominal: &'a DiffDrive,
    /// The batch settings.
    pub params: &'a BatchParams,
    /// The excitation and plausibility thresholds.
    pub checks: &'a CheckParams,
    /// The motion the intervals showed.
    pub evidence: Evidence,
    /// The closed-form start.
    pub init: Unknowns,
    /// Intervals kept and dropped.
    pub kept: usize,
    /// Intervals dropped as outliers.
    pub dropped: usize,
    /// σ's estimated from the residuals, if any.
    pub noise: Option<[f64; 3]>,
    /// The wheel stream's period (s), if timed.
    pub period: Option<f64>,
    /// Which unknowns were fitted (the others held: std 0).
    pub free: Vec<bool>,
}

/// The covariance from the Fisher information, normalised to unit diagonal
/// first; `Err` names the unknowns spanning a (near) null direction.
fn covariance(info: &DMatrix<f64>, singular: f64) -> Result<DMatrix<f64>, Vec<usize>> {
    let n = info.nrows();
    let d = DMatrix::from_diagonal(&info.diagonal().map(|x| 1.0 / x.max(1e-300).sqrt()));
    let norm = &d * info * &d;
    let eig = norm.clone().symmetric_eigen();
    let (k, min) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |a, (i, &v)| if v < a.1 { (i, v) } else { a },
        );
    if !(min > singular) || info.diagonal().iter().any(|x| !(*x > 0.0)) {
        let v = eig.eigenvectors.column(k);
        return Err((0..n)
            .filter(|&i| v[i].abs() > 0.3 || !(info[(i, i)] > 0.0))
            .collect());
    }
    let inv = norm
        .try_inverse()
        .ok_or_else(|| (0..n).collect::<Vec<_>>())?;
    Ok(&d * inv * &d)
}

/// What motion each unknown needs (for the refusal and the weak flags).
fn needs(name: &str) -> &'static str {
    match name {
        "r_right" | "r_left" => "straight driving and turns",
        "wheel_base" => "turns both ways while driving",
        "laser_x" | "laser_y" => "turns (in place or on curves) both ways",
        "laser_yaw" => "translation: straight or curved driving",
        _ => "changes of speed or of turn rate (accelerations) with the laser matching well",
    }
}

/// The reported estimate, or the reason there is none.
pub fn build(f: &Fit, c: Context) -> Result<BatchEstimate, BatchError> {
    let n = f.p.len();
    let cov = covariance(&f.info, c.params.singular).map_err(|idx| {
        BatchError::Unobservable(
            idx.iter()
                .map(|&i| format!("{} needs {}", NAMES[i], needs(NAMES[i])))
                .collect::<Vec<_>>()
                .join("; "),
        )
    })?;
    let dof = (3 * c.kept).saturating_sub(c.free.iter().filter(|x| **x).count());
    let mut notes = Vec::new();
    let widening = birge(f.chi2, dof, c.noise.is_none(), &mut notes);
    if !f.converged {
        // Every iteration took a step still worth taking: not shown to be
        // at the optimum.
        notes.push(format!(
            "the fit stopped at its iteration limit ({} iterations) while its steps were \
             still large; the estimate may not be the optimum: raise [batch] max_iterations",
            f.iterations
        ));
    }
    let mut cov = cov * (widening * widening);
    for j in (0..n).filter(|&j| !c.free[j]) {
        cov.row_mut(j).fill(0.0);
        cov.column_mut(j).fill(0.0);
    }
    let std: Vec<f64> = (0..n).map(|i| cov[(i, i)].sqrt()).collect();
    let u = Unknowns::from_slice(&f.p);
    let obs = observe(&std, &c);
    let missing: Vec<String> = obs
        .iter()
        .filter(|(_, o)| !o.observable)
        .map(|(k, o)| format!("{k}: {}", o.missing.as_deref().unwrap_or("not excited")))
        .collect();
    if !missing.is_empty() {
        return Err(BatchError::Unobservable(missing.join("; ")));
    }
    plausible(&u, &c)?;
    if let Some(note) = late_stream(&u, std.get(6).copied(), c.period) {
        notes.push(note);
    }
    let v = |i: usize| Valued {
        value: f.p[i],
        std: std[i],
    };
    Ok(BatchEstimate {
        r_right: v(0),
        r_left: v(1),
        wheel_base: v(2),
        laser: LaserValued {
            x: v(3),
            y: v(4),
            yaw: v(5),
        },
        time_offset: (n == 7).then(|| v(6)),
        correlation: Correlation {
            names: NAMES[..n].iter().map(|s| s.to_string()).collect(),
            matrix: (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| match std[i] * std[j] {
                            0.0 => f64::from(u8::from(i == j)),
                            s => cov[(i, j)] / s,
                        })
                        .collect()
                })
                .collect(),
        },
        observability: obs,
        closed_form: [
            c.init.r_right,
            c.init.r_left,
            c.init.wheel_base,
            c.init.laser[0],
            c.init.laser[1],
            c.init.laser[2],
        ],
        intervals: c.kept,
        dropped: c.dropped,
        chi2: f.chi2,
        dof,
        noise_sigma: c.noise,
        std_widening: widening,
        notes,
        excitation: c.evidence,
        covariance: cov,
    })
}

/// Per unknown: the online filters' excitation checks for the kinematics
/// ([`observability`]), turns for the laser position, translation for its
/// yaw; weak where the Fisher std exceeds the configured fraction.
fn observe(std: &[f64], c: &Context) -> BTreeMap<String, ParamObservability> {
    let sd = DiffDrive {
        r_right: std[0],
        r_left: std[1],
        wheel_base: std[2],
    };
    let mut checks = *c.checks;
    checks.weak_widening = 1.0;
    let mut out = observability(&c.evidence, &sd, c.nominal, &checks, false).parameters;
    let b0 = c.nominal.wheel_base;
    let nom = [c.nominal.r_right, c.nominal.r_left, b0];
    let ev = &c.evidence;
    let rotation = ev.turn_left_rad + ev.turn_right_rad;
    for (i, name) in NAMES.iter().enumerate().take(std.len()) {
        let (limit, unexcited) = match i {
            0..=2 => (c.params.weak_relative * nom[i], None),
            3 | 4 => (
                c.params.weak_laser_position * b0,
                (rotation < c.checks.min_rotation_rad).then(|| {
                    format!(
                        "the robot turned {rotation:.2} rad in all; the laser position needs turns"
                    )
                }),
            ),
            5 => (
                c.params.weak_laser_yaw,
                (ev.distance_m < c.checks.min_distance_wheel_bases * b0).then(|| {
                    format!(
                        "the robot drove {:.2} m; the laser yaw needs translation",
                        ev.distance_m
                    )
                }),
            ),
            _ => (0.5 * c.period.unwrap_or(f64::INFINITY), None),
        };
        let e = out.entry(name.to_string()).or_insert(ParamObservability {
            observable: true,
            weak: false,
            std: std[i],
            missing: None,
        });
        e.std = std[i];
        if !c.free.get(i).copied().unwrap_or(true) {
            // Held at a stated value: neither estimated nor weak.
            continue;
        }
        if let Some(m) = unexcited {
            e.observable = false;
            e.missing = Some(m);
        } else if e.observable && std[i] > limit && e.missing.is_none() {
            e.weak = true;
            e.missing = Some(format!(
                "weak: std {:.3e} above {:.3e}; more {} would firm it",
                std[i],
                limit,
                needs(name)
            ));
        }
    }
    out
}

/// √(χ²/dof) when the intervals' covariances were given (the scan
/// matcher's) and explain the residuals worse than they claim, else 1; the
/// note says so.
fn birge(chi2: f64, dof: usize, given: bool, notes: &mut Vec<String>) -> f64 {
    let reduced = chi2 / dof.max(1) as f64;
    if !given || !(reduced > 1.0) {
        return 1.0;
    }
    let w = reduced.sqrt();
    notes.push(format!(
        "the residuals are {w:.1} times the scan matcher's σ (χ² {chi2:.0} for {dof} degrees \
         of freedom): its covariances are too small for this recording (range bias, scan \
         skew, slip, moving objects); every std is multiplied by {w:.1}"
    ));
    w
}

/// The note for a time offset of more than one wheel period: the streams
/// are stamped apart (which one is late, by how many samples).
fn late_stream(u: &Unknowns, std: Option<f64>, period: Option<f64>) -> Option<String> {
    let (p, s) = (period?, std?);
    let d = u.time_offset;
    if d.abs() <= p {
        return None;
    }
    let (late, other) = if d < 0.0 {
        ("laser scan", "wheel reading")
    } else {
        ("wheel reading", "laser scan")
    };
    Some(format!(
        "time_offset {d:+.3} ± {s:.3} s is {:.1} wheel periods: a {late} is stamped {:.3} s \
         after the {other} of the same instant (a recorder that stamps data on arrival does \
         this); the online filters need it applied (`calibrate --init batch` does)",
        d.abs() / p,
        d.abs()
    ))
}

/// Radii and wheel base within the multiplier bounds of the nominal robot,
/// and a time offset within `max_time_offset_s`.
fn plausible(u: &Unknowns, c: &Context) -> Result<(), BatchError> {
    let est = DiffDrive {
        r_right: u.r_right,
        r_left: u.r_left,
        wheel_base: u.wheel_base,
    };
    if let Some(m) = implausible(&est, c.nominal, None, c.checks) {
        return Err(BatchError::Implausible(m));
    }
    let limit = c.params.max_time_offset_s;
    if c.period.is_some() && u.time_offset.abs() > limit {
        return Err(BatchError::Implausible(format!(
            "time_offset came out {:.4} s, more than the {limit} s accepted \
             ([calib.batch] max_time_offset_s): the wheel and laser clocks disagree; fix the \
             stamps, or raise the limit if the recorder is known to stamp that late",
            u.time_offset
        )));
    }
    Ok(())
}
