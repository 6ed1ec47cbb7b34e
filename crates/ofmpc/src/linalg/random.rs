//! Deterministic pseudo-random numbers: Knuth's MMIX linear congruential generator
//! `s ← 6364136223846793005·s + 1442695040888963407 (mod 2⁶⁴)`, mapped to a float from the
//! state's top 53 bits, `u = ⌊s / 2¹¹⌋ / 2⁵³ ∈ [0, 1)`.
//!
//! The one copy of the generator the library's perturbations ([`crate::analysis`]) and its
//! unit tests use (the integration tests have theirs in `tests/common/rng.rs`, the same
//! sequence). Not for anything that needs statistical quality or unpredictability.

/// Advances the state `s` and returns `u ∈ [0, 1)` (see the module doc).
#[inline]
pub(crate) fn uniform(s: &mut u64) -> f64 {
    *s = s
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*s >> 11) as f64 / (1u64 << 53) as f64
}

/// `2u − 1 ∈ [−1, 1)` from the next [`uniform`].
#[inline]
pub(crate) fn symmetric(s: &mut u64) -> f64 {
    uniform(s) * 2.0 - 1.0
}

/// `u − ½ ∈ [−½, ½)` from the next [`uniform`].
#[cfg(test)]
#[inline]
pub(crate) fn centered(s: &mut u64) -> f64 {
    uniform(s) - 0.5
}

/// A random symmetric positive definite `n×n` test matrix `M Mᵀ + 0.1 I`, `M` of
/// [`centered`] entries (filled column by column) from the seed `seed`.
#[cfg(test)]
pub(crate) fn spd_matrix(n: usize, seed: u64) -> nalgebra::DMatrix<f64> {
    let mut s = seed;
    let m = nalgebra::DMatrix::<f64>::from_fn(n, n, |_, _| centered(&mut s));
    &m * m.transpose() + nalgebra::DMatrix::identity(n, n) * 0.1
}
