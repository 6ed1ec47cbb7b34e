//! The Householder primitives shared by the portable and the AVX2
//! factorizations ([`super::factor`], [`super::avx2`]): the panel width, the
//! reflector of one column and the compact WY factor `T` of a panel.

#[cfg(test)]
use crate::control::solvers::dense::dot;

/// Widest panel of columns whose reflectors are applied together.
pub(super) const PANEL: usize = 8;

/// Copies of a panel's reflectors kept by the AVX2 path (see `factor_generic`).
pub(super) const VBUF_PER_ROW: usize = 2;
/// The Householder reflector `H = I − τ v vᵀ`, `v = [1; x/(x0 − β)]`, that
/// maps `[x0; x]` (with `σ = ‖x‖² > 0`) to `[β; 0]`: returns `(β, 1/(x0 − β),
/// τ)`, or `None` when `σ = 0` (the column is already triangular).
#[inline(always)]
pub(super) fn reflector(x0: f64, sigma: f64) -> Option<(f64, f64, f64)> {
    if sigma == 0.0 {
        return None;
    }
    let alpha = (x0 * x0 + sigma).sqrt();
    let beta = if x0 > 0.0 { -alpha } else { alpha };
    Some((beta, 1.0 / (x0 - beta), (beta - x0) / beta))
}

/// The upper-triangular `T` of the compact WY form `H_1 ⋯ H_k = I − V T Vᵀ`
/// of a panel's `k` reflectors (LAPACK `dlarft`, forward, columnwise), from
/// `τ` and the Gram entries `gram[j][r] = v_jᵀ v_r`, `j < r < k`.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
pub(super) fn t_from_gram(
    k: usize,
    tau: &[f64],
    gram: &[[f64; PANEL]; PANEL],
) -> [[f64; PANEL]; PANEL] {
    let mut t = [[0.0f64; PANEL]; PANEL];
    for r in 0..k.min(PANEL) {
        let tr = tau[r];
        t[r][r] = tr;
        // z_j = −τ_r v_jᵀ v_r, column r of T = T[..r, ..r] z.
        let mut z = [0.0f64; PANEL];
        for j in 0..r {
            z[j] = -tr * gram[j][r];
        }
        for i in 0..r {
            let mut s = 0.0;
            for j in i..r {
                s += t[i][j] * z[j];
            }
            t[i][r] = s;
        }
    }
    t
}

/// Portable reference of `avx2::gram`: `gram[j][r] = v_jᵀ v_r` for the
/// reflectors of the panel `c0..c1` (rows up to `end`, unit diagonal and
/// zeros above it implicit).
#[cfg(test)]
pub(super) fn gram_portable(
    left: &[f64],
    m: usize,
    c0: usize,
    c1: usize,
    end: usize,
) -> [[f64; PANEL]; PANEL] {
    let mut g = [[0.0f64; PANEL]; PANEL];
    for r in 1..c1 - c0 {
        let row0 = c0 + r;
        let vr = &left[row0 * m + row0 + 1..row0 * m + end];
        for j in 0..r {
            let col = (c0 + j) * m;
            g[j][r] = left[col + row0] + dot(&left[col + row0 + 1..col + end], vr);
        }
    }
    g
}
