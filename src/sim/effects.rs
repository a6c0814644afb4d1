//! The true robot: the nominal model changed by the injected effects
//! (design.md's table). Effects of the same kind add up.

use crate::effects::{Departures, Effect, FaultEffect};
use crate::robot::{DiffDrive, LaserMount, RobotConfig};

/// True kinematics and sensor departures of the simulated chair.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueRobot {
    nominal: DiffDrive,
    departures: Departures,
    /// True laser mounting `base_from_laser`.
    pub laser: LaserMount,
    /// Faults outside the effect table.
    faults: Vec<FaultEffect>,
}

impl TrueRobot {
    /// The true robot for a nominal configuration and a list of effects (a
    /// configuration without a laser mounting is simulated with the
    /// wheelchair's; `pipeline::simulate` always states one).
    pub fn new(robot: &RobotConfig, effects: &[Effect]) -> Self {
        let departures = Departures::of(effects);
        Self {
            nominal: robot.diff_drive(),
            laser: departures.laser_mount(&robot.laser.unwrap_or_default()),
            departures,
            faults: Vec::new(),
        }
    }

    /// The same robot with faults outside the effect table.
    pub fn with_faults(mut self, faults: &[FaultEffect]) -> Self {
        self.faults = faults.to_vec();
        self
    }

    /// True wheel rates (rad/s) after the faults that change how the wheels
    /// roll: round-wheel `rates`, the wheels' true `angles` (rad), the
    /// robot's world x (m).
    pub fn faulty_rates(&self, rates: (f64, f64), angles: (f64, f64), x: f64) -> (f64, f64) {
        self.faults
            .iter()
            .fold(rates, |r, f| f.wheel_rates(r, angles, x))
    }

    /// True time (s) at which the encoder reading stamped `stamp` was
    /// taken: the latency, plus any change of it by then.
    pub fn encoder_taken(&self, stamp: f64) -> f64 {
        let extra: f64 = self.faults.iter().map(|f| f.extra_delay(stamp)).sum();
        self.departures.encoder_taken(stamp) - extra
    }

    /// How far back (s) a latency that grows during the run can move the
    /// time a later encoder reading was taken: the sum of the growths.
    pub fn delay_margin(&self) -> f64 {
        self.faults
            .iter()
            .map(|f| f.extra_delay(f64::INFINITY).max(0.0))
            .sum()
    }

    /// True laser mounting `base_from_laser` at true time `t` (s): the
    /// effects' mounting moved by every knock by then.
    pub fn laser_at(&self, t: f64) -> LaserMount {
        let mut m = self.laser;
        for f in &self.faults {
            let [dx, dy, dyaw] = f.mount_shift(t);
            m.x += dx;
            m.y += dy;
            m.yaw += dyaw;
        }
        m
    }

    /// The (right, left) angles the encoders' wiring reports.
    pub fn wire(&self, angles: (f64, f64)) -> (f64, f64) {
        self.faults.iter().fold(angles, |a, f| f.wire(a))
    }

    /// What the effects amount to.
    pub fn departures(&self) -> &Departures {
        &self.departures
    }

    /// True radii and wheel base (m) at time `t` (s from the start), without slip.
    pub fn at(&self, t: f64) -> DiffDrive {
        let n = &self.nominal;
        let [r_right, r_left] = self
            .departures
            .radii_at_per_second([n.r_right, n.r_left], t);
        DiffDrive {
            r_right,
            r_left,
            wheel_base: self.departures.wheel_base(n.wheel_base),
        }
    }

    /// The radii (m) the wheels roll on at time `t` standing (loaded tyres
    /// deflected by their static load), with the wheel base: what the truth
    /// file reports and a calibration should find; the turns' load transfer
    /// comes on top while moving.
    pub fn rolling_at(&self, t: f64) -> DiffDrive {
        let mut k = self.at(t);
        for f in &self.faults {
            (k.r_right, k.r_left) = f.loaded_radii((k.r_right, k.r_left), k.wheel_base, 0.0, 0.0);
        }
        k
    }

    /// True wheel rates (rad/s) that realise body velocities `v` (m/s), `w`
    /// (rad/s) at time `t`, with the turn-slip effective base and the
    /// tyres' loaded radii.
    pub fn wheel_rates(&self, t: f64, v: f64, w: f64) -> (f64, f64) {
        let mut k = self.at(t);
        k.wheel_base = self.departures.turning_base(k.wheel_base, w);
        for f in &self.faults {
            (k.r_right, k.r_left) = f.loaded_radii((k.r_right, k.r_left), k.wheel_base, v, w);
        }
        k.wheel_rates(v, w)
    }

    /// What an encoder reads for a true wheel rate ω (rad/s).
    pub fn measured_rate(&self, omega: f64) -> f64 {
        self.departures.encoder_rate(omega)
    }

    /// Whether the true radii are physically possible over `[0, duration]` s
    /// (and loaded tyres deflect at most a fifth of their radius standing).
    pub fn radii_positive(&self, duration: f64) -> bool {
        let mut times = vec![0.0, duration];
        times.extend(self.departures.step_times().map(|t| t.clamp(0.0, duration)));
        times.iter().all(|&t| {
            let k = self.at(t);
            // Loaded tyres standing may deflect a fifth of their radius at
            // most: past that a linear tyre is no model of one.
            let loaded = self.faults.iter().all(|f| {
                let (r, l) = f.loaded_radii((k.r_right, k.r_left), k.wheel_base, 0.0, 0.0);
                r >= 0.8 * k.r_right && l >= 0.8 * k.r_left
            });
            k.r_right > 0.0 && k.r_left > 0.0 && k.wheel_base > 0.0 && loaded
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
    fn loaded_tyres_roll_on_radii_shrunk_by_their_deflection() {
        // 100 kg on the chair's 0.65 m axle, the centre of mass 0.065 m to
        // the left and 0.5 m high, tyres of 50 kN/m. Standing: right
        // 100·9.80665·(0.5 − 0.1) = 392.3 N (7.85 mm), left 588.4 N
        // (11.77 mm). At 0.5 m/s turning left at 1 rad/s the turn moves
        // 100·0.5·1·0.5/0.65 = 38.46 N onto the right wheel.
        let robot = RobotConfig::default();
        let f = FaultEffect::TyreLoad {
            mass: 100.0,
            com_y: 0.065,
            height: 0.5,
            stiffness: 5e4,
        };
        let t = TrueRobot::new(&robot, &[]).with_faults(&[f]);
        let (r, l) = f.loaded_radii((0.32, 0.32), 0.65, 0.0, 0.0);
        assert!((r - (0.32 - 392.266 / 5e4)).abs() < 1e-7, "{r}");
        assert!((l - (0.32 - 588.399 / 5e4)).abs() < 1e-7, "{l}");
        let (r, l) = f.loaded_radii((0.32, 0.32), 0.65, 0.5, 1.0);
        assert!((r - (0.32 - (392.266 + 38.4615) / 5e4)).abs() < 1e-7, "{r}");
        assert!((l - (0.32 - (588.399 - 38.4615) / 5e4)).abs() < 1e-7, "{l}");
        let k = t.rolling_at(0.0);
        assert!((k.r_right - (0.32 - 392.266 / 5e4)).abs() < 1e-7, "{k:?}");
        assert!((k.r_left - (0.32 - 588.399 / 5e4)).abs() < 1e-7, "{k:?}");
        // Straight at 1 m/s the wheels turn at 1 m/s over their loaded radii.
        let (wr, wl) = t.wheel_rates(0.0, 1.0, 0.0);
        assert!((wr - 1.0 / (0.32 - 392.266 / 5e4)).abs() < 1e-6, "{wr}");
        assert!((wl - 1.0 / (0.32 - 588.399 / 5e4)).abs() < 1e-6, "{wl}");
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
