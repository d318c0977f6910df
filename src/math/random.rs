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

/// Standard normal samples (Box-Muller on the seeded stream).
pub fn normal_samples(rng: &mut ChaCha8Rng, n: usize) -> Vec<f32> {
    (0..n).map(|_| standard_normal(rng) as f32).collect()
}
