//! Seeded random draws on egogen's one generator, ChaCha8.

use rand_chacha::ChaCha8Rng;
use rand_core::Rng;

/// Uniform in the open interval (0, 1), 53 bits.
pub(crate) fn uniform_open01(rng: &mut ChaCha8Rng) -> f64 {
    ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
}

/// Uniform in the open interval (lo, hi): `lo + (hi − lo)·U(0, 1)`.
pub(crate) fn uniform_in(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * uniform_open01(rng)
}

/// A standard normal sample (Box-Muller, one of the pair).
pub(crate) fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    let (u1, u2) = (uniform_open01(rng), uniform_open01(rng));
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// An index drawn with probability proportional to its weight (each ≥ 0, not all 0), from one
/// uniform draw; past the end by rounding, the last index with a weight above 0.
pub(crate) fn weighted_index<I>(rng: &mut ChaCha8Rng, weights: I) -> usize
where
    I: IntoIterator<Item = f64>,
    I::IntoIter: Clone,
{
    let weights = weights.into_iter();
    let total: f64 = weights.clone().sum();
    let mut u = uniform_open01(rng) * total;
    let mut last = 0;
    for (k, w) in weights.enumerate() {
        if u < w {
            return k;
        }
        u -= w;
        if w > 0.0 {
            last = k;
        }
    }
    last
}

/// Standard normal samples (Box-Muller on the seeded stream).
pub fn normal_samples(rng: &mut ChaCha8Rng, n: usize) -> Vec<f32> {
    (0..n).map(|_| standard_normal(rng) as f32).collect()
}

#[cfg(test)]
mod tests {
    use rand_core::SeedableRng;

    use super::*;

    #[test]
    fn weighted_indices_follow_their_weights_and_never_a_zero_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut seen = [0usize; 4];
        for _ in 0..4000 {
            seen[weighted_index(&mut rng, [1.0, 0.0, 3.0, 0.0])] += 1;
        }
        assert_eq!((seen[1], seen[3]), (0, 0));
        // 1 : 3 of 4000, ±5σ (σ ≈ 27).
        assert!((seen[0] as i64 - 1000).abs() < 137, "{seen:?}");
    }
}
