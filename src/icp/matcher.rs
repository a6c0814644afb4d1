//! The streaming scan matcher: feed scans in time order, get the motion of the
//! robot base between each scan and the previous one.

use super::params::{IcpParams, IcpParamsError};
use super::preprocess::{Preprocessor, ScanPoints};
use super::prior_model::PriorModel;
use super::reference::Reference;
use super::register::{register, RegisterSettings, Registration, Scratch};
use super::threshold::AdaptiveThreshold;
use crate::geom::{self, Pose2};
use crate::motion::{InfoSplit, Motion, PairFailure};
use crate::scan::LaserScan;
use nalgebra::{Matrix3, Vector3};
use std::collections::VecDeque;

/// Where the initial guess of a pair came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PriorSource {
    /// The caller's prior (e.g. the wheel-odometry increment).
    Given,
    /// The previous valid motion's velocity times dt.
    ConstantVelocity,
    /// The constant-velocity guess in place of a given prior that stood
    /// still while the robot could not have stopped that fast
    /// (`max_accel`, `max_angular_accel`), or that then caught up in one
    /// jump: a frozen odometry. The prior term holds the loose directions at
    /// it as it would at the given prior.
    Substituted,
    /// No information: identity.
    #[default]
    None,
}

/// Diagnostics of the last pair, beside the [`Motion`] itself.
#[derive(Debug, Clone, Default)]
pub struct MatchInfo {
    /// Where the initial guess came from.
    pub prior_source: PriorSource,
    /// Correspondence gate used (m).
    pub threshold: f64,
    /// Source points after downsampling.
    pub source_points: usize,
    /// Reference points.
    pub reference_points: usize,
    /// Smallest / largest eigenvalue of the information (θ scaled to metres
    /// by the RMS range); small = degenerate.
    pub conditioning: f64,
    /// Direction `(x, y, θ·L)` the geometry constrains least (unit vector).
    pub weak_direction: [f64; 3],
    /// Weighted RMS residual along the surface normals (m).
    pub rms: f64,
    /// Squared Mahalanobis distance between the prior term's centre and the
    /// scan-only estimate of the first registration (0 without a prior
    /// term); beyond the χ² 99.9 % quantile the pair was matched again
    /// without the prior term.
    pub prior_conflict: f64,
}

/// Matches each scan against the previous one (or a local map of recent
/// keyframes with `IcpParams::local_map`), in the robot base frame.
pub struct ScanMatcher {
    params: IcpParams,
    pre: Preprocessor,
    threshold: AdaptiveThreshold,
    reference: Reference,
    /// Pose of the last scan in the reference frame (the reference scan, or
    /// the local map's world frame).
    ref_from_last: Pose2,
    /// Covariance of `ref_from_last` from its registration (local map only).
    last_cov: Matrix3<f64>,
    /// Failed pairs since the last successful match.
    misses: usize,
    last: Option<(f64, usize)>,
    /// Last valid motion, its duration and end stamp (s).
    velocity: Option<Velocity>,
    /// Start stamp (s) of the current run of pairs whose given prior was
    /// replaced by the constant-velocity guess.
    substituted_since: Option<f64>,
    /// The local map's keyframes: pose, and the scan's points and lines
    /// placed in the map frame by it.
    keyframes: VecDeque<(Pose2, Reference)>,
    cur: ScanPoints,
    src: Vec<[f64; 2]>,
    kept: Vec<usize>,
    normals: Vec<[f64; 2]>,
    /// The current scan as a reference (lines, tree): its normals serve the
    /// registration, and it becomes the next pair's reference.
    own: Reference,
    scratch: Scratch,
    info: MatchInfo,
    /// Learned errors of the odometry and constant-velocity predictions.
    model: PriorModel,
    /// The current pair's given prior and constant-velocity guess, for the
    /// model.
    pair_given: Option<Pose2>,
    pair_cv: Option<Pose2>,
    /// The current pair's prior-term translation σ (m).
    pair_sigma: f64,
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
            reference: Reference::new(p.normal_window, p.normal_length).with_search(p.neighbours),
            ref_from_last: Pose2::identity(),
            last_cov: Matrix3::zeros(),
            misses: 0,
            last: None,
            velocity: None,
            substituted_since: None,
            keyframes: VecDeque::new(),
            cur: ScanPoints::default(),
            src: Vec::new(),
            kept: Vec::new(),
            normals: Vec::new(),
            own: Reference::new(p.normal_window, p.normal_length),
            scratch: Scratch::default(),
            info: MatchInfo::default(),
            model: PriorModel::default(),
            pair_given: None,
            pair_cv: None,
            pair_sigma: p.prior_sigma_xy,
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
            self.pre.points(scan, None, &mut self.cur);
            self.set_own();
            self.start_reference(Pose2::identity());
            self.last = Some((t1, scan.ranges.len()));
            return None;
        };
        let dt = t1 - t0;
        let given = prior.filter(pose_finite);
        let cv = self.constant_velocity(dt);
        let (prior, source) = self.choose_prior(given, cv, t1, dt);
        let prior = self.prior_term_centre(prior, given, cv, source);
        if source == PriorSource::Substituted {
            self.substituted_since.get_or_insert(t0);
        } else if dt > 0.0 {
            self.substituted_since = None;
        }
        self.info = MatchInfo {
            prior_source: source,
            ..Default::default()
        };
        if !(dt.is_finite() && dt > 0.0) {
            // Out of order or duplicate: the scan is not used as a reference.
            return Some(self.failed(t0, t1, &Pose2::identity(), PairFailure::BadTime));
        }
        self.last = Some((t1, scan.ranges.len()));
        self.prepare_scan(scan, &prior, source, dt);
        let given = given.filter(|_| source == PriorSource::Substituted);
        if let Some(f) = self.scan_failure(scan.ranges.len() != beams0) {
            return Some(self.skip_pair(t0, t1, &prior, given, f));
        }
        Some(self.match_pair(t0, t1, &prior, source, given))
    }

    /// The initial guess of a pair ending at `t1` (s, `dt` long) and where it
    /// comes from: the given prior, unless it is implausible against the last
    /// motion (then the constant-velocity guess `cv` is substituted); else
    /// `cv`; else the identity.
    fn choose_prior(
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

    /// The prior term's centre: the odometry, or its blend with a
    /// constant-velocity guess from a pair the scans fully measured (see
    /// `PriorModel::prior`). Records the pair's given prior, guess and
    /// prior-term σ for the model and the registration.
    fn prior_term_centre(
        &mut self,
        prior: Pose2,
        given: Option<Pose2>,
        cv: Option<Pose2>,
        source: PriorSource,
    ) -> Pose2 {
        self.pair_given = given.filter(|_| source == PriorSource::Given);
        self.pair_cv = cv;
        self.pair_sigma = self.params.prior_sigma_xy;
        match self.pair_given {
            Some(g) if self.params.prior_blend_rate > 0.0 => {
                let p = &self.params;
                let measured = self
                    .velocity
                    .is_some_and(|v| v.cond >= p.prior_blend_conditioning && v.agreed);
                let [lo, hi] = p.prior_sigma_bounds;
                let cv = cv.as_ref().filter(|_| measured);
                let (c, s) = self.model.prior(&g, cv, p.prior_sigma_xy, (lo, hi));
                self.pair_sigma = s;
                c
            }
            _ => prior,
        }
    }

    /// Turns the scan into base-frame points, deskewed by the prior's twist
    /// over `dt` (s) when it has one, and fits their lines.
    fn prepare_scan(&mut self, scan: &LaserScan, prior: &Pose2, source: PriorSource, dt: f64) {
        let twist = (self.params.deskew && source != PriorSource::None).then(|| {
            let (ds, dth) = geom::arc_of_increment(prior);
            (ds / dt, dth / dt)
        });
        self.pre.points(scan, twist, &mut self.cur);
        self.set_own();
    }

    /// Why the prepared scan cannot be matched, if it cannot: too few points
    /// (in it or in the reference), or a beam count other than the previous
    /// scan's (`beams_changed`).
    fn scan_failure(&self, beams_changed: bool) -> Option<PairFailure> {
        if self.cur.pts.len() < self.params.min_points {
            Some(PairFailure::TooFewPoints)
        } else if beams_changed {
            Some(PairFailure::Inconsistent)
        } else if self.reference.is_empty() {
            Some(PairFailure::TooFewPoints)
        } else {
            None
        }
    }

    /// A pair not matched (`f`): placed by the fallback of `prior`; a usable
    /// scan starts a new reference there.
    fn skip_pair(
        &mut self,
        t0: f64,
        t1: f64,
        prior: &Pose2,
        given: Option<Pose2>,
        f: PairFailure,
    ) -> Motion {
        let prior = self.fallback(prior, given, t1 - t0);
        let m = self.failed(t0, t1, &prior, f);
        let ref_from_cur = self.ref_from_last * prior;
        if self.cur.pts.len() >= self.params.min_points {
            self.start_reference(ref_from_cur);
        } else {
            self.ref_from_last = ref_from_cur;
        }
        m
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
        self.prepare_source();
        let dt = t1 - t0;
        let best = self.best_attempt(prior, source, given, dt);
        self.info.prior_source = best.source;
        if let Some(u) = best.reg.uncertainty {
            self.info.conditioning = u.conditioning;
            self.info.weak_direction = u.weak_direction;
            self.info.rms = u.rms;
        }
        if let Some(f) = best.failure {
            let prior = &self.fallback(prior, given, dt);
            let mut m = self.failed(t0, t1, prior, f);
            m.iterations = best.reg.iterations;
            m.inliers = best.reg.inliers as u32;
            self.bridge(prior, m.cov);
            return m;
        }
        self.accept(t0, t1, best)
    }

    /// The source points of the prepared scan (downsampled) and their own
    /// surface normals (NaN where none was fitted).
    fn prepare_source(&mut self) {
        let p = &self.params;
        self.pre.downsample(
            &self.cur.pts,
            p.beam_stride,
            p.voxel_size,
            &mut self.src,
            &mut self.kept,
        );
        self.normals.clear();
        self.normals.extend(
            self.kept
                .iter()
                .map(|&i| self.own.normal(i).unwrap_or([f64::NAN; 2])),
        );
    }

    /// The registration a pair is measured by: from `prior` with the prior
    /// term, again without it when the scans contradict it, the substituted
    /// guess against the `given` prior it replaced, and after a failure from
    /// a given prior, the motion guesses.
    fn best_attempt(
        &mut self,
        prior: &Pose2,
        source: PriorSource,
        given: Option<Pose2>,
        dt: f64,
    ) -> Attempt {
        // A prior the robot could have driven in dt still bounds the answer
        // of a retry (it must agree with it too); one it could not (odometry
        // that froze, then caught up in one jump) does not.
        let possible = self.within_limits(prior, &Matrix3::zeros(), dt);
        let mut best = self.attempt(prior, source);
        self.info.prior_conflict = best.conflict;
        // Scans that contradict the prior term (odometry that froze, slipped
        // or lost the sign of a reversal) beyond `CONFLICT` are matched again
        // without it, from the same guess: the scans, not the odometry, are
        // what the motion is measured by.
        if best.failure.is_none() && best.conflict > CONFLICT {
            let alt = self.attempt_with(prior, source, false);
            if alt.failure.is_none() {
                best = alt;
            }
        }
        // A substituted guess competes with the given prior it replaced: the
        // acceleration test cannot tell a frozen odometry from a real swerve,
        // the scans can (the match with more inliers is kept).
        if let Some(g) = given {
            let alt = self.attempt(&g, PriorSource::Given);
            if alt.improves_on(&best) {
                best = alt;
            }
        }
        if source == PriorSource::Given && best.failure.is_some() {
            best = self.retry_from_guesses(best, prior, source, possible, dt);
        }
        best
    }

    /// A failed match from a given prior, tried again from the
    /// constant-velocity guess and from the previous pair's increment as it
    /// was (where the stamps bunch up, velocity × dt is not a guess). With a
    /// `possible` prior, a retry must agree with it. The retry with more
    /// inliers is kept.
    fn retry_from_guesses(
        &mut self,
        mut best: Attempt,
        prior: &Pose2,
        source: PriorSource,
        possible: bool,
        dt: f64,
    ) -> Attempt {
        let guesses = [self.constant_velocity(dt), self.velocity.map(|v| v.inc)];
        for (k, guess) in guesses.iter().enumerate() {
            let Some(g) = guess else { continue };
            if k == 1 && guesses[0].is_some_and(|cv| close(&cv, g)) {
                continue;
            }
            let alt = self.attempt(g, PriorSource::ConstantVelocity);
            let admissible = !possible || self.agrees_with_prior(&alt.motion, prior, source);
            if admissible && alt.improves_on(&best) {
                best = alt;
            }
        }
        best
    }

    /// A successful match: its covariance, the error models it trains (not
    /// after failed scans), the next reference. A geometrically sound match
    /// that the robot could not have driven in dt (bursts of scans stamped
    /// milliseconds apart) means the stamps are wrong, not the geometry: the
    /// motion is kept for the trajectory but flagged, so it never becomes a
    /// velocity observation.
    fn accept(&mut self, t0: f64, t1: f64, best: Attempt) -> Motion {
        let split = best.split.map(|s| self.motion_split(s));
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
        let cov = if self.params.local_map {
            // motion = inv(W_last) W_cur, both registered against the map.
            let (ja, jb) = between_jacobians(&self.ref_from_last, &ref_from_cur);
            ja * self.last_cov * ja.transpose() + jb * own_cov * jb.transpose()
        } else {
            own_cov
        };
        let time_ok = self.within_limits(&motion, &cov, dt);
        let bridged = self.misses > 0;
        if !bridged {
            self.threshold.update(&geom::between(&init, &motion));
            if time_ok {
                self.learn(&motion, source, u.conditioning);
                let agreed = self.info.prior_conflict <= CONFLICT || self.steady(&motion, dt);
                self.velocity = Some(Velocity {
                    cond: u.conditioning,
                    agreed,
                    inc: motion,
                    dt,
                    t1,
                    cov,
                });
            }
        }
        self.advance(ref_from_cur, own_cov);
        Motion {
            iterations: reg.iterations,
            inliers: reg.inliers as u32,
            failure: if !time_ok {
                Some(PairFailure::BadTime)
            } else if bridged {
                Some(PairFailure::Bridged)
            } else {
                None
            },
            split,
            ..Motion::from_increment(t0, t1, &motion, cov)
        }
    }

    /// The information split of the motion from the last scan to a pose
    /// registered in the reference frame, given that pose's scan-only
    /// estimate and `K` there: the scan-only motion from the last pose, and
    /// `K` turned into the base frame at the last scan.
    fn motion_split(&self, (scan_pose, k): ([f64; 3], Matrix3<f64>)) -> InfoSplit {
        let own = geom::pose(scan_pose[0], scan_pose[1], scan_pose[2]);
        let (s, c) = geom::heading(&self.ref_from_last).sin_cos();
        // Base-frame coordinates at the last scan: Rᵀ on x, y.
        let r = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
        let kb = r * k * r.transpose();
        InfoSplit {
            scan_share: std::array::from_fn(|i| kb[(i, i)].clamp(0.0, 1.0)),
            scan_only: geom::xyt(&geom::between(&self.ref_from_last, &own)),
        }
    }

    /// Trains the prediction error model on a matched `motion` the scans
    /// measured in every direction (`conditioning`); the odometry only when
    /// the winning match started from it (`source`).
    fn learn(&mut self, motion: &Pose2, source: PriorSource, conditioning: f64) {
        let p = &self.params;
        if p.prior_blend_rate > 0.0 && conditioning >= p.prior_blend_conditioning {
            let odo = self.pair_given.filter(|_| source == PriorSource::Given);
            self.model.record(
                motion,
                odo.as_ref(),
                self.pair_cv.as_ref(),
                p.prior_blend_rate,
            );
        }
    }

    /// One registration of the prepared source from the initial guess
    /// `prior` (motion since the last scan), with its quality checks. A
    /// given prior is also a weak prior term (`prior_sigma_*`).
    fn attempt(&mut self, prior: &Pose2, source: PriorSource) -> Attempt {
        let hold = matches!(source, PriorSource::Given | PriorSource::Substituted);
        self.attempt_with(prior, source, hold)
    }

    /// [`attempt`](Self::attempt) with the prior term on (`hold`) or off.
    fn attempt_with(&mut self, prior: &Pose2, source: PriorSource, hold: bool) -> Attempt {
        let p = &self.params;
        let init = geom::xyt(&(self.ref_from_last * prior));
        let set = RegisterSettings {
            threshold: self.threshold.threshold(),
            max_gap: p.max_gap,
            min_normal_cos: p.max_normal_angle.cos(),
            min_kappa: p.min_kappa,
            max_iterations: p.max_iterations,
            convergence: p.convergence,
            min_correspondences: p.min_correspondences,
            cov_inflation: p.cov_inflation,
            metric: p.metric,
            prior_precision: if hold {
                let prec = |s: f64| if s > 0.0 { 1.0 / (s * s) } else { 0.0 };
                let pt = prec(if source == PriorSource::Given {
                    self.pair_sigma
                } else {
                    p.prior_sigma_xy
                });
                [pt, pt, prec(p.prior_sigma_theta)]
            } else {
                [0.0; 3]
            },
        };
        let reg = register(
            &self.reference,
            &self.src,
            &self.normals,
            init,
            &set,
            &mut self.scratch,
        );
        self.info.threshold = set.threshold;
        self.info.source_points = self.src.len();
        self.info.reference_points = self.reference.len();
        let conflict = reg.uncertainty.map_or(0.0, |u| {
            prior_conflict(&reg.pose, &init, &set.prior_precision, &u.cov)
        });
        let prec = &set.prior_precision;
        let split = reg
            .uncertainty
            .map(|u| info_split(&reg.pose, &init, prec, &u.cov, &u.measured));
        let held = prec.iter().any(|&v| v > 0.0);
        let (pose, cov) = match (reg.uncertainty, &split) {
            (Some(u), Some(sp)) if held => {
                split_estimate(sp, &init, prec, &u.measured).unwrap_or((reg.pose, u.cov))
            }
            (Some(u), _) => (reg.pose, u.cov),
            _ => (reg.pose, Matrix3::zeros()),
        };
        let ref_from_cur = geom::pose(pose[0], pose[1], pose[2]);
        let motion = geom::between(&self.ref_from_last, &ref_from_cur);
        // Only points with a surface of their own can ever be matched
        // (clutter, isolated returns and open ends never are): the inlier
        // fraction counts those.
        let matchable = self.normals.iter().filter(|n| n[0].is_finite()).count();
        let min_inliers =
            (p.min_correspondences as f64).max(p.min_inlier_fraction * matchable as f64);
        let failure = if (reg.inliers as f64) < min_inliers {
            Some(PairFailure::TooFewCorrespondences)
        } else if !reg.converged {
            Some(PairFailure::NotConverged)
        } else if reg
            .uncertainty
            .is_none_or(|u| u.conditioning < p.degenerate_ratio)
        {
            Some(PairFailure::Degenerate)
        } else if !self.agrees_with_prior(&motion, prior, source) {
            Some(PairFailure::Implausible)
        } else {
            None
        };
        Attempt {
            reg,
            ref_from_cur,
            cov,
            motion,
            failure,
            init: *prior,
            source,
            conflict,
            split,
        }
    }

    /// Whether a matched `motion` over `dt` (s) keeps the speed of the last
    /// valid motion within what the robot can change in between
    /// (`max_accel`, plus `speed_slack` per pair): a sustained contradiction
    /// of the odometry (a reversal it missed) does, a single wrong match
    /// does not.
    fn steady(&self, motion: &Pose2, dt: f64) -> bool {
        let Some(v) = self.velocity else {
            return false;
        };
        let (a, _) = geom::arc_of_increment(&v.inc);
        let (b, _) = geom::arc_of_increment(motion);
        let p = &self.params;
        let slack = p.max_accel * 0.5 * (dt + v.dt) + p.speed_slack / dt.min(v.dt);
        (b / dt - a / v.dt).abs() <= slack
    }

    /// The previous valid motion's velocity carried over `dt` (s), if any.
    fn constant_velocity(&self, dt: f64) -> Option<Pose2> {
        let Velocity { inc, dt: vdt, .. } = self.velocity?;
        if !(dt.is_finite() && dt > 0.0) {
            return None;
        }
        let (ds, dth) = geom::arc_of_increment(&inc);
        Some(geom::arc_increment(ds / vdt, dth / vdt, dt))
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
    fn plausible_change(&self, prior: &Pose2, t1: f64, dt: f64) -> bool {
        let p = &self.params;
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

    /// The motion a failed pair is placed by: the prior it was matched from,
    /// except that a substituted constant-velocity guess gives way to the
    /// given prior it replaced unless that stood still or is beyond the
    /// speed limits (no scan evidence either way: the odometry stays the
    /// better guess).
    fn fallback(&self, prior: &Pose2, given: Option<Pose2>, dt: f64) -> Pose2 {
        match given {
            Some(g) if !standing(&g) && self.within_limits(&g, &Matrix3::zeros(), dt) => g,
            _ => *prior,
        }
    }

    /// Whether a matched motion is within the robot's speed and turn-rate
    /// limits over `dt`, allowing 3σ of its covariance plus a small slack.
    fn within_limits(&self, motion: &Pose2, cov: &Matrix3<f64>, dt: f64) -> bool {
        let [x, y, th] = geom::xyt(motion);
        self.params.within_limits([x, y, th], cov, dt)
    }

    /// Whether a matched motion agrees with an informative prior.
    fn agrees_with_prior(&self, motion: &Pose2, prior: &Pose2, source: PriorSource) -> bool {
        if source == PriorSource::None {
            return true;
        }
        let p = &self.params;
        let [dx, dy, dth] = geom::xyt(&geom::between(prior, motion));
        let prior_len = prior.translation.vector.norm();
        (dx * dx + dy * dy).sqrt() <= p.prior_trans_tol + p.prior_rel_tol * prior_len
            && dth.abs() <= p.prior_rot_tol
    }

    /// After a failed match: the scan is placed by the prior. The local map
    /// is kept for the next scans to re-localise against (one odd scan — a
    /// crowd in front of the laser, a mis-stamped sweep — then costs nothing
    /// but its own pair), unless `MAP_PATIENCE` scans in a row failed: then
    /// the current scan alone starts a new map.
    /// `cov` is the failed pair's (as wide as the gates, isotropic in x, y).
    fn bridge(&mut self, prior: &Pose2, cov: Matrix3<f64>) {
        self.misses += 1;
        let ref_from_cur = self.ref_from_last * prior;
        if self.params.local_map && self.misses <= MAP_PATIENCE && !self.keyframes.is_empty() {
            // Uncertainty of the bridged pose: the last one's plus the
            // prior's (isotropic in x, y, so the same in the map frame).
            self.last_cov += cov;
            self.ref_from_last = ref_from_cur;
        } else {
            self.start_reference(ref_from_cur);
        }
    }

    /// After a successful match: the current scan becomes the reference (scan
    /// to scan) or may become a keyframe (local map).
    fn advance(&mut self, ref_from_cur: Pose2, cov: Matrix3<f64>) {
        self.misses = 0;
        if !self.params.local_map {
            self.start_reference(Pose2::identity());
            return;
        }
        self.ref_from_last = ref_from_cur;
        self.last_cov = cov;
        let key = self
            .keyframes
            .back()
            .map(|k| geom::between(&k.0, &ref_from_cur));
        let new_key = key.is_none_or(|d| {
            d.translation.vector.norm() > self.params.keyframe_dist
                || geom::heading(&d).abs() > self.params.keyframe_angle
        });
        if new_key {
            if self.keyframes.len() >= self.params.keyframes {
                self.keyframes.pop_front();
            }
            let key = self.own.placed(&ref_from_cur);
            self.keyframes.push_back((ref_from_cur, key));
            self.reference
                .set_many(self.keyframes.iter().map(|(_, s)| s));
        }
    }

    /// Fits the current scan's lines (for its normals); with scan-to-scan
    /// matching also its tree, as it becomes the next reference.
    fn set_own(&mut self) {
        if self.params.local_map {
            self.own.set_lines(&self.cur);
        } else {
            self.own.set(&self.cur);
        }
    }

    /// Makes the current scan the only reference, placed at `ref_from_cur`
    /// (local map) or as the new reference frame (scan to scan).
    fn start_reference(&mut self, ref_from_cur: Pose2) {
        self.last_cov = Matrix3::zeros();
        if self.cur.pts.len() < self.params.min_points {
            self.reference.set(&ScanPoints::default());
            self.keyframes.clear();
            self.ref_from_last = ref_from_cur;
            return;
        }
        if self.params.local_map {
            self.keyframes.clear();
            let key = self.own.placed(&ref_from_cur);
            self.keyframes.push_back((ref_from_cur, key));
            self.reference
                .set_many(self.keyframes.iter().map(|(_, s)| s));
            self.ref_from_last = ref_from_cur;
        } else {
            // The current scan's lines and tree are already built: swap them in.
            std::mem::swap(&mut self.reference, &mut self.own);
            self.ref_from_last = Pose2::identity();
        }
    }

    /// A failed pair: the prior as motion, covariance as wide as the gates.
    fn failed(&self, t0: f64, t1: f64, prior: &Pose2, f: PairFailure) -> Motion {
        let p = &self.params;
        let st = p.prior_trans_tol + p.prior_rel_tol * prior.translation.vector.norm();
        let cov = Matrix3::from_diagonal(&Vector3::new(st * st, st * st, p.prior_rot_tol.powi(2)));
        // Nothing of it was measured by the scan.
        let [dx, dy, dtheta] = geom::xyt(prior);
        Motion {
            failure: Some(f),
            split: Some(InfoSplit {
                scan_share: [0.0; 3],
                scan_only: [dx, dy, dtheta],
            }),
            ..Motion::from_increment(t0, t1, prior, cov)
        }
    }
}

/// The last valid motion, as the constant-velocity model's velocity.
#[derive(Debug, Clone, Copy)]
struct Velocity {
    /// Conditioning of its match (see `MatchInfo::conditioning`).
    cond: f64,
    /// Whether its scans agreed with their prior term (`CONFLICT`), or kept
    /// the previous velocity ([`ScanMatcher::steady`]): a single match
    /// against the odometry that jumps in speed (a wrong match) does not
    /// speak for the next pair's prior centre.
    agreed: bool,
    /// The motion (`prev_from_cur`).
    inc: Pose2,
    /// Its duration (s).
    dt: f64,
    /// Its end stamp (s).
    t1: f64,
    /// Its covariance (m², rad²).
    cov: Matrix3<f64>,
}

/// One registration and its verdict, before the matcher's state changes.
struct Attempt {
    reg: Registration,
    ref_from_cur: Pose2,
    /// Covariance of `ref_from_cur`: the scan's, or with a prior term, that
    /// of the estimate of [`split_estimate`].
    cov: Matrix3<f64>,
    motion: Pose2,
    failure: Option<PairFailure>,
    /// The initial guess (motion since the last scan) it started from.
    init: Pose2,
    source: PriorSource,
    /// Squared Mahalanobis distance between the prior term's centre and
    /// what the scan alone says (see [`prior_conflict`]); 0 without a prior
    /// term.
    conflict: f64,
    /// The scan-only pose `[x, y, θ]` and `K = (I + C P)⁻¹` in the
    /// reference frame (see [`info_split`]).
    split: Option<([f64; 3], Matrix3<f64>)>,
}

impl Attempt {
    /// Whether this attempt succeeded and beats `best`: `best` failed, or
    /// this one has more inliers.
    fn improves_on(&self, best: &Attempt) -> bool {
        self.failure.is_none() && (best.failure.is_some() || self.reg.inliers > best.reg.inliers)
    }
}

/// Squared Mahalanobis distance (3 dof) between the centre `init` of a prior
/// term of precision `prec` (diagonal, 1/m², 1/m², 1/rad²) and the scan-only
/// estimate, given the registration's result `pose` (prior term included) and
/// the scan-only covariance `cov`, all in the reference frame. At the
/// optimum of scan + prior, the scan-only optimum is `pose + cov·P·off`
/// (`off` = `pose − init`, `P` = diag(`prec`)), and its innovation against
/// the prior, of covariance `cov + P⁻¹`, has the squared distance
/// `offᵀ P off + (P off)ᵀ cov (P off)` — no inversion of a possibly
/// infinite prior variance needed.
fn prior_conflict(pose: &[f64; 3], init: &[f64; 3], prec: &[f64; 3], cov: &Matrix3<f64>) -> f64 {
    let off = Vector3::new(
        pose[0] - init[0],
        pose[1] - init[1],
        geom::wrap_angle(pose[2] - init[2]),
    );
    let poff = Vector3::new(prec[0] * off.x, prec[1] * off.y, prec[2] * off.z);
    let d2 = off.dot(&poff) + poff.dot(&(cov * poff));
    if d2.is_finite() {
        d2
    } else {
        0.0
    }
}

/// The information split of a registration's `pose` (all in the reference
/// frame) between the scan and a prior term centred at `init` with
/// precision `prec` (diagonal, 1/m², 1/m², 1/rad²), given the scan-only
/// covariance `cov` of the registration's cost and the information `info`
/// the scan measured beyond its lines' direction noise
/// (`Uncertainty::measured`): the scan-only optimum `own = pose + cov·P·off`
/// (`off` = `pose − init`, as in [`prior_conflict`]) and
/// `K = (info + P)⁻¹ info`, the share of each direction the scan measured.
/// `K = I` without a prior term; where the result is not finite, `own` is
/// the pose and the share 0.
fn info_split(
    pose: &[f64; 3],
    init: &[f64; 3],
    prec: &[f64; 3],
    cov: &Matrix3<f64>,
    info: &Matrix3<f64>,
) -> ([f64; 3], Matrix3<f64>) {
    if prec.iter().all(|&p| p == 0.0) {
        return (*pose, Matrix3::identity());
    }
    let off = Vector3::new(
        pose[0] - init[0],
        pose[1] - init[1],
        geom::wrap_angle(pose[2] - init[2]),
    );
    let p = Matrix3::from_diagonal(&Vector3::from(*prec));
    let own = Vector3::from(*pose) + cov * p * off;
    let k = (info + p).try_inverse().map(|s| s * info);
    match k {
        Some(k) if k.iter().all(|v| v.is_finite()) && own.iter().all(|v| v.is_finite()) => {
            ([own.x, own.y, geom::wrap_angle(own.z)], k)
        }
        _ => (*pose, Matrix3::zeros()),
    }
}

/// The estimate that follows from a split (`own`, `k`) and the prior
/// term's centre `init`: `init + K (own − init)` (θ wrapped), i.e. the
/// scan's own estimate only as far as the scan measured it, and its
/// covariance `(info + P)⁻¹` (`P` = diag(`prec`)). Where the scan's lines
/// hold more information than they measure (noise-tilted fits along a
/// wall), this, not the registration's optimum, is the pair's motion.
fn split_estimate(
    (own, k): &([f64; 3], Matrix3<f64>),
    init: &[f64; 3],
    prec: &[f64; 3],
    info: &Matrix3<f64>,
) -> Option<([f64; 3], Matrix3<f64>)> {
    let d = Vector3::new(
        own[0] - init[0],
        own[1] - init[1],
        geom::wrap_angle(own[2] - init[2]),
    );
    let x = Vector3::from(*init) + k * d;
    let cov = (info + Matrix3::from_diagonal(&Vector3::from(*prec))).try_inverse()?;
    let ok = x.iter().chain(cov.iter()).all(|v| v.is_finite());
    ok.then(|| {
        (
            [x.x, x.y, geom::wrap_angle(x.z)],
            (cov + cov.transpose()) * 0.5,
        )
    })
}

/// Failed scans in a row after which the local map is given up for a new
/// one started at the current scan.
const MAP_PATIENCE: usize = 3;

/// Age (s) beyond which the last valid velocity says nothing about the
/// plausibility of a given prior.
const MAX_VELOCITY_AGE: f64 = 1.0;
/// Squared Mahalanobis distance (3 dof) beyond which the scans contradict the
/// prior term: the χ² 99.9 % quantile.
const CONFLICT: f64 = 16.27;

/// Odometry increments below this (m, rad) are a robot standing still (or a
/// frozen reading).
const STANDING: f64 = 1e-9;
/// Longest run (s) of pairs whose given prior is replaced by the
/// constant-velocity guess; beyond it the given prior is trusted again.
const MAX_SUBSTITUTION: f64 = 2.0;

/// Two guesses close enough (1 cm, 0.5°) to converge alike.
fn close(a: &Pose2, b: &Pose2) -> bool {
    let [x, y, t] = geom::xyt(&geom::between(a, b));
    x.hypot(y) < 0.01 && t.abs() < 0.01
}

/// An increment of a robot standing still (or of a frozen reading).
fn standing(p: &Pose2) -> bool {
    let (ds, dth) = geom::arc_of_increment(p);
    ds.abs() < STANDING && dth.abs() < STANDING
}

fn pose_finite(p: &Pose2) -> bool {
    geom::xyt(p).iter().all(|v| v.is_finite())
}

/// Jacobians of `m = inv(a) ⊕ b` (as x, y, θ) with respect to the (x, y, θ)
/// of `a` and of `b`, all in the common parent frame.
fn between_jacobians(a: &Pose2, b: &Pose2) -> (Matrix3<f64>, Matrix3<f64>) {
    let (s, c) = geom::heading(a).sin_cos();
    let m = geom::between(a, b).translation.vector;
    let jb = Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
    let ja = Matrix3::new(-c, -s, m.y, s, -c, -m.x, 0.0, 0.0, -1.0);
    (ja, jb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prior_conflict_and_info_split_recover_the_scan_only_estimate() {
        // Scan-only estimate xs with covariance c, prior at init with
        // precision p: the fused optimum, then the closed form against the
        // explicit (xs − init)ᵀ (c + P⁻¹)⁻¹ (xs − init).
        let c = Matrix3::new(4e-4, 1e-4, 0.0, 1e-4, 1e-2, 2e-5, 0.0, 2e-5, 1e-4);
        let prec = [2500.0, 2500.0, 4.0];
        let pm = Matrix3::from_diagonal(&Vector3::from(prec));
        let init = Vector3::new(0.1, -0.2, 0.3);
        let xs = Vector3::new(0.13, -0.05, 0.29);
        let ci = c.try_inverse().unwrap();
        let fused = (ci + pm).try_inverse().unwrap() * (ci * xs + pm * init);
        let got = prior_conflict(&fused.into(), &init.into(), &prec, &c);
        let d = xs - init;
        let s = c + pm.try_inverse().unwrap();
        let want = (d.transpose() * s.try_inverse().unwrap() * d)[(0, 0)];
        assert!((got - want).abs() < 1e-9 * want, "{got} {want}");
        // The information split of that fused optimum recovers the
        // scan-only estimate, and K·xs + (I − K)·init is the fused optimum.
        let (own, k) = info_split(&fused.into(), &init.into(), &prec, &c, &ci);
        for i in 0..3 {
            assert!((own[i] - xs[i]).abs() < 1e-9, "{own:?} {xs}");
        }
        let back = k * xs + (Matrix3::identity() - k) * init;
        assert!((back - fused).norm() < 1e-9, "{back} {fused}");
        // Along the direction the scan measures poorly (y: variance 1e-2
        // against the prior's 4e-4), most of the estimate is the prior's.
        assert!(k[(1, 1)] < 0.1 && k[(0, 0)] > 0.5, "{k}");
        // No prior term: no conflict.
        assert_eq!(
            prior_conflict(&fused.into(), &init.into(), &[0.0; 3], &c),
            0.0
        );
    }
}
