//! What a set of effects amounts to at any time, and the laws by which it
//! changes the robot: forward (true motion → what the sensors report) for the
//! simulator and the synthetic streams, inverse (measured wheel angles → true
//! motion) for the diagnosis's replay.

use super::Effect;
use crate::robot::LaserMount;

/// A radius step: at `time` (s from the origin) the radii change by
/// `right`/`left` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// When (s from the origin).
    pub time: f64,
    /// Change of the right radius (m).
    pub right: f64,
    /// Change of the left radius (m).
    pub left: f64,
}

/// All effects folded into one set of numbers (zero = nominal): effects of
/// the same kind add up, radius steps are kept one by one. Units are those of
/// the effect table.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Departures {
    /// Relative right/left radius change (`radius_scale`).
    pub radius_scale: [f64; 2],
    /// Relative wheel-base change (`wheel_base_scale`).
    pub wheel_base_scale: f64,
    /// Radius steps in the order given (`radius_step`).
    pub radius_steps: Vec<Step>,
    /// Radius drift right, left (m/h) (`radius_drift`).
    pub radius_drift: [f64; 2],
    /// Encoder over-read gain k (s/rad) (`encoder_gain`).
    pub encoder_gain: f64,
    /// Delay (s) of the encoder stream behind the laser (`latency`).
    pub latency: f64,
    /// Laser mount offset x, y (m), yaw (rad), added to the nominal mount
    /// (`laser_offset`).
    pub laser_offset: [f64; 3],
    /// Gyro bias (rad/s) (`gyro_bias`).
    pub gyro_bias: f64,
    /// Turn slip k (s/rad) (`turn_slip`).
    pub turn_slip: f64,
}

impl Departures {
    /// Folds effects into one set (parameters of repeated effects add).
    pub fn of(effects: &[Effect]) -> Self {
        let mut d = Self::default();
        for e in effects {
            d.add(e);
        }
        d
    }

    /// Adds one effect.
    pub fn add(&mut self, e: &Effect) {
        match *e {
            Effect::RadiusScale { right, left } => {
                self.radius_scale[0] += right;
                self.radius_scale[1] += left;
            }
            Effect::WheelBaseScale { scale } => self.wheel_base_scale += scale,
            Effect::RadiusStep { time, right, left } => {
                self.radius_steps.push(Step { time, right, left })
            }
            Effect::RadiusDrift { right, left } => {
                self.radius_drift[0] += right;
                self.radius_drift[1] += left;
            }
            Effect::EncoderGain { k } => self.encoder_gain += k,
            Effect::Latency { delay } => self.latency += delay,
            Effect::LaserOffset { x, y, yaw } => {
                self.laser_offset[0] += x;
                self.laser_offset[1] += y;
                self.laser_offset[2] += yaw;
            }
            Effect::GyroBias { bias } => self.gyro_bias += bias,
            Effect::TurnSlip { k } => self.turn_slip += k,
        }
    }

    /// True radii (right, left) (m) at `t` s from the origin:
    /// nominal · (1 + scale) + drift · t / 3600, plus every step at or before `t`.
    pub fn radii_at(&self, nominal: [f64; 2], t: f64) -> [f64; 2] {
        let [dr, dl] = self.radius_drift;
        self.radii_with_drift(nominal, t, [dr * t / 3600.0, dl * t / 3600.0])
    }

    /// [`Self::radii_at`] with the drift rate turned into m/s before it is
    /// multiplied by `t`, (drift / 3600) · t: the rounding of the simulator,
    /// whose runs reproduce bit for bit.
    pub fn radii_at_per_second(&self, nominal: [f64; 2], t: f64) -> [f64; 2] {
        let [dr, dl] = self.radius_drift;
        self.radii_with_drift(nominal, t, [dr / 3600.0 * t, dl / 3600.0 * t])
    }

    /// Scaled radii plus the drift accumulated by `t` (m), then the steps.
    fn radii_with_drift(&self, nominal: [f64; 2], t: f64, drift: [f64; 2]) -> [f64; 2] {
        let [sr, sl] = self.radius_scale;
        let mut r = [
            nominal[0] * (1.0 + sr) + drift[0],
            nominal[1] * (1.0 + sl) + drift[1],
        ];
        for s in self.radius_steps.iter().filter(|s| t >= s.time) {
            r[0] += s.right;
            r[1] += s.left;
        }
        r
    }

    /// Times (s from the origin) at which the radii jump.
    pub fn step_times(&self) -> impl Iterator<Item = f64> + '_ {
        self.radius_steps.iter().map(|s| s.time)
    }

    /// True wheel base (m) of a nominal one, without the turn slip.
    pub fn wheel_base(&self, nominal: f64) -> f64 {
        nominal * (1.0 + self.wheel_base_scale)
    }

    /// Effective wheel base (m) while turning at `w` rad/s: D (1 + k |W|).
    pub fn turning_base(&self, base: f64, w: f64) -> f64 {
        base * (1.0 + self.turn_slip * w.abs())
    }

    /// Turn rate W (rad/s) of wheels whose rim speeds differ by `difference`
    /// (m/s, right − left) on a base of `base` m: the inverse of
    /// [`Self::turning_base`], W · D (1 + k |W|) = difference.
    pub fn turn_rate(&self, difference: f64, base: f64) -> f64 {
        invert_gain(difference / base, self.turn_slip)
    }

    /// What an encoder reads for a true wheel rate ω (rad/s): ω (1 + k|ω|).
    pub fn encoder_rate(&self, omega: f64) -> f64 {
        omega * (1.0 + self.encoder_gain * omega.abs())
    }

    /// The true wheel rate (rad/s) behind an encoder rate: the inverse of
    /// [`Self::encoder_rate`].
    pub fn wheel_rate(&self, reading: f64) -> f64 {
        invert_gain(reading, self.encoder_gain)
    }

    /// True time (s) at which the encoder reading stamped `stamp` was taken.
    pub fn encoder_taken(&self, stamp: f64) -> f64 {
        stamp - self.latency
    }

    /// Stamp (s) of the encoder reading taken at true time `t`: the inverse
    /// of [`Self::encoder_taken`].
    pub fn encoder_stamp(&self, t: f64) -> f64 {
        t + self.latency
    }

    /// True laser mounting: the nominal one plus the offset.
    pub fn laser_mount(&self, nominal: &LaserMount) -> LaserMount {
        LaserMount {
            x: nominal.x + self.laser_offset[0],
            y: nominal.y + self.laser_offset[1],
            yaw: nominal.yaw + self.laser_offset[2],
        }
    }

    /// Whether the laser sits where the nominal mount says.
    pub fn laser_nominal(&self) -> bool {
        self.laser_offset == [0.0; 3]
    }

    /// What the gyro reads (before noise) for a true yaw rate (rad/s).
    pub fn gyro_rate(&self, rate: f64) -> f64 {
        rate + self.gyro_bias
    }
}

/// Solves `x (1 + k |x|) = y` for x with the sign of y (the inverse of the
/// encoder-gain and turn-slip laws); a k that would make it unsolvable clamps.
pub fn invert_gain(y: f64, k: f64) -> f64 {
    let disc = (1.0 + 4.0 * k * y.abs()).max(0.0);
    2.0 * y / (1.0 + disc.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invert_gain_inverts_the_gain_law() {
        for k in [0.0, 0.01, 0.2] {
            for w in [-3.0, -0.2, 0.0, 0.5, 4.0] {
                let y: f64 = w * (1.0 + k * f64::abs(w));
                assert!((invert_gain(y, k) - w).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn inverse_laws_undo_the_forward_ones() {
        let d = Departures::of(&[
            Effect::EncoderGain { k: 0.03 },
            Effect::TurnSlip { k: 0.1 },
            Effect::Latency { delay: 0.05 },
        ]);
        assert!((d.wheel_rate(d.encoder_rate(-2.5)) + 2.5).abs() < 1e-12);
        let (w, base) = (0.7, 0.65);
        let diff = w * d.turning_base(base, w);
        assert!((d.turn_rate(diff, base) - w).abs() < 1e-12);
        assert_eq!(d.encoder_stamp(d.encoder_taken(3.0)), 3.0);
    }

    #[test]
    fn every_radius_step_counts_from_its_time() {
        let d = Departures::of(&[
            Effect::RadiusStep {
                time: 10.0,
                right: 0.002,
                left: 0.0,
            },
            Effect::RadiusStep {
                time: 20.0,
                right: 0.0,
                left: -0.003,
            },
        ]);
        assert_eq!(d.radii_at([0.3, 0.3], 9.9), [0.3, 0.3]);
        assert_eq!(d.radii_at([0.3, 0.3], 10.0), [0.3 + 0.002, 0.3]);
        assert_eq!(d.radii_at([0.3, 0.3], 20.0), [0.3 + 0.002, 0.3 - 0.003]);
    }
}
