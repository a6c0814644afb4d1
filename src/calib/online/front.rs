//! The front end's decisions as the stream comes: compose motions into
//! intervals, keep them in the window, fit the window after the warm-up and
//! then every `resolve_s` of stream time, choose the mounting, and hand each
//! interval on as a velocity observation (or, for untimed tuples, a whole
//! filter step) once the filters have started.

use std::collections::VecDeque;

use super::report::{LaserReport, OffsetReport, OnlineReport, Solve, WarmupReport};
use super::{velocity, GeometryWindow, MountChoice, OnlineParams};
use crate::calib::batch::{
    residual_scales, BatchEstimate, BatchParams, Interval, IntervalBuilder, LaserMotion, Valued,
    WheelMotion, P3,
};
use crate::calib::{CalibStep, CheckParams, Kind};
use crate::geom::wrap_angle;
use crate::motion::VelocityObs;
use crate::recording::WheelSample;
use crate::robot::DiffDrive;
use crate::stats::chi2_quantile;
use nalgebra::{Matrix3, Vector3};

/// Where the filters start, once the front end knows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Started {
    /// Stream time (s) at which they start.
    pub t: f64,
    /// The centre of their initial belief.
    pub centre: DiffDrive,
    /// Whether the centre is the warm-up's estimate (else the nominal).
    pub from_warmup: bool,
    /// Half-width of the initial search, relative to the centre.
    pub search: f64,
}

/// What the front end hands on: a velocity observation over laser time, to
/// be read against the wheel samples, or (tuples, whose wheel motion comes
/// with them) a whole filter step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mounted {
    /// Velocities measured over `[t0, t1]` (laser clock).
    Observation(VelocityObs),
    /// A step with its wheel rates and measurements.
    Step(CalibStep),
}

/// The online front end ([`super`]).
#[derive(Debug, Clone)]
pub struct FrontEnd {
    p: OnlineParams,
    batch: BatchParams,
    checks: CheckParams,
    nominal: Option<DiffDrive>,
    /// The stated mounting and where it was stated.
    stated: Option<(P3, String)>,
    builder: IntervalBuilder,
    window: GeometryWindow,
    /// Intervals with their laser-clock span, not yet handed on.
    pending: VecDeque<(Interval, f64, f64)>,
    started: Option<Started>,
    first_t: Option<f64>,
    last_fit_t: Option<f64>,
    /// Intervals in the window at the last fit.
    last_fit_n: usize,
    /// The time offset and mounting in use, and the mounting's std's.
    offset: f64,
    laser: P3,
    laser_std: Option<[f64; 3]>,
    laser_estimated: bool,
    /// Whether the last fit contradicted the stated mounting.
    laser_contradicted: bool,
    laser_check: Option<String>,
    /// The residuals' σ's of the last fit (untimed tuples carry none).
    noise: Option<[f64; 3]>,
    /// How much larger than the scan matcher's σ's the last fit's residuals
    /// are, per `[x, y, θ]` (at least 1).
    scales: [f64; 3],
    fits: Vec<Solve>,
    offsets: Vec<(f64, Valued)>,
    /// Whether the intervals carry no time (Censi's tuples).
    untimed: bool,
    /// The mounting's running information and information-weighted sum.
    mount_info: Matrix3<f64>,
    mount_sum: Vector3<f64>,
    /// Intervals in the window at the last fit (the rest is new).
    mount_overlap: usize,
}

impl FrontEnd {
    /// A front end with `nominal` values (`None`: none are known) and the
    /// `stated` mounting with its source (`None`: none stated; the scan
    /// matcher's motions are then the laser's own).
    pub fn new(
        p: &OnlineParams,
        batch: &BatchParams,
        checks: &CheckParams,
        nominal: Option<DiffDrive>,
        stated: Option<(P3, String)>,
    ) -> Self {
        let batch = BatchParams {
            time_offset: p.time_offset,
            ..*batch
        };
        Self {
            builder: IntervalBuilder::new(p.interval_s, p.interval_rad, 1e-3),
            window: GeometryWindow::new(p.window_s, p.max_intervals, batch.max_time_offset_s),
            p: p.clone(),
            batch,
            checks: *checks,
            nominal,
            laser: stated.as_ref().map_or([0.0; 3], |s| s.0),
            stated,
            pending: VecDeque::new(),
            started: None,
            first_t: None,
            last_fit_t: None,
            last_fit_n: 0,
            offset: 0.0,
            laser_std: None,
            laser_estimated: false,
            laser_contradicted: false,
            laser_check: None,
            noise: None,
            scales: [1.0; 3],
            fits: Vec::new(),
            offsets: Vec::new(),
            untimed: false,
            mount_info: Matrix3::zeros(),
            mount_sum: Vector3::zeros(),
            mount_overlap: 0,
        }
    }

    /// A wheel sample (stamp order).
    pub fn push_wheel(&mut self, w: &WheelSample) {
        self.window.push_wheel(w);
    }

    /// A laser-frame motion of the scan matcher (time order).
    pub fn push_motion(&mut self, m: &LaserMotion) {
        if let Some(iv) = self.builder.push(m) {
            self.push_interval(iv);
        }
    }

    /// An interval (time order): kept in the window and for the filters;
    /// fits the window when it is due.
    pub fn push_interval(&mut self, iv: Interval) {
        self.untimed |= matches!(iv.wheels, WheelMotion::Steps(_));
        let (t0, t1) = self.window.push(iv.clone());
        self.first_t.get_or_insert(t0);
        self.pending.push_back((iv, t0, t1));
        self.schedule(t1);
    }

    /// The stream has ended: a last fit when the filters have not started
    /// (a short recording), then the start from the nominal values if even
    /// that fails.
    pub fn finish(&mut self) {
        if self.started.is_some() {
            return;
        }
        if let Some(&(_, _, t1)) = self.pending.back() {
            if self.last_fit_t != Some(t1) {
                self.fit(t1);
            }
            if self.started.is_none() {
                self.start_nominal(t1);
            }
        }
    }

    /// The filters' detector fired at `t` (s, laser clock): the window
    /// keeps only what comes after, so that the next fits (the time offset,
    /// the mounting check) describe the robot as it is now; a fit that the
    /// few intervals left cannot support is refused, and the offset and
    /// mounting in use stay.
    pub fn changed_at(&mut self, t: f64) {
        self.window.forget_before(t);
    }

    /// Where the filters start, once known.
    pub fn started(&self) -> Option<&Started> {
        self.started.as_ref()
    }

    /// The time offset in use: wheel stamp minus laser stamp of one
    /// instant (s).
    pub fn time_offset(&self) -> f64 {
        self.offset
    }

    /// The mounting in use, base_from_laser `[x, y, yaw]`.
    pub fn laser(&self) -> P3 {
        self.laser
    }

    /// Once the filters have started, every interval not yet handed on, as
    /// an observation or a step with the offset and mounting in use now.
    pub fn drain(&mut self, out: &mut dyn FnMut(Mounted)) {
        if self.started.is_none() {
            return;
        }
        while let Some((iv, t0, t1)) = self.pending.pop_front() {
            if let Some(m) = self.mounted(&iv, t0, t1) {
                out(m);
            }
        }
    }

    /// Fits when one is due at stream time `t` (s); starts the filters on
    /// the warm-up's success or when the warm-up has run out.
    fn schedule(&mut self, t: f64) {
        let since_first = t - self.first_t.unwrap_or(t);
        let since_fit = self.last_fit_t.map_or(f64::INFINITY, |l| t - l);
        let grown = 4 * self.window.len() >= 5 * self.last_fit_n;
        let due = match self.started {
            None => since_first >= self.p.warmup_s && since_fit >= self.p.retry_s && grown,
            Some(_) => since_fit >= self.p.resolve_s,
        };
        if due {
            self.fit(t);
        }
        // A robot on the move cannot wait for ever; intervals without time
        // (tuples, read whole) wait for the fit to the end.
        if self.started.is_none() && since_first >= self.p.warmup_max_s && !self.untimed {
            self.start_nominal(t);
        }
    }

    /// Fits the window at stream time `t` and takes what it found: the
    /// joint fit decides the mounting; when the stated one is kept, the
    /// window is fitted again with it held, for the time offset, the start
    /// and the residuals' scale.
    fn fit(&mut self, t: f64) {
        self.last_fit_t = Some(t);
        self.last_fit_n = self.window.len();
        let nominal = match self.nominal {
            Some(n) => Ok(n),
            None => self.window_start(),
        };
        let joint = nominal.and_then(|n| self.solve(&n, None).map(|e| (n, e)));
        let mut report = Solve {
            t,
            intervals: self.window.len(),
            time_offset: None,
            laser: None,
            kinematics: None,
            residual_scale: None,
            refused: None,
        };
        match joint {
            Ok((n, joint)) => {
                report.laser = Some([
                    joint.laser.x.value,
                    joint.laser.y.value,
                    joint.laser.yaw.value,
                ]);
                let held = self.choose_mount(&joint);
                let e = match held {
                    Some(l) => self.solve(&n, Some(l)).unwrap_or(joint),
                    None => joint,
                };
                report.time_offset = e.time_offset;
                report.kinematics = Some(e.drive());
                self.take(t, &e);
                report.residual_scale = Some(self.scales);
            }
            Err(why) => report.refused = Some(why),
        }
        self.fits.push(report);
    }

    /// The window's fit, the mounting held at `laser` when given.
    fn solve(&self, nominal: &DiffDrive, laser: Option<P3>) -> Result<BatchEstimate, String> {
        self.window
            .solve(nominal, &self.batch, &self.checks, laser)
            .map_err(|e| e.to_string())
    }

    /// The closed-form start of the window, when there are no nominal values.
    fn window_start(&self) -> Result<DiffDrive, String> {
        crate::calib::batch::closed_form_start(&self.window.problem(), &self.batch)
            .map_err(|e| e.to_string())
    }

    /// Takes a fit: its time offset, the mounting by the configured choice,
    /// the residuals' σ's and, the first time, the filters' start.
    fn take(&mut self, t: f64, e: &BatchEstimate) {
        if let Some(d) = e.time_offset {
            self.offset = d.value;
            self.offsets.push((t, d));
        }
        self.noise = e.noise_sigma;
        let robust = residual_scales(&self.window.problem(), &e.unknowns());
        self.scales = if self.started.is_none() {
            hand_over_scales(robust, e.std_widening)
        } else {
            robust
        };
        if self.started.is_none() {
            self.started = Some(Started {
                t,
                centre: e.drive(),
                from_warmup: true,
                search: self.p.search_warm,
            });
        }
        self.window.slide();
    }

    /// The filters start from the nominal values (no fit succeeded in time).
    fn start_nominal(&mut self, t: f64) {
        if let Some(n) = self.nominal {
            self.started = Some(Started {
                t,
                centre: n,
                from_warmup: false,
                search: self.p.search_nominal,
            });
        }
    }

    /// The mounting after a joint fit: the stated one unless contradicted
    /// (or as configured), else the estimate. Returns the stated mounting
    /// when it is kept.
    fn choose_mount(&mut self, e: &BatchEstimate) -> Option<P3> {
        let (est, cov) = self.mount_mean(e);
        let std = [0, 1, 2].map(|i| cov[(i, i)].max(0.0).sqrt());
        let (use_estimate, check, contradicted) = match (&self.stated, self.p.mount) {
            (_, MountChoice::Estimate) => (true, None, false),
            (None, _) => (true, None, false),
            (Some((s, src)), choice) => {
                let d = Vector3::new(est[0] - s[0], est[1] - s[1], wrap_angle(est[2] - s[2]));
                let chi2 = cov
                    .try_inverse()
                    .map_or(f64::INFINITY, |i| (d.transpose() * i * d)[0]);
                let limit = chi2_quantile(1.0 - self.p.mount_probability, 3);
                let contradicted = chi2 > limit;
                let words = format!(
                    "the {src} mounting x {:.4} m, y {:.4} m, yaw {:.4} rad against the \
                     stream's x {:.4} ± {:.4} m, y {:.4} ± {:.4} m, yaw {:.4} ± {:.4} rad: \
                     χ² {chi2:.1} {} {limit:.1}",
                    s[0],
                    s[1],
                    s[2],
                    est[0],
                    std[0],
                    est[1],
                    std[1],
                    est[2],
                    std[2],
                    if contradicted { ">" } else { "≤" }
                );
                let verdict = match (contradicted, choice) {
                    (true, MountChoice::Check) => "contradicted: the estimate is used",
                    (true, _) => "contradicted, but kept as configured ([calib.online] mount)",
                    (false, _) => "consistent: the stated one is kept",
                };
                (
                    contradicted && choice == MountChoice::Check,
                    Some(format!("{words}, {verdict}")),
                    contradicted,
                )
            }
        };
        self.laser_check = check;
        self.laser_contradicted = contradicted;
        self.laser_estimated = use_estimate;
        if use_estimate {
            self.laser = est;
            self.laser_std = Some(std);
            None
        } else {
            let (s, _) = self.stated.as_ref()?;
            self.laser = *s;
            self.laser_std = None;
            Some(*s)
        }
    }

    /// The mounting so far and its covariance: a constant of the robot, so
    /// each fit's estimate enters an information-weighted mean, its
    /// information counted for the share of its window that is new since the
    /// previous fit (overlapping windows would count the same data again).
    fn mount_mean(&mut self, e: &BatchEstimate) -> (P3, Matrix3<f64>) {
        let est = Vector3::new(e.laser.x.value, e.laser.y.value, e.laser.yaw.value);
        let cov: Matrix3<f64> = e.covariance.fixed_view::<3, 3>(3, 3).into_owned();
        let new = self.window.len().saturating_sub(self.mount_overlap);
        let share = new as f64 / self.window.len().max(1) as f64;
        self.mount_overlap = self.window.len();
        if let Some(info) = cov.try_inverse().filter(|_| share > 0.0) {
            // Yaw taken near the mean so far (no wrap inside the sum).
            let mut x = est;
            if let Some(m) = self.mount_info.try_inverse().map(|c| c * self.mount_sum) {
                x[2] = m[2] + wrap_angle(x[2] - m[2]);
            }
            self.mount_info += info * share;
            self.mount_sum += info * share * x;
        }
        match self.mount_info.try_inverse() {
            Some(c) => {
                let m = c * self.mount_sum;
                ([m[0], m[1], wrap_angle(m[2])], c)
            }
            None => ([est[0], est[1], est[2]], cov),
        }
    }

    /// One interval as the filters take it, with the offset and mounting in
    /// use now.
    fn mounted(&self, iv: &Interval, t0: f64, t1: f64) -> Option<Mounted> {
        // The scan matcher's covariance, scaled to what the window's
        // residuals show (a real scanner's errors are larger than its
        // Hessian says); without one (tuples), the residuals' σ's.
        let cov = match iv.cov {
            Some(c) => {
                let d = Matrix3::from_diagonal(&Vector3::from(self.scales));
                d * c * d
            }
            None => {
                let n = self.noise?;
                Matrix3::from_diagonal(&Vector3::new(n[0] * n[0], n[1] * n[1], n[2] * n[2]))
            }
        };
        let obs = velocity(t0, t1, iv.s, &cov, self.laser)?;
        match &iv.wheels {
            WheelMotion::Span { .. } => Some(Mounted::Observation(obs)),
            WheelMotion::Steps(steps) => {
                let d = steps
                    .iter()
                    .fold([0.0; 2], |a, x| [a[0] + x[0], a[1] + x[1]]);
                let dt = t1 - t0;
                let s = CalibStep::new(t0, t1, d[1] / dt, d[0] / dt)
                    .with(Kind::V, obs.v, obs.sigma_v)
                    .with(Kind::W, obs.w, obs.sigma_w);
                Some(Mounted::Step(s))
            }
        }
    }

    /// What the front end used and found.
    pub fn report(&self) -> OnlineReport {
        let source = |e: bool| -> String {
            if e {
                "estimated".into()
            } else {
                self.stated
                    .as_ref()
                    .map_or("default".into(), |(_, s)| s.clone())
            }
        };
        let sd = self.laser_std.unwrap_or([0.0; 3]);
        let v = |i: usize| Valued {
            value: self.laser[i],
            std: sd[i],
        };
        let time_offset = OffsetReport::of(&self.offsets).unwrap_or(OffsetReport {
            value: 0.0,
            std: 0.0,
            converged_s: None,
            source: "default",
        });
        OnlineReport {
            route: self.route(),
            time_offset,
            laser: LaserReport {
                x: v(0),
                y: v(1),
                yaw: v(2),
                source: source(self.laser_estimated),
                check: self.laser_check.clone(),
                contradicted: self.laser_contradicted,
            },
            warmup: self.started.map(|s| WarmupReport {
                t: s.t,
                from: if s.from_warmup { "warm-up" } else { "nominal" },
                centre: s.centre,
                search: s.search,
            }),
            solves: self.fits.clone(),
        }
    }

    /// The route the observations took, in words.
    fn route(&self) -> String {
        if self.untimed {
            return "one filter step per tuple (interval): its laser displacement moved into the \
                    base frame with the mounting in use, σ's from the window's residuals; the \
                    tuples carry no time, so no time offset"
                .into();
        }
        let per = if self.p.interval_s > 0.0 {
            format!(
                "scan-matched motions composed into intervals of at least {} s or {} rad",
                self.p.interval_s, self.p.interval_rad
            )
        } else {
            "every scan-matched motion on its own".into()
        };
        format!(
            "{per}, moved into the base frame with the mounting in use and read against the \
             wheels at the time offset in use; both from the joint fit of the last {} s, first \
             after {} s and then every {} s",
            self.p.window_s, self.p.warmup_s, self.p.resolve_s
        )
    }
}

/// The scales the scan matcher's covariance is multiplied by for the
/// intervals handed to the filters at their start: each component's robust
/// scale (successive differences, [`residual_scales`]), but never under the
/// warm-up fit's own √(χ²/dof) (`widening`, by which the fit widens its
/// std's). The filters start from that fit's estimate and then take the
/// very intervals it was fitted on; with residuals heavier-tailed than
/// normal, or structure the fit leaves over seconds, the robust scale alone
/// makes them more certain than the fit was: the LEGO robot's warm-up fit
/// reads its turn rate ×4.7 robustly and ×8.5 by χ², the whole recording
/// ×16.6, and the filters took the first 21 s as the most precise part of
/// the run and kept that fit's wheel base (164 against 173–177 mm). Later
/// intervals keep the robust scales alone: a window that straddles a change
/// of the robot has a large χ², which is for the filters to follow, not to
/// be counted as noise.
fn hand_over_scales(robust: [f64; 3], widening: f64) -> [f64; 3] {
    let floor = if widening.is_finite() { widening } else { 1.0 };
    robust.map(|s| s.max(floor))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib::synth::{generate, SynthData, SynthParams};
    use crate::geom::{between, pose, xyt};
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// The scan matcher's σ's of a 1 s interval `[x m, y m, θ rad]`.
    const SIGMA: [f64; 3] = [2e-3, 2e-3, 1e-3];

    fn chair() -> DiffDrive {
        DiffDrive {
            r_right: 0.3210,
            r_left: 0.3150,
            wheel_base: 0.6600,
        }
    }

    /// A 50 s run of `truth` (wheel clock = true time) and its scan
    /// matcher's 1 s intervals on the laser's clock, which stamps each
    /// instant `offset` s before the wheels do, the laser at `laser`
    /// (base_from_laser): each interval's laser displacement is the true
    /// base motion seen from the laser, `laser⁻¹ ⊕ B ⊕ laser`, with noise
    /// of the σ's it states (seed 7).
    fn stream(truth: DiffDrive, laser: P3, offset: f64) -> (SynthData, Vec<Interval>) {
        let p = SynthParams {
            duration: 50.0,
            ..SynthParams::default()
        };
        let data = generate(&p, truth, 3);
        let l = pose(laser[0], laser[1], laser[2]);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
        let intervals = (0..48)
            .map(|k| {
                let (t0, t1) = (k as f64, k as f64 + 1.0);
                let at = |t: f64| data.reference.pose_at(t + offset).unwrap();
                let b = between(&at(t0), &at(t1));
                let d = xyt(&(l.inverse() * b * l));
                Interval {
                    s: [0, 1, 2].map(|i| d[i] + SIGMA[i] * normal()),
                    cov: Some(Matrix3::from_diagonal(&Vector3::from(SIGMA.map(|x| x * x)))),
                    duration: 1.0,
                    wheels: WheelMotion::Span { t0, t1 },
                }
            })
            .collect();
        (data, intervals)
    }

    fn front(nominal: Option<DiffDrive>, stated: Option<P3>, mount: MountChoice) -> FrontEnd {
        let p = OnlineParams {
            mount,
            ..OnlineParams::default()
        };
        let stated = stated.map(|l| (l, "robot file".to_string()));
        FrontEnd::new(
            &p,
            &BatchParams::default(),
            &CheckParams::default(),
            nominal,
            stated,
        )
    }

    /// Runs the stream through `f`, draining after every interval; the
    /// observations handed on, with the interval count when the filters
    /// started.
    fn run(f: &mut FrontEnd, data: &SynthData, ivs: &[Interval]) -> (Vec<Mounted>, Option<usize>) {
        for w in &data.wheels {
            f.push_wheel(w);
        }
        let (mut out, mut started_after) = (Vec::new(), None);
        for (k, iv) in ivs.iter().enumerate() {
            f.push_interval(iv.clone());
            if f.started().is_some() && started_after.is_none() {
                started_after = Some(k + 1);
            }
            f.drain(&mut |m| out.push(m));
        }
        (out, started_after)
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a / b - 1.0).abs()
    }

    #[test]
    fn a_far_off_nominal_a_late_laser_and_a_wrong_mounting_are_found_after_the_warm_up() {
        let truth = chair();
        let laser = [0.30, -0.05, 0.04];
        let (data, ivs) = stream(truth, laser, 0.2);
        // Nominal radii 15 % over the truth, wheel base 15 % under; the
        // mounting stated at the axle, turned the other way.
        let nominal = DiffDrive {
            r_right: 0.37,
            r_left: 0.37,
            wheel_base: 0.56,
        };
        let stated = [0.0, 0.0, -0.04];
        let mut f = front(Some(nominal), Some(stated), MountChoice::Check);
        let (out, started_after) = run(&mut f, &data, &ivs);
        // The first fit is due when the intervals span the warm-up's 20 s.
        assert_eq!(started_after, Some(20));
        let s = *f.started().unwrap();
        assert_eq!((s.t, s.from_warmup, s.search), (20.0, true, 0.1));
        let k = s.centre;
        for (e, t, n) in [
            (k.r_right, truth.r_right, nominal.r_right),
            (k.r_left, truth.r_left, nominal.r_left),
            (k.wheel_base, truth.wheel_base, nominal.wheel_base),
        ] {
            assert!(rel(e, t) < 0.01, "start {e} against the truth {t}");
            assert!(rel(n, t) > 0.1);
        }
        // The clock and the mounting, and the stated one reported as
        // contradicted and replaced.
        assert!(
            (f.time_offset() - 0.2).abs() < 0.01,
            "offset {}",
            f.time_offset()
        );
        let l = f.laser();
        assert!(
            (l[0] - laser[0]).abs() < 0.02 && (l[1] - laser[1]).abs() < 0.02,
            "{l:?}"
        );
        assert!((l[2] - laser[2]).abs() < 0.01, "{l:?}");
        let r = f.report();
        assert!(r.laser.contradicted);
        assert_eq!(r.laser.source, "estimated");
        let check = r.laser.check.unwrap();
        assert!(
            check.starts_with("the robot file mounting x 0.0000 m"),
            "{check}"
        );
        assert!(
            check.ends_with("contradicted: the estimate is used"),
            "{check}"
        );
        assert!(r.laser.x.std > 0.0 && r.laser.x.std < 0.02);
        assert_eq!(r.time_offset.source, "estimated");
        assert_eq!(r.warmup.unwrap().from, "warm-up");
        // Fits at 20 s, then every 15 s: 35 s; the stream ends at 48 s.
        let at: Vec<f64> = r.solves.iter().map(|x| x.t).collect();
        assert_eq!(at, [20.0, 35.0]);
        assert!(r.solves.iter().all(|x| x.refused.is_none()));
        // Every interval handed on once, in order, as a velocity observation
        // on the laser's clock whose V and W are the truth's over the
        // wheels' matching span (the mounting undone).
        assert_eq!(out.len(), ivs.len());
        for (k, m) in out.iter().enumerate() {
            let Mounted::Observation(o) = m else {
                panic!("a step for a timed interval");
            };
            assert_eq!((o.t0, o.t1), (k as f64, k as f64 + 1.0));
            let (v, w) = data.mean_velocity(o.t0 + 0.2, o.t1 + 0.2);
            assert!(
                (o.v - v).abs() < 6.0 * o.sigma_v.max(1e-3),
                "{k}: V {} against {v}",
                o.v
            );
            assert!(
                (o.w - w).abs() < 6.0 * o.sigma_w.max(1e-3),
                "{k}: W {} against {w}",
                o.w
            );
        }
    }

    #[test]
    fn a_stated_mounting_the_stream_agrees_with_is_kept_and_one_it_contradicts_only_when_told() {
        let truth = chair();
        let laser = [0.30, -0.05, 0.04];
        let (data, ivs) = stream(truth, laser, 0.0);
        let mut f = front(Some(truth), Some(laser), MountChoice::Check);
        run(&mut f, &data, &ivs);
        assert_eq!(f.laser(), laser);
        let r = f.report();
        assert!(!r.laser.contradicted);
        assert_eq!(r.laser.source, "robot file");
        assert_eq!((r.laser.x.std, r.laser.yaw.std), (0.0, 0.0));
        assert!(r
            .laser
            .check
            .unwrap()
            .ends_with("consistent: the stated one is kept"));
        // Contradicted, but kept as configured.
        let wrong = [0.0, 0.0, 0.0];
        let mut f = front(Some(truth), Some(wrong), MountChoice::Stated);
        run(&mut f, &data, &ivs);
        assert_eq!(f.laser(), wrong);
        let r = f.report();
        assert!(r.laser.contradicted);
        assert_eq!(r.laser.source, "robot file");
        assert!(r
            .laser
            .check
            .unwrap()
            .ends_with("contradicted, but kept as configured ([calib.online] mount)"));
        // Estimated, whatever is stated: no check is made.
        let mut f = front(Some(truth), Some(laser), MountChoice::Estimate);
        run(&mut f, &data, &ivs);
        let r = f.report();
        assert_eq!(
            (r.laser.source.as_str(), r.laser.check),
            ("estimated", None)
        );
        assert!((f.laser()[0] - laser[0]).abs() < 0.02);
        // Nothing stated: the estimate.
        let mut f = front(Some(truth), None, MountChoice::Check);
        run(&mut f, &data, &ivs);
        assert_eq!(f.report().laser.source, "estimated");
        assert!((f.laser()[2] - laser[2]).abs() < 0.01);
    }

    #[test]
    fn no_nominal_values_start_from_the_window_itself() {
        let truth = chair();
        let (data, ivs) = stream(truth, [0.3, 0.0, 0.0], 0.1);
        let mut f = front(None, Some([0.3, 0.0, 0.0]), MountChoice::Check);
        let (_, started_after) = run(&mut f, &data, &ivs);
        assert_eq!(started_after, Some(20));
        let k = f.started().unwrap().centre;
        assert!(rel(k.r_right, truth.r_right) < 0.01, "{k:?}");
        assert!(rel(k.wheel_base, truth.wheel_base) < 0.01, "{k:?}");
    }

    #[test]
    fn failed_fits_are_retried_as_the_window_grows_then_the_nominal_starts_the_filters() {
        // No wheel samples: every fit is refused. Intervals of 1 s from 0 s:
        // a retry needs 3 s and a quarter more intervals (25, 32 (31.25),
        // 40, 50, 63 (62.5), 79 (78.125)); at 90 s the warm-up has run out
        // and the filters start from the nominal values with the wider
        // search; then a fit every 15 s (94 s, 109 s).
        let truth = chair();
        let mut f = front(Some(truth), None, MountChoice::Check);
        let mut started_at = None;
        for k in 0..110 {
            f.push_interval(with_cov(k));
            if started_at.is_none() && f.started().is_some() {
                started_at = Some(k + 1);
            }
        }
        let r = f.report();
        let at: Vec<f64> = r.solves.iter().map(|x| x.t).collect();
        assert_eq!(at, [20.0, 25.0, 32.0, 40.0, 50.0, 63.0, 79.0, 94.0, 109.0]);
        assert!(r.solves.iter().all(|x| x.refused.is_some()));
        assert_eq!(started_at, Some(90));
        let s = *f.started().unwrap();
        assert_eq!(
            (s.t, s.from_warmup, s.search, s.centre),
            (90.0, false, 0.2, truth)
        );
        assert_eq!(r.warmup.unwrap().from, "nominal");
        assert_eq!((f.time_offset(), f.laser()), (0.0, [0.0; 3]));
        assert_eq!(r.time_offset.source, "default");
        // Without nominal values nothing starts, and a stream that ends
        // before the warm-up fits once more at its end.
        let mut f = front(None, None, MountChoice::Check);
        for k in 0..100 {
            f.push_interval(span(k));
        }
        assert!(f.started().is_none());
        let mut short = front(Some(truth), None, MountChoice::Check);
        for k in 0..10 {
            short.push_interval(with_cov(k));
        }
        assert!(short.report().solves.is_empty() && short.started().is_none());
        short.finish();
        assert_eq!(short.report().solves.len(), 1);
        assert_eq!(short.started().unwrap().t, 10.0);
        assert!(!short.started().unwrap().from_warmup);
        let mut out = Vec::new();
        short.drain(&mut |m| out.push(m));
        assert_eq!(out.len(), 10);
    }

    #[test]
    fn an_interval_is_handed_on_with_the_scaled_covariance_or_the_tuples_residuals() {
        let mut f = front(None, None, MountChoice::Check);
        f.scales = [2.0, 3.0, 4.0];
        // Straight along the laser's x at the base origin: V is the
        // displacement over 2 s, its σ twice the x σ over 2 s, W's four
        // times the θ σ.
        let cov = Matrix3::from_diagonal(&Vector3::new(1e-6, 4e-6, 9e-6));
        let timed = Interval {
            s: [0.4, 0.0, 0.0],
            cov: Some(cov),
            duration: 2.0,
            wheels: WheelMotion::Span { t0: 1.0, t1: 3.0 },
        };
        let Some(Mounted::Observation(o)) = f.mounted(&timed, 1.0, 3.0) else {
            panic!("no observation");
        };
        assert!((o.v - 0.2).abs() < 1e-12 && o.w.abs() < 1e-12);
        assert!(
            (o.sigma_v - 2.0 * 1e-3 / 2.0).abs() < 1e-12,
            "{}",
            o.sigma_v
        );
        assert!(
            (o.sigma_w - 4.0 * 3e-3 / 2.0).abs() < 1e-12,
            "{}",
            o.sigma_w
        );
        // The laser 0.5 m ahead, turned by 0.1 rad: its own forward 0.4 m
        // is 0.4 m at 0.1 rad to the base's heading, of which V takes the
        // component along it.
        f.laser = [0.5, 0.0, 0.1];
        let Some(Mounted::Observation(o)) = f.mounted(&timed, 1.0, 3.0) else {
            panic!("no observation");
        };
        assert!((o.v - 0.2 * 0.1f64.cos()).abs() < 1e-9, "{}", o.v);
        // A tuple: wheel rates from its sub-steps over its span (right, then
        // left), σ's from the residuals, none before a fit gave them.
        f.laser = [0.0; 3];
        let tuple = Interval {
            s: [0.4, 0.0, 0.2],
            cov: None,
            duration: 2.0,
            wheels: WheelMotion::Steps(vec![[0.1, 0.2], [0.3, 0.4]]),
        };
        assert_eq!(f.mounted(&tuple, 1.0, 3.0), None);
        f.noise = Some([0.01, 0.02, 0.03]);
        let Some(Mounted::Step(st)) = f.mounted(&tuple, 1.0, 3.0) else {
            panic!("no step");
        };
        assert_eq!((st.t0, st.t1), (1.0, 3.0));
        assert!((st.omega_right - 0.3).abs() < 1e-12 && (st.omega_left - 0.2).abs() < 1e-12);
        let m = st.measurements();
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].kind, Kind::V);
        assert_eq!(m[1].kind, Kind::W);
        assert!((m[1].value - 0.1).abs() < 1e-12 && (m[1].sigma - 0.015).abs() < 1e-12);
        // V's σ: straight, the x residual over 2 s; turned half round (the
        // chord across the heading), the y residual times the arc's length
        // over its chord, π/2.
        let sigma_v = |s: P3| match f.mounted(&Interval { s, ..tuple.clone() }, 1.0, 3.0) {
            Some(Mounted::Step(st)) => st.measurements()[0].sigma,
            other => panic!("{other:?}"),
        };
        assert!((sigma_v([0.4, 0.0, 0.0]) - 0.01 / 2.0).abs() < 1e-12);
        let half_round = sigma_v([0.0, 0.4, std::f64::consts::PI]);
        assert!(
            (half_round - std::f64::consts::FRAC_PI_2 * 0.02 / 2.0).abs() < 1e-9,
            "{half_round}"
        );
        // No duration: nothing.
        assert_eq!(f.mounted(&timed, 3.0, 3.0), None);
    }

    #[test]
    fn the_mounting_is_a_mean_over_new_data_only() {
        // Two fits of one unknown-yaw mounting: the first over 10 intervals,
        // the second over 20 of which 10 are new, so it counts half. Yaw
        // 3.1 and −3.1 rad (3.183 taken near the first): the mean
        // (1e4 · 3.1 + 5e3 · 3.1832) / 1.5e4, not the wrapped −0.
        let mut f = front(None, None, MountChoice::Check);
        let v = |value: f64| Valued { value, std: 0.01 };
        let estimate = |x: f64, yaw: f64| BatchEstimate {
            r_right: v(0.3),
            r_left: v(0.3),
            wheel_base: v(0.6),
            laser: crate::calib::batch::LaserValued {
                x: v(x),
                y: v(0.0),
                yaw: v(yaw),
            },
            time_offset: None,
            correlation: crate::calib::batch::Correlation {
                names: Vec::new(),
                matrix: Vec::new(),
            },
            observability: Default::default(),
            closed_form: [0.0; 6],
            intervals: 0,
            dropped: 0,
            chi2: 0.0,
            dof: 0,
            noise_sigma: None,
            std_widening: 1.0,
            notes: Vec::new(),
            excitation: Default::default(),
            covariance: nalgebra::DMatrix::identity(7, 7) * 1e-4,
        };
        for k in 0..10 {
            f.window.push(span(k));
        }
        let (m, c) = f.mount_mean(&estimate(0.1, 3.1));
        assert!((m[0] - 0.1).abs() < 1e-12 && (c[(0, 0)] - 1e-4).abs() < 1e-15);
        for k in 10..20 {
            f.window.push(span(k));
        }
        let (m, c) = f.mount_mean(&estimate(0.2, -3.1));
        let second = -3.1 + std::f64::consts::TAU;
        assert!(
            (m[0] - (0.1 * 1e4 + 0.2 * 5e3) / 1.5e4).abs() < 1e-12,
            "{m:?}"
        );
        assert!(
            (m[2] - (3.1 * 1e4 + second * 5e3) / 1.5e4).abs() < 1e-12,
            "{m:?}"
        );
        assert!((c[(0, 0)] - 1.0 / 1.5e4).abs() < 1e-15);
        // The same window again: nothing new, nothing counted.
        let (again, _) = f.mount_mean(&estimate(0.9, 0.0));
        assert_eq!(again, m);
    }

    fn span(k: usize) -> Interval {
        Interval {
            s: [0.1, 0.0, 0.0],
            cov: None,
            duration: 1.0,
            wheels: WheelMotion::Span {
                t0: k as f64,
                t1: k as f64 + 1.0,
            },
        }
    }

    #[test]
    fn motions_become_intervals_and_a_change_empties_the_window_before_it() {
        // Ten scan pairs of 0.1 s from 500 s make one interval of 1 s.
        let mut f = front(None, None, MountChoice::Check);
        let motion = |k: usize| LaserMotion {
            t0: 500.0 + 0.1 * k as f64,
            t1: 500.0 + 0.1 * (k + 1) as f64,
            s: [0.01, 0.0, 0.001],
            cov: Matrix3::identity() * 1e-8,
            valid: true,
        };
        for k in 0..9 {
            f.push_motion(&motion(k));
        }
        assert_eq!(f.window.len(), 0);
        f.push_motion(&motion(9));
        assert_eq!(f.window.len(), 1);
        let (_, t0, t1) = f.pending[0];
        assert!((t0 - 500.0).abs() < 1e-9 && (t1 - 501.0).abs() < 1e-9);
        // The warm-up counts from the stream's first interval (500 s), not
        // from 0: the first fit at 520 s.
        let mut g = front(Some(chair()), None, MountChoice::Check);
        for k in 500..530 {
            g.push_interval(span(k));
        }
        let at: Vec<f64> = g.report().solves.iter().map(|x| x.t).collect();
        assert_eq!(at, [520.0, 525.0]);
        // A change at 510.5 s: the intervals starting before it are gone.
        g.changed_at(510.5);
        assert_eq!(g.window.len(), 19);
    }

    /// `span(k)` with the scan matcher's covariance.
    fn with_cov(k: usize) -> Interval {
        Interval {
            cov: Some(Matrix3::identity() * 1e-6),
            ..span(k)
        }
    }

    #[test]
    fn the_route_says_how_observations_were_made() {
        let mut f = front(None, None, MountChoice::Check);
        assert!(f.route().starts_with(
            "scan-matched motions composed into intervals of at least 1 s or 0.3 rad, moved"
        ));
        assert!(f
            .route()
            .ends_with("of the last 120 s, first after 20 s and then every 15 s"));
        f.p.interval_s = 0.0;
        assert!(f
            .route()
            .starts_with("every scan-matched motion on its own, moved"));
        f.push_interval(Interval {
            wheels: WheelMotion::Steps(vec![[0.1, 0.1]]),
            ..span(0)
        });
        assert!(f
            .route()
            .starts_with("one filter step per tuple (interval)"));
    }

    #[test]
    fn the_filters_are_never_more_certain_than_the_fits_chi2() {
        // Robust turn scale 4.7 under the fit's √(χ²/dof) 8.5: 8.5; a
        // component above it keeps its own; a fit without widening (1) or
        // with none computed leaves the robust scales.
        assert_eq!(hand_over_scales([6.0, 1.8, 4.7], 8.5), [8.5, 8.5, 8.5]);
        assert_eq!(hand_over_scales([6.0, 1.8, 14.4], 5.0), [6.0, 5.0, 14.4]);
        assert_eq!(hand_over_scales([1.0, 2.0, 3.0], 1.0), [1.0, 2.0, 3.0]);
        assert_eq!(hand_over_scales([1.0, 2.0, 3.0], f64::NAN), [1.0, 2.0, 3.0]);
    }
}
