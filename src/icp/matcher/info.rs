//! What the matcher reports of a pair besides its motion: where the initial
//! guess came from, and the registration's diagnostics.

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

impl PriorSource {
    /// Whether a registration from this guess carries the weak prior term
    /// (`prior_sigma_*`): the given prior and the guess substituted for it
    /// do, a constant-velocity guess of its own and the identity do not.
    pub fn holds(self) -> bool {
        matches!(self, Self::Given | Self::Substituted)
    }
}

/// Diagnostics of the last pair, beside the [`Motion`](crate::motion::Motion) itself.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_given_prior_and_its_substitute_hold_the_prior_term() {
        assert!(PriorSource::Given.holds());
        assert!(PriorSource::Substituted.holds());
        assert!(!PriorSource::ConstantVelocity.holds());
        assert!(!PriorSource::None.holds());
        assert_eq!(PriorSource::default(), PriorSource::None);
    }
}
