//! Which registration a pair is measured by when the first one is not
//! enough: again without the prior term when the scans contradict it, the
//! given prior against the guess substituted for it, the motion guesses
//! after a failure from a given prior; and the motion a failed pair is
//! placed by (the fallback).

use super::acceptance::Acceptance;
use super::attempt::Attempt;
use super::prior::standing;
use super::split::CONFLICT;
use super::PriorSource;
use crate::geom::{self, Pose2};
use crate::icp::limits::SpeedLimits;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// What a prior the robot could have driven is. Units: m, rad, s.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RetrySettings {
    /// A prior within these bounds a retry must agree with, and a
    /// substituted guess gives way to on failure.
    pub limits: SpeedLimits,
}

/// The guesses a pair may be matched from.
#[derive(Debug, Clone, Copy)]
pub struct Guesses {
    /// The chosen initial guess (the prior term's centre when it holds one).
    pub prior: Pose2,
    /// Where it came from.
    pub source: PriorSource,
    /// The given prior `prior` was substituted for, if it was.
    pub given: Option<Pose2>,
    /// The constant-velocity guess.
    pub cv: Option<Pose2>,
    /// The previous pair's increment as it was (where the stamps bunch up,
    /// velocity × dt is not a guess).
    pub last: Option<Pose2>,
}

/// Chooses among a pair's registrations.
#[derive(Debug, Clone, Copy, Default)]
pub struct Retry {
    set: RetrySettings,
}

impl Retry {
    /// A policy with these settings.
    pub fn new(set: RetrySettings) -> Self {
        Self { set }
    }

    /// The registration a pair `dt` s long is measured by, and the first
    /// registration's conflict with the prior term. `attempt(guess, source,
    /// hold)` registers from `guess` with the prior term on or off.
    pub fn best(
        &self,
        g: &Guesses,
        dt: f64,
        accept: &Acceptance,
        mut attempt: impl FnMut(&Pose2, PriorSource, bool) -> Attempt,
    ) -> (Attempt, f64) {
        // A prior the robot could have driven in dt still bounds the answer
        // of a retry (it must agree with it too); one it could not (odometry
        // that froze, then caught up in one jump) does not.
        let possible = self.possible(&g.prior, dt);
        let mut best = attempt(&g.prior, g.source, g.source.holds());
        let conflict = best.conflict;
        // Scans that contradict the prior term (odometry that froze, slipped
        // or lost the sign of a reversal) beyond `CONFLICT` are matched again
        // without it, from the same guess: the scans, not the odometry, are
        // what the motion is measured by.
        if best.failure.is_none() && best.conflict > CONFLICT {
            let alt = attempt(&g.prior, g.source, false);
            if alt.failure.is_none() {
                best = alt;
            }
        }
        // A substituted guess competes with the given prior it replaced: the
        // acceleration test cannot tell a frozen odometry from a real swerve,
        // the scans can (the match with more inliers is kept).
        if let Some(given) = g.given {
            let alt = attempt(&given, PriorSource::Given, PriorSource::Given.holds());
            if alt.improves_on(&best) {
                best = alt;
            }
        }
        if g.source == PriorSource::Given && best.failure.is_some() {
            best = retry_from_guesses(best, g, possible, accept, &mut attempt);
        }
        (best, conflict)
    }

    /// The motion a failed pair is placed by: the prior it was matched from,
    /// except that a substituted constant-velocity guess gives way to the
    /// given prior it replaced unless that stood still or is beyond the
    /// speed limits (no scan evidence either way: the odometry stays the
    /// better guess).
    pub fn fallback(&self, prior: &Pose2, given: Option<Pose2>, dt: f64) -> Pose2 {
        match given {
            Some(g) if !standing(&g) && self.possible(&g, dt) => g,
            _ => *prior,
        }
    }

    /// Whether the robot could have driven `prior` in `dt` s.
    fn possible(&self, prior: &Pose2, dt: f64) -> bool {
        self.set
            .limits
            .within(geom::xyt(prior), &Matrix3::zeros(), dt)
    }
}

/// A failed match from a given prior, tried again from the
/// constant-velocity guess and from the previous pair's increment. With a
/// `possible` prior, a retry must agree with it. The retry with more inliers
/// is kept.
fn retry_from_guesses(
    mut best: Attempt,
    g: &Guesses,
    possible: bool,
    accept: &Acceptance,
    attempt: &mut impl FnMut(&Pose2, PriorSource, bool) -> Attempt,
) -> Attempt {
    let guesses = [g.cv, g.last];
    for (k, guess) in guesses.iter().enumerate() {
        let Some(guess) = guess else { continue };
        if k == 1 && guesses[0].is_some_and(|cv| close(&cv, guess)) {
            continue;
        }
        let cv = PriorSource::ConstantVelocity;
        let alt = attempt(guess, cv, cv.holds());
        let admissible = !possible || accept.agrees_with_prior(&alt.motion, &g.prior, g.source);
        if admissible && alt.improves_on(&best) {
            best = alt;
        }
    }
    best
}

/// Two guesses close enough (1 cm, 0.5°) to converge alike.
fn close(a: &Pose2, b: &Pose2) -> bool {
    let [x, y, t] = geom::xyt(&geom::between(a, b));
    x.hypot(y) < 0.01 && t.abs() < 0.01
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::icp::register::Registration;
    use crate::motion::PairFailure;

    /// A hand-made registration that moved by `motion` with `inliers`.
    fn made(
        motion: &Pose2,
        source: PriorSource,
        inliers: usize,
        ok: bool,
        conflict: f64,
    ) -> Attempt {
        let reg = Registration {
            pose: geom::xyt(motion),
            iterations: 3,
            converged: ok,
            inliers,
            uncertainty: None,
        };
        let failure = (!ok).then_some(PairFailure::NotConverged);
        let (cov, split, init) = (Matrix3::zeros(), None, *motion);
        let ref_from_cur = *motion;
        let motion = *motion;
        Attempt {
            reg,
            ref_from_cur,
            cov,
            motion,
            failure,
            init,
            source,
            conflict,
            split,
        }
    }

    fn guesses(prior: Pose2, source: PriorSource) -> Guesses {
        let (given, cv, last) = (None, None, None);
        Guesses {
            prior,
            source,
            given,
            cv,
            last,
        }
    }

    #[test]
    fn the_first_match_stands_unless_it_contradicts_its_prior_term() {
        let (r, a, p) = (
            Retry::default(),
            Acceptance::default(),
            geom::pose(0.1, 0.0, 0.0),
        );
        let mut calls = Vec::new();
        let (best, c) = r.best(&guesses(p, PriorSource::Given), 0.1, &a, |g, s, hold| {
            calls.push(hold);
            made(g, s, 100, true, 1.0)
        });
        assert_eq!((calls, c, best.reg.inliers), (vec![true], 1.0, 100));
        // Beyond the χ² bound: matched again without the term, which is kept;
        // the conflict reported is the first match's.
        let mut calls = Vec::new();
        let (best, c) = r.best(&guesses(p, PriorSource::Given), 0.1, &a, |g, s, hold| {
            calls.push(hold);
            made(g, s, if hold { 100 } else { 90 }, true, 20.0)
        });
        assert_eq!((calls, c, best.reg.inliers), (vec![true, false], 20.0, 90));
    }

    #[test]
    fn a_substitute_competes_with_the_given_prior_it_replaced() {
        let (r, a) = (Retry::default(), Acceptance::default());
        let cv = geom::pose(0.1, 0.0, 0.0);
        let mut g = guesses(cv, PriorSource::Substituted);
        g.given = Some(Pose2::identity());
        for (given_inliers, winner) in [(120, PriorSource::Given), (80, PriorSource::Substituted)] {
            let (best, _) = r.best(&g, 0.1, &a, |g, s, _| {
                made(
                    g,
                    s,
                    if s == PriorSource::Given {
                        given_inliers
                    } else {
                        100
                    },
                    true,
                    0.0,
                )
            });
            assert_eq!(best.source, winner);
        }
    }

    #[test]
    fn a_failed_given_prior_is_retried_from_the_motion_guesses() {
        let (r, a) = (Retry::default(), Acceptance::default());
        let odo = geom::pose(0.1, 0.0, 0.0);
        let mut g = guesses(odo, PriorSource::Given);
        (g.cv, g.last) = (
            Some(geom::pose(0.2, 0.0, 0.0)),
            Some(geom::pose(0.205, 0.0, 0.0)),
        );
        // The last increment is within 1 cm of the guess: tried once.
        let mut tried = Vec::new();
        let (best, _) = r.best(&g, 0.1, &a, |x, s, _| {
            tried.push(s);
            made(x, s, 100, s != PriorSource::Given, 0.0)
        });
        assert_eq!(tried, [PriorSource::Given, PriorSource::ConstantVelocity]);
        assert!(best.failure.is_none() && best.motion == g.cv.unwrap());
        // A retry must agree with a prior the robot could have driven...
        g.last = Some(geom::pose(0.5, 0.0, 0.0));
        let far = |x: &Pose2, s, _| {
            made(
                x,
                s,
                100,
                s != PriorSource::Given && x != &g.cv.unwrap(),
                0.0,
            )
        };
        assert!(r.best(&g, 0.1, &a, far).0.failure.is_some());
        // ...not with one it could not (3 m in 0.1 s).
        g.prior = geom::pose(3.0, 0.0, 0.0);
        let far = |x: &Pose2, s, _| {
            made(
                x,
                s,
                100,
                s != PriorSource::Given && x != &g.cv.unwrap(),
                0.0,
            )
        };
        let best = r.best(&g, 0.1, &a, far).0;
        assert!(best.failure.is_none() && best.motion == g.last.unwrap());
    }

    #[test]
    fn a_failed_substitute_falls_back_to_a_moving_possible_given_prior() {
        let r = Retry::default();
        let (cv, odo) = (geom::pose(0.1, 0.0, 0.0), geom::pose(0.12, 0.0, 0.0));
        assert_eq!(r.fallback(&cv, Some(odo), 0.1), odo);
        assert_eq!(r.fallback(&cv, None, 0.1), cv);
        assert_eq!(r.fallback(&cv, Some(Pose2::identity()), 0.1), cv);
        assert_eq!(r.fallback(&cv, Some(geom::pose(1.0, 0.0, 0.0)), 0.1), cv);
    }
}
