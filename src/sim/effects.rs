//! The true robot: the nominal model changed by the injected effects
//! (design.md's table). Effects of the same kind add up.

use crate::effects::Effect;
use crate::robot::{DiffDrive, LaserMount, RobotConfig};

/// True kinematics and sensor departures of the simulated chair.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueRobot {
    nominal: DiffDrive,
    /// Relative radius changes (right, left).
    scale: (f64, f64),
    /// Relative wheel-base change.
    base_scale: f64,
    /// Radius steps: (time s, right m, left m).
    steps: Vec<(f64, f64, f64)>,
    /// Radius drift (right, left) in m/s.
    drift: (f64, f64),
    /// Encoder over-read gain k (s/rad): ω_meas = ω (1 + k|ω|).
    pub encoder_gain: f64,
    /// Delay (s) of the encoder stream behind the laser.
    pub latency: f64,
    /// True laser mounting `base_from_laser`.
    pub laser: LaserMount,
    /// Gyro bias (rad/s).
    pub gyro_bias: f64,
    /// Turn slip k (s/rad): D_eff = D (1 + k |W|).
    pub turn_slip: f64,
}

impl TrueRobot {
    /// The true robot for a nominal configuration and a list of effects.
    pub fn new(robot: &RobotConfig, effects: &[Effect]) -> Self {
        let mut t = Self {
            nominal: robot.diff_drive(),
            scale: (0.0, 0.0),
            base_scale: 0.0,
            steps: Vec::new(),
            drift: (0.0, 0.0),
            encoder_gain: 0.0,
            latency: 0.0,
            laser: robot.laser,
            gyro_bias: 0.0,
            turn_slip: 0.0,
        };
        for e in effects {
            match *e {
                Effect::RadiusScale { right, left } => {
                    t.scale.0 += right;
                    t.scale.1 += left;
                }
                Effect::WheelBaseScale { scale } => t.base_scale += scale,
                Effect::RadiusStep { time, right, left } => t.steps.push((time, right, left)),
                Effect::RadiusDrift { right, left } => {
                    t.drift.0 += right / 3600.0;
                    t.drift.1 += left / 3600.0;
                }
                Effect::EncoderGain { k } => t.encoder_gain += k,
                Effect::Latency { delay } => t.latency += delay,
                Effect::LaserOffset { x, y, yaw } => {
                    t.laser.x += x;
                    t.laser.y += y;
                    t.laser.yaw += yaw;
                }
                Effect::GyroBias { bias } => t.gyro_bias += bias,
                Effect::TurnSlip { k } => t.turn_slip += k,
            }
        }
        t
    }

    /// True radii and wheel base (m) at time `t` (s from the start), without slip.
    pub fn at(&self, t: f64) -> DiffDrive {
        let mut r = self.nominal.r_right * (1.0 + self.scale.0) + self.drift.0 * t;
        let mut l = self.nominal.r_left * (1.0 + self.scale.1) + self.drift.1 * t;
        for &(ts, dr, dl) in &self.steps {
            if t >= ts {
                r += dr;
                l += dl;
            }
        }
        DiffDrive {
            r_right: r,
            r_left: l,
            wheel_base: self.nominal.wheel_base * (1.0 + self.base_scale),
        }
    }

    /// True wheel rates (rad/s) that realise body velocities `v` (m/s), `w`
    /// (rad/s) at time `t`, with the turn-slip effective base.
    pub fn wheel_rates(&self, t: f64, v: f64, w: f64) -> (f64, f64) {
        let mut k = self.at(t);
        k.wheel_base *= 1.0 + self.turn_slip * w.abs();
        k.wheel_rates(v, w)
    }

    /// What an encoder reads for a true wheel rate ω (rad/s): ω (1 + k|ω|).
    pub fn measured_rate(&self, omega: f64) -> f64 {
        omega * (1.0 + self.encoder_gain * omega.abs())
    }

    /// Whether the true radii are physically possible over `[0, duration]` s.
    pub fn radii_positive(&self, duration: f64) -> bool {
        let mut times = vec![0.0, duration];
        times.extend(self.steps.iter().map(|s| s.0.clamp(0.0, duration)));
        times.iter().all(|&t| {
            let k = self.at(t);
            k.r_right > 0.0 && k.r_left > 0.0 && k.wheel_base > 0.0
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effects_change_the_right_parameters_at_the_right_time() {
        let robot = RobotConfig::default();
        let e = [
            Effect::RadiusScale {
                right: 0.01,
                left: -0.02,
            },
            Effect::RadiusStep {
                time: 5.0,
                right: 0.004,
                left: 0.002,
            },
            Effect::RadiusDrift {
                right: 0.036,
                left: 0.0,
            },
            Effect::WheelBaseScale { scale: 0.03 },
        ];
        let t = TrueRobot::new(&robot, &e);
        let a = t.at(4.999);
        assert!((a.r_right - (0.32 * 1.01 + 0.036 * 4.999 / 3600.0)).abs() < 1e-12);
        assert!((a.r_left - 0.32 * 0.98).abs() < 1e-12);
        let b = t.at(5.0);
        assert!((b.r_right - a.r_right - 0.004).abs() < 1e-6);
        assert!((b.r_left - a.r_left - 0.002).abs() < 1e-12);
        assert!((b.wheel_base - 0.65 * 1.03).abs() < 1e-12);
        assert!(t.radii_positive(100.0));
    }

    #[test]
    fn turn_slip_widens_the_effective_base_and_gain_over_reads() {
        let robot = RobotConfig::default();
        let t = TrueRobot::new(
            &robot,
            &[Effect::TurnSlip { k: 0.1 }, Effect::EncoderGain { k: 0.02 }],
        );
        let (r, l) = t.wheel_rates(0.0, 0.0, 1.0);
        let nominal = robot.diff_drive();
        let (_, w_nom) = nominal.body_velocity(r, l);
        assert!(
            (w_nom - 1.1).abs() < 1e-12,
            "nominal model over-reads the turn"
        );
        assert!((t.measured_rate(-2.0) - (-2.0 * 1.04)).abs() < 1e-12);
    }
}
