//! Which guess a pair starts from: the given prior (the odometry increment),
//! the constant-velocity guess from the last valid motion, or the identity;
//! and when a given prior that froze is replaced by the constant-velocity
//! guess (a substitution), also for the jump with which it catches up.

use super::PriorSource;
use crate::geom::{self, Pose2};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// Age (s) beyond which the last valid velocity says nothing about the
/// plausibility of a given prior.
const MAX_VELOCITY_AGE: f64 = 1.0;
/// Odometry increments below this (m, rad) are a robot standing still (or a
/// frozen reading).
const STANDING: f64 = 1e-9;
/// Longest run (s) of pairs whose given prior is replaced by the
/// constant-velocity guess; beyond it the given prior is trusted again.
const MAX_SUBSTITUTION: f64 = 2.0;

/// How fast the robot's speed can change. Units: m, rad, s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PriorSettings {
    /// Largest plausible deceleration (m/s²) from the last valid velocity.
    pub max_accel: f64,
    /// Same for the turn rate (rad/s²).
    pub max_angular_accel: f64,
    /// Slack on a change of speed × dt (m).
    pub speed_slack: f64,
    /// Slack on a change of turn rate × dt (rad).
    pub turn_slack: f64,
}

impl Default for PriorSettings {
    fn default() -> Self {
        Self {
            max_accel: 1.5,
            max_angular_accel: 3.0,
            speed_slack: 0.01,
            turn_slack: 0.01,
        }
    }
}

/// The last valid motion, as the constant-velocity model's velocity.
#[derive(Debug, Clone, Copy)]
pub struct Velocity {
    /// Conditioning of its match (see `MatchInfo::conditioning`).
    pub cond: f64,
    /// Whether its scans agreed with their prior term, or kept the previous
    /// velocity ([`PriorSelector::steady`]): a single match against the
    /// odometry that jumps in speed (a wrong match) does not speak for the
    /// next pair's prior centre.
    pub agreed: bool,
    /// The motion (`prev_from_cur`).
    pub inc: Pose2,
    /// Its duration (s).
    pub dt: f64,
    /// Its end stamp (s).
    pub t1: f64,
    /// Its covariance (m², rad²).
    pub cov: Matrix3<f64>,
}

/// Chooses each pair's initial guess from the given prior and the last
/// valid velocity.
#[derive(Debug, Clone, Default)]
pub struct PriorSelector {
    set: PriorSettings,
    /// The last valid motion.
    velocity: Option<Velocity>,
    /// Start stamp (s) of the current run of pairs whose given prior was
    /// replaced by the constant-velocity guess.
    substituted_since: Option<f64>,
}

impl PriorSelector {
    /// A selector with no velocity yet.
    pub fn new(set: PriorSettings) -> Self {
        Self {
            set,
            ..Default::default()
        }
    }

    /// The last valid motion, if any.
    pub fn velocity(&self) -> Option<Velocity> {
        self.velocity
    }

    /// Records a valid motion as the velocity of the next guesses.
    pub fn record(&mut self, v: Velocity) {
        self.velocity = Some(v);
    }

    /// The previous valid motion's velocity carried over `dt` (s), if any.
    pub fn constant_velocity(&self, dt: f64) -> Option<Pose2> {
        let Velocity { inc, dt: vdt, .. } = self.velocity?;
        if !(dt.is_finite() && dt > 0.0) {
            return None;
        }
        let (ds, dth) = geom::arc_of_increment(&inc);
        Some(geom::arc_increment(ds / vdt, dth / vdt, dt))
    }

    /// The initial guess of a pair ending at `t1` (s, `dt` long) and where it
    /// comes from: the given prior, unless it is implausible against the last
    /// motion (then the constant-velocity guess `cv` is substituted); else
    /// `cv`; else the identity.
    pub fn choose(
        &self,
        given: Option<Pose2>,
        cv: Option<Pose2>,
        t1: f64,
        dt: f64,
    ) -> (Pose2, PriorSource) {
        match (given, cv) {
            (Some(p), Some(cv)) if !self.plausible_change(&p, t1, dt) => {
                (cv, PriorSource::Substituted)
            }
            (Some(p), _) => (p, PriorSource::Given),
            (None, Some(cv)) => (cv, PriorSource::ConstantVelocity),
            _ => (Pose2::identity(), PriorSource::None),
        }
    }

    /// Keeps track of the run of substituted pairs: one starting at `t0` (s)
    /// opens or continues it, any other pair of positive `dt` ends it.
    pub fn note(&mut self, source: PriorSource, t0: f64, dt: f64) {
        if source == PriorSource::Substituted {
            self.substituted_since.get_or_insert(t0);
        } else if dt > 0.0 {
            self.substituted_since = None;
        }
    }

    /// Whether a given prior over the pair ending at `t1` (s, `dt` long) is
    /// plausible against the last valid motion. Implausible: an odometry
    /// that stands still (a frozen reading) while the robot was moving faster
    /// than it could stop in the time since (`max_accel`,
    /// `max_angular_accel`, plus the slacks); and, after such a freeze, any
    /// increment beyond that change of speed (the odometry catching up in a
    /// jump). Only a standing odometry opens such a run: where stamps are
    /// irregular (bursts), speed changes between pairs say little, and the
    /// odometry increment stays the better guess. Always plausible without a
    /// recent velocity, and once `MAX_SUBSTITUTION` s of pairs in a row were
    /// replaced (the scans, not the odometry, may be what went wrong).
    pub fn plausible_change(&self, prior: &Pose2, t1: f64, dt: f64) -> bool {
        let p = &self.set;
        let Some(Velocity {
            inc,
            dt: vdt,
            t1: vt1,
            cov,
            ..
        }) = self.velocity
        else {
            return true;
        };
        let elapsed = (t1 - 0.5 * dt) - (vt1 - 0.5 * vdt);
        let stale = self
            .substituted_since
            .is_some_and(|s| t1 - s > MAX_SUBSTITUTION);
        if !(elapsed > 0.0 && elapsed <= MAX_VELOCITY_AGE && dt > 0.0) || stale {
            return true;
        }
        if !standing(prior) && self.substituted_since.is_none() {
            return true;
        }
        let (ds, dth) = geom::arc_of_increment(prior);
        let (cs, cth) = geom::arc_of_increment(&inc);
        // The velocity's own uncertainty (3σ), carried over dt: large where
        // it was measured over a short pair.
        let scale = dt / vdt;
        let st = 3.0 * scale * (cov[(0, 0)] + cov[(1, 1)]).max(0.0).sqrt();
        let sr = 3.0 * scale * cov[(2, 2)].max(0.0).sqrt();
        (ds - cs * scale).abs() <= p.max_accel * elapsed * dt + st + p.speed_slack
            && (dth - cth * scale).abs() <= p.max_angular_accel * elapsed * dt + sr + p.turn_slack
    }

    /// Whether a matched `motion` over `dt` (s) keeps the speed of the last
    /// valid motion within what the robot can change in between
    /// (`max_accel`, plus `speed_slack` per pair): a sustained contradiction
    /// of the odometry (a reversal it missed) does, a single wrong match
    /// does not.
    pub fn steady(&self, motion: &Pose2, dt: f64) -> bool {
        let Some(v) = self.velocity else {
            return false;
        };
        let (a, _) = geom::arc_of_increment(&v.inc);
        let (b, _) = geom::arc_of_increment(motion);
        let p = &self.set;
        let slack = p.max_accel * 0.5 * (dt + v.dt) + p.speed_slack / dt.min(v.dt);
        (b / dt - a / v.dt).abs() <= slack
    }
}

/// An increment of a robot standing still (or of a frozen reading).
pub fn standing(p: &Pose2) -> bool {
    let (ds, dth) = geom::arc_of_increment(p);
    ds.abs() < STANDING && dth.abs() < STANDING
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A selector that last drove `speed` m/s straight for 0.1 s, ending at 1 s.
    fn driving(speed: f64) -> PriorSelector {
        let mut s = PriorSelector::new(PriorSettings::default());
        s.record(Velocity {
            cond: 0.5,
            agreed: true,
            inc: geom::pose(0.1 * speed, 0.0, 0.0),
            dt: 0.1,
            t1: 1.0,
            cov: Matrix3::zeros(),
        });
        s
    }

    #[test]
    fn constant_velocity_carries_the_last_motion_over_dt() {
        let s = PriorSelector::default();
        assert!(s.constant_velocity(0.1).is_none());
        let s = driving(1.0);
        let g = geom::xyt(&s.constant_velocity(0.2).unwrap());
        assert!((g[0] - 0.2).abs() < 1e-12 && g[1].abs() < 1e-12, "{g:?}");
        assert!(s.constant_velocity(0.0).is_none());
        assert!(s.constant_velocity(f64::NAN).is_none());
    }

    #[test]
    fn the_given_prior_wins_unless_it_froze_while_the_robot_drove() {
        let odo = geom::pose(0.1, 0.0, 0.0);
        let still = Pose2::identity();
        // Nothing known: the given prior, else the identity.
        let s = PriorSelector::default();
        assert_eq!(s.choose(Some(odo), None, 1.1, 0.1).1, PriorSource::Given);
        assert_eq!(s.choose(None, None, 1.1, 0.1), (still, PriorSource::None));
        // Driving at 1 m/s: no prior gives the guess; a moving odometry stays.
        let s = driving(1.0);
        let cv = s.constant_velocity(0.1);
        assert_eq!(
            s.choose(None, cv, 1.1, 0.1).1,
            PriorSource::ConstantVelocity
        );
        assert_eq!(s.choose(Some(odo), cv, 1.1, 0.1).1, PriorSource::Given);
        // A standing odometry: 1 m/s cannot stop within 0.1 s at 1.5 m/s².
        assert_eq!(
            s.choose(Some(still), cv, 1.1, 0.1).1,
            PriorSource::Substituted
        );
        // Crawling at 1 cm/s it could, and a velocity 2 s old says nothing.
        let slow = driving(0.01);
        assert!(slow.plausible_change(&still, 1.1, 0.1));
        assert!(s.plausible_change(&still, 3.0, 0.1));
    }

    #[test]
    fn a_substitution_run_catches_the_jump_and_ends_after_two_seconds() {
        let mut s = driving(1.0);
        s.note(PriorSource::Substituted, 1.0, 0.1);
        // The odometry catching up in one jump (1 m in 0.1 s).
        let jump = geom::pose(1.0, 0.0, 0.0);
        assert!(!s.plausible_change(&jump, 1.1, 0.1));
        // The same increment without a run is trusted.
        assert!(driving(1.0).plausible_change(&jump, 1.1, 0.1));
        // A run older than MAX_SUBSTITUTION: trusted again.
        s.velocity.as_mut().unwrap().t1 = 3.05;
        assert!(s.plausible_change(&jump, 3.1, 0.1));
        // A pair of positive dt that is not substituted ends the run; a
        // duplicate stamp does not.
        s.note(PriorSource::Given, 3.0, 0.0);
        assert!(s.substituted_since.is_some());
        s.note(PriorSource::Given, 3.0, 0.1);
        assert!(s.substituted_since.is_none());
    }

    #[test]
    fn steady_speeds_and_standing_increments() {
        let s = driving(1.0);
        assert!(s.steady(&geom::pose(0.11, 0.0, 0.0), 0.1));
        assert!(!s.steady(&geom::pose(-0.1, 0.0, 0.0), 0.1));
        assert!(!PriorSelector::default().steady(&geom::pose(0.1, 0.0, 0.0), 0.1));
        assert!(standing(&Pose2::identity()));
        assert!(!standing(&geom::pose(0.0, 0.0, 1e-6)));
    }
}
