//! The tests' deterministic pseudo-random generators, re-exported as `common::Rng` (the LCG),
//! `common::robots::Rng` (the LCG) and `common::ik_model::Rng` (SplitMix64): thin stateful
//! handles on the library's one copy of the generators, `ofmpc::random` (its module doc gives
//! both algorithms), so the sequences are the library's.
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector};

pub use ofmpc::random::unit;
use ofmpc::random::{lcg_next, splitmix64_next};

/// Knuth's MMIX LCG (see the module doc); the field is the state (the seed).
pub struct Lcg(pub u64);

impl Lcg {
    /// Next state `s ← 6364136223846793005·s + 1442695040888963407`.
    pub fn next_u64(&mut self) -> u64 {
        lcg_next(&mut self.0)
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
        splitmix64_next(&mut self.0)
    }
    /// Uniform in `[a, b)`: `a + (b − a) u`.
    pub fn uniform(&mut self, a: f64, b: f64) -> f64 {
        let u = unit(self.next_u64());
        a + (b - a) * u
    }
}
