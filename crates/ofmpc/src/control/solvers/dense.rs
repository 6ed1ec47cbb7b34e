//! Small dense kernels on column-major slices, used in the real-time step.
//! They never allocate; the caller sizes every slice.

/// `c = alpha·a·b + beta·c` with `a` m×k, `b` k×p, `c` m×p, all column-major.
/// `beta == 0` overwrites `c` (it may hold anything, even NaN).
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn gemm(
    m: usize,
    k: usize,
    p: usize,
    alpha: f64,
    a: &[f64],
    b: &[f64],
    beta: f64,
    c: &mut [f64],
) {
    debug_assert!(a.len() >= m * k && b.len() >= k * p && c.len() >= m * p);
    if m == k && k == p {
        // Square products of the per-step model (n×n): fixed-size kernels
        // with the same operation order as the loop below.
        match m {
            2 => return gemm_sq::<2>(alpha, a, b, beta, c),
            3 => return gemm_sq::<3>(alpha, a, b, beta, c),
            4 => return gemm_sq::<4>(alpha, a, b, beta, c),
            5 => return gemm_sq::<5>(alpha, a, b, beta, c),
            6 => return gemm_sq::<6>(alpha, a, b, beta, c),
            7 => return gemm_sq::<7>(alpha, a, b, beta, c),
            8 => return gemm_sq::<8>(alpha, a, b, beta, c),
            _ => {}
        }
    }
    for (j, cj) in c.chunks_exact_mut(m).take(p).enumerate() {
        if beta == 0.0 {
            cj.fill(0.0);
        } else if beta != 1.0 {
            cj.iter_mut().for_each(|v| *v *= beta);
        }
        let bj = &b[j * k..j * k + k];
        for (l, &blj) in bj.iter().enumerate() {
            let s = alpha * blj;
            if s != 0.0 {
                axpy(s, &a[l * m..l * m + m], cj);
            }
        }
    }
}

/// [`gemm`] for `N×N` matrices: columns held in arrays so that the compiler
/// unrolls and vectorizes them; per entry the same sequence of operations
/// (scale by `beta`, then add `(alpha·b_lj)·a_l` for `l = 0..N`, skipping
/// zero multipliers).
#[inline(always)]
fn gemm_sq<const N: usize>(alpha: f64, a: &[f64], b: &[f64], beta: f64, c: &mut [f64]) {
    let mut av = [[0.0f64; N]; N];
    for (dst, col) in av.iter_mut().zip(a.chunks_exact(N)) {
        dst.copy_from_slice(col);
    }
    for (cj, bj) in c.chunks_exact_mut(N).zip(b.chunks_exact(N)) {
        let mut acc = [0.0f64; N];
        if beta != 0.0 {
            for (x, y) in acc.iter_mut().zip(cj.iter()) {
                *x = if beta == 1.0 { *y } else { *y * beta };
            }
        }
        for (al, &blj) in av.iter().zip(bj) {
            let s = alpha * blj;
            if s != 0.0 {
                for (x, y) in acc.iter_mut().zip(al) {
                    *x += s * y;
                }
            }
        }
        cj.copy_from_slice(&acc);
    }
}

/// `y += s·x` over the common length.
#[inline(always)]
pub(crate) fn axpy(s: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += s * xi;
    }
}

/// Dot product with eight independent accumulators so that it vectorizes (shared with the
/// Cholesky back substitution of [`crate::linalg`]).
pub(crate) use crate::linalg::dot;

/// `true` iff every entry is finite. Branch-free over 8 lanes (`0·x` is ±0
/// for finite `x` and NaN for ±∞ and NaN), so it vectorizes.
#[inline]
pub(crate) fn all_finite(a: &[f64]) -> bool {
    let chunks = a.chunks_exact(8);
    let rest = chunks.remainder();
    let mut acc = [0.0f64; 8];
    for x in chunks {
        for q in 0..8 {
            acc[q] += x[q] * 0.0;
        }
    }
    let mut s = acc.iter().sum::<f64>();
    for x in rest {
        s += x * 0.0;
    }
    s == 0.0
}

/// Induced 1-norm (largest absolute column sum) of an m×p column-major
/// matrix; NaN if any entry is NaN.
pub(crate) fn norm1(m: usize, a: &[f64]) -> f64 {
    let mut best = 0.0f64;
    for c in a.chunks_exact(m) {
        let s = c.iter().map(|v| v.abs()).sum::<f64>();
        if s.is_nan() {
            return f64::NAN;
        }
        best = best.max(s);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    #[test]
    fn gemm_matches_nalgebra() {
        let a = DMatrix::<f64>::from_fn(5, 3, |i, j| (i as f64 + 1.0) * 0.3 - j as f64);
        let b = DMatrix::<f64>::from_fn(3, 4, |i, j| (i * j) as f64 * 0.7 - 1.1);
        let c0 = DMatrix::<f64>::from_fn(5, 4, |i, j| i as f64 - 0.5 * j as f64);
        for (alpha, beta) in [(1.0, 0.0), (-2.0, 1.0), (0.5, -3.0)] {
            let mut c = c0.clone();
            gemm(
                5,
                3,
                4,
                alpha,
                a.as_slice(),
                b.as_slice(),
                beta,
                c.as_mut_slice(),
            );
            let want = &a * &b * alpha + &c0 * beta;
            assert!((c - want).norm() < 1e-13);
        }
    }

    /// The fixed-size square kernels give exactly the general loop's result.
    #[test]
    fn square_kernels_match_the_general_loop() {
        for n in 1..=9 {
            let a = DMatrix::<f64>::from_fn(n, n, |i, j| ((i * 7 + j * 3) as f64 * 0.37).sin());
            let b = DMatrix::<f64>::from_fn(n, n, |i, j| ((i * 5 + j) as f64 * 0.11).cos());
            let c0 = DMatrix::<f64>::from_fn(n, n, |i, j| i as f64 - 0.5 * j as f64);
            for (alpha, beta) in [(1.0, 0.0), (-2.0, 1.0), (0.5, -3.0)] {
                let mut fast = c0.clone();
                gemm(
                    n,
                    n,
                    n,
                    alpha,
                    a.as_slice(),
                    b.as_slice(),
                    beta,
                    fast.as_mut_slice(),
                );
                // The general loop on an n×n product split into n columns.
                let mut slow = c0.clone();
                for j in 0..n {
                    gemm(
                        n,
                        n,
                        1,
                        alpha,
                        a.as_slice(),
                        &b.as_slice()[j * n..],
                        beta,
                        &mut slow.as_mut_slice()[j * n..],
                    );
                }
                assert_eq!(fast, slow, "n = {n}");
                let want = &a * &b * alpha + &c0 * beta;
                assert!((fast - want).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn all_finite_finds_every_bad_value() {
        for len in 0..20 {
            let a: Vec<f64> = (0..len).map(|i| 1e300 * (i as f64 - 7.0)).collect();
            assert!(all_finite(&a));
            for pos in 0..len {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let mut b = a.clone();
                    b[pos] = bad;
                    assert!(!all_finite(&b), "len {len} pos {pos} {bad}");
                }
            }
        }
    }

    #[test]
    fn dot_matches_naive_for_all_remainders() {
        for len in 0..40 {
            let a: Vec<f64> = (0..len).map(|i| (i as f64 * 0.37).sin()).collect();
            let b: Vec<f64> = (0..len).map(|i| (i as f64 * 0.11).cos()).collect();
            let naive: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            assert!((dot(&a, &b) - naive).abs() < 1e-13);
        }
    }
}
