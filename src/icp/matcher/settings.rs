//! Each component's settings, taken from the matcher's parameters: the
//! components never see `IcpParams` itself.

use super::acceptance::AcceptSettings;
use super::local_map::LocalMapSettings;
use super::prior::PriorSettings;
use super::prior_term::PriorTermSettings;
use super::retry::RetrySettings;
use super::source::SourceSettings;
use crate::icp::params::IcpParams;
use crate::icp::register::RegisterSettings;

/// The registration's settings; its gate (`threshold`) and prior term
/// (`prior_precision`) are set per registration.
pub fn register_settings(p: &IcpParams) -> RegisterSettings {
    RegisterSettings {
        threshold: p.initial_threshold,
        max_gap: p.max_gap,
        min_normal_cos: p.max_normal_angle.cos(),
        min_kappa: p.min_kappa,
        max_iterations: p.max_iterations,
        convergence: p.convergence,
        min_correspondences: p.min_correspondences,
        cov_inflation: p.cov_inflation,
        metric: p.metric,
        prior_precision: [0.0; 3],
    }
}

/// How fast the speed can change, for the choice of the guess.
pub fn prior_settings(p: &IcpParams) -> PriorSettings {
    PriorSettings {
        max_accel: p.max_accel,
        max_angular_accel: p.max_angular_accel,
        speed_slack: p.speed_slack,
        turn_slack: p.turn_slack,
    }
}

/// The prior term's spread and learning.
pub fn prior_term_settings(p: &IcpParams) -> PriorTermSettings {
    PriorTermSettings {
        sigma_xy: p.prior_sigma_xy,
        sigma_theta: p.prior_sigma_theta,
        blend_rate: p.prior_blend_rate,
        blend_conditioning: p.prior_blend_conditioning,
        sigma_bounds: p.prior_sigma_bounds,
    }
}

/// Deskewing and thinning of the source.
pub fn source_settings(p: &IcpParams) -> SourceSettings {
    SourceSettings {
        deskew: p.deskew,
        beam_stride: p.beam_stride,
        voxel_size: p.voxel_size,
    }
}

/// The speed limits a retry and a fallback are held to.
pub fn retry_settings(p: &IcpParams) -> RetrySettings {
    RetrySettings {
        limits: p.speed_limits(),
    }
}

/// The gates of a pair.
pub fn accept_settings(p: &IcpParams) -> AcceptSettings {
    AcceptSettings {
        min_points: p.min_points,
        min_correspondences: p.min_correspondences,
        min_inlier_fraction: p.min_inlier_fraction,
        degenerate_ratio: p.degenerate_ratio,
        prior_trans_tol: p.prior_trans_tol,
        prior_rel_tol: p.prior_rel_tol,
        prior_rot_tol: p.prior_rot_tol,
        limits: p.speed_limits(),
    }
}

/// The reference's shape and the keyframe policy.
pub fn local_map_settings(p: &IcpParams) -> LocalMapSettings {
    LocalMapSettings {
        local_map: p.local_map,
        keyframes: p.keyframes,
        keyframe_dist: p.keyframe_dist,
        keyframe_angle: p.keyframe_angle,
        min_points: p.min_points,
        normal_window: p.normal_window,
        normal_length: p.normal_length,
        neighbours: p.neighbours,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_components_defaults_are_the_parameters_defaults() {
        let p = IcpParams::default();
        assert_eq!(prior_settings(&p), PriorSettings::default());
        assert_eq!(prior_term_settings(&p), PriorTermSettings::default());
        assert_eq!(source_settings(&p), SourceSettings::default());
        assert_eq!(retry_settings(&p), RetrySettings::default());
        assert_eq!(accept_settings(&p), AcceptSettings::default());
        assert_eq!(local_map_settings(&p), LocalMapSettings::default());
    }

    #[test]
    fn settings_round_trip_through_toml_and_refuse_unknown_keys() {
        let s = accept_settings(&IcpParams::default());
        let back: AcceptSettings = toml::from_str(&toml::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
        let partial: LocalMapSettings = toml::from_str("keyframes = 3").unwrap();
        assert_eq!(partial.keyframes, 3);
        assert!(toml::from_str::<PriorSettings>("max_speed = 1.0").is_err());
    }
}
