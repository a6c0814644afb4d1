//! Repetitions of a simulated experiment: each robot gets its own hidden
//! radius and wheel-base errors from its seed, and an experiment needs at
//! least one repetition of everything it counts.

use crate::classic::ClassicError;
use crate::robot::DiffDrive;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// Hidden parameters: nominal radii and wheel base scaled by uniform relative
/// errors in ± `radius_error` and ± `wheel_base_error`.
pub fn draw_hidden_truth(
    nominal: &DiffDrive,
    radius_error: f64,
    wheel_base_error: f64,
    seed: u64,
) -> DiffDrive {
    let mut rng = StdRng::seed_from_u64(seed ^ 0x6869_6464_656e);
    let mut u = |a: f64| {
        if a > 0.0 {
            rng.random_range(-a..a)
        } else {
            0.0
        }
    };
    DiffDrive {
        r_right: nominal.r_right * (1.0 + u(radius_error)),
        r_left: nominal.r_left * (1.0 + u(radius_error)),
        wheel_base: nominal.wheel_base * (1.0 + u(wheel_base_error)),
    }
}

/// Refuses an experiment when any of `counts` is zero: `method` needs at
/// least one of `what`.
pub(crate) fn at_least_one(
    method: &'static str,
    what: &'static str,
    counts: &[usize],
) -> Result<(), ClassicError> {
    if counts.contains(&0) {
        return Err(ClassicError::TooFew {
            method,
            what,
            needed: 1,
            got: 0,
        });
    }
    Ok(())
}
