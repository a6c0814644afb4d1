//! Closed-form weighted 2D rigid alignment (Arun et al. 1987 / Umeyama 1991 in
//! 2D): the rotation maximising Σ wᵢ (qᵢ − q̄)ᵀ R (pᵢ − p̄) is
//! θ = atan2(H_xy − H_yx, H_xx + H_yy) with H = Σ wᵢ (pᵢ − p̄)(qᵢ − q̄)ᵀ, and
//! t = q̄ − R p̄. No SVD is needed in 2D: the atan2 is its exact solution.

/// Accumulates weighted pairs (p → q) and solves for the pose mapping p onto q.
#[derive(Debug, Clone, Copy, Default)]
pub struct Aligner {
    w: f64,
    p: [f64; 2],
    q: [f64; 2],
    pq: [[f64; 2]; 2],
}

impl Aligner {
    /// Starts empty.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one pair with weight `w` ≥ 0.
    #[inline]
    pub fn add(&mut self, p: [f64; 2], q: [f64; 2], w: f64) {
        self.w += w;
        self.p[0] += w * p[0];
        self.p[1] += w * p[1];
        self.q[0] += w * q[0];
        self.q[1] += w * q[1];
        self.pq[0][0] += w * p[0] * q[0];
        self.pq[0][1] += w * p[0] * q[1];
        self.pq[1][0] += w * p[1] * q[0];
        self.pq[1][1] += w * p[1] * q[1];
    }

    /// Total weight added.
    pub fn weight(&self) -> f64 {
        self.w
    }

    /// The pose `[x, y, θ]` (m, rad) with `R(θ) p + t ≈ q`; `None` without
    /// weight or when the pairs do not fix a rotation.
    pub fn solve(&self) -> Option<[f64; 3]> {
        if !(self.w > 0.0) {
            return None;
        }
        let pm = [self.p[0] / self.w, self.p[1] / self.w];
        let qm = [self.q[0] / self.w, self.q[1] / self.w];
        // Centred cross-covariance H = Σ w p qᵀ − W p̄ q̄ᵀ.
        let h = |i: usize, j: usize| self.pq[i][j] - self.w * pm[i] * qm[j];
        let (sin_num, cos_num) = (h(0, 1) - h(1, 0), h(0, 0) + h(1, 1));
        if sin_num == 0.0 && cos_num == 0.0 {
            return None;
        }
        let th = sin_num.atan2(cos_num);
        let (s, c) = th.sin_cos();
        let t = [
            qm[0] - (c * pm[0] - s * pm[1]),
            qm[1] - (s * pm[0] + c * pm[1]),
        ];
        [t[0], t[1], th]
            .iter()
            .all(|v| v.is_finite())
            .then_some([t[0], t[1], th])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn recovers_a_random_transform_exactly() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        for _ in 0..200 {
            let (x, y, th) = (
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.1..3.1),
            );
            let (s, c) = f64::sin_cos(th);
            let mut a = Aligner::new();
            for _ in 0..10 {
                let p = [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)];
                let q = [c * p[0] - s * p[1] + x, s * p[0] + c * p[1] + y];
                a.add(p, q, rng.random_range(0.1..1.0));
            }
            let r = a.solve().unwrap();
            assert!((r[0] - x).abs() < 1e-9 && (r[1] - y).abs() < 1e-9);
            assert!((r[2] - th).abs() < 1e-9);
        }
    }

    #[test]
    fn nothing_to_align_gives_none() {
        assert!(Aligner::new().solve().is_none());
        let mut a = Aligner::new();
        a.add([1.0, 1.0], [2.0, 2.0], 1.0);
        // one pair fixes no rotation
        assert!(a.solve().is_none());
    }
}
