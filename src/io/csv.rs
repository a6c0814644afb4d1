//! The pipeline's CSV files (design.md): ICP motions, wheel streams and the
//! calibration history. Header line first; every number finite.

use super::atomic::write_atomic;
use crate::error::InputError;
use crate::motion::{InfoSplit, Motion, PairFailure};
use crate::recording::WheelSample;
use nalgebra::Matrix3;
use std::io::{self, Write};
use std::path::Path;

/// Header of the motions CSV: the core columns, then the information split
/// (`scan_share_*`: the fraction of each direction's estimate the scan
/// measured; `scan_d*`: the scan's own estimate, see `motion::InfoSplit`).
pub const MOTIONS_HEADER: &str = "t0,t1,dx,dy,dtheta,cov_xx,cov_xy,cov_xt,cov_yy,cov_yt,cov_tt,\
     iterations,inliers,valid,scan_share_x,scan_share_y,scan_share_theta,scan_dx,scan_dy,scan_dtheta";

/// The core columns alone, as motions files without the information split
/// have them (still read: every motion is then taken as the scan's alone).
pub const MOTIONS_HEADER_CORE: &str =
    "t0,t1,dx,dy,dtheta,cov_xx,cov_xy,cov_xt,cov_yy,cov_yt,cov_tt,iterations,inliers,valid";

/// Header of the calibration history CSV.
pub const HISTORY_HEADER: &str =
    "t,r_right,r_left,wheel_base,std_r_right,std_r_left,std_wheel_base,particles,process_sigma,change";

/// Writes ICP motions (base frame; m, rad) with covariance and quality.
pub fn write_motions(path: &Path, motions: &[Motion]) -> io::Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "{MOTIONS_HEADER}")?;
        for m in motions {
            write_motion_row(w, m)?;
        }
        Ok(())
    })
}

/// One line of the motions CSV (after [`MOTIONS_HEADER`]); a motion
/// without a split is written as the scan's alone.
pub fn write_motion_row(w: &mut impl Write, m: &Motion) -> io::Result<()> {
    let c = &m.cov;
    let (share, own) = m.split.map_or(([1.0; 3], [m.dx, m.dy, m.dtheta]), |s| {
        (s.scan_share, s.scan_only)
    });
    writeln!(
        w,
        "{:.9},{:.9},{:.9},{:.9},{:.9},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{:.6},{:.6},{:.6},{:.9},{:.9},{:.9}",
        m.t0,
        m.t1,
        m.dx,
        m.dy,
        m.dtheta,
        c[(0, 0)],
        c[(0, 1)],
        c[(0, 2)],
        c[(1, 1)],
        c[(1, 2)],
        c[(2, 2)],
        m.iterations,
        m.inliers,
        u8::from(m.is_valid()),
        share[0],
        share[1],
        share[2],
        own[0],
        own[1],
        own[2],
    )
}

fn numbers(line: &str, n: usize, file: &str, lineno: usize) -> Result<Vec<f64>, InputError> {
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != n {
        return Err(
            InputError::new(file, format!("expected {n} fields, found {}", fields.len()))
                .at(format!("line {lineno}")),
        );
    }
    fields
        .iter()
        .enumerate()
        .map(|(i, f)| match f.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(InputError::new(
                file,
                format!("field {} is not a finite number: '{f}'", i + 1),
            )
            .at(format!("line {lineno}"))),
        })
        .collect()
}

fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

fn read_text(path: &Path) -> Result<(String, String), InputError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::new(&file, format!("cannot read: {e}")))?;
    Ok((file, text))
}

/// Reads a motions CSV written by [`write_motions`] (or by another tool in the
/// same layout). Invalid rows come back flagged, never as observations.
pub fn read_motions(path: &Path) -> Result<Vec<Motion>, InputError> {
    Ok(read_motions_numbered(path)?
        .into_iter()
        .map(|(_, m)| m)
        .collect())
}

/// Like [`read_motions`], each motion with its line number in the file (for
/// the messages of checks made after parsing).
pub fn read_motions_numbered(path: &Path) -> Result<Vec<(usize, Motion)>, InputError> {
    let (file, text) = read_text(path)?;
    let mut lines = data_lines(&text);
    let fields = match lines.next() {
        Some((_, h)) if h.replace(' ', "") == MOTIONS_HEADER => 20,
        Some((_, h)) if h.replace(' ', "") == MOTIONS_HEADER_CORE => 14,
        Some((n, _)) => {
            return Err(
                InputError::new(&file, format!("expected header '{MOTIONS_HEADER}'"))
                    .at(format!("line {n}")),
            )
        }
        None => return Err(InputError::new(&file, "empty motions file")),
    };
    let mut out = Vec::new();
    for (n, l) in lines {
        let v = numbers(l, fields, &file, n)?;
        let split = split_of(&v, &file, n)?;
        let cov = Matrix3::new(v[5], v[6], v[7], v[6], v[8], v[9], v[7], v[9], v[10]);
        if out
            .last()
            .is_some_and(|(_, m): &(usize, Motion)| v[0] < m.t0)
        {
            return Err(InputError::new(&file, "t0 goes backwards").at(format!("line {n}")));
        }
        out.push((
            n,
            Motion {
                t0: v[0],
                t1: v[1],
                dx: v[2],
                dy: v[3],
                dtheta: v[4],
                cov,
                iterations: v[11] as u32,
                inliers: v[12] as u32,
                failure: if v[13] != 0.0 {
                    None
                } else {
                    Some(PairFailure::Implausible)
                },
                split,
            },
        ));
    }
    Ok(out)
}

/// The information split of a motions row (`None` for core columns only);
/// shares outside [0, 1] are refused.
fn split_of(v: &[f64], file: &str, n: usize) -> Result<Option<InfoSplit>, InputError> {
    if v.len() < 20 {
        return Ok(None);
    }
    let scan_share = [v[14], v[15], v[16]];
    if scan_share.iter().any(|s| !(0.0..=1.0).contains(s)) {
        return Err(
            InputError::new(file, "scan_share_* must lie in [0, 1]").at(format!("line {n}"))
        );
    }
    Ok(Some(InfoSplit {
        scan_share,
        scan_only: [v[17], v[18], v[19]],
    }))
}

/// Reads wheel data: either angles `t,left,right` (rad) or mean rates over
/// intervals `t0,t1,omega_right,omega_left` (rad/s), which are integrated into
/// angles starting at 0. Stamps must not go backwards.
pub fn read_wheels(path: &Path) -> Result<Vec<WheelSample>, InputError> {
    let (file, text) = read_text(path)?;
    let mut lines = data_lines(&text);
    let Some((hn, header)) = lines.next() else {
        return Err(InputError::new(&file, "empty wheel file"));
    };
    let header = header.replace(' ', "");
    let mut out: Vec<WheelSample> = Vec::new();
    let backwards = |n| InputError::new(&file, "time goes backwards").at(format!("line {n}"));
    match header.as_str() {
        "t,left,right" => {
            for (n, l) in lines {
                let v = numbers(l, 3, &file, n)?;
                if out.last().is_some_and(|s| v[0] < s.stamp) {
                    return Err(backwards(n));
                }
                out.push(WheelSample { stamp: v[0], left: v[1], right: v[2] });
            }
        }
        "t0,t1,omega_right,omega_left" => {
            for (n, l) in lines {
                let v = numbers(l, 4, &file, n)?;
                if !(v[1] > v[0]) || out.last().is_some_and(|s| v[0] < s.stamp) {
                    return Err(backwards(n));
                }
                let prev = match out.last() {
                    Some(s) if s.stamp == v[0] => *s,
                    Some(s) => WheelSample { stamp: v[0], ..*s },
                    None => WheelSample { stamp: v[0], left: 0.0, right: 0.0 },
                };
                if out.last().is_none_or(|s| s.stamp != v[0]) {
                    out.push(prev);
                }
                let dt = v[1] - v[0];
                out.push(WheelSample {
                    stamp: v[1],
                    left: prev.left + v[3] * dt,
                    right: prev.right + v[2] * dt,
                });
            }
        }
        _ => {
            return Err(InputError::new(
                &file,
                "expected header 't,left,right' (angles, rad) or 't0,t1,omega_right,omega_left' (rad/s)",
            )
            .at(format!("line {hn}")))
        }
    }
    if out.len() < 2 {
        return Err(InputError::new(&file, "fewer than 2 wheel samples"));
    }
    Ok(out)
}

/// Writes wheel angles as `t,left,right` (s, rad).
pub fn write_wheels(path: &Path, wheels: &[WheelSample]) -> io::Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "t,left,right")?;
        for s in wheels {
            writeln!(w, "{:.9},{:.12},{:.12}", s.stamp, s.left, s.right)?;
        }
        Ok(())
    })
}

/// One row of the calibration history (design.md column order).
pub type HistoryFields = [f64; 9];

/// One line of the calibration history CSV (after [`HISTORY_HEADER`]);
/// `change` names the effect that changed where the change detector fired
/// (empty elsewhere).
pub fn write_history_row(w: &mut impl Write, r: &HistoryFields, change: &str) -> io::Result<()> {
    writeln!(
        w,
        "{:.6},{:.9},{:.9},{:.9},{:e},{:e},{:e},{},{:e},{change}",
        r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7] as u64, r[8]
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("odocal-csv-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn motions_round_trip_and_failed_pairs_stay_failed() {
        let d = dir("motions");
        let m = |t: f64, failure| Motion {
            t0: t,
            t1: t + 0.02,
            dx: 0.01,
            dy: -0.001,
            dtheta: 0.003,
            cov: Matrix3::new(1e-6, 1e-8, 0.0, 1e-8, 2e-6, 1e-9, 0.0, 1e-9, 3e-7),
            iterations: 7,
            inliers: 480,
            failure,
            split: Some(InfoSplit {
                scan_share: [0.25, 1.0, 0.5],
                scan_only: [0.02, -0.001, 0.0031],
            }),
        };
        let ms = vec![m(0.0, None), m(0.02, Some(PairFailure::Degenerate))];
        write_motions(&d.join("m.csv"), &ms).unwrap();
        let back = read_motions(&d.join("m.csv")).unwrap();
        assert_eq!(back.len(), 2);
        assert!(back[0].is_valid() && !back[1].is_valid());
        let (a, b) = (ms[0].split.unwrap(), back[0].split.unwrap());
        assert_eq!(a.scan_share, b.scan_share);
        for k in 0..3 {
            assert!((a.scan_only[k] - b.scan_only[k]).abs() < 1e-9);
        }
        assert!((back[0].cov[(2, 2)] - 3e-7).abs() < 1e-15);
        assert!((back[0].dtheta - 0.003).abs() < 1e-12);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn wheel_rates_integrate_into_angles_and_errors_name_lines() {
        let d = dir("wheels");
        let p = d.join("w.csv");
        std::fs::write(
            &p,
            "t0,t1,omega_right,omega_left\n0,1,2,1\n1,3,1,0.5\n5,6,1,1\n",
        )
        .unwrap();
        let w = read_wheels(&p).unwrap();
        assert_eq!(w.len(), 5);
        assert_eq!((w[2].right, w[2].left), (4.0, 2.0));
        assert_eq!(w[3].stamp, 5.0);
        assert_eq!(w[3].right, 4.0, "gaps carry no motion");
        std::fs::write(&p, "t,left,right\n0,0,0\n1,nan,0\n").unwrap();
        let e = read_wheels(&p).unwrap_err().to_string();
        assert!(e.contains("line 3"), "{e}");
        std::fs::write(&p, "t,left,right\n1,0,0\n0,0,0\n").unwrap();
        assert!(read_wheels(&p)
            .unwrap_err()
            .to_string()
            .contains("backwards"));
        std::fs::write(&p, "time,l,r\n").unwrap();
        assert!(read_wheels(&p).is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
