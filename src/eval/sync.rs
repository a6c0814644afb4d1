//! Time association of an estimate with a reference, as evo's
//! `sync.associate_trajectories` (1.38): the trajectory with fewer poses drives
//! the search; each of its stamps takes the closest stamp of the other
//! (offset added to the estimate's stamps) if within `max_diff`; optionally the
//! denser trajectory is resampled at the matched stamps instead (linear in
//! position, SLERP in rotation, evo's `SyncMethod.interpolation`).
//!
//! Nearest-stamp pairing only works when both streams are sampled together: a
//! tracker on its own clock (the LEGO robot's overhead camera, ≈ 5 Hz, its
//! stamps 66 ms from the wheels' on median) pairs 37 of 278 poses within evo's
//! 0.01 s. [`resample`] instead interpolates the reference at every estimate
//! stamp inside its span whose two neighbouring reference samples are at most
//! `max_gap` apart — what a reference denser or sparser than the estimate
//! needs. [`SyncOptions::resample`] chooses it (by default for a
//! position-only reference, see `report`).

use super::traj3::{Pose3, Trajectory3};
use super::EvalError;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

/// How to associate stamps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SyncOptions {
    /// Largest accepted stamp difference (s); evo's `--t_max_diff` (default 0.01).
    pub max_diff: f64,
    /// Added to the estimate's stamps before matching (s); evo's `--t_offset`.
    pub offset: f64,
    /// Resample the denser trajectory at the matched stamps (evo's
    /// `--sync_method interpolation`) instead of taking its nearest poses.
    pub interpolate: bool,
    /// Interpolate the reference at every estimate stamp (see [`resample`])
    /// instead of pairing nearest stamps; unset: only for a reference with
    /// positions only, unless `interpolate` asks for evo's pairing.
    pub resample: Option<bool>,
    /// Largest gap (s) between the two reference samples around an estimate
    /// stamp that resampling bridges (default 0.5 s: the LEGO tracker's gaps
    /// reach 0.38 s).
    pub max_gap: f64,
}

impl Default for SyncOptions {
    fn default() -> Self {
        Self {
            max_diff: 0.01,
            offset: 0.0,
            interpolate: false,
            resample: None,
            max_gap: 0.5,
        }
    }
}

/// Pose pairs at (nearly) equal times, in time order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Matched {
    /// Reference stamp of each pair (s, reference clock).
    pub ref_stamps: Vec<f64>,
    /// Estimate stamp of each pair (s, estimate clock, without offset).
    pub est_stamps: Vec<f64>,
    /// Reference poses.
    pub reference: Vec<Pose3>,
    /// Estimate poses.
    pub estimate: Vec<Pose3>,
}

impl Matched {
    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.reference.len()
    }

    /// True when no pair matched.
    pub fn is_empty(&self) -> bool {
        self.reference.is_empty()
    }
}

/// evo's `matching_time_indices` for sorted stamps: for each stamp of `s1`,
/// the index of the closest `s2[j] + offset` within `max_diff` (ties go to the
/// earlier stamp).
fn matching_time_indices(
    s1: &[f64],
    s2: &[f64],
    max_diff: f64,
    offset: f64,
) -> Vec<(usize, usize)> {
    let s2: Vec<f64> = s2.iter().map(|s| s + offset).collect();
    let mut out = Vec::new();
    let (first, last) = (s2[0], s2[s2.len() - 1]);
    for (i, &t) in s1.iter().enumerate() {
        if t < first - max_diff || t > last + max_diff {
            continue;
        }
        let mut j = s2.partition_point(|&s| s <= t);
        if j >= s2.len() {
            j = s2.len() - 1;
        }
        let diff_ub = s2[j] - t;
        let diff_lb = if j > 0 { t - s2[j - 1] } else { f64::INFINITY };
        let best = if diff_ub <= max_diff && diff_ub < diff_lb {
            j
        } else if diff_lb <= max_diff && diff_lb <= diff_ub {
            j - 1
        } else {
            continue;
        };
        out.push((i, best));
    }
    out
}

/// transformations.py `quaternion_slerp` (shortest path), as evo uses it.
fn slerp(q0: &UnitQuaternion<f64>, q1: &UnitQuaternion<f64>, frac: f64) -> UnitQuaternion<f64> {
    if frac == 0.0 {
        return *q0;
    }
    if frac == 1.0 {
        return *q1;
    }
    let a = q0.coords;
    let mut b = q1.coords;
    let mut d = a.dot(&b);
    if (d.abs() - 1.0).abs() < 4.0 * f64::EPSILON {
        return *q0;
    }
    if d < 0.0 {
        d = -d;
        b = -b;
    }
    let angle = d.acos();
    if angle.abs() < 4.0 * f64::EPSILON {
        return *q0;
    }
    let isin = 1.0 / angle.sin();
    let c = a * (((1.0 - frac) * angle).sin() * isin) + b * ((frac * angle).sin() * isin);
    UnitQuaternion::new_normalize(Quaternion::from(c))
}

/// evo's `PoseTrajectory3D.interpolate` (no extrapolation): positions linear,
/// rotations SLERP, times outside the span clamped to the end poses.
pub fn interpolate_at(traj: &Trajectory3, t: f64) -> Pose3 {
    let n = traj.len();
    let idx = traj.stamps.partition_point(|&s| s < t).clamp(1, n - 1);
    let (t0, t1) = (traj.stamps[idx - 1], traj.stamps[idx]);
    let dt = t1 - t0;
    let frac = if dt > 0.0 {
        ((t - t0) / dt).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (p0, p1) = (&traj.poses[idx - 1], &traj.poses[idx]);
    let xyz = p0.translation.vector + (p1.translation.vector - p0.translation.vector) * frac;
    Isometry3::from_parts(
        Translation3::from(xyz),
        slerp(&p0.rotation, &p1.rotation, frac),
    )
}

/// Associates `estimate` with `reference` by time (evo's association; see the
/// module doc). Needs at least 2 poses on each side; an error when the time
/// ranges do not overlap or fewer than 2 pairs match.
pub fn sync(
    reference: &Trajectory3,
    estimate: &Trajectory3,
    opts: &SyncOptions,
) -> Result<Matched, EvalError> {
    let max_diff_ok = opts.max_diff.is_finite() && opts.max_diff >= 0.0;
    if !max_diff_ok || !opts.offset.is_finite() {
        return Err(EvalError::InvalidOption(format!(
            "max_diff must be finite and ≥ 0 and offset finite (got {}, {})",
            opts.max_diff, opts.offset
        )));
    }
    check_inputs(reference, estimate)?;
    let (r0, r1) = (reference.stamps[0], reference.stamps[reference.len() - 1]);
    let (e0, e1) = (
        estimate.stamps[0] + opts.offset,
        estimate.stamps[estimate.len() - 1] + opts.offset,
    );
    if e1 < r0 - opts.max_diff || e0 > r1 + opts.max_diff {
        return Err(EvalError::NoOverlap {
            est_start: estimate.stamps[0],
            est_end: estimate.stamps[estimate.len() - 1],
            ref_start: r0,
            ref_end: r1,
            offset: opts.offset,
        });
    }
    // evo: the trajectory with fewer poses drives the search (the estimate is
    // the second trajectory, its offset applied with the matching sign).
    let est_longer = estimate.len() > reference.len();
    let (short, long, off) = if est_longer {
        (reference, estimate, opts.offset)
    } else {
        (estimate, reference, -opts.offset)
    };
    let pairs = matching_time_indices(&short.stamps, &long.stamps, opts.max_diff, off);
    if pairs.len() < 2 {
        return Err(EvalError::TooFewMatches {
            matched: pairs.len(),
            needed: 2,
            max_diff: opts.max_diff,
            offset: opts.offset,
        });
    }
    let mut m = Matched::default();
    for &(i, j) in &pairs {
        let (ts, ps) = (short.stamps[i], short.poses[i]);
        let (tl, pl) = if opts.interpolate {
            let t = ts - off;
            (t, interpolate_at(long, t))
        } else {
            (long.stamps[j], long.poses[j])
        };
        let ((tr, pr), (te, pe)) = if est_longer {
            ((ts, ps), (tl, pl))
        } else {
            ((tl, pl), (ts, ps))
        };
        m.ref_stamps.push(tr);
        m.reference.push(pr);
        m.est_stamps.push(te);
        m.estimate.push(pe);
    }
    Ok(m)
}

/// The reference interpolated at every estimate stamp (offset added) that lies
/// inside the reference's span and whose neighbouring reference samples are at
/// most `opts.max_gap` apart (positions linear, rotations SLERP). Returns the
/// pairs and the number of estimate poses; an error when fewer than 2 pair.
pub fn resample(
    reference: &Trajectory3,
    estimate: &Trajectory3,
    opts: &SyncOptions,
) -> Result<(Matched, usize), EvalError> {
    if !(opts.max_gap.is_finite() && opts.max_gap > 0.0 && opts.offset.is_finite()) {
        return Err(EvalError::InvalidOption(format!(
            "max_gap must be finite and > 0 and offset finite (got {}, {})",
            opts.max_gap, opts.offset
        )));
    }
    check_inputs(reference, estimate)?;
    let rs = &reference.stamps;
    let mut m = Matched::default();
    for (&te, pe) in estimate.stamps.iter().zip(&estimate.poses) {
        let t = te + opts.offset;
        if t < rs[0] || t > rs[rs.len() - 1] {
            continue;
        }
        // The reference samples at or just before and at or just after t.
        let j = rs.partition_point(|&s| s < t);
        let (lo, hi) = if rs[j] == t { (j, j) } else { (j - 1, j) };
        if rs[hi] - rs[lo] > opts.max_gap {
            continue;
        }
        m.ref_stamps.push(t);
        m.reference.push(if lo == hi {
            reference.poses[lo] // a shared stamp: the sample itself, no rounding
        } else {
            interpolate_at(reference, t)
        });
        m.est_stamps.push(te);
        m.estimate.push(*pe);
    }
    if m.len() < 2 {
        return Err(EvalError::TooFewResampled {
            paired: m.len(),
            max_gap: opts.max_gap,
            offset: opts.offset,
        });
    }
    Ok((m, estimate.len()))
}

/// At least 2 poses on each side, all finite.
fn check_inputs(reference: &Trajectory3, estimate: &Trajectory3) -> Result<(), EvalError> {
    for (what, t) in [("reference", reference), ("estimate", estimate)] {
        if t.len() < 2 {
            return Err(EvalError::TooFewPoses {
                what,
                count: t.len(),
                needed: 2,
            });
        }
        if let Some(index) = t.first_non_finite() {
            return Err(EvalError::NonFinite { what, index });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(stamps: &[f64]) -> Trajectory3 {
        Trajectory3::from_parts(
            stamps.to_vec(),
            stamps
                .iter()
                .map(|&t| Isometry3::translation(t, 0.0, 0.0))
                .collect(),
        )
        .unwrap()
    }

    #[test]
    fn nearest_within_max_diff_and_offset() {
        let r = line(&[0.0, 0.1, 0.2, 0.3, 0.4, 0.5]);
        let e = line(&[0.104, 0.2, 0.33, 0.395]);
        let m = sync(&r, &e, &SyncOptions::default()).unwrap();
        assert_eq!(m.ref_stamps, vec![0.1, 0.2, 0.4]);
        assert_eq!(m.est_stamps, vec![0.104, 0.2, 0.395]);
        // Estimate clock 1 s late: offset −1 restores the pairs.
        let late = line(&[1.104, 1.2, 1.33, 1.395]);
        assert!(matches!(
            sync(&r, &late, &SyncOptions::default()),
            Err(EvalError::NoOverlap { .. })
        ));
        let m = sync(
            &r,
            &late,
            &SyncOptions {
                offset: -1.0,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(m.ref_stamps, vec![0.1, 0.2, 0.4]);
        // Interpolation resamples the denser reference at the estimate stamps.
        let m = sync(
            &r,
            &e,
            &SyncOptions {
                interpolate: true,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(m.ref_stamps, vec![0.104, 0.2, 0.395]);
        assert!((m.reference[0].translation.x - 0.104).abs() < 1e-12);
    }

    #[test]
    fn resampling_interpolates_inside_the_span_and_short_gaps_only() {
        let r = line(&[0.0, 0.2, 0.4, 1.5, 1.7]);
        let e = line(&[-0.1, 0.1, 0.3, 0.9, 1.6, 1.8]);
        let (m, of) = resample(&r, &e, &SyncOptions::default()).unwrap();
        // -0.1 and 1.8 lie outside the reference, 0.9 inside its 1.1 s gap.
        assert_eq!(m.ref_stamps, vec![0.1, 0.3, 1.6]);
        assert_eq!(m.est_stamps, vec![0.1, 0.3, 1.6]);
        assert_eq!(of, 6);
        for (p, t) in m.reference.iter().zip([0.1, 0.3, 1.6]) {
            assert!((p.translation.x - t).abs() < 1e-12);
        }
        // The estimate's clock 1 s late, corrected by the offset.
        let late = line(&[1.1, 1.3, 2.6]);
        let opts = SyncOptions {
            offset: -1.0,
            ..Default::default()
        };
        let (m, _) = resample(&r, &late, &opts).unwrap();
        assert_eq!(m.est_stamps, vec![1.1, 1.3, 2.6]);
        assert!((m.reference[2].translation.x - 1.6).abs() < 1e-12);
        let wide = SyncOptions {
            max_gap: 0.1,
            ..Default::default()
        };
        assert!(matches!(
            resample(&r, &e, &wide),
            Err(EvalError::TooFewResampled { paired: 0, .. })
        ));
    }

    #[test]
    fn too_few_matches_is_an_error() {
        let r = line(&[0.0, 1.0, 2.0]);
        let e = line(&[0.5, 1.001]);
        assert!(matches!(
            sync(&r, &e, &SyncOptions::default()),
            Err(EvalError::TooFewMatches { matched: 1, .. })
        ));
    }
}
