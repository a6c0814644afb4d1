//! Relative pose error, as evo's `metrics.RPE` with consecutive pairs: pairs
//! (i, j) chosen on the estimate by index step, travelled distance or elapsed
//! time; error E = inv(Q_i⁻¹ Q_j) (P_i⁻¹ P_j) with Q the reference and P the
//! estimate; translation ‖t(E)‖ (m) and rotation angle of E (rad, deg).

use super::ape::rotation_angle;
use super::stats::Stats;
use super::sync::Matched;
use super::traj3::Pose3;
use super::EvalError;
use serde::{Deserialize, Serialize};

/// Unit of the RPE delta (CLI words `frames|m|s`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DeltaUnit {
    /// Index steps among the matched pairs (evo `--delta_unit f`).
    #[default]
    Frames,
    /// Metres travelled by the estimate (evo `--delta_unit m`).
    #[serde(rename = "m")]
    Metres,
    /// Seconds elapsed on the estimate's clock (odocal's own; evo has none).
    #[serde(rename = "s")]
    Seconds,
}

impl DeltaUnit {
    /// The CLI word.
    pub fn word(self) -> &'static str {
        match self {
            Self::Frames => "frames",
            Self::Metres => "m",
            Self::Seconds => "s",
        }
    }
}

impl std::str::FromStr for DeltaUnit {
    type Err = EvalError;
    fn from_str(s: &str) -> Result<Self, EvalError> {
        match s {
            "frames" | "f" => Ok(Self::Frames),
            "m" => Ok(Self::Metres),
            "s" => Ok(Self::Seconds),
            _ => Err(EvalError::InvalidOption(format!(
                "RPE unit '{s}' (expected frames|m|s)"
            ))),
        }
    }
}

/// The RPE step between the two poses of a pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RpeDelta {
    /// Step size (a whole number for frames).
    pub value: f64,
    /// Its unit.
    pub unit: DeltaUnit,
}

impl Default for RpeDelta {
    fn default() -> Self {
        Self {
            value: 1.0,
            unit: DeltaUnit::Frames,
        }
    }
}

/// RPE of matched (and aligned) pairs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Rpe {
    /// Translation error statistics (m).
    pub trans: Stats,
    /// Rotation angle statistics (rad); `None` for position-only RPE.
    pub rot_rad: Option<Stats>,
    /// Rotation angle statistics (deg); `None` for position-only RPE.
    pub rot_deg: Option<Stats>,
    /// Index pairs (i, j) into the matched pairs.
    pub pairs: Vec<(usize, usize)>,
    /// Per-pair translation error (m).
    pub trans_errors: Vec<f64>,
    /// Per-pair rotation error (rad); empty for position-only RPE.
    pub rot_errors: Vec<f64>,
}

/// evo's `filter_pairs_by_index` (consecutive): 0, d, 2d, … paired in turn.
fn pairs_by_index(n: usize, d: usize) -> Vec<(usize, usize)> {
    let ids: Vec<usize> = (0..n).step_by(d).collect();
    ids.windows(2).map(|w| (w[0], w[1])).collect()
}

/// evo's `filter_pairs_by_path` (consecutive): a new id whenever the path since
/// the last id reaches `delta` (m).
fn pairs_by_path(poses: &[Pose3], delta: f64) -> Vec<(usize, usize)> {
    let mut ids = vec![0];
    let mut path = 0.0;
    for i in 1..poses.len() {
        path += (poses[i].translation.vector - poses[i - 1].translation.vector).norm();
        if path >= delta {
            ids.push(i);
            path = 0.0;
        }
    }
    ids.windows(2).map(|w| (w[0], w[1])).collect()
}

/// The time analogue: a new id whenever `delta` seconds have passed since the last.
fn pairs_by_time(stamps: &[f64], delta: f64) -> Vec<(usize, usize)> {
    let mut ids = vec![0];
    for (i, &t) in stamps.iter().enumerate().skip(1) {
        if t - stamps[*ids.last().unwrap()] >= delta {
            ids.push(i);
        }
    }
    ids.windows(2).map(|w| (w[0], w[1])).collect()
}

/// The index pairs (i, j) for `delta`, chosen on the estimate (evo's default).
/// An error for a delta that is not positive (or not whole, for frames) or
/// that selects no pair.
pub fn rpe_pairs(m: &Matched, delta: &RpeDelta) -> Result<Vec<(usize, usize)>, EvalError> {
    let d = delta.value;
    let valid = d.is_finite() && d > 0.0 && (delta.unit != DeltaUnit::Frames || d.fract() == 0.0);
    if !valid {
        return Err(EvalError::InvalidOption(format!(
            "RPE delta {d} {} (must be positive{})",
            delta.unit.word(),
            if delta.unit == DeltaUnit::Frames {
                " and whole"
            } else {
                ""
            }
        )));
    }
    let pairs = match delta.unit {
        DeltaUnit::Frames => pairs_by_index(m.len(), d as usize),
        DeltaUnit::Metres => pairs_by_path(&m.estimate, d),
        DeltaUnit::Seconds => pairs_by_time(&m.est_stamps, d),
    };
    if pairs.is_empty() {
        return Err(EvalError::NoRpePairs {
            delta: d,
            unit: delta.unit.word(),
        });
    }
    Ok(pairs)
}

/// Computes the full-pose RPE (evo `-r trans_part` and `-r angle_deg`).
pub fn rpe(m: &Matched, delta: &RpeDelta) -> Result<Rpe, EvalError> {
    let pairs = rpe_pairs(m, delta)?;
    let mut trans_errors = Vec::with_capacity(pairs.len());
    let mut rot_errors = Vec::with_capacity(pairs.len());
    for &(i, j) in &pairs {
        let q_rel = m.reference[i].inv_mul(&m.reference[j]);
        let p_rel = m.estimate[i].inv_mul(&m.estimate[j]);
        let e = q_rel.inv_mul(&p_rel);
        trans_errors.push(e.translation.vector.norm());
        rot_errors.push(rotation_angle(&e.rotation));
    }
    let bad = || EvalError::NonFinite {
        what: "matched poses",
        index: 0,
    };
    let deg: Vec<f64> = rot_errors.iter().map(|a| a.to_degrees()).collect();
    Ok(Rpe {
        trans: Stats::of(&trans_errors).ok_or_else(bad)?,
        rot_rad: Some(Stats::of(&rot_errors).ok_or_else(bad)?),
        rot_deg: Some(Stats::of(&deg).ok_or_else(bad)?),
        pairs,
        trans_errors,
        rot_errors,
    })
}

/// Position-only RPE for references without orientation (PointStamped):
/// |‖P_j − P_i‖ − ‖Q_j − Q_i‖| (m), evo's `-r point_distance`.
pub fn rpe_positions(m: &Matched, delta: &RpeDelta) -> Result<Rpe, EvalError> {
    let pairs = rpe_pairs(m, delta)?;
    let dist = |p: &[Pose3], i: usize, j: usize| {
        (p[j].translation.vector - p[i].translation.vector).norm()
    };
    let trans_errors: Vec<f64> = pairs
        .iter()
        .map(|&(i, j)| (dist(&m.reference, i, j) - dist(&m.estimate, i, j)).abs())
        .collect();
    let trans = Stats::of(&trans_errors).ok_or(EvalError::NonFinite {
        what: "matched poses",
        index: 0,
    })?;
    Ok(Rpe {
        trans,
        rot_rad: None,
        rot_deg: None,
        pairs,
        trans_errors,
        rot_errors: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_read_back_from_their_words() {
        for u in [DeltaUnit::Frames, DeltaUnit::Metres, DeltaUnit::Seconds] {
            assert_eq!(u.word().parse::<DeltaUnit>().unwrap(), u);
        }
        assert_eq!(DeltaUnit::Metres.word(), "m");
        assert_eq!("f".parse::<DeltaUnit>().unwrap(), DeltaUnit::Frames);
        assert!("km".parse::<DeltaUnit>().is_err());
    }

    fn straight(n: usize, step: f64, yaw_step: f64) -> Vec<Pose3> {
        (0..n)
            .map(|i| {
                Pose3::from_parts(
                    nalgebra::Translation3::new(i as f64 * step, 0.0, 0.0),
                    nalgebra::UnitQuaternion::from_axis_angle(
                        &nalgebra::Vector3::z_axis(),
                        i as f64 * yaw_step,
                    ),
                )
            })
            .collect()
    }

    #[test]
    fn deltas_that_select_nothing_sensible_are_refused() {
        let m = Matched {
            ref_stamps: vec![0.0, 1.0, 2.0],
            est_stamps: vec![0.0, 1.0, 2.0],
            reference: straight(3, 1.0, 0.0),
            estimate: straight(3, 1.0, 0.0),
        };
        let d = |value: f64, unit: DeltaUnit| RpeDelta { value, unit };
        for bad in [
            d(0.0, DeltaUnit::Frames),
            d(-1.0, DeltaUnit::Seconds),
            d(f64::NAN, DeltaUnit::Metres),
            d(f64::INFINITY, DeltaUnit::Metres),
            d(1.5, DeltaUnit::Frames),
        ] {
            assert!(rpe_pairs(&m, &bad).is_err(), "{bad:?}");
        }
        // Half a metre is a valid delta (not whole, but not frames).
        assert_eq!(rpe_pairs(&m, &d(0.5, DeltaUnit::Metres)).unwrap().len(), 2);
        // Valid but longer than the run: no pair.
        assert!(rpe_pairs(&m, &d(5.0, DeltaUnit::Frames)).is_err());
        assert_eq!(
            rpe_pairs(&m, &d(2.0, DeltaUnit::Frames)).unwrap(),
            vec![(0, 2)]
        );
    }

    #[test]
    fn a_turn_the_reference_does_not_make_is_the_rotation_error() {
        // The estimate turns 0.01 rad a frame more than the reference and
        // travels the same: each 2-frame pair is 0.02 rad off, and its
        // translation error is that of the second metre seen 0.01 rad turned:
        // ‖R(−0.01)·(1, 0) − (1, 0)‖ = 2 sin(0.005).
        let m = Matched {
            ref_stamps: (0..5).map(f64::from).collect(),
            est_stamps: (0..5).map(f64::from).collect(),
            reference: straight(5, 1.0, 0.0),
            estimate: (0..5)
                .map(|i| {
                    let yaw = 0.01 * f64::from(i);
                    // Each step of 1 m along the heading it had.
                    let (x, y) = (0..i).fold((0.0, 0.0), |(x, y), k| {
                        let h = 0.01 * f64::from(k);
                        (x + h.cos(), y + h.sin())
                    });
                    Pose3::from_parts(
                        nalgebra::Translation3::new(x, y, 0.0),
                        nalgebra::UnitQuaternion::from_axis_angle(
                            &nalgebra::Vector3::z_axis(),
                            yaw,
                        ),
                    )
                })
                .collect(),
        };
        let r = rpe(
            &m,
            &RpeDelta {
                value: 2.0,
                unit: DeltaUnit::Frames,
            },
        )
        .unwrap();
        assert_eq!(r.pairs, vec![(0, 2), (2, 4)]);
        for (&a, &t) in r.rot_errors.iter().zip(&r.trans_errors) {
            assert!((a - 0.02).abs() < 1e-12, "{a}");
            assert!((t - 2.0 * 0.005f64.sin()).abs() < 1e-12, "{t}");
        }
        assert!((r.rot_deg.unwrap().mean - 0.02f64.to_degrees()).abs() < 1e-9);
        // Positions only: the distances agree (1 m steps along either path
        // differ only by the chord), so the error is the chord's shortfall.
        let p = rpe_positions(
            &m,
            &RpeDelta {
                value: 2.0,
                unit: DeltaUnit::Frames,
            },
        )
        .unwrap();
        let chord = |h0: f64| {
            let (a, b) = (
                (h0).cos() + (h0 + 0.01).cos(),
                (h0).sin() + (h0 + 0.01).sin(),
            );
            (a * a + b * b).sqrt()
        };
        assert!((p.trans_errors[0] - (2.0 - chord(0.0))).abs() < 1e-12);
        assert!((p.trans_errors[1] - (2.0 - chord(0.02))).abs() < 1e-12);
        assert!(p.rot_rad.is_none() && p.rot_errors.is_empty());
    }

    #[test]
    fn pair_selection_follows_evo() {
        assert_eq!(pairs_by_index(7, 3), vec![(0, 3), (3, 6)]);
        let poses: Vec<Pose3> = [0.0, 0.4, 0.8, 1.2, 1.6, 2.0, 2.4]
            .iter()
            .map(|&x| Pose3::translation(x, 0.0, 0.0))
            .collect();
        // 0.4 + 0.4 + 0.4 = 1.2 ≥ 1 at index 3; again at index 6.
        assert_eq!(pairs_by_path(&poses, 1.0), vec![(0, 3), (3, 6)]);
        assert_eq!(
            pairs_by_time(&[0.0, 0.5, 1.0, 1.2, 2.1], 1.0),
            vec![(0, 2), (2, 4)]
        );
    }

    #[test]
    fn scale_error_shows_as_known_relative_error_in_every_unit() {
        // Straight line at 1 m/s, 10 Hz; the estimate reads 2 % long.
        let n = 101;
        let m = Matched {
            ref_stamps: (0..n).map(|i| i as f64 * 0.1).collect(),
            est_stamps: (0..n).map(|i| i as f64 * 0.1).collect(),
            reference: (0..n)
                .map(|i| Pose3::translation(i as f64 * 0.1, 0.0, 0.0))
                .collect(),
            estimate: (0..n)
                .map(|i| Pose3::translation(i as f64 * 0.102, 0.0, 0.0))
                .collect(),
        };
        let s = rpe(
            &m,
            &RpeDelta {
                value: 1.0,
                unit: DeltaUnit::Seconds,
            },
        )
        .unwrap();
        // Stamps i·0.1 reach a 1 s step at 10 frames (or 11 by rounding).
        assert!(s.pairs.len() >= 9 && s.pairs.iter().all(|(i, j)| j - i == 10 || j - i == 11));
        for (&(i, j), e) in s.pairs.iter().zip(&s.trans_errors) {
            assert!((e - 0.002 * (j - i) as f64).abs() < 1e-12);
        }
        let f = rpe(
            &m,
            &RpeDelta {
                value: 5.0,
                unit: DeltaUnit::Frames,
            },
        )
        .unwrap();
        assert_eq!(f.pairs.len(), 20);
        assert!((f.trans.mean - 0.01).abs() < 1e-12 && f.trans.std < 1e-12);
        assert!(f.rot_deg.unwrap().max == 0.0);
        // 1.02 m of estimate path: every 10th frame (10 × 0.102 ≥ 1.02).
        let d = rpe(
            &m,
            &RpeDelta {
                value: 1.02,
                unit: DeltaUnit::Metres,
            },
        )
        .unwrap();
        assert!(d.pairs.iter().all(|(i, j)| j - i == 10 || j - i == 11));
        let p = rpe_positions(
            &m,
            &RpeDelta {
                value: 5.0,
                unit: DeltaUnit::Frames,
            },
        )
        .unwrap();
        assert!((p.trans.mean - 0.01).abs() < 1e-12 && p.rot_deg.is_none());
    }
}
