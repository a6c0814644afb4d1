//! Choosing which particles to draw when a cloud is too large to show whole.

/// Indices (ascending, distinct) of at most `k` particles chosen by
/// systematic resampling of `weights` with the fixed offset ½: K evenly
/// spaced points `(j + ½)/K` on the cumulative normalised weights pick the
/// particle whose interval holds them, so heavy particles are always shown and
/// the picture is deterministic. Non-finite or negative weights count as 0;
/// all-zero weights are treated as uniform. With `weights.len() <= k` every
/// index is returned.
pub fn systematic_subsample(weights: &[f64], k: usize) -> Vec<usize> {
    let n = weights.len();
    if n <= k {
        return (0..n).collect();
    }
    if k == 0 {
        return Vec::new();
    }
    let clean = |w: f64| if w.is_finite() && w > 0.0 { w } else { 0.0 };
    let total: f64 = weights.iter().map(|&w| clean(w)).sum();
    let uniform = !(total > 0.0 && total.is_finite());
    let weight = |i: usize| {
        if uniform {
            1.0 / n as f64
        } else {
            clean(weights[i]) / total
        }
    };
    let mut out = Vec::with_capacity(k);
    let mut cum = weight(0);
    let mut i = 0;
    for j in 0..k {
        let u = (j as f64 + 0.5) / k as f64;
        while cum < u && i + 1 < n {
            i += 1;
            cum += weight(i);
        }
        if out.last() != Some(&i) {
            out.push(i);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_clouds_are_shown_whole() {
        assert_eq!(systematic_subsample(&[0.1, 0.0, 0.9], 5), vec![0, 1, 2]);
    }

    #[test]
    fn uniform_weights_give_evenly_spaced_distinct_indices() {
        let w = vec![1.0; 1000];
        let idx = systematic_subsample(&w, 100);
        assert_eq!(idx.len(), 100);
        assert!(idx[0] <= 10);
        assert!(idx.windows(2).all(|p| (9..=11).contains(&(p[1] - p[0]))));
    }

    #[test]
    fn heavy_particle_is_always_kept_and_zero_weights_never() {
        let mut w = vec![0.0; 10_000];
        for (i, x) in w.iter_mut().enumerate() {
            if i % 2 == 0 {
                *x = 1.0;
            }
        }
        w[7] = 5_000.0;
        let idx = systematic_subsample(&w, 50);
        assert!(idx.contains(&7));
        assert!(idx.len() <= 50);
        assert!(idx.iter().all(|&i| i == 7 || i % 2 == 0));
        assert!(idx.windows(2).all(|p| p[0] < p[1]));
    }

    #[test]
    fn degenerate_weights_fall_back_to_uniform() {
        let w = vec![f64::NAN; 400];
        let idx = systematic_subsample(&w, 4);
        assert_eq!(idx.len(), 4);
        assert!(idx.windows(2).all(|p| (99..=101).contains(&(p[1] - p[0]))));
    }
}
