//! The gyro as an instrument: its turn-rate scale checked against the scan
//! matching before any effect of the robot is fitted.
//!
//! The effect table has a gyro bias but no gyro scale: the fit reads the
//! gyro as the true turn rate plus a constant. A gyro that reads turns a few
//! per cent large (a MEMS scale-factor error, a wrong sensitivity setting)
//! then pulls the wheels' turn rate its way, and the diagnosis names a
//! wheel base that the scan matching contradicts. The wheels do not enter
//! this check: over one-second segments the gyro's integrated angle is
//! regressed on the scan-matched one, g = (1 + s)·c + b·T (least squares),
//! and the scale s is a fault of the gyro when it is both larger than
//! `min_scale` and `min_sigmas` standard errors from zero (delete-one-block
//! jackknife over `blocks` stretches of the run, which keeps the serial
//! correlation of scan-matching errors inside a block). The default
//! `min_scale` (1 %) lies above scan-to-scan ICP's own turn-rate error
//! beyond the smallest rotations (a few tenths of a per cent,
//! [`super::instrument`]); the diagnosis hands it the scan matching's turns
//! read on the instrument's scale (each pair's own error taken out,
//! [`super::instrument::Instrument::turns_debiased`]). When named, the
//! diagnosis leaves the gyro out, as on a robot without one: rescaled by the
//! estimate instead it would carry what is left of ICP's turn-rate error
//! into the fit with the gyro's weight.

use super::data::{GyroRow, IcpRow};
use serde::{Deserialize, Serialize};

/// Settings of the gyro check (`[diagnose.gyro_check]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GyroCheck {
    /// Whether the gyro's scale is checked (off: the gyro is trusted).
    pub enabled: bool,
    /// Smallest relative scale named (0.01 = 1 %).
    pub min_scale: f64,
    /// Standard errors from zero a named scale must lie.
    pub min_sigmas: f64,
    /// Length of the segments compared (s).
    pub segment: f64,
    /// Stretches of the run left out one at a time for the standard error.
    pub blocks: usize,
    /// Share of a gyro window the scan matching must cover for it to count.
    pub min_coverage: f64,
}

impl Default for GyroCheck {
    fn default() -> Self {
        Self {
            enabled: true,
            min_scale: 0.01,
            min_sigmas: 5.0,
            segment: 1.0,
            blocks: 10,
            min_coverage: 0.9,
        }
    }
}

impl GyroCheck {
    /// Checks ranges.
    pub fn validate(&self) -> Result<(), String> {
        for (k, v) in [
            ("min_scale", self.min_scale),
            ("min_sigmas", self.min_sigmas),
            ("segment", self.segment),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("gyro_check.{k} must be positive, got {v}"));
            }
        }
        if !(self.min_coverage > 0.0 && self.min_coverage <= 1.0) {
            return Err(format!(
                "gyro_check.min_coverage must be in (0, 1], got {}",
                self.min_coverage
            ));
        }
        if self.blocks < 3 {
            return Err(format!(
                "gyro_check.blocks must be ≥ 3, got {}",
                self.blocks
            ));
        }
        Ok(())
    }
}

/// The gyro's scale against the scan matching.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroScale {
    /// Relative scale s: the gyro reads (1 + s) times the scan-matched turn.
    pub scale: f64,
    /// Its standard error (jackknife over blocks).
    pub stderr: f64,
    /// Segments compared.
    pub segments: usize,
}

impl GyroScale {
    /// Whether `c` names it as a fault.
    pub fn is_fault(&self, c: &GyroCheck) -> bool {
        self.scale.abs() >= c.min_scale && self.scale.abs() >= c.min_sigmas * self.stderr
    }
}

/// Integral of the ICP turn rate over [t0, t1] and the time covered
/// (`icp` sorted by start; rows may not overlap each other).
fn icp_turn(icp: &[IcpRow], t0: f64, t1: f64) -> (f64, f64) {
    let first = icp.partition_point(|r| r.t1 <= t0);
    let (mut angle, mut covered) = (0.0, 0.0);
    for r in icp[first..].iter().take_while(|r| r.t0 < t1) {
        // Positive only for a row that runs forward (t1 > t0) into the window.
        let overlap = r.t1.min(t1) - r.t0.max(t0);
        if overlap > 0.0 {
            angle += r.z[2] * overlap;
            covered += overlap;
        }
    }
    (angle, covered)
}

/// Segments of about `c.segment` s: (gyro angle, scan-matched angle,
/// duration), each summed over the gyro windows the scan matching covers.
fn segments(icp: &[IcpRow], gyro: &[GyroRow], c: &GyroCheck) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    let mut acc = [0.0; 3];
    let mut start = f64::NAN;
    for g in gyro {
        let dt = g.t1 - g.t0;
        if !(dt > 0.0 && g.w.is_finite()) {
            continue;
        }
        let (angle, covered) = icp_turn(icp, g.t0, g.t1);
        if covered < c.min_coverage * dt || !angle.is_finite() {
            continue;
        }
        if start.is_nan() {
            start = g.t0;
        }
        acc[0] += g.w * dt;
        acc[1] += angle * dt / covered;
        acc[2] += dt;
        if g.t1 - start >= c.segment {
            out.push(acc);
            acc = [0.0; 3];
            start = f64::NAN;
        }
    }
    out
}

/// Least-squares (s, b) of g − c = s·c + b·T over `rows`.
fn fit(rows: &[[f64; 3]]) -> Option<f64> {
    let (mut scc, mut sct, mut stt, mut scy, mut sty) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &[g, c, t] in rows {
        let y = g - c;
        scc += c * c;
        sct += c * t;
        stt += t * t;
        scy += c * y;
        sty += t * y;
    }
    let det = scc * stt - sct * sct;
    (det > 1e-12 * scc.max(1e-300) * stt.max(1e-300)).then(|| (scy * stt - sty * sct) / det)
}

/// The gyro's scale against the scan matching, or `None` when too few
/// segments (fewer than two per block) or no turning to read it from.
pub fn gyro_scale(icp: &[IcpRow], gyro: &[GyroRow], c: &GyroCheck) -> Option<GyroScale> {
    let rows = segments(icp, gyro, c);
    if rows.len() < 2 * c.blocks {
        return None;
    }
    let (scale, stderr) = jackknife(&rows, c.blocks)?;
    Some(GyroScale {
        scale,
        stderr,
        segments: rows.len(),
    })
}

/// The scale of `rows` and its delete-one-block jackknife standard error
/// over `k` consecutive blocks (Efron): var = (k−1)/k Σ (s₋ⱼ − mean)².
fn jackknife(rows: &[[f64; 3]], k: usize) -> Option<(f64, f64)> {
    let scale = fit(rows)?;
    let bound = |j: usize| j * rows.len() / k;
    let mut left_out = Vec::with_capacity(k);
    for j in 0..k {
        let rest: Vec<[f64; 3]> = rows[..bound(j)]
            .iter()
            .chain(&rows[bound(j + 1)..])
            .copied()
            .collect();
        left_out.push(fit(&rest)?);
    }
    let mean = left_out.iter().sum::<f64>() / k as f64;
    let var = (k - 1) as f64 / k as f64 * left_out.iter().map(|s| (s - mean).powi(2)).sum::<f64>();
    Some((scale, var.sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ICP rows of 20 ms and gyro windows of 100 ms over `seconds` of a turn
    /// rate 0.5 sin(0.7 t) + 0.2 sin(0.13 t) rad/s; the gyro reads
    /// (1 + scale) times it plus `bias`, and every ICP turn rate carries
    /// ±`noise` rad/s alternating in sign.
    fn streams(seconds: f64, scale: f64, bias: f64, noise: f64) -> (Vec<IcpRow>, Vec<GyroRow>) {
        // Mean over [a, b] of w, in closed form.
        let mean = |a: f64, b: f64| {
            let f = |t: f64| -0.5 / 0.7 * (0.7 * t).cos() - 0.2 / 0.13 * (0.13 * t).cos();
            (f(b) - f(a)) / (b - a)
        };
        let icp = (0..(seconds / 0.02) as usize)
            .map(|i| {
                let (t0, t1) = (i as f64 * 0.02, (i + 1) as f64 * 0.02);
                let e = if i % 2 == 0 { noise } else { -noise };
                IcpRow {
                    t0,
                    t1,
                    z: [0.3, 0.0, mean(t0, t1) + e],
                    sigma: [0.01, 0.01, 0.01],
                }
            })
            .collect();
        let gyro = (0..(seconds / 0.1) as usize)
            .map(|i| {
                let (t0, t1) = (i as f64 * 0.1, (i + 1) as f64 * 0.1);
                GyroRow {
                    t0,
                    t1,
                    w: (1.0 + scale) * mean(t0, t1) + bias,
                    sigma: 0.3,
                }
            })
            .collect();
        (icp, gyro)
    }

    #[test]
    fn a_gyro_reading_two_per_cent_large_is_read_as_such_through_a_bias() {
        let (icp, gyro) = streams(150.0, 0.02, 0.003, 0.01);
        let s = gyro_scale(&icp, &gyro, &GyroCheck::default()).unwrap();
        assert!((s.scale - 0.02).abs() < 1e-4, "{s:?}");
        assert_eq!(s.segments, 150);
        assert!(s.is_fault(&GyroCheck::default()));
        // Read on the scan matching's scale, the same gyro shows none.
        let rescaled: Vec<GyroRow> = gyro
            .iter()
            .map(|g| GyroRow {
                w: g.w / (1.0 + s.scale),
                ..*g
            })
            .collect();
        let again = gyro_scale(&icp, &rescaled, &GyroCheck::default()).unwrap();
        assert!(again.scale.abs() < 1e-4, "{again:?}");
        assert!(!again.is_fault(&GyroCheck::default()));
    }

    #[test]
    fn a_true_gyro_is_no_fault_and_a_small_scale_is_not_named() {
        let c = GyroCheck::default();
        let (icp, gyro) = streams(150.0, 0.0, 0.003, 0.01);
        let s = gyro_scale(&icp, &gyro, &c).unwrap();
        assert!(s.scale.abs() < 1e-4 && !s.is_fault(&c), "{s:?}");
        // 0.5 %: well measured, but under min_scale.
        let (icp, gyro) = streams(150.0, 0.005, 0.0, 0.0);
        let s = gyro_scale(&icp, &gyro, &c).unwrap();
        assert!((s.scale - 0.005).abs() < 1e-6 && !s.is_fault(&c), "{s:?}");
    }

    #[test]
    fn a_scale_the_data_cannot_support_is_not_named() {
        // Turning only in the first block, then a slow drift of the scan
        // matching the gyro does not show: the jackknife sees the scale rest
        // on one stretch.
        let c = GyroCheck::default();
        let (mut icp, mut gyro) = streams(150.0, 0.03, 0.0, 0.0);
        for r in icp.iter_mut().filter(|r| r.t0 >= 15.0) {
            r.z[2] = 0.01 * (0.9 * r.t0).sin();
        }
        for g in gyro.iter_mut().filter(|g| g.t0 >= 15.0) {
            g.w = 0.0;
        }
        let s = gyro_scale(&icp, &gyro, &c).unwrap();
        assert!(!s.is_fault(&c), "{s:?}");
        // Too short a run for the blocks: no reading at all.
        let (icp, gyro) = streams(15.0, 0.03, 0.0, 0.0);
        assert!(gyro_scale(&icp, &gyro, &c).is_none());
    }

    #[test]
    fn gyro_windows_the_scan_matching_does_not_cover_are_left_out() {
        let (mut icp, gyro) = streams(150.0, 0.02, 0.0, 0.0);
        // A 30 s gap in the scan matching: 30 fewer segments.
        icp.retain(|r| r.t1 <= 60.0 || r.t0 >= 90.0);
        let s = gyro_scale(&icp, &gyro, &GyroCheck::default()).unwrap();
        assert_eq!(s.segments, 120);
        assert!((s.scale - 0.02).abs() < 1e-4, "{s:?}");
    }

    #[test]
    fn a_window_the_scan_matching_covers_in_part_counts_at_its_mean_rate() {
        // One 20 ms row of every third 100 ms window missing: those windows
        // are covered 80 %, their scan-matched turn read at the covered
        // part's mean rate over the whole window.
        let (mut icp, gyro) = streams(150.0, 0.02, 0.0, 0.0);
        icp.retain(|r| {
            let k = (r.t0 / 0.02).round() as usize;
            !(k % 15 == 2)
        });
        let c = GyroCheck {
            min_coverage: 0.75,
            ..GyroCheck::default()
        };
        let s = gyro_scale(&icp, &gyro, &c).unwrap();
        assert!((s.scale - 0.02).abs() < 5e-4, "{s:?}");
        // At the default 90 % those windows are left out.
        let s = gyro_scale(&icp, &gyro, &GyroCheck::default()).unwrap();
        assert!(s.segments < 150, "{s:?}");
    }

    #[test]
    fn the_fit_reads_scale_and_bias_exactly_from_segments_of_any_length() {
        // g = 1.03·c + 0.2·T on segments of 0.5–2 s: the scale 0.03 whatever
        // the bias, and no fit without turning.
        let rows: Vec<[f64; 3]> = [(0.4, 0.5), (-0.7, 1.0), (1.1, 2.0), (0.2, 1.5), (-0.3, 0.7)]
            .iter()
            .map(|&(c, t)| [1.03 * c + 0.2 * t, c, t])
            .collect();
        assert!((fit(&rows).unwrap() - 0.03).abs() < 1e-12);
        let still: Vec<[f64; 3]> = rows.iter().map(|r| [0.2 * r[2], 0.0, r[2]]).collect();
        assert_eq!(fit(&still), None);
    }

    #[test]
    fn gyro_rows_of_no_length_or_no_rate_are_left_out() {
        let (icp, mut gyro) = streams(150.0, 0.02, 0.0, 0.0);
        // A row of no length and a row without a rate, every 10 s.
        for k in 1..15 {
            let t = 10.0 * k as f64 + 0.05;
            gyro.push(GyroRow {
                t0: t,
                t1: t,
                w: 1.0,
                sigma: 0.3,
            });
            gyro.push(GyroRow {
                t0: t,
                t1: t + 0.1,
                w: f64::NAN,
                sigma: 0.3,
            });
        }
        gyro.sort_by(|a, b| a.t0.total_cmp(&b.t0));
        let s = gyro_scale(&icp, &gyro, &GyroCheck::default()).unwrap();
        assert!((s.scale - 0.02).abs() < 1e-4, "{s:?}");
    }

    #[test]
    fn settings_out_of_range_are_refused_at_their_bounds() {
        let ok = |c: GyroCheck| c.validate().is_ok();
        assert!(ok(GyroCheck::default()));
        let with = |f: fn(&mut GyroCheck)| {
            let mut c = GyroCheck::default();
            f(&mut c);
            c
        };
        // Positive and finite: 0, a negative value and NaN refused.
        assert!(!ok(with(|c| c.min_scale = 0.0)));
        assert!(!ok(with(|c| c.min_sigmas = -1.0)));
        assert!(!ok(with(|c| c.segment = f64::NAN)));
        assert!(!ok(with(|c| c.segment = f64::INFINITY)));
        assert!(ok(with(|c| c.min_scale = 1e-9)));
        // Coverage in (0, 1]: 1 allowed, 0 and above 1 refused.
        assert!(ok(with(|c| c.min_coverage = 1.0)));
        assert!(!ok(with(|c| c.min_coverage = 0.0)));
        assert!(!ok(with(|c| c.min_coverage = 1.01)));
        assert!(ok(with(|c| c.min_coverage = 0.5)));
        // At least three blocks to leave out.
        assert!(ok(with(|c| c.blocks = 3)));
        assert!(!ok(with(|c| c.blocks = 2)));
        assert!(with(|c| c.blocks = 2)
            .validate()
            .unwrap_err()
            .contains("blocks"));
    }

    /// Twenty one-second segments whose scan-matched turns are all 3 rad up
    /// to ±3·10⁻⁷: the turn column is the duration column times 3 to within
    /// 10⁻⁷, so scale and bias cannot be told apart (det / (Σc²·Σt²) =
    /// ε²/9 = 10⁻¹⁴, under the 10⁻¹² the fit asks): refused. The same
    /// segments with turns spread by ±1 rad are read.
    #[test]
    fn a_turn_column_nearly_proportional_to_the_durations_is_refused() {
        let rows = |eps: f64| -> Vec<[f64; 3]> {
            (0..20)
                .map(|i| {
                    let c = 3.0 + if i % 2 == 0 { eps } else { -eps };
                    [1.02 * c + 0.01, c, 1.0]
                })
                .collect()
        };
        assert_eq!(fit(&rows(3e-7)), None);
        let spread = fit(&rows(1.0)).expect("read");
        assert!((spread - 0.02).abs() < 1e-12, "{spread}");
    }

    /// Ten blocks need twenty segments: twenty (20 s) are read, nineteen
    /// (19 s) are not.
    #[test]
    fn twice_the_blocks_in_segments_is_the_least_that_is_read() {
        let c = GyroCheck::default();
        assert_eq!(c.blocks, 10);
        let (icp, gyro) = streams(20.0, 0.02, 0.003, 0.01);
        let s = gyro_scale(&icp, &gyro, &c).expect("twenty segments are read");
        assert_eq!(s.segments, 20);
        assert!((s.scale - 0.02).abs() < 1e-3, "{s:?}");
        let (icp, gyro) = streams(19.0, 0.02, 0.003, 0.01);
        assert_eq!(segments(&icp, &gyro, &c).len(), 19);
        assert_eq!(gyro_scale(&icp, &gyro, &c), None);
    }

    /// Three blocks of two one-second segments, (scan-matched turn c, gyro
    /// minus scan-matched y) = (0, 0), (1, 1) twice and (0, 0), (1, 2): the
    /// slope of y on c with an intercept is 4/3 over all six, 3/2 without
    /// either of the first two blocks and 1 without the third; their mean
    /// is 4/3, the squared deviations sum to 1/36 + 1/36 + 1/9 = 1/6, and
    /// (k − 1)/k of that, 1/9, is the variance: a standard error of 1/3.
    #[test]
    fn the_jackknife_by_hand() {
        let row = |c: f64, y: f64| [y + c, c, 1.0];
        let rows = [
            row(0.0, 0.0),
            row(1.0, 1.0),
            row(0.0, 0.0),
            row(1.0, 1.0),
            row(0.0, 0.0),
            row(1.0, 2.0),
        ];
        let (scale, stderr) = jackknife(&rows, 3).unwrap();
        assert!((scale - 4.0 / 3.0).abs() < 1e-12, "{scale}");
        assert!((stderr - 1.0 / 3.0).abs() < 1e-12, "{stderr}");
    }
}
