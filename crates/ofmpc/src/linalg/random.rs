//! Deterministic pseudo-random numbers, the workspace's one copy of its generators (the
//! library's perturbations in [`crate::analysis`] and its unit tests, the integration tests'
//! `tests/common/rng.rs`, the benches and the CLI's tests all draw from here):
//!
//! - Knuth's MMIX linear congruential generator
//!   `s ← 6364136223846793005·s + 1442695040888963407 (mod 2⁶⁴)`, output the new state
//!   ([`lcg_next`]);
//! - SplitMix64 (Steele, Lea, Flood 2014): `s ← s + 0x9E3779B97F4A7C15`, output
//!   `z ^ (z >> 31)` after two xor-shift-multiply rounds of `z = s` ([`splitmix64_next`]).
//!
//! Both map 64 bits to a float from their top 53 bits, `u = ⌊x / 2¹¹⌋ / 2⁵³ ∈ [0, 1)`
//! ([`unit`]). The tests' data (and so what they assert) depend on the exact sequences, so
//! neither changes. Not for anything that needs statistical quality or unpredictability.
//!
//! Public (as `ofmpc::random`, hidden from the documentation) only so that the integration
//! tests, the benches and the other crates' tests share this copy; not part of the API.

/// `[0, 1)` from the top 53 bits of `x`: `⌊x / 2¹¹⌋ / 2⁵³`.
#[inline]
pub fn unit(x: u64) -> f64 {
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// Advances the MMIX LCG state `s ← 6364136223846793005·s + 1442695040888963407` and
/// returns it.
#[inline]
pub fn lcg_next(s: &mut u64) -> u64 {
    *s = s
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    *s
}

/// Advances the SplitMix64 state `s` and returns its next 64 bits (see the module doc).
#[inline]
pub fn splitmix64_next(s: &mut u64) -> u64 {
    *s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *s;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Advances the LCG state `s` and returns `u ∈ [0, 1)` ([`lcg_next`], [`unit`]).
#[inline]
pub fn uniform(s: &mut u64) -> f64 {
    unit(lcg_next(s))
}

/// `2u − 1 ∈ [−1, 1)` from the next [`uniform`].
#[inline]
pub fn symmetric(s: &mut u64) -> f64 {
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
