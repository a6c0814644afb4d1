//! The calibration tuples of \[Censi2013\] (github.com/AndreaCensi/calibration,
//! `reference-output/*.tuple`): a stream of JSON objects
//! `{"T": s, "phi_l": rad/s, "phi_r": rad/s, "sm": [dx m, dy m, dθ rad]}`,
//! some back to back on one line, so the file is read as a JSON stream.
//! `sm` is the laser's displacement over `T` in the laser frame at its start.

use crate::error::InputError;
use crate::geom::{self, Pose2};
use crate::motion::Motion;
use crate::recording::WheelSample;
use nalgebra::Matrix3;
use serde::Deserialize;
use std::path::Path;

/// One tuple: an interval with mean wheel rates and the laser's displacement.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CensiTuple {
    /// Interval length (s).
    #[serde(rename = "T")]
    pub t: f64,
    /// Mean left wheel rate (rad/s).
    pub phi_l: f64,
    /// Mean right wheel rate (rad/s).
    pub phi_r: f64,
    /// Laser displacement `[dx, dy, dθ]` (m, m, rad), laser frame at the start.
    pub sm: [f64; 3],
}

/// The authors' solver output (`*_results.json`); diameters, not radii.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct CensiResults {
    /// Wheel base (m).
    pub axle: f64,
    /// Left wheel diameter (m).
    pub l_diam: f64,
    /// Right wheel diameter (m).
    pub r_diam: f64,
    /// Laser x in the robot frame (m).
    pub l_x: f64,
    /// Laser y in the robot frame (m).
    pub l_y: f64,
    /// Laser yaw in the robot frame (rad).
    pub l_theta: f64,
}

impl CensiResults {
    /// The laser mounting `base_from_laser`.
    pub fn base_from_laser(&self) -> Pose2 {
        geom::pose(self.l_x, self.l_y, self.l_theta)
    }
}

fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Shortest interval a tuple may span (s): no laser scan interval is shorter
/// than a microsecond, and a shorter one would not move a clock of seconds
/// laid end to end (0.8 s + 1e-201 s is 0.8 s).
pub const MIN_INTERVAL_S: f64 = 1e-6;

/// Longest interval a tuple may span (s): a tuple is the motion between two
/// laser scans, not an hour of driving; a longer one (8·10³⁰¹ s) would
/// swallow every later interval into a clock that no longer moves.
pub const MAX_INTERVAL_S: f64 = 3600.0;

/// Parses a tuple stream; `file` names the source in errors. Every tuple must
/// have [`MIN_INTERVAL_S`] ≤ T ≤ [`MAX_INTERVAL_S`] and finite values.
pub fn parse(text: &str, file: &str) -> Result<Vec<CensiTuple>, InputError> {
    let mut out = Vec::new();
    let mut stream = serde_json::Deserializer::from_str(text).into_iter::<CensiTuple>();
    loop {
        let start = stream.byte_offset();
        match stream.next() {
            None => break,
            Some(Err(e)) => {
                return Err(InputError::new(file, e.to_string())
                    .topic("tuple")
                    .at(format!("object {} (line {})", out.len() + 1, e.line())));
            }
            Some(Ok(t)) => {
                let ok = (MIN_INTERVAL_S..=MAX_INTERVAL_S).contains(&t.t)
                    && [t.t, t.phi_l, t.phi_r, t.sm[0], t.sm[1], t.sm[2]]
                        .iter()
                        .all(|x| x.is_finite());
                if !ok {
                    return Err(InputError::new(
                        file,
                        format!(
                            "T = {} s: T must lie in [{MIN_INTERVAL_S}, {MAX_INTERVAL_S}] s \
                             (the interval between two scans) and all values be finite",
                            t.t
                        ),
                    )
                    .topic("tuple")
                    .at(format!(
                        "object {} (line {})",
                        out.len() + 1,
                        line_of(text, start + 1)
                    )));
                }
                out.push(t);
            }
        }
    }
    Ok(out)
}

/// Reads and parses a `.tuple` file.
pub fn read(path: &Path) -> Result<Vec<CensiTuple>, InputError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| InputError::new(&name, e.to_string()))?;
    parse(&text, &name)
}

/// Reads a `*_results.json` file.
pub fn read_results(path: &Path) -> Result<CensiResults, InputError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| InputError::new(&name, e.to_string()))?;
    #[derive(Deserialize)]
    struct Raw {
        #[serde(flatten)]
        r: CensiResults,
        #[serde(flatten)]
        _rest: serde_json::Map<String, serde_json::Value>,
    }
    serde_json::from_str::<Raw>(&text)
        .map(|x| x.r)
        .map_err(|e| InputError::new(&name, e.to_string()).at(format!("line {}", e.line())))
}

/// Lays the tuples end to end in time (the first starting at 0 s) and
/// converts them into what the pipeline consumes: integrated wheel angles
/// (rad) at the interval ends, and one robot motion per tuple,
/// `o = l ⊕ sm ⊕ l⁻¹` with `l = base_from_laser`, carrying a diagonal
/// covariance from the laser-frame σ's (translation σ inflated by the lever
/// arm |l_t|·σ_θ).
pub fn to_streams(
    tuples: &[CensiTuple],
    base_from_laser: &Pose2,
    sigma_xy: f64,
    sigma_theta: f64,
) -> (Vec<WheelSample>, Vec<Motion>) {
    let mut wheels = Vec::with_capacity(tuples.len() + 1);
    let mut motions = Vec::with_capacity(tuples.len());
    let (mut t, mut left, mut right) = (0.0, 0.0, 0.0);
    wheels.push(WheelSample {
        stamp: t,
        left,
        right,
    });
    let lever = base_from_laser.translation.vector.norm();
    let sxy2 = sigma_xy * sigma_xy + (lever * sigma_theta).powi(2);
    let cov = Matrix3::from_diagonal(&nalgebra::Vector3::new(
        sxy2,
        sxy2,
        sigma_theta * sigma_theta,
    ));
    let inv = base_from_laser.inverse();
    for tu in tuples {
        let sm = geom::pose(tu.sm[0], tu.sm[1], tu.sm[2]);
        let o = base_from_laser * sm * inv;
        let [dx, dy, dth] = geom::xyt(&o);
        let t1 = t + tu.t;
        left += tu.phi_l * tu.t;
        right += tu.phi_r * tu.t;
        wheels.push(WheelSample {
            stamp: t1,
            left,
            right,
        });
        motions.push(Motion {
            t0: t,
            t1,
            dx,
            dy,
            dtheta: dth,
            cov,
            iterations: 0,
            inliers: 0,
            failure: None,
            split: None,
        });
        t = t1;
    }
    (wheels, motions)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_back_to_back_objects_and_reports_positions() {
        let text = "{ \"T\": 0.8, \"phi_l\": 0.5, \"phi_r\": 0.4, \"sm\": [0.01, 0.0, 0.001] }{ \"T\": 1.0, \"phi_l\": 0.0, \"phi_r\": 0.0, \"sm\": [0, 0, 0] }\n{ \"T\": 0.9, \"phi_l\": 1, \"phi_r\": 1, \"sm\": [0, 0, 0] }\n";
        let t = parse(text, "x.tuple").unwrap();
        assert_eq!(t.len(), 3);
        assert_eq!(t[0].phi_r, 0.4);
        assert_eq!(t[2].t, 0.9);
        let bad = "{ \"T\": 0.8, \"phi_l\": 0.5, \"phi_r\": 0.4, \"sm\": [0.01, 0.0, 0.001] }\n{ \"T\": -1, \"phi_l\": 0, \"phi_r\": 0, \"sm\": [0, 0, 0] }\n";
        let e = parse(bad, "x.tuple").unwrap_err();
        assert_eq!(e.position.as_deref(), Some("object 2 (line 2)"));
        let e = parse("{ \"T\": 0.8, \"phi_l\": 0.5 }", "x.tuple").unwrap_err();
        assert!(e.position.unwrap().starts_with("object 1"));
    }

    #[test]
    fn an_interval_is_a_microsecond_to_an_hour() {
        let one =
            |t: f64| format!("{{ \"T\": {t}, \"phi_l\": 0.5, \"phi_r\": 0.4, \"sm\": [0, 0, 0] }}");
        for ok in [1e-6, 0.8, 3600.0] {
            assert!(parse(&one(ok), "x.tuple").is_ok(), "{ok}");
        }
        for bad in [9e-7, 3600.5, 7.93058e301] {
            let e = parse(&one(bad), "x.tuple").unwrap_err();
            assert!(e.to_string().contains("[0.000001, 3600] s"), "{bad}: {e}");
        }
    }

    #[test]
    fn laser_motion_is_conjugated_into_the_base_frame() {
        // Laser 0.1 m ahead, yawed 90°: a pure laser translation along its
        // own x is a robot translation along the robot's y.
        let l = geom::pose(0.1, 0.0, std::f64::consts::FRAC_PI_2);
        let tu = CensiTuple {
            t: 1.0,
            phi_l: 1.0,
            phi_r: 2.0,
            sm: [0.02, 0.0, 0.0],
        };
        let (w, m) = to_streams(&[tu, tu], &l, 1e-3, 1e-3);
        assert_eq!(w.len(), 3);
        assert_eq!((w[2].left, w[2].right, w[2].stamp), (2.0, 4.0, 2.0));
        assert!((m[0].dy - 0.02).abs() < 1e-12 && m[0].dx.abs() < 1e-12);
        assert_eq!((m[1].t0, m[1].t1), (1.0, 2.0));
    }
}
