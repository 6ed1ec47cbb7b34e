//! Small dense numerical kernels shared by the layers above (the bottom of the library's
//! dependency graph: it imports nothing from the crate). Every routine works on slices the
//! caller sized and never allocates, so that it can run in the real-time step.
//!
//! Matrices are column-major with a leading dimension `ld ≥ n`: entry `(i, j)` of an `n×n`
//! matrix is `a[j·ld + i]` (an `nalgebra::DMatrix`'s `as_slice()` with `ld = nrows`).
//!
//! Each routine fixes its floating-point operation order (documented on it): the closed-loop
//! simulation's results are reproducible bit for bit, so a caller that switches routine, or a
//! change of order here, changes the published numbers.

mod cholesky;
pub mod random;
mod rk4;

pub(crate) use cholesky::{
    cholesky_in_place, cholesky_solve_in_place, cholesky_solve_in_place_dot,
};
pub(crate) use rk4::{rk4_second_order_step, RK4_WORK_PER_DOF};

/// Dot product `Σ_i a_i b_i` over the common length, with eight independent accumulators so
/// that it vectorizes.
///
/// Operation order: for the whole chunks of eight, `acc_q += a_{8c+q} b_{8c+q}` (`q = 0..8`,
/// chunks in order); then `s = ((acc₀ + acc₄) + (acc₁ + acc₅)) + ((acc₂ + acc₆) + (acc₃ + acc₇))`;
/// then the remaining products are added to `s` one by one, in order.
#[inline(always)]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let len = a.len().min(b.len());
    let (a, b) = (&a[..len], &b[..len]);
    let ca = a.chunks_exact(8);
    let cb = b.chunks_exact(8);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    let mut acc = [0.0f64; 8];
    for (x, y) in ca.zip(cb) {
        for q in 0..8 {
            acc[q] += x[q] * y[q];
        }
    }
    let mut s = ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]));
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}
