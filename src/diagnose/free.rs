//! The free parameters of an effect: those the diagnosis fits by least
//! squares, in table order (every parameter but the ones searched on a grid,
//! such as a radius step's time; see [`Estimate`]).

use crate::effects::{Effect, Estimate, Param};

/// The free parameters' metadata and values of an effect.
fn free(e: &Effect) -> impl Iterator<Item = (&'static Param, f64)> {
    e.kind()
        .params()
        .iter()
        .zip(e.values())
        .filter(|(p, _)| p.is_free())
}

/// Values of the free parameters.
pub fn free_params(e: &Effect) -> Vec<f64> {
    free(e).map(|(_, v)| v).collect()
}

/// Names of the free parameters, in [`free_params`] order.
pub fn free_names(e: &Effect) -> Vec<&'static str> {
    free(e).map(|(p, _)| p.key).collect()
}

/// Finite-difference step of each free parameter (its units).
pub fn free_steps(e: &Effect) -> Vec<f64> {
    e.kind()
        .params()
        .iter()
        .filter_map(|p| match p.estimate {
            Estimate::Fitted(step) => Some(step),
            Estimate::Searched => None,
        })
        .collect()
}

/// The effect with its free parameters replaced by `v` (the others kept).
pub fn with_free(e: &Effect, v: &[f64]) -> Effect {
    let kind = e.kind();
    let mut free = v.iter();
    let values: Vec<f64> = kind
        .params()
        .iter()
        .zip(e.values())
        .map(|(p, old)| {
            if p.is_free() {
                *free.next().expect("one value per free parameter")
            } else {
                old
            }
        })
        .collect();
    kind.effect(&values)
}

/// The effect of a name with every free parameter zero (the nominal model).
pub fn zero_effect(name: &str) -> Option<Effect> {
    let e = Effect::default_for(name)?;
    let n = free_params(&e).len();
    Some(with_free(&e, &vec![0.0; n]))
}

/// Degrees of freedom of a set of effects: every parameter is estimated,
/// fitted or searched.
pub fn dof(effects: &[Effect]) -> usize {
    effects.iter().map(|e| e.kind().params().len()).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::EFFECT_NAMES;

    #[test]
    fn a_radius_step_frees_its_sizes_not_its_time() {
        let e = Effect::RadiusStep {
            time: 30.0,
            right: 0.004,
            left: -0.002,
        };
        assert_eq!(free_names(&e), ["right", "left"]);
        assert_eq!(free_params(&e), [0.004, -0.002]);
        assert_eq!(free_steps(&e), [1e-6, 1e-6]);
        assert_eq!(
            with_free(&e, &[0.1, 0.2]),
            Effect::RadiusStep {
                time: 30.0,
                right: 0.1,
                left: 0.2
            }
        );
        assert_eq!(dof(&[e]), 3);
    }

    #[test]
    fn zero_effects_are_nominal() {
        for name in EFFECT_NAMES {
            let z = zero_effect(name).unwrap();
            assert!(free_params(&z).iter().all(|v| *v == 0.0), "{z}");
            assert_eq!(free_steps(&z).len(), free_names(&z).len());
        }
    }
}
