//! Parameters of the scan matcher: one plain struct with defaults, read from the
//! `[icp]` table of a config file and validated once.

use super::limits::SpeedLimits;
use serde::{Deserialize, Serialize};

/// Everything the scan matcher can be tuned by. Units: m, rad, s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IcpParams {
    /// Readings shorter than this are dropped, on top of the scan's own range_min (m).
    pub min_range: f64,
    /// Readings longer than this are dropped, on top of the scan's own range_max (m).
    pub max_range: f64,
    /// Voxel size of the source-scan downsampling (m); 0 keeps every point.
    pub voxel_size: f64,
    /// Keep every n-th beam of the source scan before voxelisation (1 = all).
    pub beam_stride: usize,
    /// Two consecutive reference points closer than `gap_factor` × range ×
    /// beam spacing (and `max_gap`) lie on one surface: correspondences may
    /// land anywhere on the segment between them.
    pub gap_factor: f64,
    /// Upper bound of the surface gap test (m).
    pub max_gap: f64,
    /// A reference point's local surface line is fitted through
    /// `normal_window + 1` consecutive linked points (the straightest such
    /// window containing it): averages the range noise out of the surface the
    /// source is matched against.
    pub normal_window: usize,
    /// Surface length (m) a line window should span: where `normal_window`
    /// beams would span more (sparse 1° scanners, long ranges), the window
    /// has fewer points, down to 3. 0 = always `normal_window`.
    pub normal_length: f64,
    /// Largest angle (rad) between a source point's own surface normal and
    /// the reference line it is matched to.
    pub max_normal_angle: f64,
    /// The error ICP minimises: `"point-to-line"` (the distance from the
    /// nearest reference point's fitted line) or `"point-to-point"` (from
    /// the nearest reference point itself; same correspondences and robust
    /// kernel). Point-to-point is measured in the manual's results.
    pub metric: super::Metric,
    /// What answers the nearest-neighbour queries: `"grid"` (a uniform 0.2 m
    /// grid, the faster here) or `"kd-tree"` (kiddo's k-d tree). Both are
    /// exact, so the motions are the same; only the time differs.
    pub neighbours: super::NeighbourSearch,
    /// Smallest scale of the robust kernel (m); the kernel otherwise follows
    /// twice the robust standard deviation of the residuals.
    pub min_kappa: f64,
    /// Compensate the motion during each sweep (needs the scan's
    /// `time_increment`), with the pair's prior as velocity.
    pub deskew: bool,
    /// Fewest valid points a scan needs to be matched.
    pub min_points: usize,
    /// Fewest correspondences, absolute.
    pub min_correspondences: usize,
    /// Fewest correspondences as a fraction of the source points that have a
    /// surface line of their own (only those can be matched).
    pub min_inlier_fraction: f64,
    /// Largest number of iterations before the pair is declared not converged.
    pub max_iterations: u32,
    /// Convergence: pose change of one iteration below this (m, and rad × 1 m).
    pub convergence: f64,
    /// Correspondence gate before any motion-model error has been seen (m).
    pub initial_threshold: f64,
    /// Smallest correspondence gate (m): the sensor noise floor.
    pub min_threshold: f64,
    /// Largest correspondence gate (m).
    pub max_threshold: f64,
    /// Model errors below this are not counted by the adaptive threshold (m).
    pub min_motion: f64,
    /// Lever arm turning rotation errors into displacement in the threshold (m).
    pub threshold_range: f64,
    /// Factor on the Hessian-based covariance: corrects its known
    /// over-confidence (correlated residuals, reference noise), fitted on
    /// simulated runs with known truth (NEES ≈ 3).
    pub cov_inflation: f64,
    /// Ratio of smallest to largest eigenvalue of the normalised information
    /// below which a pair is degenerate.
    pub degenerate_ratio: f64,
    /// Largest plausible translation deviation from the prior (m), on top of
    /// `prior_rel_tol` × prior translation.
    pub prior_trans_tol: f64,
    /// Relative slack on the prior translation.
    pub prior_rel_tol: f64,
    /// Largest plausible rotation deviation from the prior (rad).
    pub prior_rot_tol: f64,
    /// Standard deviation (m) of the given prior's translation (the wheel
    /// odometry), per pair: a weak prior term in the registration that holds
    /// the directions the geometry leaves loose (a corridor's axis) at the
    /// odometry. 0 = no prior term. A motion owes to the scan only the
    /// information it measured beyond its lines' direction noise; its
    /// covariance is that information plus the prior term's, inverted.
    pub prior_sigma_xy: f64,
    /// Same for the given prior's heading change (rad).
    pub prior_sigma_theta: f64,
    /// Forgetting rate (per matched pair) of the online error model of the
    /// odometry and constant-velocity predictions against the matched
    /// motions. With it the prior term's translation is centred on the
    /// inverse-variance mean of both predictions instead of on the odometry
    /// alone, and where it is the odometry alone, its σ is the odometry's
    /// learned error (within `prior_sigma_bounds`). 0 = centred on the
    /// odometry with `prior_sigma_xy`.
    pub prior_blend_rate: f64,
    /// Smallest conditioning (`MatchInfo::conditioning`) of a pair for it to
    /// train that error model, and of the pair a constant-velocity guess
    /// comes from for it to take part: only motions the scans measured in
    /// every direction say how good a prediction is.
    pub prior_blend_conditioning: f64,
    /// Smallest and largest learned translation σ of the prior term (m).
    pub prior_sigma_bounds: [f64; 2],
    /// Largest plausible speed (m/s) and turn rate (rad/s) of the robot.
    pub max_speed: f64,
    /// See `max_speed` (rad/s).
    pub max_turn_rate: f64,
    /// Largest plausible deceleration (m/s²) from the last matched velocity:
    /// a given prior (odometry increment) that stands still while the robot
    /// could not have stopped that fast is a frozen odometry, and the
    /// constant-velocity guess replaces it (also for the jump with which it
    /// catches up) while the scans agree.
    pub max_accel: f64,
    /// Same for the turn rate (rad/s²).
    pub max_angular_accel: f64,
    /// Slack on `max_speed` × dt beyond 3σ of the match (m).
    pub speed_slack: f64,
    /// Slack on `max_turn_rate` × dt beyond 3σ of the match (rad).
    pub turn_slack: f64,
    /// Offset (s) of the prior's clock: odometry (or wheel) stamp minus laser
    /// stamp of one instant, as `calibrate --method batch` estimates it
    /// (`time_offset`). The prior of a pair of scans stamped `t0`, `t1` is the
    /// odometry's motion over `[t0 + time_offset, t1 + time_offset]`.
    /// 0 = one clock; `odocal icp` reports the offset at which the
    /// odometry's turns fit the matched ones best (`prior_time_offset`).
    pub time_offset: f64,
    /// Match against a local map of recent keyframes instead of the previous
    /// scan (default). Scan-to-scan matching has a small pull towards zero
    /// motion (things that move with the sensor: sampling, occlusion edges,
    /// range and field-of-view limits) that adds up pair after pair; against a
    /// keyframe it is paid once per keyframe, not once per scan.
    pub local_map: bool,
    /// Keyframes kept in the local map.
    pub keyframes: usize,
    /// New keyframe after this much translation (m) …
    pub keyframe_dist: f64,
    /// … or this much rotation (rad).
    pub keyframe_angle: f64,
    /// Which stream gives each pair's initial guess and the prior term's
    /// centre: `auto` (default; see [`PriorChoice::Auto`]), `wheels`,
    /// `odometry` (the recording's own) or `none`.
    pub prior: PriorChoice,
}

/// The stream the scan matcher's prior comes from (`[icp] prior`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PriorChoice {
    /// The wheels when the recording has a wheel stream, else its own
    /// odometry, else none. The commands refine it: without a robot file
    /// stating the wheels' kinematics, a recording's own odometry is
    /// preferred to wheels integrated with assumed ones.
    #[default]
    Auto,
    /// Wheel odometry integrated with the nominal robot.
    Wheels,
    /// The recording's own odometry.
    Odometry,
    /// None: each pair starts from the previous matched pair's velocity.
    None,
}

impl PriorChoice {
    /// The word of the config file (`auto`, `wheels`, `odometry`, `none`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Wheels => "wheels",
            Self::Odometry => "odometry",
            Self::None => "none",
        }
    }
}

impl Default for IcpParams {
    fn default() -> Self {
        Self {
            min_range: 0.0,
            max_range: 30.0,
            voxel_size: 0.0,
            beam_stride: 1,
            gap_factor: 6.0,
            max_gap: 0.5,
            normal_window: 8,
            normal_length: 0.3,
            max_normal_angle: 0.5,
            metric: super::Metric::default(),
            neighbours: super::NeighbourSearch::default(),
            min_kappa: 0.005,
            deskew: true,
            min_points: 20,
            min_correspondences: 15,
            min_inlier_fraction: 0.3,
            max_iterations: 60,
            convergence: 1e-5,
            initial_threshold: 1.0,
            min_threshold: 0.1,
            max_threshold: 1.5,
            min_motion: 0.005,
            threshold_range: 5.0,
            cov_inflation: 1.7,
            degenerate_ratio: 1e-4,
            prior_trans_tol: 0.25,
            prior_rel_tol: 0.5,
            prior_rot_tol: 0.35,
            prior_sigma_xy: 0.02,
            prior_sigma_theta: 0.5,
            prior_blend_rate: 0.05,
            prior_blend_conditioning: 0.03,
            prior_sigma_bounds: [0.005, 0.1],
            max_speed: 3.0,
            max_turn_rate: 3.0,
            max_accel: 1.5,
            max_angular_accel: 3.0,
            speed_slack: 0.01,
            turn_slack: 0.01,
            time_offset: 0.0,
            local_map: true,
            keyframes: 5,
            keyframe_dist: 0.3,
            keyframe_angle: 0.2,
            prior: PriorChoice::Auto,
        }
    }
}

/// A parameter set that cannot work.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid ICP parameter {name}: {why}")]
pub struct IcpParamsError {
    /// The parameter's field name.
    pub name: &'static str,
    /// What is wrong with it.
    pub why: &'static str,
}

impl IcpParams {
    /// Whether a motion (dx, dy, dθ in m, m, rad) over `dt` s is within the
    /// robot's speed and turn-rate limits, allowing 3σ of its covariance
    /// `cov` plus the slacks: the plausibility gate of every match, and the
    /// check of motions read from a file.
    pub fn within_limits(&self, motion: [f64; 3], cov: &nalgebra::Matrix3<f64>, dt: f64) -> bool {
        self.speed_limits().within(motion, cov, dt)
    }

    /// The robot's speed and turn-rate limits with their slacks.
    pub fn speed_limits(&self) -> SpeedLimits {
        SpeedLimits {
            max_speed: self.max_speed,
            max_turn_rate: self.max_turn_rate,
            speed_slack: self.speed_slack,
            turn_slack: self.turn_slack,
        }
    }

    /// Checks ranges and orderings once, before any matching.
    pub fn validate(&self) -> Result<(), IcpParamsError> {
        self.check_positive()?;
        self.check_non_negative()?;
        self.check_bounds()?;
        self.check_counts()
    }

    /// Lengths, angles, tolerances and rates that must be positive and finite.
    fn check_positive(&self) -> Result<(), IcpParamsError> {
        let pos = [
            ("max_range", self.max_range),
            ("gap_factor", self.gap_factor),
            ("max_gap", self.max_gap),
            ("max_normal_angle", self.max_normal_angle),
            ("min_kappa", self.min_kappa),
            ("convergence", self.convergence),
            ("initial_threshold", self.initial_threshold),
            ("min_threshold", self.min_threshold),
            ("max_threshold", self.max_threshold),
            ("threshold_range", self.threshold_range),
            ("cov_inflation", self.cov_inflation),
            ("degenerate_ratio", self.degenerate_ratio),
            ("prior_trans_tol", self.prior_trans_tol),
            ("prior_rot_tol", self.prior_rot_tol),
            ("max_speed", self.max_speed),
            ("max_turn_rate", self.max_turn_rate),
            ("max_accel", self.max_accel),
            ("max_angular_accel", self.max_angular_accel),
            ("speed_slack", self.speed_slack),
            ("turn_slack", self.turn_slack),
            ("keyframe_dist", self.keyframe_dist),
            ("keyframe_angle", self.keyframe_angle),
        ];
        for (name, v) in pos {
            if !(v > 0.0 && v.is_finite()) {
                return invalid(name, "must be positive and finite");
            }
        }
        Ok(())
    }

    /// Values where 0 means "off" or "none": non-negative and finite.
    fn check_non_negative(&self) -> Result<(), IcpParamsError> {
        let nonneg = [
            ("min_range", self.min_range),
            ("normal_length", self.normal_length),
            ("voxel_size", self.voxel_size),
            ("min_motion", self.min_motion),
            ("prior_rel_tol", self.prior_rel_tol),
            ("prior_sigma_xy", self.prior_sigma_xy),
            ("prior_sigma_theta", self.prior_sigma_theta),
            ("prior_blend_rate", self.prior_blend_rate),
            ("prior_blend_conditioning", self.prior_blend_conditioning),
            ("min_inlier_fraction", self.min_inlier_fraction),
        ];
        for (name, v) in nonneg {
            if !(v >= 0.0 && v.is_finite()) {
                return invalid(name, "must be non-negative and finite");
            }
        }
        Ok(())
    }

    /// Orderings of paired limits and upper bounds of fractions.
    fn check_bounds(&self) -> Result<(), IcpParamsError> {
        if self.min_range >= self.max_range {
            return invalid("min_range", "must be below max_range");
        }
        if self.min_threshold > self.max_threshold {
            return invalid("min_threshold", "must not exceed max_threshold");
        }
        if self.prior_blend_rate > 1.0 {
            return invalid("prior_blend_rate", "must be at most 1");
        }
        let [lo, hi] = self.prior_sigma_bounds;
        if !(lo > 0.0 && lo <= hi && hi.is_finite()) {
            return invalid("prior_sigma_bounds", "must be positive, finite and ordered");
        }
        if self.min_inlier_fraction > 1.0 {
            return invalid("min_inlier_fraction", "must be at most 1");
        }
        if !(self.time_offset.abs() <= MAX_TIME_OFFSET_S) {
            return invalid(
                "time_offset",
                "must be finite and within 1 s (beyond it the clocks disagree: fix the stamps)",
            );
        }
        Ok(())
    }

    /// Counts: strides, windows, iterations, points and keyframes.
    fn check_counts(&self) -> Result<(), IcpParamsError> {
        if self.beam_stride == 0 {
            return invalid("beam_stride", "must be at least 1");
        }
        if self.normal_window == 0 {
            return invalid("normal_window", "must be at least 1");
        }
        if self.max_iterations == 0 {
            return invalid("max_iterations", "must be at least 1");
        }
        if self.min_points < 3 || self.min_correspondences < 3 {
            return invalid("min_points", "need at least 3 points to fix a 2D pose");
        }
        if self.local_map && self.keyframes == 0 {
            return invalid("keyframes", "must be at least 1 with local_map");
        }
        Ok(())
    }
}

/// Largest `time_offset` (s) accepted: a second between the odometry's and
/// the scans' stamps of one instant is a clock error, not a latency (as the
/// batch calibration's `max_time_offset_s`).
pub const MAX_TIME_OFFSET_S: f64 = 1.0;

/// The error for parameter `name`.
fn invalid(name: &'static str, why: &'static str) -> Result<(), IcpParamsError> {
    Err(IcpParamsError { name, why })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_round_trip_through_toml() {
        let p = IcpParams::default();
        p.validate().unwrap();
        let s = toml::to_string(&p).unwrap();
        let q: IcpParams = toml::from_str(&s).unwrap();
        assert_eq!(p, q);
        let partial: IcpParams = toml::from_str("max_range = 12.0").unwrap();
        assert_eq!(partial.max_range, 12.0);
        assert!(toml::from_str::<IcpParams>("bogus = 1").is_err());
    }

    #[test]
    fn bad_values_are_named() {
        let p = IcpParams {
            convergence: 0.0,
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err().name, "convergence");
        let p = IcpParams {
            min_range: 40.0,
            ..Default::default()
        };
        assert_eq!(p.validate().unwrap_err().name, "min_range");
    }
}
