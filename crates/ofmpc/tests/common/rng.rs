//! The tests' deterministic pseudo-random generators: the one copy of them, shared by
//! `tests/common` (as `common::Rng`), `tests/robot_common` (as `robot_common::Rng`) and
//! `tests/ik_common` (as `ik_common::Rng`); the last two include this file with `#[path]`.
//!
//! Two algorithms, kept apart because the tests' data (and so what they assert) depend on
//! the exact sequences:
//!
//! - [`Lcg`], Knuth's MMIX linear congruential generator
//!   `s ← 6364136223846793005·s + 1442695040888963407 (mod 2⁶⁴)`, output after the step;
//! - [`SplitMix64`] (Steele, Lea, Flood 2014): `s ← s + 0x9E3779B97F4A7C15`, output
//!   `z ^ (z >> 31)` after two xor-shift-multiply rounds of `z = s`.
//!
//! Both turn 64 bits into a float in `[0, 1)` with [`unit`]: `⌊x / 2¹¹⌋ / 2⁵³`.
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector};

/// `[0, 1)` from the top 53 bits of `x`: `⌊x / 2¹¹⌋ / 2⁵³`.
pub fn unit(x: u64) -> f64 {
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// Knuth's MMIX LCG (see the module doc); the field is the state (the seed).
pub struct Lcg(pub u64);

impl Lcg {
    /// Next state `s ← 6364136223846793005·s + 1442695040888963407`.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0
    }
    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        unit(self.next_u64())
    }
    /// Uniform in `[-1, 1)`: `2u − 1`.
    pub fn next(&mut self) -> f64 {
        self.uniform() * 2.0 - 1.0
    }
    /// Uniform in `[lo, hi)`: `lo + (hi − lo) u`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    /// `n` values of [`Lcg::range`].
    pub fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.range(lo, hi)).collect()
    }
    /// An `r×c` matrix of [`Lcg::next`] values, filled column by column.
    pub fn matrix(&mut self, r: usize, c: usize) -> DMatrix<f64> {
        DMatrix::from_fn(r, c, |_, _| self.next())
    }
    /// A vector of `r` [`Lcg::next`] values.
    pub fn vector(&mut self, r: usize) -> DVector<f64> {
        DVector::from_fn(r, |_, _| self.next())
    }
}

/// SplitMix64 (see the module doc).
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Generator with a fixed seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[a, b)`: `a + (b − a) u`.
    pub fn uniform(&mut self, a: f64, b: f64) -> f64 {
        let u = unit(self.next_u64());
        a + (b - a) * u
    }
}
