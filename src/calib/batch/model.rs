//! The measurement model of the batch calibration ([Censi2013,
//! eqs. 3–5]): the robot's motion over an interval is the composition of the
//! exact arcs of its wheel sub-steps, and the laser sees
//! `ŝ = ℓ⁻¹ ⊕ o ⊕ ℓ` with `ℓ = base_from_laser`. Poses are `[x m, y m, θ rad]`.

use super::{Interval, WheelMotion, WheelTrack};
use crate::geom::wrap_angle;

/// A planar pose or displacement `[x (m), y (m), θ (rad)]`.
pub type P3 = [f64; 3];

/// `a ⊕ b`: `b` applied in the frame of `a`.
pub fn oplus(a: P3, b: P3) -> P3 {
    let (s, c) = a[2].sin_cos();
    [
        a[0] + c * b[0] - s * b[1],
        a[1] + s * b[0] + c * b[1],
        a[2] + b[2],
    ]
}

/// `a⁻¹`.
pub fn inverse(a: P3) -> P3 {
    let (s, c) = a[2].sin_cos();
    [-(c * a[0] + s * a[1]), s * a[0] - c * a[1], -a[2]]
}

/// The unknowns, in the order of [`super::NAMES`]: radii and wheel base (m),
/// the laser mounting `base_from_laser` (m, m, rad) and the wheel stream's
/// lateness against the laser (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unknowns {
    /// Right wheel radius (m).
    pub r_right: f64,
    /// Left wheel radius (m).
    pub r_left: f64,
    /// Wheel base (m).
    pub wheel_base: f64,
    /// `base_from_laser` `[x, y, yaw]` (m, m, rad).
    pub laser: P3,
    /// Wheel stamps minus laser stamps of the same instant (s).
    pub time_offset: f64,
}

impl Unknowns {
    /// As a vector of the first `n` unknowns (6, or 7 with the time offset).
    pub fn to_vec(self, n: usize) -> Vec<f64> {
        let all = [
            self.r_right,
            self.r_left,
            self.wheel_base,
            self.laser[0],
            self.laser[1],
            self.laser[2],
            self.time_offset,
        ];
        all[..n].to_vec()
    }

    /// From a vector of 6 or 7 unknowns (a missing time offset is 0).
    pub fn from_slice(p: &[f64]) -> Self {
        Self {
            r_right: p[0],
            r_left: p[1],
            wheel_base: p[2],
            laser: [p[3], p[4], p[5]],
            time_offset: p.get(6).copied().unwrap_or(0.0),
        }
    }
}

/// The exact arc of one wheel sub-step ([Censi2013, eq. 4]): distance
/// `(r_R Δφ_R + r_L Δφ_L)/2`, rotation `(r_R Δφ_R − r_L Δφ_L)/b`.
pub fn arc(dl: f64, dr: f64, r_right: f64, r_left: f64, b: f64) -> P3 {
    let d = 0.5 * (r_right * dr + r_left * dl);
    let th = (r_right * dr - r_left * dl) / b;
    let (t1, t2) = if th.abs() > 1e-9 {
        (th.sin() / th, (1.0 - th.cos()) / th)
    } else {
        (1.0 - th * th / 6.0, 0.5 * th)
    };
    [d * t1, d * t2, th]
}

/// Wheel angles (left, right; rad) at time `t` (s) on the track, linear
/// between samples and clamped at the ends.
fn angles_at(track: &WheelTrack, t: f64) -> [f64; 2] {
    let n = track.t.len();
    let i = track.t.partition_point(|&x| x <= t);
    if i == 0 {
        return [track.left[0], track.right[0]];
    }
    if i >= n {
        return [track.left[n - 1], track.right[n - 1]];
    }
    let (a, b) = (i - 1, i);
    let s = (t - track.t[a]) / (track.t[b] - track.t[a]);
    [
        track.left[a] + s * (track.left[b] - track.left[a]),
        track.right[a] + s * (track.right[b] - track.right[a]),
    ]
}

/// The wheel increments `(Δφ_L, Δφ_R)` (rad) of an interval, its span read
/// `delta` s later on the wheel track (the wheel stamp of laser time t is
/// t + δ).
pub fn increments(iv: &Interval, track: Option<&WheelTrack>, delta: f64, out: &mut Vec<[f64; 2]>) {
    out.clear();
    match (&iv.wheels, track) {
        (WheelMotion::Steps(s), _) => out.extend_from_slice(s),
        (WheelMotion::Span { t0, t1 }, Some(tr)) => {
            let (a, b) = (t0 + delta, t1 + delta);
            let mut prev = angles_at(tr, a);
            let i0 = tr.t.partition_point(|&x| x <= a);
            let i1 = tr.t.partition_point(|&x| x < b);
            for i in i0..i1 {
                let cur = [tr.left[i], tr.right[i]];
                out.push([cur[0] - prev[0], cur[1] - prev[1]]);
                prev = cur;
            }
            let end = angles_at(tr, b);
            out.push([end[0] - prev[0], end[1] - prev[1]]);
        }
        (WheelMotion::Span { .. }, None) => {}
    }
}

/// The robot's motion `o` over the increments (arcs composed in order; the
/// angle is not wrapped).
pub fn robot_motion(inc: &[[f64; 2]], u: &Unknowns) -> P3 {
    inc.iter().fold([0.0; 3], |o, &[dl, dr]| {
        oplus(o, arc(dl, dr, u.r_right, u.r_left, u.wheel_base))
    })
}

/// The laser displacement the unknowns predict, `ℓ⁻¹ ⊕ o ⊕ ℓ` (Eq. 5).
pub fn predicted(inc: &[[f64; 2]], u: &Unknowns) -> P3 {
    oplus(oplus(inverse(u.laser), robot_motion(inc, u)), u.laser)
}

/// The residual `s − ŝ` in the laser frame at the interval's start, the
/// angle wrapped (Censi's `err_sm` with the opposite sign).
pub fn residual(s: P3, pred: P3) -> P3 {
    [s[0] - pred[0], s[1] - pred[1], wrap_angle(s[2] - pred[2])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oplus_and_inverse_are_a_group() {
        let a = [0.3, -0.2, 1.1];
        let b = [-0.5, 0.7, -2.0];
        let id = oplus(a, inverse(a));
        assert!(id.iter().all(|x| x.abs() < 1e-12), "{id:?}");
        // Against nalgebra's isometries (an independent implementation).
        let na = crate::geom::pose(a[0], a[1], a[2]) * crate::geom::pose(b[0], b[1], b[2]);
        let ab = oplus(a, b);
        assert!((na.translation.x - ab[0]).abs() < 1e-12);
        assert!((na.translation.y - ab[1]).abs() < 1e-12);
        assert!((wrap_angle(na.rotation.angle() - ab[2])).abs() < 1e-12);
    }

    #[test]
    fn many_small_arcs_compose_to_one_arc() {
        // A constant-rate motion split in 100 sub-steps is the same circle.
        let u = Unknowns {
            r_right: 0.1,
            r_left: 0.09,
            wheel_base: 0.5,
            laser: [0.0; 3],
            time_offset: 0.0,
        };
        let one = robot_motion(&[[2.0, 3.0]], &u);
        let many = robot_motion(&[[0.02, 0.03]; 100], &u);
        for i in 0..3 {
            assert!((one[i] - many[i]).abs() < 1e-12, "{one:?} {many:?}");
        }
    }
}
