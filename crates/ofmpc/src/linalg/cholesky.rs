//! Cholesky factorization `A = L Lᵀ` of a symmetric positive definite matrix and the solution
//! of `L Lᵀ x = b`, in place on column-major slices.
//!
//! The factorization is the column-oriented (left-looking) form: for `j = 0..n`,
//!
//! `l_ij ← a_ij − Σ_{k<j} l_jk l_ik` (`i ≥ j`, the products subtracted one by one for
//! `k = 0, 1, …, j−1`), then `l_jj = √(l_jj)`, `l_ij ← l_ij / l_jj` (`i > j`).
//!
//! Entry by entry this is the same sequence of roundings as the row-oriented
//! (Cholesky–Banachiewicz) loop `s = a_ij; for k < j: s −= l_ik l_jk; l_ij = s / l_jj` (the
//! product of two floats does not depend on their order), so every former copy of either form
//! gives the same bits through this one.

use super::dot;

/// A pivot of the factorization was not positive (or not finite): the matrix is not
/// (numerically) positive definite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NotPositiveDefinite {
    /// 0-based column of the failed pivot.
    pub(crate) pivot: usize,
    /// The pivot `a_jj − Σ_{k<j} l_jk²` before the square root (≤ 0, or NaN, or infinite).
    pub(crate) value: f64,
}

/// Factors the `n×n` symmetric positive definite matrix held in the lower triangle of `l`
/// (column-major, leading dimension `ld`) in place: on return its lower triangle is `L`,
/// `A = L Lᵀ` (see the module's equations for the operation order). Neither the strict upper
/// triangle nor rows `n..ld` are read or written.
///
/// Fails at the first pivot `d_j = a_jj − Σ_{k<j} l_jk²` that is not `> 0` and finite; columns
/// from `j` on are then partly updated.
pub(crate) fn cholesky_in_place(
    n: usize,
    ld: usize,
    l: &mut [f64],
) -> Result<(), NotPositiveDefinite> {
    debug_assert!(ld >= n && l.len() >= ld * n.saturating_sub(1) + n);
    for j in 0..n {
        // Column j: l_ij −= l_jk l_ik for k < j, i ≥ j.
        for k in 0..j {
            let ljk = l[k * ld + j];
            let (left, right) = l.split_at_mut(j * ld);
            let colk = &left[k * ld + j..k * ld + n];
            for (x, y) in right[j..n].iter_mut().zip(colk) {
                *x -= ljk * y;
            }
        }
        let d = l[j * ld + j];
        // Also catches NaN.
        if !(d > 0.0 && d.is_finite()) {
            return Err(NotPositiveDefinite { pivot: j, value: d });
        }
        let d = d.sqrt();
        l[j * ld + j] = d;
        for v in &mut l[j * ld + j + 1..j * ld + n] {
            *v /= d;
        }
    }
    Ok(())
}

/// Forward substitution `L z = b` in place, column-oriented: for `j = 0..n`,
/// `z_j = b_j / l_jj`, then `b_i −= l_ij z_j` (`i > j`). Per entry the same order as the
/// row-oriented `z_i = (b_i − Σ_{k<i} l_ik z_k) / l_ii` with the sum subtracted term by term.
#[inline]
fn forward_in_place(n: usize, ld: usize, l: &[f64], b: &mut [f64]) {
    for j in 0..n {
        let zj = b[j] / l[j * ld + j];
        b[j] = zj;
        for (bi, li) in b[j + 1..n].iter_mut().zip(&l[j * ld + j + 1..j * ld + n]) {
            *bi -= li * zj;
        }
    }
}

/// Solves `L Lᵀ x = b` in place (`b ← x`, `n` entries) with the factor of
/// [`cholesky_in_place`]: forward substitution `L z = b`, then back substitution
/// `x_i = (z_i − l_{i+1,i} x_{i+1} − … − l_{n−1,i} x_{n−1}) / l_ii`, `i = n−1 … 0`, the
/// products subtracted one by one in increasing row order (the forward dynamics' and the
/// numeric IK's order).
pub(crate) fn cholesky_solve_in_place(n: usize, ld: usize, l: &[f64], b: &mut [f64]) {
    forward_in_place(n, ld, l, b);
    for i in (0..n).rev() {
        let mut s = b[i];
        for (lki, xk) in l[i * ld + i + 1..i * ld + n].iter().zip(&b[i + 1..n]) {
            s -= lki * xk;
        }
        b[i] = s / l[i * ld + i];
    }
}

/// [`cholesky_solve_in_place`] with the back substitution's sum taken by the vectorized
/// [`dot`]: `x_i = (z_i − dot(L[i+1..n, i], x[i+1..n])) / l_ii` (the controllers' order:
/// the linear-like model's `H⁻¹` and the torque-limit QP).
pub(crate) fn cholesky_solve_in_place_dot(n: usize, ld: usize, l: &[f64], b: &mut [f64]) {
    forward_in_place(n, ld, l, b);
    for i in (0..n).rev() {
        let s = dot(&l[i * ld + i + 1..i * ld + n], &b[i + 1..n]);
        b[i] = (b[i] - s) / l[i * ld + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    use crate::linalg::random::spd_matrix as spd;

    /// The row-oriented loop the module doc compares with (the former copy in the forward
    /// dynamics and the numeric IK).
    fn banachiewicz(a: &DMatrix<f64>) -> DMatrix<f64> {
        let n = a.nrows();
        let mut l = DMatrix::zeros(n, n);
        for j in 0..n {
            let mut d = a[(j, j)];
            for k in 0..j {
                d -= l[(j, k)] * l[(j, k)];
            }
            let d = d.sqrt();
            l[(j, j)] = d;
            for i in j + 1..n {
                let mut s = a[(i, j)];
                for k in 0..j {
                    s -= l[(i, k)] * l[(j, k)];
                }
                l[(i, j)] = s / d;
            }
        }
        l
    }

    #[test]
    fn factor_is_bitwise_the_row_oriented_one_and_solves() {
        for n in [1, 2, 3, 6, 7, 11, 17] {
            let a = spd(n, 7 + n as u64);
            // Leading dimension larger than n: the extra rows are left alone.
            let ld = n + 2;
            let mut l = vec![f64::NAN; ld * n];
            for j in 0..n {
                for i in 0..n {
                    l[j * ld + i] = a[(i, j)];
                }
            }
            cholesky_in_place(n, ld, &mut l).unwrap();
            let reference = banachiewicz(&a);
            for j in 0..n {
                for i in j..n {
                    assert_eq!(l[j * ld + i].to_bits(), reference[(i, j)].to_bits());
                }
                assert!(l[j * ld + n..j * ld + ld].iter().all(|v| v.is_nan()));
            }
            let x_true = DVector::from_fn(n, |i, _| (i as f64 * 0.7).sin());
            let b = &a * &x_true;
            for solve in [cholesky_solve_in_place, cholesky_solve_in_place_dot] {
                let mut x = b.as_slice().to_vec();
                solve(n, ld, &l, &mut x);
                for (xi, ti) in x.iter().zip(x_true.iter()) {
                    assert!((xi - ti).abs() < 1e-9, "{xi} vs {ti}");
                }
            }
        }
    }

    #[test]
    fn indefinite_and_nan_pivots_are_reported() {
        let mut l = vec![1.0, 2.0, 2.0, 1.0]; // eigenvalues 3, −1
        let e = cholesky_in_place(2, 2, &mut l).unwrap_err();
        assert_eq!(e.pivot, 1);
        assert_eq!(e.value, -3.0);
        let mut l = vec![f64::NAN];
        assert!(cholesky_in_place(1, 1, &mut l).unwrap_err().value.is_nan());
        let mut l = vec![0.0];
        assert_eq!(cholesky_in_place(1, 1, &mut l).unwrap_err().pivot, 0);
    }
}
