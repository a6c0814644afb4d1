//! Property tests of the resampling schemes: one contract, counts, bounds,
//! offspring bounds and unbiasedness.

use odocal::calib::{resample, Scheme};
use proptest::prelude::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;

fn normalised(raw: &[f64]) -> Vec<f64> {
    let s: f64 = raw.iter().sum();
    raw.iter().map(|x| x / s).collect()
}

fn counts(idx: &[usize], n: usize) -> Vec<usize> {
    let mut c = vec![0; n];
    for &i in idx {
        c[i] += 1;
    }
    c
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn every_scheme_returns_n_in_bound_indices_of_positive_weight(
        raw in prop::collection::vec(prop_oneof![Just(0.0), 0.001f64..1.0], 1..60),
        n in 1usize..200,
        seed in any::<u64>(),
    ) {
        prop_assume!(raw.iter().any(|&x| x > 0.0));
        let w = normalised(&raw);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        for s in Scheme::ALL {
            let idx = resample(s, &w, n, &mut rng);
            prop_assert_eq!(idx.len(), n);
            prop_assert!(idx.iter().all(|&i| i < w.len() && w[i] > 0.0));
        }
    }

    #[test]
    fn systematic_residual_and_stratified_offspring_stay_near_n_w(
        raw in prop::collection::vec(0.001f64..1.0, 1..60),
        n in 1usize..200,
        seed in any::<u64>(),
    ) {
        let w = normalised(&raw);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        for s in [Scheme::Systematic, Scheme::Residual, Scheme::Stratified] {
            let c = counts(&resample(s, &w, n, &mut rng), w.len());
            for (ci, wi) in c.iter().zip(&w) {
                let x = n as f64 * wi;
                // Systematic: floor/ceil of N w_i; residual: at least floor;
                // stratified: within ±2 of N w_i (one stratum at each end).
                let (lo, hi) = match s {
                    Scheme::Systematic => (x.floor() - 1e-9, x.ceil() + 1e-9),
                    Scheme::Residual => (x.floor() - 1e-9, f64::INFINITY),
                    _ => (x - 2.0, x + 2.0),
                };
                prop_assert!((*ci as f64) >= lo && (*ci as f64) <= hi,
                    "{:?}: count {} for N w = {}", s, ci, x);
            }
        }
    }
}

#[test]
fn every_scheme_is_unbiased_over_many_draws() {
    let w = normalised(&[0.05, 0.3, 0.0, 0.12, 0.33, 0.2]);
    let (n, draws) = (10usize, 20_000usize);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(99);
    for s in Scheme::ALL {
        let mut total = vec![0usize; w.len()];
        for _ in 0..draws {
            for (t, c) in total
                .iter_mut()
                .zip(counts(&resample(s, &w, n, &mut rng), w.len()))
            {
                *t += c;
            }
        }
        for (t, wi) in total.iter().zip(&w) {
            let mean = *t as f64 / draws as f64;
            let expect = n as f64 * wi;
            // Multinomial variance bounds the others: 5σ of the mean count.
            let sd = (n as f64 * wi * (1.0 - wi) / draws as f64).sqrt();
            assert!(
                (mean - expect).abs() <= 5.0 * sd + 1e-12,
                "{s:?}: {mean} vs {expect}"
            );
        }
    }
}
