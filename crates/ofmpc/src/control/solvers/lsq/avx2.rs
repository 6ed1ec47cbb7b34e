//! AVX2 + FMA kernels of the least-squares solve ([`super`]): dot product,
//! scaling, panel factorization, Gram matrix and the blocked (compact WY)
//! application of a panel's reflectors, with explicit 4-wide intrinsics.
//!
//! Their safe entry points ([`super::factor`]) take an `Avx2Fma` token: one exists
//! only on a CPU that runs AVX2 and FMA, so no safe caller can reach AVX2 code
//! elsewhere. The kernels below them are `#[target_feature]` functions whose
//! remaining precondition (documented under `# Safety`) is the CPU support
//! (the token) and, for the raw-pointer kernels, the index ranges that their
//! callers check.
#![allow(clippy::needless_range_loop)] // index loops read like the matrix formulas
#![deny(unsafe_op_in_unsafe_fn)]

use std::arch::x86_64::*;

use super::householder::{reflector, PANEL};

/// Sum of the four lanes (value intrinsics only: safe where AVX2 is enabled).
#[inline]
#[target_feature(enable = "avx2,fma")]
fn hsum(v: __m256d) -> f64 {
    let lo = _mm256_castpd256_pd128(v);
    let hi = _mm256_extractf128_pd(v, 1);
    let s = _mm_add_pd(lo, hi);
    let h = _mm_unpackhi_pd(s, s);
    _mm_cvtsd_f64(_mm_add_sd(s, h))
}

/// `Σ x_i y_i` over the common length: four 4-wide accumulators, then
/// single vectors, then a scalar tail of at most three.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[inline]
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn dot(x: &[f64], y: &[f64]) -> f64 {
    let len = x.len().min(y.len());
    let (px, py) = (x.as_ptr(), y.as_ptr());
    let mut acc = [_mm256_setzero_pd(); 4];
    let mut i = 0;
    // SAFETY (all loads): `i + 4 ≤ len` (resp. `i < len`), both slices
    // are at least `len` long.
    while i + 16 <= len {
        for l in 0..4 {
            let o = i + 4 * l;
            acc[l] = _mm256_fmadd_pd(
                // SAFETY: offsets below `len`, the common length of `x` and `y` (loop bounds)
                unsafe { _mm256_loadu_pd(px.wrapping_add(o)) },
                // SAFETY: offsets below `len`, the common length of `x` and `y` (loop bounds)
                unsafe { _mm256_loadu_pd(py.wrapping_add(o)) },
                acc[l],
            );
        }
        i += 16;
    }
    while i + 4 <= len {
        acc[0] = _mm256_fmadd_pd(
            // SAFETY: offsets below `len`, the common length of `x` and `y` (loop bounds)
            unsafe { _mm256_loadu_pd(px.wrapping_add(i)) },
            // SAFETY: offsets below `len`, the common length of `x` and `y` (loop bounds)
            unsafe { _mm256_loadu_pd(py.wrapping_add(i)) },
            acc[0],
        );
        i += 4;
    }
    let mut s = hsum(_mm256_add_pd(
        _mm256_add_pd(acc[0], acc[1]),
        _mm256_add_pd(acc[2], acc[3]),
    ));
    while i < len {
        // SAFETY: offsets below `len`, the common length of `x` and `y` (loop bounds)
        unsafe {
            s = (*px.wrapping_add(i)).mul_add(*py.wrapping_add(i), s);
        }
        i += 1;
    }
    s
}

/// `x ← s·x` (each product rounded once, as the scalar loop).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[inline]
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn scale(s: f64, x: &mut [f64]) {
    let len = x.len();
    let px = x.as_mut_ptr();
    let sv = _mm256_set1_pd(s);
    let mut i = 0;
    // SAFETY: `i + 4 ≤ len` (resp. `i < len`).
    while i + 4 <= len {
        // SAFETY: offsets below `len = x.len()` (loop bounds)
        unsafe {
            _mm256_storeu_pd(
                px.wrapping_add(i),
                _mm256_mul_pd(sv, _mm256_loadu_pd(px.wrapping_add(i))),
            )
        };
        i += 4;
    }
    while i < len {
        // SAFETY: offsets below `len = x.len()` (loop bounds)
        unsafe {
            *px.wrapping_add(i) *= s;
        }
        i += 1;
    }
}

/// Factors the panel `c0..c1` (all with `row_end = end`) of the
/// column-major m-row array `a` in place, column by column: reflector of
/// column `c`, applied at once to the panel's later columns. Writes
/// `tau[c0..c1]` and the explicit reflectors to `vbuf` (`m` per column,
/// rows `c0..end`, see [`apply_block`]), returns `max |R_cc|`.
///
/// # Safety
/// The CPU must support AVX2 and FMA. Index ranges are checked (slices,
/// and the asserts of `apply_block_k`): the caller passes a panel with
/// `c0 < c1 ≤ c0 + PANEL`, `c1 ≤ end ≤ m`, `c1·m ≤ a.len()`,
/// `c1 ≤ tau.len()`, `(c1 − c0)·m ≤ vbuf.len()`.
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn factor_panel(
    a: &mut [f64],
    m: usize,
    c0: usize,
    c1: usize,
    end: usize,
    tau: &mut [f64],
    vbuf: &mut [f64],
) -> f64 {
    let mut rmax = 0.0f64;
    for c in c0..c1 {
        let (left, right) = a.split_at_mut((c + 1) * m);
        let v = &mut left[c * m + c..c * m + end];
        let (head, tail) = v.split_at_mut(1);
        // SAFETY: AVX2 and FMA are enabled (this function's target features); the callee asserts its index ranges
        let t = match reflector(head[0], unsafe { dot(tail, tail) }) {
            None => 0.0,
            Some((beta, inv, t)) => {
                // SAFETY: AVX2 and FMA are enabled (this function's target features); the callee asserts its index ranges
                unsafe { scale(inv, tail) };
                head[0] = beta;
                t
            }
        };
        tau[c] = t;
        rmax = rmax.max(head[0].abs());
        // Column r of the explicit V: rows c0..end.
        let r = c - c0;
        let vcol = &mut vbuf[r * m..r * m + (end - c0)];
        vcol[..r].fill(0.0);
        vcol[r] = 1.0;
        vcol[r + 1..].copy_from_slice(tail);
        if t != 0.0 && c + 1 < c1 {
            let mut t1 = [[0.0f64; PANEL]; PANEL];
            t1[0][0] = t;
            let vb = &vbuf[r * m + r..(r + 1) * m];
            // SAFETY: AVX2 and FMA are enabled (this function's target features); the callee asserts its index ranges
            unsafe {
                apply_block_k::<1, false>(vb, m, c, end, m, &t1, &mut right[..(c1 - c - 1) * m])
            };
        }
    }
    rmax
}

/// `gram[j][r] = v_jᵀ v_r` for `j < r` of the panel `c0..c1` of `left`
/// (reflector `j` has its unit entry at row `c0 + j`, stored entries
/// below it, rows up to `end`).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn gram(
    left: &[f64],
    m: usize,
    c0: usize,
    c1: usize,
    end: usize,
) -> [[f64; PANEL]; PANEL] {
    assert!(c1 <= c0 + PANEL && c1 * m <= left.len() && end <= m && c1 <= end);
    let mut g = [[0.0f64; PANEL]; PANEL];
    let v = left.as_ptr();
    for r in 1..c1 - c0 {
        let col = match r {
            // SAFETY: AVX2 and FMA are enabled; `gram` asserted that columns c0..c1 and rows below `end` lie in `left`
            1 => unsafe { gram_col::<1>(v, m, c0, end) },
            // SAFETY: AVX2 and FMA are enabled; `gram` asserted that columns c0..c1 and rows below `end` lie in `left`
            2 => unsafe { gram_col::<2>(v, m, c0, end) },
            // SAFETY: AVX2 and FMA are enabled; `gram` asserted that columns c0..c1 and rows below `end` lie in `left`
            3 => unsafe { gram_col::<3>(v, m, c0, end) },
            // SAFETY: AVX2 and FMA are enabled; `gram` asserted that columns c0..c1 and rows below `end` lie in `left`
            4 => unsafe { gram_col::<4>(v, m, c0, end) },
            // SAFETY: AVX2 and FMA are enabled; `gram` asserted that columns c0..c1 and rows below `end` lie in `left`
            5 => unsafe { gram_col::<5>(v, m, c0, end) },
            // SAFETY: AVX2 and FMA are enabled; `gram` asserted that columns c0..c1 and rows below `end` lie in `left`
            6 => unsafe { gram_col::<6>(v, m, c0, end) },
            // SAFETY: AVX2 and FMA are enabled; `gram` asserted that columns c0..c1 and rows below `end` lie in `left`
            _ => unsafe { gram_col::<7>(v, m, c0, end) },
        };
        for j in 0..r {
            g[j][r] = col[j];
        }
    }
    g
}

/// `v_jᵀ v_R` for `j < R`, one pass over the rows below `c0 + R`.
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn gram_col<const R: usize>(v: *const f64, m: usize, c0: usize, end: usize) -> [f64; PANEL] {
    // SAFETY: the caller (`gram`) checked that columns c0..=c0+R, rows
    // below `end ≤ m`, lie inside the array `v` points to.
    let row0 = c0 + R;
    let vr = v.wrapping_add(row0 * m);
    let mut s = [0.0f64; PANEL];
    for j in 0..R {
        // SAFETY: columns c0..=c0+R and rows below `end ≤ m` lie in the array (asserted by `gram`)
        unsafe {
            s[j] = *v.wrapping_add((c0 + j) * m + row0);
        }
    }
    let start = row0 + 1;
    let len = end - start;
    let mut acc = [_mm256_setzero_pd(); R];
    let mut i = 0;
    while i + 4 <= len {
        let row = start + i;
        // SAFETY: columns c0..=c0+R and rows below `end ≤ m` lie in the array (asserted by `gram`)
        let x = unsafe { _mm256_loadu_pd(vr.wrapping_add(row)) };
        for j in 0..R {
            // SAFETY: columns c0..=c0+R and rows below `end ≤ m` lie in the array (asserted by `gram`)
            acc[j] = _mm256_fmadd_pd(
                unsafe { _mm256_loadu_pd(v.wrapping_add((c0 + j) * m + row)) },
                x,
                acc[j],
            );
        }
        i += 4;
    }
    for j in 0..R {
        s[j] += hsum(acc[j]);
    }
    while i < len {
        let row = start + i;
        // SAFETY: columns c0..=c0+R and rows below `end ≤ m` lie in the array (asserted by `gram`)
        let x = unsafe { *vr.wrapping_add(row) };
        for j in 0..R {
            // SAFETY: columns c0..=c0+R and rows below `end ≤ m` lie in the array (asserted by `gram`)
            unsafe {
                s[j] = (*v.wrapping_add((c0 + j) * m + row)).mul_add(x, s[j]);
            }
        }
        i += 1;
    }
    s
}

/// `A ← (I − V Tᵀ Vᵀ) A` on rows `lo..end` of every column in `right`
/// (each `m` long), for `k` reflectors held explicitly in `vb`: column
/// `r` starts at `vb[r·ld]` and holds rows `lo..end` (zeros above the unit
/// diagonal). `T` from `t_from_gram`.
///
/// # Safety
/// The CPU must support AVX2 and FMA. (Index ranges are asserted.)
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn apply_block(
    vb: &[f64],
    ld: usize,
    k: usize,
    lo: usize,
    end: usize,
    m: usize,
    t: &[[f64; PANEL]; PANEL],
    right: &mut [f64],
) {
    match k {
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        1 => unsafe { apply_block_k::<1, false>(vb, ld, lo, end, m, t, right) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        2 => unsafe { apply_block_k::<2, false>(vb, ld, lo, end, m, t, right) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        3 => unsafe { apply_block_k::<3, false>(vb, ld, lo, end, m, t, right) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        4 => unsafe { apply_block_k::<4, false>(vb, ld, lo, end, m, t, right) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        5 => unsafe { apply_block_k::<5, false>(vb, ld, lo, end, m, t, right) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        6 => unsafe { apply_block_k::<6, false>(vb, ld, lo, end, m, t, right) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        7 => unsafe { apply_block_k::<7, false>(vb, ld, lo, end, m, t, right) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        _ => unsafe { apply_block_k::<8, false>(vb, ld, lo, end, m, t, right) },
    }
}

#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn apply_block_k<const K: usize, const IL: bool>(
    vb: &[f64],
    ld: usize,
    lo: usize,
    end: usize,
    m: usize,
    t: &[[f64; PANEL]; PANEL],
    right: &mut [f64],
) {
    // Every V entry read lies in `vb` (column layout: column r < K,
    // offset < end − lo; interleaved: all chunks of the K columns), every
    // A entry (row < end ≤ m) in its column.
    assert!(K <= PANEL && lo < end && end <= m);
    let len = end - lo;
    if IL {
        assert!(len >= 4 && ld == 4 && len.div_ceil(4) * 4 * K <= vb.len());
    } else {
        assert!((K - 1) * ld + len <= vb.len());
    }
    let v = vb.as_ptr();
    let mut pairs = right.chunks_exact_mut(2 * m);
    for pair in &mut pairs {
        let (a0, a1) = pair.split_at_mut(m);
        // SAFETY: AVX2 and FMA are enabled; the V and A ranges were asserted above (rows < end ≤ m of each column)
        unsafe { block::<K, 2, IL>(v, ld, lo, end, t, [a0.as_mut_ptr(), a1.as_mut_ptr()]) };
    }
    for col in pairs.into_remainder().chunks_exact_mut(m) {
        // SAFETY: AVX2 and FMA are enabled; the V and A ranges were asserted above (rows < end ≤ m of each column)
        unsafe { block::<K, 1, IL>(v, ld, lo, end, t, [col.as_mut_ptr()]) };
    }
}

/// [`apply_block`] with the reflectors first copied to `vpack` in an
/// interleaved layout (per 4-row chunk, the `k` columns side by side), so
/// that the inner loops address `V` with constant offsets. Same
/// operations in the same order: bit-for-bit the result of
/// [`apply_block`].
///
/// # Safety
/// The CPU must support AVX2 and FMA. (Index ranges are asserted.)
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn apply_block_packed(
    vb: &[f64],
    ld: usize,
    k: usize,
    lo: usize,
    end: usize,
    m: usize,
    t: &[[f64; PANEL]; PANEL],
    right: &mut [f64],
    vpack: &mut [f64],
) {
    let len = end.saturating_sub(lo);
    let chunks = len.div_ceil(4);
    if len < 4 || k == 0 || k > PANEL || chunks * 4 * k > vpack.len() {
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        return unsafe { apply_block(vb, ld, k, lo, end, m, t, right) };
    }
    match k {
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        1 => unsafe { pack_apply::<1>(vb, ld, lo, end, m, t, right, vpack) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        2 => unsafe { pack_apply::<2>(vb, ld, lo, end, m, t, right, vpack) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        3 => unsafe { pack_apply::<3>(vb, ld, lo, end, m, t, right, vpack) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        4 => unsafe { pack_apply::<4>(vb, ld, lo, end, m, t, right, vpack) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        5 => unsafe { pack_apply::<5>(vb, ld, lo, end, m, t, right, vpack) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        6 => unsafe { pack_apply::<6>(vb, ld, lo, end, m, t, right, vpack) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        7 => unsafe { pack_apply::<7>(vb, ld, lo, end, m, t, right, vpack) },
        // SAFETY: AVX2 and FMA are enabled; the callee asserts its index ranges
        _ => unsafe { pack_apply::<8>(vb, ld, lo, end, m, t, right, vpack) },
    }
}

/// Packs `K` columns (`len = end − lo ≥ 4` rows each) of `vb` into
/// `vpack`, chunk by chunk: chunk 0 holds rows 0..4 when `head = len mod
/// 4 ≠ 0` (masked later), then the full chunks at row offsets
/// `head + 4j`; within a chunk the `K` columns are side by side. Then
/// applies them with the interleaved kernel.
#[inline]
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
unsafe fn pack_apply<const K: usize>(
    vb: &[f64],
    ld: usize,
    lo: usize,
    end: usize,
    m: usize,
    t: &[[f64; PANEL]; PANEL],
    right: &mut [f64],
    vpack: &mut [f64],
) {
    let len = end - lo;
    let head = len % 4;
    assert!(len >= 4 && (K - 1) * ld + len <= vb.len() && len.div_ceil(4) * 4 * K <= vpack.len());
    let (src, dst) = (vb.as_ptr(), vpack.as_mut_ptr());
    // SAFETY: reads at column offsets `< len` of the K columns of `vb`,
    // writes to the `ceil(len/4)·4K` first entries of `vpack` (asserted).
    let mut d = dst;
    if head != 0 {
        for r in 0..K {
            // SAFETY: column offsets below `len` of the K columns of `vb`, and the first ceil(len/4)·4K entries of `vpack` (asserted above)
            unsafe {
                _mm256_storeu_pd(
                    d.wrapping_add(4 * r),
                    _mm256_loadu_pd(src.wrapping_add(r * ld)),
                )
            };
        }
        d = d.wrapping_add(4 * K);
    }
    let mut off = head;
    while off + 4 <= len {
        for r in 0..K {
            // SAFETY: column offsets below `len` of the K columns of `vb`, and the first ceil(len/4)·4K entries of `vpack` (asserted above)
            unsafe {
                _mm256_storeu_pd(
                    d.wrapping_add(4 * r),
                    _mm256_loadu_pd(src.wrapping_add(r * ld + off)),
                )
            };
        }
        d = d.wrapping_add(4 * K);
        off += 4;
    }
    // SAFETY: column offsets below `len` of the K columns of `vb`, and the first ceil(len/4)·4K entries of `vpack` (asserted above)
    unsafe { apply_block_k::<K, true>(vpack, 4, lo, end, m, t, right) };
}

/// One group of `Q` columns, rows `lo..end`. The rows are taken four at
/// a time; when their count is not a multiple of four (and at least
/// four), the first `head` rows go first as a masked 4-row chunk (loads
/// and stores of the lanes `≥ head` are suppressed), so that no scalar
/// tail remains. `V` is column-major with leading dimension `ld`, or,
/// when `IL`, interleaved as built by [`apply_block_packed`] (`ld = 4`,
/// then `len ≥ 4`).
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn block<const K: usize, const Q: usize, const IL: bool>(
    v: *const f64,
    ld: usize,
    lo: usize,
    end: usize,
    t: &[[f64; PANEL]; PANEL],
    cols: [*mut f64; Q],
) {
    // SAFETY (all accesses): `apply_block_k` asserted that the V
    // entries read (column layout: offsets `r·ld + i`, `r < K`,
    // `i < end − lo`; interleaved: the chunks of all K columns) lie in
    // the V buffer and rows `lo + i < end ≤ m` in each column; masked
    // chunks start at offset 0 and are only used when `end − lo ≥ 4`.
    let len = end - lo;
    let head = len % 4;
    // Distance between the columns of V and between successive chunks;
    // first full chunk.
    let (rs, cs) = if IL { (4, 4 * K) } else { (ld, 4) };
    let v_full = if IL {
        v.wrapping_add(usize::from(head != 0) * 4 * K)
    } else {
        v.wrapping_add(head)
    };
    let ap: [*mut f64; Q] = std::array::from_fn(|q| cols[q].wrapping_add(lo + head));
    let full = len / 4;
    let mut y = [[0.0f64; Q]; K];
    let mask = _mm256_cmpgt_epi64(
        _mm256_set1_epi64x(head as i64),
        _mm256_set_epi64x(3, 2, 1, 0),
    );
    // Y = Vᵀ A.
    if len < 4 {
        for i in 0..len {
            for r in 0..K {
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                let vr = unsafe { *v.wrapping_add(r * ld + i) };
                for q in 0..Q {
                    // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                    unsafe {
                        y[r][q] = vr.mul_add(*cols[q].wrapping_add(lo + i), y[r][q]);
                    }
                }
            }
        }
    } else {
        let mut acc = [[_mm256_setzero_pd(); Q]; K];
        if head != 0 {
            let mut av = [_mm256_setzero_pd(); Q];
            for q in 0..Q {
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                av[q] = unsafe { _mm256_maskload_pd(cols[q].wrapping_add(lo), mask) };
            }
            for r in 0..K {
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                let vv = unsafe { _mm256_maskload_pd(v.wrapping_add(r * rs), mask) };
                for q in 0..Q {
                    acc[r][q] = _mm256_fmadd_pd(vv, av[q], acc[r][q]);
                }
            }
        }
        let mut vc = v_full;
        for j in 0..full {
            let mut av = [_mm256_setzero_pd(); Q];
            for q in 0..Q {
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                av[q] = unsafe { _mm256_loadu_pd(ap[q].wrapping_add(4 * j)) };
            }
            for r in 0..K {
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                let vv = unsafe { _mm256_loadu_pd(vc.wrapping_add(r * rs)) };
                for q in 0..Q {
                    acc[r][q] = _mm256_fmadd_pd(vv, av[q], acc[r][q]);
                }
            }
            vc = vc.wrapping_add(cs);
        }
        for r in 0..K {
            for q in 0..Q {
                y[r][q] = hsum(acc[r][q]);
            }
        }
    }
    // W = Tᵀ Y.
    let mut w = [[0.0f64; Q]; K];
    for r in 0..K {
        for j in 0..=r {
            for q in 0..Q {
                w[r][q] = t[j][r].mul_add(y[j][q], w[r][q]);
            }
        }
    }
    // A −= V W.
    if len < 4 {
        for i in 0..len {
            for q in 0..Q {
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                let mut a = unsafe { *cols[q].wrapping_add(lo + i) };
                for r in 0..K {
                    // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                    unsafe {
                        a = (-w[r][q]).mul_add(*v.wrapping_add(r * ld + i), a);
                    }
                }
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                unsafe {
                    *cols[q].wrapping_add(lo + i) = a;
                }
            }
        }
        return;
    }
    let mut wb = [[_mm256_setzero_pd(); Q]; K];
    for r in 0..K {
        for q in 0..Q {
            wb[r][q] = _mm256_set1_pd(-w[r][q]);
        }
    }
    if head != 0 {
        for q in 0..Q {
            // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
            let mut av = unsafe { _mm256_maskload_pd(cols[q].wrapping_add(lo), mask) };
            for r in 0..K {
                // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
                let vv = unsafe { _mm256_maskload_pd(v.wrapping_add(r * rs), mask) };
                av = _mm256_fmadd_pd(wb[r][q], vv, av);
            }
            // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
            unsafe { _mm256_maskstore_pd(cols[q].wrapping_add(lo), mask, av) };
        }
    }
    let mut vc = v_full;
    for j in 0..full {
        let mut av = [_mm256_setzero_pd(); Q];
        for q in 0..Q {
            // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
            av[q] = unsafe { _mm256_loadu_pd(ap[q].wrapping_add(4 * j)) };
        }
        for r in 0..K {
            // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
            let vv = unsafe { _mm256_loadu_pd(vc.wrapping_add(r * rs)) };
            for q in 0..Q {
                av[q] = _mm256_fmadd_pd(wb[r][q], vv, av[q]);
            }
        }
        for q in 0..Q {
            // SAFETY: entries asserted by `apply_block_k`: V offsets inside the V buffer, rows lo..end ≤ m of each column
            unsafe { _mm256_storeu_pd(ap[q].wrapping_add(4 * j), av[q]) };
        }
        vc = vc.wrapping_add(cs);
    }
}
