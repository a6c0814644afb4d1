//! When to resample, kept apart from how [Farina, Sec. IV.C].

use super::weights::Weights;
use serde::{Deserialize, Serialize};

/// The rule deciding whether a step resamples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Trigger {
    /// Every step.
    Every,
    /// When `N_eff < ratio · N` (ratio 0.5 by default).
    #[default]
    Neff,
    /// When the largest normalised weight falls below a threshold.
    MaxWeight,
}

impl Trigger {
    /// Every trigger, in the order of the paper's Table I.
    pub const ALL: [Trigger; 3] = [Trigger::Neff, Trigger::MaxWeight, Trigger::Every];

    /// The name used on the command line and in tables.
    pub fn as_str(&self) -> &'static str {
        match self {
            Self::Every => "every",
            Self::Neff => "neff",
            Self::MaxWeight => "max-weight",
        }
    }

    /// Whether to resample now. `neff_ratio` is the N_eff threshold as a
    /// fraction of N; `max_weight_factor` sets the max-weight threshold to
    /// `factor / N` (the weights are spread thin, no particle dominates: the
    /// set has lost its focus and is renewed). The paper gives no value for
    /// the latter threshold; a factor of 2 is odocal's choice.
    pub fn fires(&self, w: &Weights, neff_ratio: f64, max_weight_factor: f64) -> bool {
        let n = w.len() as f64;
        match self {
            Self::Every => true,
            Self::Neff => w.ess() < neff_ratio * n,
            Self::MaxWeight => w.max_weight() < max_weight_factor / n,
        }
    }
}

impl std::str::FromStr for Trigger {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|x| x.as_str() == s)
            .ok_or_else(|| format!("unknown trigger {s:?} (every|neff|max-weight)"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triggers_fire_on_their_own_criterion() {
        let flat = Weights::uniform(100);
        let mut peaked = Weights::uniform(100);
        peaked.log_mut()[3] = 10.0;
        peaked.normalize();
        assert!(Trigger::Every.fires(&flat, 0.5, 2.0));
        assert!(!Trigger::Neff.fires(&flat, 0.5, 2.0));
        assert!(Trigger::Neff.fires(&peaked, 0.5, 2.0));
        assert!(Trigger::MaxWeight.fires(&flat, 0.5, 2.0));
        assert!(!Trigger::MaxWeight.fires(&peaked, 0.5, 2.0));
        // At exactly the threshold neither fires (strict comparisons): two
        // equal weights have N_eff = 1/(0.5² + 0.5²) = 2 = 1.0 · N, and four
        // equal weights have a largest weight of 1/4 = 1.0 / N.
        assert!(!Trigger::Neff.fires(&Weights::uniform(2), 1.0, 2.0));
        assert!(!Trigger::MaxWeight.fires(&Weights::uniform(4), 0.5, 1.0));
        for t in Trigger::ALL {
            assert_eq!(t.as_str().parse::<Trigger>().unwrap(), t);
        }
    }
}
