//! The batch calibration's steps: closed-form start, outlier rounds of
//! maximum-likelihood fits, the final fit, the covariance and the checks.

use super::closed_form::{closed_form, Row};
use super::model::{increments, inverse, oplus, Unknowns, P3};
use super::report::{self, BatchEstimate};
use super::solve::{fit, raw_residual, Data, Fit};
use super::{outliers, BatchError, BatchParams, Problem, WheelMotion};
use crate::calib::{CalibStep, CheckParams, Evidence, Kind, Measurement};
use crate::robot::DiffDrive;
use nalgebra::Matrix3;

/// Estimates the radii, wheel base, laser mounting and (when the intervals
/// are time spans on a wheel track and `p.time_offset`) the time offset;
/// `nominal` sets the scale and the plausibility bounds. What the data
/// cannot support is an error saying why.
pub fn estimate(
    pb: &Problem,
    nominal: &DiffDrive,
    p: &BatchParams,
    checks: &CheckParams,
) -> Result<BatchEstimate, BatchError> {
    estimate_with_laser(pb, nominal, p, checks, None)
}

/// [`estimate`] with the laser mounting held at `laser` (base_from_laser
/// `[x, y, yaw]`) when given: the radii, the wheel base and the time offset
/// alone, better determined when the mounting is known (a corridor's turns
/// hardly tell a laser's position from the wheel base). The held unknowns
/// are reported with std 0.
pub fn estimate_with_laser(
    pb: &Problem,
    nominal: &DiffDrive,
    p: &BatchParams,
    checks: &CheckParams,
    laser: Option<P3>,
) -> Result<BatchEstimate, BatchError> {
    validate(pb, p)?;
    let track = pb.track.as_ref();
    let spans = pb
        .intervals
        .iter()
        .all(|iv| matches!(iv.wheels, WheelMotion::Span { .. }));
    let n = if p.time_offset && spans && track.is_some() {
        7
    } else {
        6
    };
    let given = pb.intervals.iter().all(|iv| iv.cov.is_some());
    let incs: Vec<Vec<[f64; 2]>> = pb
        .intervals
        .iter()
        .map(|iv| {
            let mut v = Vec::new();
            increments(iv, track, 0.0, &mut v);
            v
        })
        .collect();
    let mut covs: Vec<Matrix3<f64>> = match given {
        true => pb.intervals.iter().map(|iv| iv.cov.unwrap()).collect(),
        false => vec![Matrix3::identity(); pb.intervals.len()],
    };
    let mut init = closed_form(&rows(pb, &incs, &covs))?;
    if let Some(l) = laser {
        init.laser = l;
    }
    let free: Vec<bool> = (0..n)
        .map(|i| laser.is_none() || !(3..6).contains(&i))
        .collect();
    let keep = vec![true; pb.intervals.len()];
    if !given {
        covs = noise(pb, &residuals(pb, &init.to_vec(6)), &keep);
    }
    signs(&init)?;
    let evidence = excitation(pb, &incs, &covs, &init);
    let step = steps(&init, nominal, track.map(|t| t.period()));
    let f = Fit {
        p: init.to_vec(n),
        info: nalgebra::DMatrix::zeros(n, n),
        chi2: 0.0,
        iterations: 0,
        converged: true,
    };
    let how = Rounds {
        given,
        step: &step,
        free: &free,
    };
    let (f, keep, covs) = fit_rounds(pb, p, &how, f, keep, covs);
    let ctx = report::Context {
        nominal,
        params: p,
        checks,
        evidence,
        init,
        kept: keep.iter().filter(|k| **k).count(),
        dropped: keep.iter().filter(|k| !**k).count(),
        noise: (!given).then(|| [0, 1, 2].map(|i| covs[0][(i, i)].sqrt())),
        period: track.map(|t| t.period()),
        free,
    };
    report::build(&f, ctx)
}

/// How the fit-and-reject rounds fit: whether the intervals carry their own
/// covariances (else the σ's come from the residuals), the unknowns' steps
/// and which are free.
struct Rounds<'a> {
    given: bool,
    step: &'a [f64],
    free: &'a [bool],
}

/// Censi's fit-and-reject rounds from `f`, with the robust rule on top: the
/// last fit, which intervals it kept and their covariances.
fn fit_rounds(
    pb: &Problem,
    p: &BatchParams,
    how: &Rounds<'_>,
    mut f: Fit,
    mut keep: Vec<bool>,
    mut covs: Vec<Matrix3<f64>>,
) -> (Fit, Vec<bool>, Vec<Matrix3<f64>>) {
    let (given, step, free) = (how.given, how.step, how.free);
    // Censi's drops accumulate over his rounds; the robust rule judges every
    // round afresh among those, so that its cap holds for the whole.
    let mut censi = keep.clone();
    for round in 0..MAX_ROUNDS {
        f = fit(&data(pb, &covs, &keep, step, free), &f.p, p.max_iterations);
        let res = residuals(pb, &f.p);
        let before = keep.clone();
        if round < p.outlier_iterations {
            drop_outliers(&res, &covs, &mut censi, p.outlier_fraction);
        }
        let fits = outliers::consistent(
            &res,
            &covs,
            &censi,
            p.outlier_probability,
            p.outlier_max_fraction,
        );
        keep = censi.iter().zip(&fits).map(|(c, f)| *c && *f).collect();
        if keep.iter().filter(|k| **k).count() < p.min_intervals.max(6) {
            // Too few would be left to fit: `f` is the fit of the last set.
            keep = before;
            break;
        }
        if keep == before {
            break;
        }
        if !given {
            covs = noise(pb, &res, &keep);
        }
    }
    if !given {
        // The σ's of the final residuals, and the fit they weight.
        covs = noise(pb, &residuals(pb, &f.p), &keep);
        f = fit(&data(pb, &covs, &keep, step, free), &f.p, p.max_iterations);
    }
    (f, keep, covs)
}

/// Most fit-and-reject rounds: Censi's `outlier_iterations` (with the
/// robust rule), then rounds of the robust rule alone until the kept set
/// stops changing.
const MAX_ROUNDS: usize = 12;

/// How much larger than their covariances claim the intervals' residuals
/// are at `u`, per component `[x, y, θ]`, from the differences of
/// consecutive whitened residuals (the successive differences of
/// \[VonNeumann1941\]):
/// √(median of (z_k − z_{k−1})²/2 over the median of χ²₁), at least 1. The
/// differences keep the scan matcher's own noise, independent from one
/// interval to the next, and drop what changes slowly (parameters that
/// change during the window, a drift), which is for the filters to follow,
/// not to be counted as noise; the median keeps outliers out. Intervals
/// without a covariance count as σ = 1 (their scale is then the residuals'
/// own).
pub fn residual_scales(pb: &Problem, u: &Unknowns) -> [f64; 3] {
    const MEDIAN_CHI2_1: f64 = 0.454_936_423_119_572_8;
    let res = residuals(pb, &u.to_vec(7));
    std::array::from_fn(|k| {
        let z: Vec<f64> = res
            .iter()
            .zip(&pb.intervals)
            .map(|(e, iv)| e[k] / iv.cov.map_or(1.0, |c| c[(k, k)].sqrt()))
            .collect();
        let mut d: Vec<f64> = z
            .windows(2)
            .map(|w| 0.5 * (w[1] - w[0]).powi(2))
            .filter(|x| x.is_finite())
            .collect();
        if d.is_empty() {
            return 1.0;
        }
        d.sort_by(f64::total_cmp);
        (d[d.len() / 2] / MEDIAN_CHI2_1).sqrt().max(1.0)
    })
}

/// The kinematics of the closed-form start alone ([Censi2013, Sec. IV], time
/// offset 0): where a calibration without nominal values begins.
pub fn closed_form_start(pb: &Problem, p: &BatchParams) -> Result<DiffDrive, BatchError> {
    validate(pb, p)?;
    let incs: Vec<Vec<[f64; 2]>> = pb
        .intervals
        .iter()
        .map(|iv| {
            let mut v = Vec::new();
            increments(iv, pb.track.as_ref(), 0.0, &mut v);
            v
        })
        .collect();
    let covs: Vec<Matrix3<f64>> = pb
        .intervals
        .iter()
        .map(|iv| iv.cov.unwrap_or_else(Matrix3::identity))
        .collect();
    let u = closed_form(&rows(pb, &incs, &covs))?;
    signs(&u)?;
    Ok(DiffDrive {
        r_right: u.r_right,
        r_left: u.r_left,
        wheel_base: u.wheel_base,
    })
}

fn validate(pb: &Problem, p: &BatchParams) -> Result<(), BatchError> {
    if pb.intervals.len() < p.min_intervals.max(6) {
        return Err(BatchError::Input(format!(
            "{} intervals: the batch calibration needs at least {}",
            pb.intervals.len(),
            p.min_intervals.max(6)
        )));
    }
    let some = pb.intervals.iter().filter(|iv| iv.cov.is_some()).count();
    if some != 0 && some != pb.intervals.len() {
        return Err(BatchError::Input(
            "some intervals carry a covariance and others none".into(),
        ));
    }
    if let Some(i) = pb.intervals.iter().position(|iv| {
        !(iv.s.iter().all(|x| x.is_finite()) && iv.duration > 0.0)
            || iv
                .cov
                .is_some_and(|c| c.iter().any(|x| !x.is_finite()) || c.cholesky().is_none())
    }) {
        return Err(BatchError::Input(format!(
            "interval {i}: displacement not finite, duration not positive or covariance not \
             positive definite"
        )));
    }
    Ok(())
}

/// Closed-form rows weighted by the inverse variances.
fn rows<'a>(pb: &Problem, incs: &'a [Vec<[f64; 2]>], covs: &[Matrix3<f64>]) -> Vec<Row<'a>> {
    pb.intervals
        .iter()
        .zip(incs)
        .zip(covs)
        .map(|((iv, inc), c)| Row {
            inc,
            s: iv.s,
            w_rot: 1.0 / c[(2, 2)],
            w_tr: 2.0 / (c[(0, 0)] + c[(1, 1)]),
        })
        .collect()
}

/// Every interval's residual at `p`.
fn residuals(pb: &Problem, p: &[f64]) -> Vec<P3> {
    let mut buf = Vec::new();
    pb.intervals
        .iter()
        .map(|iv| raw_residual(iv, pb.track.as_ref(), p, &mut buf))
        .collect()
}

/// Censi's noise estimate (`estimate_noise`): one σ per component from the
/// kept residuals (root mean square), as a diagonal covariance for all.
fn noise(pb: &Problem, res: &[P3], keep: &[bool]) -> Vec<Matrix3<f64>> {
    let kept: Vec<&P3> = res
        .iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .map(|(e, _)| e)
        .collect();
    let m = kept.len().max(1) as f64;
    let var = [0, 1, 2].map(|i| (kept.iter().map(|e| e[i] * e[i]).sum::<f64>() / m).max(1e-24));
    vec![Matrix3::from_diagonal(&var.into()); pb.intervals.len()]
}

fn drop_outliers(res: &[P3], covs: &[Matrix3<f64>], keep: &mut [bool], fraction: f64) {
    let idx: Vec<usize> = (0..keep.len()).filter(|&i| keep[i]).collect();
    let r: Vec<P3> = idx.iter().map(|&i| res[i]).collect();
    let c: Vec<Matrix3<f64>> = idx.iter().map(|&i| covs[i]).collect();
    for (j, k) in outliers::keep(&r, &c, fraction).into_iter().enumerate() {
        keep[idx[j]] = k;
    }
}

fn data<'a>(
    pb: &'a Problem,
    covs: &[Matrix3<f64>],
    keep: &[bool],
    step: &[f64],
    free: &[bool],
) -> Data<'a> {
    let sel: Vec<usize> = (0..keep.len()).filter(|&i| keep[i]).collect();
    Data {
        intervals: sel.iter().map(|&i| &pb.intervals[i]).collect(),
        whiten: sel
            .iter()
            .map(|&i| {
                let info = covs[i].try_inverse().unwrap_or_else(Matrix3::zeros);
                info.cholesky()
                    .map(|c| c.l().transpose())
                    .unwrap_or_else(Matrix3::zeros)
            })
            .collect(),
        track: pb.track.as_ref(),
        step: step.to_vec(),
        free: free.to_vec(),
    }
}

/// Central-difference steps: 1e-6 of each unknown's scale (radii and base
/// from the estimate or the nominal robot, laser position by the wheel
/// base, yaw in rad, time by the wheel period).
fn steps(init: &Unknowns, nominal: &DiffDrive, period: Option<f64>) -> Vec<f64> {
    let b = nominal.wheel_base.max(init.wheel_base.abs());
    vec![
        nominal.r_right.max(init.r_right.abs()),
        nominal.r_left.max(init.r_left.abs()),
        b,
        b,
        b,
        1.0,
        period.filter(|p| *p > 0.0).unwrap_or(0.01),
    ]
    .into_iter()
    .map(|s| 1e-6 * s)
    .collect()
}

/// Negative radii are a swapped or mirrored wheel, not a calibration. The
/// rotation alone tells them apart (J21 = −r_L/b < 0 < J22 = r_R/b is the
/// right wiring); the online filters' forward-speed test needs the laser's
/// orientation, which the batch estimates, so it is not used here.
fn signs(u: &Unknowns) -> Result<(), BatchError> {
    let what = match (u.r_right > 0.0, u.r_left > 0.0) {
        (true, true) => return Ok(()),
        (false, false) => {
            "the wheels turn the robot the opposite way to what the laser sees: the joint \
             named left carries the right encoder (or both count backwards). Swap left_joint \
             and right_joint in the robot file"
        }
        (true, false) => "the left encoder counts backwards (negate it or fix the joint's axis)",
        (false, true) => "the right encoder counts backwards (negate it or fix the joint's axis)",
    };
    Err(BatchError::Implausible(format!(
        "wheel encoders wired wrongly: the rotation fit gives r_right {:.4} m, r_left {:.4} m \
         (J21 = −r_L/b must be < 0 and J22 = r_R/b > 0): {what}",
        u.r_right, u.r_left
    )))
}

/// The motion the intervals show, as the online filters' evidence: per
/// interval the mean wheel rates, the robot's forward speed from the laser
/// displacement moved into the base frame with the closed-form mounting,
/// and the turn rate, with σ's from the covariances.
fn excitation(
    pb: &Problem,
    incs: &[Vec<[f64; 2]>],
    covs: &[Matrix3<f64>],
    u: &Unknowns,
) -> Evidence {
    let mut ev = Evidence::default();
    for ((iv, inc), c) in pb.intervals.iter().zip(incs).zip(covs) {
        let t = iv.duration;
        let d = inc.iter().fold([0.0; 2], |s, x| [s[0] + x[0], s[1] + x[1]]);
        let o = oplus(oplus(u.laser, iv.s), inverse(u.laser));
        let mut st = CalibStep::new(0.0, t, d[1] / t, d[0] / t);
        let sv = (0.5 * (c[(0, 0)] + c[(1, 1)])).sqrt() / t;
        st.push(Measurement {
            kind: Kind::V,
            value: o[0] / t,
            sigma: sv,
        });
        st.push(Measurement {
            kind: Kind::W,
            value: iv.s[2] / t,
            sigma: c[(2, 2)].sqrt() / t,
        });
        ev.add(&st);
    }
    ev
}
