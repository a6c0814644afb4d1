//! A pool of standard normal variates for the particle filters' random walks
//! and kernel moves. Drawing three ziggurat normals per particle per step
//! (24,000 per step at N = 8,000) would cost more than the whole rest of the
//! step; instead the pool is filled once from the filter's RNG, a block of it
//! is redrawn at every request (so it never goes stale), and each request
//! reads contiguous runs of it at independent uniform offsets. Within one
//! request every particle gets distinct, independent normals; across requests
//! a particle's increments are draws at independent random positions.

use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};

/// Smallest pool (entries): large against any block a request reads.
const MIN_POOL: usize = 1 << 16;
/// Entries redrawn at every request.
const REFRESH: usize = 512;

/// Standard normals, read as runs at random offsets (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct NormalPool {
    data: Vec<f64>,
    next: usize,
}

impl NormalPool {
    /// An empty pool; it fills on the first request.
    pub fn new() -> Self {
        Self::default()
    }

    /// Redraws a block of the pool and returns `K` offsets, each the start of
    /// a run of `n` normals inside [`NormalPool::data`]. The pool grows (and
    /// is refilled) when `n` is large against it.
    pub fn offsets<const K: usize, R: Rng + ?Sized>(
        &mut self,
        n: usize,
        rng: &mut R,
    ) -> [usize; K] {
        let want = MIN_POOL.max(4 * n).next_power_of_two();
        if self.data.len() < want {
            self.data.clear();
            self.data
                .extend((0..want).map(|_| -> f64 { StandardNormal.sample(rng) }));
            self.next = 0;
        }
        let m = self.data.len();
        for _ in 0..REFRESH {
            self.data[self.next] = StandardNormal.sample(rng);
            self.next = (self.next + 1) & (m - 1);
        }
        let span = (m - n + 1) as u64;
        std::array::from_fn(|_| (rng.random::<u64>() % span) as usize)
    }

    /// The pool's normals.
    pub fn data(&self) -> &[f64] {
        &self.data
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn runs_are_standard_normal_and_uncorrelated() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(9);
        let mut pool = NormalPool::new();
        let n = 8000;
        let (mut s, mut s2, mut s4, mut cross, mut k) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for _ in 0..50 {
            let [a, b] = pool.offsets::<2, _>(n, &mut rng);
            let d = pool.data();
            for i in 0..n {
                let (x, y) = (d[a + i], d[b + i]);
                s += x;
                s2 += x * x;
                s4 += x.powi(4);
                cross += x * y;
                k += 1.0;
            }
        }
        let (m, v) = (s / k, s2 / k);
        assert!(m.abs() < 0.01, "mean {m}");
        assert!((v - 1.0).abs() < 0.02, "variance {v}");
        assert!((s4 / k - 3.0).abs() < 0.15, "kurtosis {}", s4 / k);
        assert!((cross / k).abs() < 0.02, "cross-correlation {}", cross / k);
        // Large requests grow the pool.
        let [o] = pool.offsets::<1, _>(100_000, &mut rng);
        assert!(pool.data().len() >= o + 100_000);
    }
}
