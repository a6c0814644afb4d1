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
    use super::hand_over_scales;

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
