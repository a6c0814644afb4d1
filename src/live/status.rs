//! What a live run says of itself, as a `diagnostic_msgs/DiagnosticStatus`
//! would: the current radii, wheel base, their std and the time offset as
//! values; the level WARN while the filters have not started or not
//! converged, a stream is silent or a change was just named, and ERROR
//! once the laser mounting is named as changed (the scan matching's
//! motions no longer mean what they did). Pure: the ROS 2 side publishes
//! what [`StatusBoard::status`] gives.

use std::time::{Duration, Instant};

use super::params::LiveParams;
use super::source::Traffic;
use crate::calib::Estimate;
use crate::diagnose::onset::{NamedChange, MOUNT, UNDETERMINED};
use crate::robot::DiffDrive;

/// How long a named change keeps the level at WARN.
const CHANGE_HOLD: Duration = Duration::from_secs(60);

/// `diagnostic_msgs/DiagnosticStatus` levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// `OK` (0).
    Ok = 0,
    /// `WARN` (1).
    Warn = 1,
    /// `ERROR` (2).
    Error = 2,
}

/// One status: level, message, key-value pairs.
#[derive(Debug, Clone, PartialEq)]
pub struct Status {
    /// Its level.
    pub level: Level,
    /// One line: why the level is what it is.
    pub message: String,
    /// Keys and values (as text, as the message carries them).
    pub values: Vec<(String, String)>,
}

/// A named change as the status shows it.
#[derive(Debug, Clone)]
struct Shown {
    line: String,
    fault: bool,
    at: Instant,
}

/// What the calibration knows now, kept up to date by the run.
#[derive(Debug, Clone)]
pub struct StatusBoard {
    /// The nominal kinematics the multipliers are relative to (`None`: the
    /// robot file states none).
    pub nominal: Option<DiffDrive>,
    /// The latest filter estimate.
    pub estimate: Option<Estimate>,
    /// The time offset in use (s).
    pub time_offset_s: f64,
    /// The laser mounting in use `[x (m), y (m), yaw (rad)]`.
    pub laser: [f64; 3],
    /// Filter steps so far.
    pub steps: u64,
    /// Odometry messages published so far.
    pub odometry: u64,
    change: Option<Shown>,
}

impl StatusBoard {
    /// A board for a robot with `nominal` kinematics.
    pub fn new(nominal: Option<DiffDrive>) -> Self {
        Self {
            nominal,
            estimate: None,
            time_offset_s: 0.0,
            laser: [0.0; 3],
            steps: 0,
            odometry: 0,
            change: None,
        }
    }

    /// A filter step's estimate.
    pub fn step(&mut self, e: &Estimate) {
        self.estimate = Some(*e);
        self.steps += 1;
    }

    /// A change named at `now`.
    pub fn named(&mut self, c: &NamedChange, now: Instant) {
        if c.effect == UNDETERMINED {
            return;
        }
        let fault = c.detector == MOUNT || c.effect == "laser_offset";
        let prev_fault = self.change.as_ref().is_some_and(|s| s.fault);
        if prev_fault && !fault {
            return;
        }
        self.change = Some(Shown {
            line: change_line(c),
            fault,
            at: now,
        });
    }

    /// The kinematics the odometry is integrated with now: the estimate,
    /// else the nominal ones.
    pub fn drive(&self) -> Option<DiffDrive> {
        match &self.estimate {
            Some(e) => Some(DiffDrive {
                r_right: e.r_right,
                r_left: e.r_left,
                wheel_base: e.wheel_base,
            }),
            None => self.nominal,
        }
    }

    /// The controller's multipliers (estimate over nominal, radii over the
    /// nominal mean radius as `diff_drive_controller` has one radius):
    /// `[left_wheel_radius, right_wheel_radius, wheel_separation,
    /// wheel_radius]`, the last the distance scale of one radius multiplier.
    pub fn multipliers(&self) -> Option<[f64; 4]> {
        let (n, e) = (self.nominal?, self.estimate.as_ref()?);
        let r = 0.5 * (n.r_right + n.r_left);
        let (ml, mr) = (e.r_left / r, e.r_right / r);
        Some([
            ml,
            mr,
            e.wheel_base / n.wheel_base,
            2.0 / (1.0 / mr + 1.0 / ml),
        ])
    }

    /// The status at `now` with the traffic seen and the inlet's counts
    /// `[queued, dropped full, oversized, refused]`.
    pub fn status(
        &self,
        traffic: &Traffic,
        counts: [u64; 4],
        params: &LiveParams,
        now: Instant,
    ) -> Status {
        let (level, message) = self.level(traffic, params, now);
        Status {
            level,
            message,
            values: self.values(traffic, counts),
        }
    }

    fn level(&self, traffic: &Traffic, params: &LiveParams, now: Instant) -> (Level, String) {
        let mut worst = (Level::Ok, String::new());
        let mut raise = |l: Level, m: String| {
            if l > worst.0 || (l == worst.0 && worst.1.is_empty()) {
                worst = (l, m);
            }
        };
        if let Some(c) = &self.change {
            if c.fault {
                raise(Level::Error, c.line.clone());
            } else if now.duration_since(c.at) < CHANGE_HOLD {
                raise(Level::Warn, c.line.clone());
            }
        }
        for (k, what) in [(0, "scans"), (1, "wheel data")] {
            let silent = traffic.heard[k].map(|h| now.duration_since(h).as_secs_f64());
            if let Some(s) = silent.filter(|s| *s > params.silence_s) {
                raise(Level::Warn, format!("no {what} for {s:.1} s"));
            }
        }
        match &self.estimate {
            None => raise(
                Level::Warn,
                "warming up: the filters start once the front end's window fits".into(),
            ),
            Some(e) => {
                let rel = [
                    ("r_right", e.std_r_right / e.r_right),
                    ("r_left", e.std_r_left / e.r_left),
                    ("wheel_base", e.std_wheel_base / e.wheel_base),
                ];
                if let Some((name, r)) = rel.iter().find(|(_, r)| !(*r <= params.converged_rel_std))
                {
                    raise(
                        Level::Warn,
                        format!(
                            "not converged: {name} std {:.2} % of its value (above {:.2} %)",
                            100.0 * r,
                            100.0 * params.converged_rel_std
                        ),
                    );
                }
            }
        }
        if traffic.gyro_dropped {
            raise(
                Level::Warn,
                "the gyro went silent: calibrating without it".into(),
            );
        }
        if worst.1.is_empty() {
            worst.1 = "calibrated".into();
        }
        worst
    }

    fn values(&self, traffic: &Traffic, counts: [u64; 4]) -> Vec<(String, String)> {
        let mut v: Vec<(String, String)> = Vec::new();
        let mut put = |k: &str, s: String| v.push((k.to_string(), s));
        if let Some(e) = &self.estimate {
            put("r_right", format!("{:.6}", e.r_right));
            put("r_left", format!("{:.6}", e.r_left));
            put("wheel_base", format!("{:.6}", e.wheel_base));
            put("r_right_std", format!("{:.6}", e.std_r_right));
            put("r_left_std", format!("{:.6}", e.std_r_left));
            put("wheel_base_std", format!("{:.6}", e.std_wheel_base));
            put("t", format!("{:.3}", e.t));
        }
        put("time_offset", format!("{:.4}", self.time_offset_s));
        put("laser_x", format!("{:.4}", self.laser[0]));
        put("laser_y", format!("{:.4}", self.laser[1]));
        put("laser_yaw", format!("{:.5}", self.laser[2]));
        if let Some([l, r, s, m]) = self.multipliers() {
            put("left_wheel_radius_multiplier", format!("{l:.6}"));
            put("right_wheel_radius_multiplier", format!("{r:.6}"));
            put("wheel_separation_multiplier", format!("{s:.6}"));
            put("wheel_radius_multiplier", format!("{m:.6}"));
        }
        put("steps", self.steps.to_string());
        put("odometry_published", self.odometry.to_string());
        let [queued, full, big, refused] = counts;
        put("messages_received", queued.to_string());
        put("messages_refused", refused.to_string());
        put("messages_dropped_queue_full", full.to_string());
        put("messages_oversized", big.to_string());
        put("scans_dropped_no_wheels", traffic.scans_dropped.to_string());
        if let Some(c) = &self.change {
            put("last_change", c.line.clone());
        }
        if let Some(r) = &traffic.last_refusal {
            put("last_refusal", r.clone());
        }
        v
    }
}

/// "radius_step right −4.9 mm at 40.0 s": a named change in a line.
pub fn change_line(c: &NamedChange) -> String {
    if c.parameter.is_empty() {
        return format!(
            "{} at {:.1} s, wheel not told (baseline unconverged)",
            c.effect, c.onset_s
        );
    }
    let unit = crate::effects::EffectKind::from_name(&c.effect)
        .and_then(|k| k.params().iter().find(|p| p.key == c.parameter))
        .map_or("", |p| p.unit);
    let size = match unit {
        "m" => format!("{:+.1} mm", 1e3 * c.estimate),
        "s" => format!("{:+.1} ms", 1e3 * c.estimate),
        "rad" => format!("{:+.2}°", c.estimate.to_degrees()),
        "1" | "" => format!("{:+.4}", c.estimate),
        u => format!("{:+.4} {u}", c.estimate),
    }
    .replace('-', "−");
    let by = if c.detector == MOUNT {
        " (laser-mounting watch)"
    } else {
        ""
    };
    format!(
        "{} {} {size} at {:.1} s{by}",
        c.effect, c.parameter, c.onset_s
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate(rel_std: f64) -> Estimate {
        Estimate {
            t: 12.0,
            r_right: 0.32,
            r_left: 0.319,
            wheel_base: 0.65,
            std_r_right: 0.32 * rel_std,
            std_r_left: 0.319 * rel_std,
            std_wheel_base: 0.65 * rel_std,
            v: 0.0,
            w: 0.0,
            particles: 0,
            process_sigma: 0.0,
            resampled: false,
            weights_reset: false,
            changed: false,
            respread: false,
        }
    }

    fn heard_now() -> Traffic {
        let now = Instant::now();
        Traffic {
            heard: [Some(now), Some(now), None, None, None],
            ..Traffic::default()
        }
    }

    fn change(effect: &str, detector: &'static str, estimate: f64) -> NamedChange {
        NamedChange {
            effect: effect.into(),
            detector,
            parameter: "right".into(),
            estimate,
            onset_s: 40.0,
            ..NamedChange::undetermined(41.0)
        }
    }

    const NOMINAL: DiffDrive = DiffDrive {
        r_right: 0.32,
        r_left: 0.32,
        wheel_base: 0.65,
    };

    #[test]
    fn the_level_follows_what_the_calibration_knows() {
        let p = LiveParams::default();
        let now = Instant::now();
        let mut b = StatusBoard::new(Some(NOMINAL));
        let s = b.status(&heard_now(), [0; 4], &p, now);
        assert_eq!(s.level, Level::Warn);
        assert!(s.message.contains("warming up"), "{}", s.message);
        b.step(&estimate(0.02));
        let s = b.status(&heard_now(), [0; 4], &p, now);
        assert_eq!(s.level, Level::Warn);
        assert!(s.message.contains("not converged"), "{}", s.message);
        b.step(&estimate(0.001));
        let s = b.status(&heard_now(), [0; 4], &p, now);
        assert_eq!((s.level, s.message.as_str()), (Level::Ok, "calibrated"));
        let value = |k: &str| {
            s.values
                .iter()
                .find(|(key, _)| key == k)
                .map(|(_, v)| v.clone())
        };
        assert_eq!(value("r_left").as_deref(), Some("0.319000"));
        assert_eq!(value("wheel_base_std").as_deref(), Some("0.000650"));
        assert!(value("time_offset").is_some());
        // Multipliers against the nominal mean radius 0.32.
        assert_eq!(
            value("left_wheel_radius_multiplier").as_deref(),
            Some("0.996875")
        );
        assert_eq!(
            value("wheel_separation_multiplier").as_deref(),
            Some("1.000000")
        );
    }

    #[test]
    fn a_named_change_warns_and_a_moved_laser_is_an_error() {
        let p = LiveParams::default();
        let now = Instant::now();
        let mut b = StatusBoard::new(Some(NOMINAL));
        b.step(&estimate(0.001));
        b.named(&change("radius_step", "filter", -0.0049), now);
        let s = b.status(&heard_now(), [0; 4], &p, now);
        assert_eq!(s.level, Level::Warn);
        assert_eq!(s.message, "radius_step right −4.9 mm at 40.0 s");
        // After the hold, calibrated again.
        let later = now + CHANGE_HOLD + Duration::from_secs(1);
        let heard_later = Traffic {
            heard: [Some(later), Some(later), None, None, None],
            ..Traffic::default()
        };
        assert_eq!(b.status(&heard_later, [0; 4], &p, later).level, Level::Ok);
        b.named(&change("laser_offset", MOUNT, 0.05), now);
        let s = b.status(&heard_now(), [0; 4], &p, now);
        assert_eq!(s.level, Level::Error);
        assert!(s.message.contains("laser-mounting watch"), "{}", s.message);
        // A later wheel change does not hide the fault.
        b.named(&change("radius_step", "filter", 0.003), now);
        assert_eq!(b.status(&heard_now(), [0; 4], &p, now).level, Level::Error);
        // An undetermined firing says nothing.
        let mut q = StatusBoard::new(Some(NOMINAL));
        q.step(&estimate(0.001));
        q.named(&NamedChange::undetermined(5.0), now);
        assert_eq!(q.status(&heard_now(), [0; 4], &p, now).level, Level::Ok);
    }

    #[test]
    fn a_silent_stream_warns() {
        let p = LiveParams::default();
        let mut b = StatusBoard::new(Some(NOMINAL));
        b.step(&estimate(0.001));
        let then = Instant::now();
        let t = Traffic {
            heard: [Some(then), Some(then), None, None, None],
            ..Traffic::default()
        };
        let now = then + Duration::from_secs_f64(p.silence_s + 1.0);
        let s = b.status(&t, [0; 4], &p, now);
        assert_eq!(s.level, Level::Warn);
        assert!(s.message.starts_with("no scans for 4.0 s"), "{}", s.message);
    }
}
