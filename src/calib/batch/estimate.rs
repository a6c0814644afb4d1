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
    let init = closed_form(&rows(pb, &incs, &covs))?;
    let mut keep = vec![true; pb.intervals.len()];
    if !given {
        covs = noise(pb, &residuals(pb, &init.to_vec(6)), &keep);
    }
    signs(&init)?;
    let evidence = excitation(pb, &incs, &covs, &init);
    let step = steps(&init, nominal, track.map(|t| t.period()));
    let mut f = Fit {
        p: init.to_vec(n),
        info: nalgebra::DMatrix::zeros(n, n),
        chi2: 0.0,
    };
    for round in 0..=p.outlier_iterations {
        f = fit(&data(pb, &covs, &keep, &step), &f.p, p.max_iterations);
        if round == p.outlier_iterations {
            break;
        }
        let res = residuals(pb, &f.p);
        drop_outliers(&res, &covs, &mut keep, p.outlier_fraction);
        if !given {
            covs = noise(pb, &res, &keep);
        }
    }
    if !given {
        // The σ's of the final residuals, and the fit they weight.
        covs = noise(pb, &residuals(pb, &f.p), &keep);
        f = fit(&data(pb, &covs, &keep, &step), &f.p, p.max_iterations);
    }
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
    };
    report::build(&f, ctx)
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

fn data<'a>(pb: &'a Problem, covs: &[Matrix3<f64>], keep: &[bool], step: &[f64]) -> Data<'a> {
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
