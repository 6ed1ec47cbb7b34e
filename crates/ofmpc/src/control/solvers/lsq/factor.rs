//! The Householder QR of the least-squares solve and its back substitution:
//! the portable code (generic over fused multiply-add), its AVX2 + FMA
//! builds (the same code compiled with `#[target_feature]`, safe entry
//! points behind an [`Avx2Fma`] token) and the run-time dispatch between
//! them; the explicit 4-wide kernels are in [`super::avx2`].

use crate::control::solvers::dense::{all_finite, axpy, dot};
use crate::control::solvers::simd::Avx2Fma;

#[cfg(target_arch = "x86_64")]
use super::avx2;
use super::householder::{reflector, t_from_gram, PANEL};

/// The first non-finite entry `(row, column)` of `[𝒜 | b]` inside the
/// profile (column `p` is `b`, checked everywhere). Dispatches like
/// [`factor`] (the AVX2 build only vectorizes wider; same result).
pub(super) fn first_non_finite(
    a: &[f64],
    m: usize,
    p: usize,
    row_end: &[usize],
) -> Option<(usize, usize)> {
    #[cfg(target_arch = "x86_64")]
    if let Some(token) = Avx2Fma::detect() {
        return first_non_finite_avx2(token, a, m, p, row_end);
    }
    first_non_finite_generic(a, m, p, row_end)
}

#[inline(always)]
pub(super) fn first_non_finite_generic(
    a: &[f64],
    m: usize,
    p: usize,
    row_end: &[usize],
) -> Option<(usize, usize)> {
    for c in 0..=p {
        let end = if c < p { row_end[c] } else { m };
        let col = &a[c * m..c * m + end];
        if all_finite(col) {
            continue;
        }
        if let Some(row) = col.iter().position(|v| !v.is_finite()) {
            return Some((row, c));
        }
    }
    None
}

/// Back substitution `R1 x = c1` (column-oriented) on the factored
/// `[R1 … | c]`, returns `J_min = ‖c2‖²`. Dispatches like [`factor`]: the
/// AVX2 build runs the same operations (no contraction), so the results are
/// identical.
pub(super) fn back_substitute(a: &[f64], m: usize, p: usize, x: &mut [f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if let Some(token) = Avx2Fma::detect() {
        return back_substitute_avx2(token, a, m, p, x);
    }
    back_substitute_generic(a, m, p, x)
}

#[inline(always)]
pub(super) fn back_substitute_generic(a: &[f64], m: usize, p: usize, x: &mut [f64]) -> f64 {
    let (r, cvec) = a.split_at(m * p);
    x.copy_from_slice(&cvec[..p]);
    for j in (0..p).rev() {
        let xj = x[j] / r[j * m + j];
        x[j] = xj;
        axpy(-xj, &r[j * m..j * m + j], &mut x[..j]);
    }
    dot(&cvec[p..], &cvec[p..])
}

/// Householder QR of the m×(p+1) column-major `[𝒜 | b]` with the given
/// profile, in place: `R1` on and above the diagonal, reflector tails below,
/// `Qᵀb` in the last column. Returns `max |R_ii|`.
///
/// Columns are processed in panels (runs of at most [`PANEL`] columns with
/// the same `row_end`): the panel is factored column by column, then its
/// reflectors are applied, in order, to four trailing columns at a time while
/// those stay in L1 cache. Per column this is exactly the operation sequence of
/// the textbook algorithm. Where the CPU has AVX2 and FMA (detected at run
/// time) the panel is factored with explicit 4-wide kernels and applied to
/// the trailing columns in compact WY form (same reflectors, other rounding).
pub(super) fn factor(
    a: &mut [f64],
    m: usize,
    p: usize,
    row_end: &[usize],
    tau: &mut [f64],
    vbuf: &mut [f64],
) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if let Some(token) = Avx2Fma::detect() {
        return factor_avx2(token, a, m, p, row_end, tau, vbuf);
    }
    factor_generic::<false>(None, a, m, p, row_end, tau, vbuf)
}

/// `a·b + c`, fused when `FMA`.
#[inline(always)]
pub(super) fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `vbuf` (at least `2·PANEL·(m + 4)` long) holds the current panel's
/// reflectors explicitly (`PANEL·m`) and interleaved (the rest) for the AVX2
/// kernels; the portable path does not use it. The explicit AVX2 kernels
/// run only with an [`Avx2Fma`] token (`avx`), which proves the CPU support;
/// `FMA` only selects fused multiply-adds in the portable loops.
#[inline(always)]
#[cfg_attr(not(target_arch = "x86_64"), allow(unused_variables))]
pub(super) fn factor_generic<const FMA: bool>(
    avx: Option<Avx2Fma>,
    a: &mut [f64],
    m: usize,
    p: usize,
    row_end: &[usize],
    tau: &mut [f64],
    vbuf: &mut [f64],
) -> f64 {
    let mut rmax = 0.0f64;
    let mut c0 = 0;
    while c0 < p {
        let end = row_end[c0];
        let mut c1 = c0 + 1;
        while c1 < p && c1 - c0 < PANEL && row_end[c1] == end {
            c1 += 1;
        }
        // AVX2+FMA: vectorized panel factorization, then blocked (compact WY)
        // application of the panel's reflectors, Qᵀ = I − V Tᵀ Vᵀ, to the
        // trailing columns.
        #[cfg(target_arch = "x86_64")]
        if let Some(_token) = avx {
            let (vbuf, vpack) = vbuf.split_at_mut(PANEL * m);
            // SAFETY: the token proves AVX2 and FMA; `end > c` for every
            // panel column (checked profile), `c0 < c1 ≤ c0 + PANEL`,
            // `c1 ≤ p`, `tau` has p entries and `vbuf` PANEL·m, so all rows
            // and columns touched lie inside the m×(p+1) array `a`.
            let pr = unsafe { avx2::factor_panel(a, m, c0, c1, end, tau, vbuf) };
            rmax = rmax.max(pr);
            let (left, right) = a.split_at_mut(c1 * m);
            // SAFETY: the token proves AVX2 and FMA; columns c0..c1 of
            // `left` hold the panel's reflectors in rows c0..end ≤ m.
            let gram = unsafe { avx2::gram(left, m, c0, c1, end) };
            let tmat = t_from_gram(c1 - c0, &tau[c0..c1], &gram);
            // SAFETY: the token proves AVX2 and FMA; `vbuf` holds the
            // c1 − c0 reflectors written by `factor_panel` (rows c0..end),
            // `right` the trailing columns and b (whole columns of m rows),
            // `vpack` is (VBUF_PER_ROW − 1)·PANEL·(m + 4) long.
            unsafe { avx2::apply_block_packed(vbuf, m, c1 - c0, c0, end, m, &tmat, right, vpack) };
            c0 = c1;
            continue;
        }
        // Panel factorization.
        for c in c0..c1 {
            let (left, right) = a.split_at_mut((c + 1) * m);
            let v = &mut left[c * m + c..c * m + end];
            let sigma = dot_k::<FMA>(&v[1..], &v[1..]);
            let t = match reflector(v[0], sigma) {
                None => 0.0, // already triangular in this column
                Some((beta, inv, t)) => {
                    v[1..].iter_mut().for_each(|e| *e *= inv);
                    v[0] = beta;
                    t
                }
            };
            tau[c] = t;
            rmax = rmax.max(v[0].abs());
            if t != 0.0 {
                let vt = &v[1..];
                for col in right[..(c1 - c - 1) * m].chunks_exact_mut(m) {
                    apply1::<FMA>(t, vt, &mut col[c..end]);
                }
            }
        }
        // Trailing columns c1..p−1 and b, four at a time.
        let (left, right) = a.split_at_mut(c1 * m);
        let mut quads = right.chunks_exact_mut(4 * m);
        for quad in &mut quads {
            let (q0, rest) = quad.split_at_mut(m);
            let (q1, rest) = rest.split_at_mut(m);
            let (q2, q3) = rest.split_at_mut(m);
            for c in c0..c1 {
                let t = tau[c];
                if t != 0.0 {
                    let vt = &left[c * m + c + 1..c * m + end];
                    let quad = [
                        &mut q0[c..end],
                        &mut q1[c..end],
                        &mut q2[c..end],
                        &mut q3[c..end],
                    ];
                    apply4::<FMA>(t, vt, quad);
                }
            }
        }
        for col in quads.into_remainder().chunks_exact_mut(m) {
            for c in c0..c1 {
                let t = tau[c];
                if t != 0.0 {
                    apply1::<FMA>(t, &left[c * m + c + 1..c * m + end], &mut col[c..end]);
                }
            }
        }
        c0 = c1;
    }
    rmax
}

/// Dot product with four independent 4-wide accumulators.
#[inline(always)]
pub(super) fn dot_k<const FMA: bool>(x: &[f64], y: &[f64]) -> f64 {
    let len = x.len().min(y.len());
    let (x, y) = (&x[..len], &y[..len]);
    let mut acc = [0.0f64; 16];
    let (cx, cy) = (x.chunks_exact(16), y.chunks_exact(16));
    let (rx, ry) = (cx.remainder(), cy.remainder());
    for (a, b) in cx.zip(cy) {
        for l in 0..16 {
            acc[l] = madd::<FMA>(a[l], b[l], acc[l]);
        }
    }
    let mut s4 = [0.0f64; 4];
    for l in 0..4 {
        s4[l] = (acc[l] + acc[l + 4]) + (acc[l + 8] + acc[l + 12]);
    }
    let mut s = (s4[0] + s4[1]) + (s4[2] + s4[3]);
    for (a, b) in rx.iter().zip(ry) {
        s = madd::<FMA>(*a, *b, s);
    }
    s
}

/// `seg ← (I − τ v vᵀ) seg` with `v = [1; vt]`.
#[inline(always)]
pub(super) fn apply1<const FMA: bool>(tau: f64, vt: &[f64], seg: &mut [f64]) {
    let (head, tail) = seg.split_at_mut(1);
    let s = tau * (head[0] + dot_k::<FMA>(vt, tail));
    head[0] -= s;
    for (t, v) in tail.iter_mut().zip(vt) {
        *t = madd::<FMA>(-s, *v, *t);
    }
}

/// [`apply1`] on four columns at once: `v` is loaded once per row.
#[inline(always)]
pub(super) fn apply4<const FMA: bool>(tau: f64, vt: &[f64], quad: [&mut [f64]; 4]) {
    let [s0, s1, s2, s3] = quad;
    let len = vt.len();
    let (h0, t0) = s0.split_at_mut(1);
    let (h1, t1) = s1.split_at_mut(1);
    let (h2, t2) = s2.split_at_mut(1);
    let (h3, t3) = s3.split_at_mut(1);
    let (t0, t1, t2, t3) = (
        &mut t0[..len],
        &mut t1[..len],
        &mut t2[..len],
        &mut t3[..len],
    );
    // Four dot products in one pass.
    let mut acc = [[0.0f64; 4]; 4];
    let chunks = len / 4;
    for k in 0..chunks {
        let i = 4 * k;
        let v = &vt[i..i + 4];
        let (a0, a1, a2, a3) = (&t0[i..i + 4], &t1[i..i + 4], &t2[i..i + 4], &t3[i..i + 4]);
        for l in 0..4 {
            acc[0][l] = madd::<FMA>(v[l], a0[l], acc[0][l]);
            acc[1][l] = madd::<FMA>(v[l], a1[l], acc[1][l]);
            acc[2][l] = madd::<FMA>(v[l], a2[l], acc[2][l]);
            acc[3][l] = madd::<FMA>(v[l], a3[l], acc[3][l]);
        }
    }
    let mut d = [0.0f64; 4];
    for q in 0..4 {
        d[q] = (acc[q][0] + acc[q][1]) + (acc[q][2] + acc[q][3]);
    }
    for i in 4 * chunks..len {
        d[0] = madd::<FMA>(vt[i], t0[i], d[0]);
        d[1] = madd::<FMA>(vt[i], t1[i], d[1]);
        d[2] = madd::<FMA>(vt[i], t2[i], d[2]);
        d[3] = madd::<FMA>(vt[i], t3[i], d[3]);
    }
    let s = [
        tau * (h0[0] + d[0]),
        tau * (h1[0] + d[1]),
        tau * (h2[0] + d[2]),
        tau * (h3[0] + d[3]),
    ];
    h0[0] -= s[0];
    h1[0] -= s[1];
    h2[0] -= s[2];
    h3[0] -= s[3];
    for i in 0..len {
        let v = vt[i];
        t0[i] = madd::<FMA>(-s[0], v, t0[i]);
        t1[i] = madd::<FMA>(-s[1], v, t1[i]);
        t2[i] = madd::<FMA>(-s[2], v, t2[i]);
        t3[i] = madd::<FMA>(-s[3], v, t3[i]);
    }
}

#[cfg(target_arch = "x86_64")]
/// [`factor`] compiled for AVX2 + FMA: vectorized panels, blocked
/// application of their reflectors.
pub(super) fn factor_avx2(
    token: Avx2Fma,
    a: &mut [f64],
    m: usize,
    p: usize,
    row_end: &[usize],
    tau: &mut [f64],
    vbuf: &mut [f64],
) -> f64 {
    // SAFETY: `token` proves the CPU supports AVX2 and FMA, the only
    // precondition of `factor_unchecked`.
    unsafe { factor_unchecked(token, a, m, p, row_end, tau, vbuf) }
}

/// # Safety
/// The CPU must support AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
unsafe fn factor_unchecked(
    token: Avx2Fma,
    a: &mut [f64],
    m: usize,
    p: usize,
    row_end: &[usize],
    tau: &mut [f64],
    vbuf: &mut [f64],
) -> f64 {
    factor_generic::<true>(Some(token), a, m, p, row_end, tau, vbuf)
}

#[cfg(target_arch = "x86_64")]
/// [`first_non_finite`] compiled for AVX2 (wider vectors, same result).
pub(super) fn first_non_finite_avx2(
    token: Avx2Fma,
    a: &[f64],
    m: usize,
    p: usize,
    row_end: &[usize],
) -> Option<(usize, usize)> {
    let _proof = token;
    // SAFETY: `token` proves the CPU supports AVX2 and FMA.
    unsafe { first_non_finite_unchecked(a, m, p, row_end) }
}

/// # Safety
/// The CPU must support AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
unsafe fn first_non_finite_unchecked(
    a: &[f64],
    m: usize,
    p: usize,
    row_end: &[usize],
) -> Option<(usize, usize)> {
    first_non_finite_generic(a, m, p, row_end)
}

#[cfg(target_arch = "x86_64")]
/// [`back_substitute`] compiled for AVX2 (the same operations, no
/// contraction: identical results).
pub(super) fn back_substitute_avx2(
    token: Avx2Fma,
    a: &[f64],
    m: usize,
    p: usize,
    x: &mut [f64],
) -> f64 {
    let _proof = token;
    // SAFETY: `token` proves the CPU supports AVX2 and FMA.
    unsafe { back_substitute_unchecked(a, m, p, x) }
}

/// # Safety
/// The CPU must support AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
unsafe fn back_substitute_unchecked(a: &[f64], m: usize, p: usize, x: &mut [f64]) -> f64 {
    back_substitute_generic(a, m, p, x)
}
