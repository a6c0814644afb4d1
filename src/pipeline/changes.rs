//! Names what changed at every firing of a calibration run's change
//! detector ([`crate::diagnose::onset`]), against the filter's estimate at
//! the start of the firing's window, as soon as the run has passed the
//! window: the wheel, gyro and ICP streams and the estimates are kept only
//! as far back as a window reaches.
//!
//! In the history (`calibration.csv`'s `change` column,
//! [`super::outputs::CalibFiles`]) a filter firing's name goes at the row
//! of the step that fired; a laser-mounting firing's at the first row at or
//! after its time that carries no filter name (one name a row). The watch
//! dates a firing back (at most [`MountWatch::lag_s`]) and names it once its
//! window has passed, so rows are held until
//! [`ChangeWatch::mount_named_before`] has passed them: a lag and a window's
//! worth of rows at most.

use crate::calib::Estimate;
use crate::diagnose::mount::MountWatch;
use crate::diagnose::onset::{
    name_change, NamedChange, OnsetParams, CANDIDATES, FILTER, FILTER_CANDIDATES, MOUNT,
};
use crate::diagnose::Measured;
use crate::effects::change::UNCONVERGED;
use crate::io::Item;
use crate::motion::Motion;
use crate::recording::{GyroSample, WheelSample};
use crate::robot::RobotConfig;
use std::collections::VecDeque;

/// Time (s) kept beyond a firing's window on either side, on top of the
/// naming's own margin and gyro window: streams arrive interleaved, not in
/// one order.
const SLACK_S: f64 = 1.0;

/// The streams and estimates of the last seconds of a run (a window that
/// slides with it, so that a run of any length is named in bounded memory),
/// the firings of the change detector still to be named and those named.
#[derive(Debug)]
pub struct ChangeWatch {
    robot: RobotConfig,
    p: OnsetParams,
    wheels: VecDeque<WheelSample>,
    gyro: VecDeque<GyroSample>,
    motions: VecDeque<Motion>,
    /// (end of step (s), estimated radii and wheel base (m), the larger
    /// radius std over its radius).
    steps: VecDeque<(f64, [f64; 3], f64)>,
    /// Firings (time (s), detector) whose window is not complete yet, in
    /// time order.
    pending: VecDeque<(f64, &'static str)>,
    /// The laser-mounting watch (when on).
    mount: Option<MountWatch>,
    /// Latest stamp seen (s).
    now: f64,
    /// The last change reported: its effect, its firing's time and the
    /// time of the latest firing that continued it (s).
    last: Option<(String, f64, f64)>,
    /// The effect the last window showed there all along, and that
    /// firing's time (s).
    standing: Option<(String, f64)>,
}

impl ChangeWatch {
    /// A watch for a filter started from `robot` (the baseline of a firing
    /// before any estimate), naming by `p`.
    pub fn new(robot: &RobotConfig, p: &OnsetParams) -> Self {
        Self {
            robot: robot.clone(),
            p: p.clone(),
            wheels: VecDeque::new(),
            gyro: VecDeque::new(),
            motions: VecDeque::new(),
            steps: VecDeque::new(),
            pending: VecDeque::new(),
            mount: p.mount.enabled.then(|| MountWatch::new(&p.mount)),
            now: f64::NEG_INFINITY,
            last: None,
            standing: None,
        }
    }

    /// Takes a stream item.
    pub fn item(&mut self, item: &Item) {
        match item {
            Item::Wheel(w) => {
                self.now = self.now.max(w.stamp);
                self.wheels.push_back(*w);
            }
            Item::Gyro(g) => {
                self.now = self.now.max(g.stamp);
                self.gyro.push_back(*g);
            }
            _ => {}
        }
    }

    /// Takes a scan-matching motion (the mounting watch dates a firing
    /// back to where the mounting moved).
    pub fn motion(&mut self, motion: &Motion) {
        self.now = self.now.max(motion.t1);
        self.motions.push_back(motion.clone());
        if let Some(t) = self.mount.as_mut().and_then(|w| w.motion(motion)) {
            let at = self.pending.partition_point(|p| p.0 <= t);
            self.pending.insert(at, (t, MOUNT));
        }
    }

    /// Takes the estimate after a filter step; returns the firings whose
    /// window is now complete, named, in firing order.
    pub fn step(&mut self, e: &Estimate) -> Vec<NamedChange> {
        self.now = self.now.max(e.t);
        let rel_std = (e.std_r_right / e.r_right).max(e.std_r_left / e.r_left);
        self.steps
            .push_back((e.t, [e.r_right, e.r_left, e.wheel_base], rel_std));
        if e.changed {
            let at = self.pending.partition_point(|p| p.0 <= e.t);
            self.pending.insert(at, (e.t, FILTER));
        }
        let named = self.name_ready(false);
        self.forget_old();
        named
    }

    /// The time (s) before which every firing of the laser-mounting watch
    /// is named: the earliest pending one's, or the earliest a firing still
    /// to come can be dated at; +∞ when the watch is off or has seen no
    /// motion (a firing is dated at the end of a block of motions).
    pub fn mount_named_before(&self) -> f64 {
        let Some(next) = self.mount.as_ref().map(MountWatch::earliest_next_s) else {
            return f64::INFINITY;
        };
        let pending = self.pending.iter().find(|p| p.1 == MOUNT).map(|p| p.0);
        pending
            .into_iter()
            .chain(next)
            .fold(f64::INFINITY, f64::min)
    }

    /// Names the firings still pending at the end of the run.
    pub fn finish(&mut self) -> Vec<NamedChange> {
        self.name_ready(true)
    }

    /// Names the pending firings whose window has passed (all at the end).
    fn name_ready(&mut self, end: bool) -> Vec<NamedChange> {
        let mut out = Vec::new();
        while let Some(&(t, detector)) = self.pending.front() {
            if !end && self.now < t + self.p.after_s + self.p.margin + SLACK_S {
                break;
            }
            let named = NamedChange {
                detector,
                ..self.name(t, detector)
            };
            let named = self.still_standing(named);
            out.push(self.merge(named));
            self.pending.pop_front();
        }
        out
    }

    /// What changed at the firing at `t` (s) of `detector`, against the
    /// filter's estimate at the start of its window.
    fn name(&mut self, t: f64, detector: &str) -> NamedChange {
        let start = t - self.p.before_s;
        let mut base = self.robot.clone();
        let mut rel_std = None;
        if let Some((_, [rr, rl, d], r)) = self.steps.iter().take_while(|s| s.0 <= start).last() {
            (base.r_right, base.r_left, base.wheel_base) = (*rr, *rl, *d);
            rel_std = Some(*r);
        }
        let measured = Measured {
            wheels: self.wheels.make_contiguous(),
            motions: self.motions.make_contiguous(),
            gyro: self.gyro.make_contiguous(),
            reference: &[],
        };
        let candidates: &[&str] = if detector == MOUNT {
            &CANDIDATES
        } else {
            &FILTER_CANDIDATES
        };
        let named = name_change(&base, &measured, t, candidates, &self.p)
            .unwrap_or_else(|| NamedChange::undetermined(t));
        against_baseline(named, rel_std, self.p.converged_rel_std)
    }

    /// Marks a firing that continues the last change reported: the same
    /// effect, begun (its onset) no later than the previous firing, so the
    /// detector fired again on a change its filter does not model (a
    /// latency) rather than on a second one.
    /// A firing whose window shows the last change's effect there all
    /// along (before its onset too) continues it as well.
    fn merge(&mut self, mut c: NamedChange) -> NamedChange {
        let undetermined = c.effect == crate::diagnose::onset::UNDETERMINED;
        match self.last.as_mut() {
            Some((effect, first, latest))
                if (!undetermined && *effect == c.effect && c.onset_s <= *latest)
                    || (undetermined && *effect == c.standing) =>
            {
                c.continues = Some(*first);
                c.effect = effect.clone();
                *latest = c.time_s;
            }
            _ if !undetermined => self.last = Some((c.effect.clone(), c.time_s, c.time_s)),
            _ => {}
        }
        c
    }

    /// A firing that names the effect an earlier window within reach (its
    /// window and this one's together) showed there all along: the same
    /// departure of the baseline showing again where the streams let it
    /// (a constant latency in the turns after a straight stretch), not a
    /// change; it stands too.
    fn still_standing(&mut self, mut c: NamedChange) -> NamedChange {
        let reach = self.p.before_s + self.p.after_s;
        let effect = if c.effect == crate::diagnose::onset::UNDETERMINED {
            c.standing.clone()
        } else {
            match &self.standing {
                Some((e, t)) if *e == c.effect && c.time_s - t <= reach => {
                    c = NamedChange {
                        standing: c.effect.clone(),
                        onset_s: c.onset_s,
                        onset_interval_s: c.onset_interval_s,
                        candidates: std::mem::take(&mut c.candidates),
                        rows: c.rows,
                        detector: c.detector,
                        baseline: c.baseline.clone(),
                        baseline_rel_std: c.baseline_rel_std,
                        ..NamedChange::undetermined(c.time_s)
                    };
                    c.standing.clone()
                }
                _ => String::new(),
            }
        };
        if !effect.is_empty() {
            self.standing = Some((effect, c.time_s));
        }
        c
    }

    /// Forgets what no pending or future firing's window reaches (the
    /// mounting watch dates its firings back by up to its lag).
    fn forget_old(&mut self) {
        let lag = self.mount.as_ref().map_or(0.0, MountWatch::lag_s);
        let from = self
            .pending
            .front()
            .map_or(self.now, |p| p.0)
            .min(self.now - lag);
        let keep = from - self.p.before_s - self.p.margin - self.p.gyro_window - SLACK_S;
        while self.wheels.front().is_some_and(|w| w.stamp < keep) {
            self.wheels.pop_front();
        }
        while self.gyro.front().is_some_and(|g| g.stamp < keep) {
            self.gyro.pop_front();
        }
        while self.motions.front().is_some_and(|m| m.t1 < keep) {
            self.motions.pop_front();
        }
        // The last step before the window stays: it is a firing's baseline.
        while self.steps.get(1).is_some_and(|s| s.0 <= keep) {
            self.steps.pop_front();
        }
    }
}

/// Why a named change names no parameter: its baseline had not converged
/// (the fitted sizes given as they are).
pub fn untold(c: &NamedChange) -> String {
    let how = c.baseline_rel_std.map_or(
        "no estimate yet, the robot file's values".to_string(),
        |r| format!("radius std {:.2} % of the radius", 100.0 * r),
    );
    let sizes: Vec<String> = c
        .parameters
        .iter()
        .map(|(k, v)| format!("{k} {v:+.6}"))
        .collect();
    format!(
        "wheel not told: the baseline had not converged ({how}); fitted {}",
        sizes.join(", ")
    )
}

/// `c` as named against a baseline whose larger radius std over its radius
/// is `rel_std` (`None`: no estimate yet, the robot file's values): above
/// `converged` it has not converged, and a radius step then names no wheel
/// (its fitted right and left changes stay in `parameters`).
fn against_baseline(mut c: NamedChange, rel_std: Option<f64>, converged: f64) -> NamedChange {
    c.baseline_rel_std = rel_std;
    let settled = rel_std.is_some_and(|r| r <= converged);
    if settled {
        return c;
    }
    c.baseline = UNCONVERGED.into();
    if c.effect == "radius_step" {
        c.parameter = String::new();
        c.estimate = f64::NAN;
        c.stderr = f64::NAN;
    }
    c
}

/// The recording's text entries of `changes`: (time (s), text) of every
/// firing, a firing on a change already named saying so.
pub fn entries(changes: &[NamedChange]) -> Vec<(f64, String)> {
    let mut at = Vec::new();
    for c in changes {
        at.push((c.time_s, describe(c)));
        for t in &c.refired_s {
            let again = format!(
                "change at {t:.2} s: {} again, the change named at {:.2} s continuing",
                c.effect, c.time_s
            );
            at.push((*t, again));
        }
    }
    at
}

/// One line per named change for the terminal.
pub fn describe(c: &NamedChange) -> String {
    let by = if c.detector == MOUNT {
        " (laser-mounting watch)"
    } else {
        ""
    };
    if c.effect == crate::diagnose::onset::UNDETERMINED {
        let stood;
        let why = if c.candidates.is_empty() {
            "too few scan-matching rows on a side of the window"
        } else if !c.standing.is_empty() {
            stood = format!(
                "{} explains the window, but stood before it too (before its onset, or all \
                 window long at a firing just before): not a change here",
                c.standing
            );
            &stood
        } else {
            "no candidate lowers BIC by the margin"
        };
        return format!("change at {:.2} s{by}: undetermined ({why})", c.time_s);
    }
    if c.parameter.is_empty() {
        return format!(
            "change at {:.2} s{by} (onset {:.2} s): {} ({}), ΔBIC {:.1}",
            c.time_s,
            c.onset_s,
            c.effect,
            untold(c),
            c.delta_bic
        );
    }
    let unit = crate::effects::EffectKind::from_name(&c.effect)
        .and_then(|k| k.params().iter().find(|p| p.key == c.parameter))
        .map_or("", |p| p.unit);
    // Relative sizes ("1") carry no unit.
    let unit = match unit {
        "" | "1" => String::new(),
        u => format!(" {u}"),
    };
    let mut line = format!(
        "change at {:.2} s{by} (onset {:.2} s, between {:.2} and {:.2} s): {} {} = {:.6} ± {:.6}{unit}, \
         ΔBIC {:.1}",
        c.time_s,
        c.onset_s,
        c.onset_interval_s[0],
        c.onset_interval_s[1],
        c.effect,
        c.parameter,
        c.estimate,
        c.stderr,
        c.delta_bic
    );
    if !c.refired_s.is_empty() {
        let at: Vec<String> = c.refired_s.iter().map(|t| format!("{t:.2} s")).collect();
        line += &format!(
            "; the detector fired again at {} on this same change (begun before)",
            at.join(", ")
        );
    }
    line
}
