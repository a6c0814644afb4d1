//! The streaming scan matcher: feed scans in time order, get the motion of the
//! robot base between each scan and the previous one.
//!
//! Each pair runs through named components, each with its own settings:
//! - `prior`: which guess the pair starts from (the given prior, the
//!   constant-velocity guess, the identity) and when a frozen odometry is
//!   replaced; `prior_term`: where the registration's weak prior term is
//!   centred and how tight it is, learned from the matched motions;
//! - `source`: the scan's points, deskewed and thinned, with their normals;
//! - `attempt`: one registration from one guess and its verdict;
//! - `retry`: which of several registrations the pair is measured by, and
//!   the motion a failed pair is placed by;
//! - `acceptance`: the gates of a pair and the motion of a failed one;
//!   `split`: what the scan measured and what the prior term supplied;
//! - `local_map`: the reference (previous scan or keyframes), kept across
//!   a few failed scans.

mod acceptance;
mod attempt;
mod info;
mod local_map;
mod prior;
mod prior_term;
mod retry;
mod settings;
mod source;
mod split;

pub use info::{MatchInfo, PriorSource};

use super::params::{IcpParams, IcpParamsError};
use super::preprocess::Preprocessor;
use super::register::RegisterSettings;
use super::threshold::AdaptiveThreshold;
use crate::geom::{self, Pose2};
use crate::motion::{Motion, PairFailure};
use crate::scan::LaserScan;
use acceptance::Acceptance;
use attempt::{Attempt, Inputs};
use local_map::LocalMap;
use prior::{PriorSelector, Velocity};
use prior_term::PriorTerm;
use retry::{Guesses, Retry};
use settings::{
    accept_settings, local_map_settings, prior_settings, prior_term_settings, register_settings,
    retry_settings, source_settings,
};
use source::Source;
use split::CONFLICT;

/// Matches each scan against the previous one (or a local map of recent
/// keyframes with `IcpParams::local_map`), in the robot base frame.
pub struct ScanMatcher {
    params: IcpParams,
    pre: Preprocessor,
    threshold: AdaptiveThreshold,
    /// The registration's settings; gate and prior term set per attempt.
    register: RegisterSettings,
    priors: PriorSelector,
    term: PriorTerm,
    source: Source,
    retry: Retry,
    acceptance: Acceptance,
    map: LocalMap,
    /// Stamp (s) and beam count of the last scan.
    last: Option<(f64, usize)>,
    scratch: super::register::Scratch,
    info: MatchInfo,
}

impl ScanMatcher {
    /// A matcher for a laser mounted at `base_from_laser` (from /tf_static or
    /// the robot config). Fails on parameters that cannot work.
    pub fn new(params: IcpParams, base_from_laser: Pose2) -> Result<Self, IcpParamsError> {
        params.validate()?;
        let p = &params;
        Ok(Self {
            pre: Preprocessor::new(
                base_from_laser,
                p.min_range,
                p.max_range,
                p.gap_factor,
                p.max_gap,
            ),
            threshold: AdaptiveThreshold::new(
                p.initial_threshold,
                p.min_threshold,
                p.max_threshold,
                p.min_motion,
                p.threshold_range,
            ),
            register: register_settings(p),
            priors: PriorSelector::new(prior_settings(p)),
            term: PriorTerm::new(prior_term_settings(p)),
            source: Source::new(source_settings(p)),
            retry: Retry::new(retry_settings(p)),
            acceptance: Acceptance::new(accept_settings(p)),
            map: LocalMap::new(local_map_settings(p)),
            last: None,
            scratch: Default::default(),
            info: MatchInfo::default(),
            params,
        })
    }

    /// The parameters in use.
    pub fn params(&self) -> &IcpParams {
        &self.params
    }

    /// Diagnostics of the last pair.
    pub fn info(&self) -> &MatchInfo {
        &self.info
    }

    /// Adds the next scan. `prior` is the expected motion of the base since
    /// the previous scan (`prev_from_cur`, e.g. the wheel-odometry increment);
    /// without it the previous velocity × dt is used, else the identity.
    /// Returns `None` for the first scan, else the motion since the previous
    /// scan. A failed pair carries its reason in `failure` and, as its motion,
    /// the prior (the best estimate left), with a covariance as wide as the
    /// plausibility gates.
    pub fn push(&mut self, scan: &LaserScan, prior: Option<Pose2>) -> Option<Motion> {
        let t1 = scan.stamp;
        let Some((t0, beams0)) = self.last else {
            self.prepare_scan(scan, None);
            self.map
                .start_reference(&self.source.cur, Pose2::identity());
            self.last = Some((t1, scan.ranges.len()));
            return None;
        };
        let dt = t1 - t0;
        let (prior, source, given) = self.guess(prior, t0, t1);
        if !(dt.is_finite() && dt > 0.0) {
            // Out of order or duplicate: the scan is not used as a reference.
            let bad = PairFailure::BadTime;
            return Some(self.acceptance.failed(t0, t1, &Pose2::identity(), bad));
        }
        self.last = Some((t1, scan.ranges.len()));
        self.prepare_scan(scan, self.source.twist(&prior, source, dt));
        let given = given.filter(|_| source == PriorSource::Substituted);
        let points = self.source.cur.pts.len();
        let changed = scan.ranges.len() != beams0;
        let empty = self.map.reference().is_empty();
        if let Some(f) = self.acceptance.scan_failure(points, changed, empty) {
            // Not matched: placed by the fallback of the prior.
            let prior = self.retry.fallback(&prior, given, dt);
            self.map.skip(&self.source.cur, &prior);
            return Some(self.acceptance.failed(t0, t1, &prior, f));
        }
        Some(self.match_pair(t0, t1, &prior, source, given))
    }

    /// The guess of the pair from `t0` to `t1` (s) and where it came from
    /// (`prior`), centred as the prior term is, and the given prior when it
    /// is finite. Starts the pair's diagnostics.
    fn guess(
        &mut self,
        prior: Option<Pose2>,
        t0: f64,
        t1: f64,
    ) -> (Pose2, PriorSource, Option<Pose2>) {
        let dt = t1 - t0;
        let given = prior.filter(pose_finite);
        let cv = self.priors.constant_velocity(dt);
        let (prior, source) = self.priors.choose(given, cv, t1, dt);
        let last = self.priors.velocity();
        let prior = self.term.centre(prior, given, cv, source, last);
        self.priors.note(source, t0, dt);
        self.info = MatchInfo {
            prior_source: source,
            ..Default::default()
        };
        (prior, source, given)
    }

    /// Turns the scan into base-frame points, deskewed by `twist` (the
    /// base's velocity during the sweep) when there is one, and fits their
    /// lines.
    fn prepare_scan(&mut self, scan: &LaserScan, twist: Option<(f64, f64)>) {
        self.pre.points(scan, twist, &mut self.source.cur);
        self.map.set_own(&self.source.cur);
    }

    /// Matches the prepared scan from `prior`; `given` is the caller's prior
    /// when `prior` was substituted for it, tried too.
    fn match_pair(
        &mut self,
        t0: f64,
        t1: f64,
        prior: &Pose2,
        source: PriorSource,
        given: Option<Pose2>,
    ) -> Motion {
        self.source.prepare(&mut self.pre, self.map.own());
        let dt = t1 - t0;
        let guesses = Guesses {
            prior: *prior,
            source,
            given,
            cv: self.priors.constant_velocity(dt),
            last: self.priors.velocity().map(|v| v.inc),
        };
        let (retry, acceptance) = (self.retry, self.acceptance);
        let (best, conflict) = retry.best(&guesses, dt, &acceptance, |g, s, hold| {
            self.attempt(g, s, hold)
        });
        self.info.prior_conflict = conflict;
        self.info.prior_source = best.source;
        if let Some(u) = best.reg.uncertainty {
            self.info.conditioning = u.conditioning;
            self.info.weak_direction = u.weak_direction;
            self.info.rms = u.rms;
        }
        if let Some(f) = best.failure {
            let prior = &self.retry.fallback(prior, given, dt);
            let mut m = self.acceptance.failed(t0, t1, prior, f);
            m.iterations = best.reg.iterations;
            m.inliers = best.reg.inliers as u32;
            self.map.bridge(&self.source.cur, prior, m.cov);
            return m;
        }
        self.take(t0, t1, best)
    }

    /// One registration from `prior` (of `source`), the prior term on
    /// (`hold`) or off.
    fn attempt(&mut self, prior: &Pose2, source: PriorSource, hold: bool) -> Attempt {
        let set = RegisterSettings {
            threshold: self.threshold.threshold(),
            prior_precision: self.term.precision(source, hold),
            ..self.register
        };
        self.info.threshold = set.threshold;
        self.info.source_points = self.source.src.len();
        self.info.reference_points = self.map.reference().len();
        let inp = Inputs {
            reference: self.map.reference(),
            src: &self.source.src,
            normals: &self.source.normals,
            ref_from_last: self.map.ref_from_last(),
            accept: &self.acceptance,
        };
        attempt::attempt(&inp, prior, source, &set, &mut self.scratch)
    }

    /// A successful match: its covariance, the models it trains (not after
    /// failed scans), the next reference. A match the robot could not have
    /// driven in dt is kept for the trajectory but flagged, so it never
    /// becomes a velocity observation.
    fn take(&mut self, t0: f64, t1: f64, best: Attempt) -> Motion {
        let last = self.map.ref_from_last();
        let split = best.split.map(|s| split::motion_split(&last, s));
        let Attempt {
            reg,
            ref_from_cur,
            cov: own_cov,
            motion,
            init,
            source,
            ..
        } = best;
        let dt = t1 - t0;
        let u = reg.uncertainty.expect("checked by attempt");
        let cov = self.map.motion_cov(&ref_from_cur, &own_cov);
        let time_ok = self.acceptance.within_limits(&motion, &cov, dt);
        let bridged = self.map.bridged();
        if !bridged {
            self.threshold.update(&geom::between(&init, &motion));
            if time_ok {
                self.term.learn(&motion, source, u.conditioning);
                let agreed =
                    self.info.prior_conflict <= CONFLICT || self.priors.steady(&motion, dt);
                self.priors.record(Velocity {
                    cond: u.conditioning,
                    agreed,
                    inc: motion,
                    dt,
                    t1,
                    cov,
                });
            }
        }
        self.map.advance(&self.source.cur, ref_from_cur, own_cov);
        Motion {
            iterations: reg.iterations,
            inliers: reg.inliers as u32,
            failure: self.acceptance.flag(time_ok, bridged),
            split,
            ..Motion::from_increment(t0, t1, &motion, cov)
        }
    }
}

fn pose_finite(p: &Pose2) -> bool {
    geom::xyt(p).iter().all(|v| v.is_finite())
}
