//! Least squares `min ‖𝒜 ΔU − b‖₂` by Householder QR, Eq. (40)–(42):
//! `Qᵀ[𝒜 | b] = [[R1, c1], [0, c2]]`, `R1 ΔU = c1` by back substitution,
//! `J_min = c2ᵀ c2`.
//!
//! In place on preallocated column-major storage (`[𝒜 | b]` is one m×(p+1)
//! array), no allocation per solve. The inner loops run over contiguous column
//! segments (dot product and axpy) so that they vectorize.
//!
//! **Profile.** A column `c` may declare that its entries at rows
//! `≥ row_end[c]` are zero (`row_end` non-decreasing). A Householder reflector
//! of column `c` then only touches rows `c..row_end[c]`, and no fill-in can
//! appear outside the profile of a later column, so the factorization is the
//! same as the dense one with fewer flops. The controllers order rows and
//! unknowns so that their block-triangular `𝒜` has such a profile.

use crate::control::solvers::simd::AlignedBuf;
use factor::{back_substitute, factor, first_non_finite};
use householder::{PANEL, VBUF_PER_ROW};

/// Outcome of a successful solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LsqInfo {
    /// `J_min = c2ᵀ c2 = ‖𝒜 ΔU − b‖²` (Eq. (42)).
    pub residual_sq: f64,
    /// `max |R_ii| / min |R_ii|`, a lower bound of the 2-norm condition number
    /// of `𝒜`.
    pub r_diag_ratio: f64,
}

/// Why a solve failed. The solution buffer is then unspecified.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum LsqError {
    /// `𝒜` or `b` holds NaN or ±∞.
    #[error("the least-squares system has a non-finite entry at row {row}, column {col} (column {p} is b)")]
    NonFiniteInput {
        /// Row of the first bad entry.
        row: usize,
        /// Column (`p` means `b`).
        col: usize,
        /// Number of unknowns `p`.
        p: usize,
    },
    /// A diagonal entry of `R1` is negligible: `𝒜` has (numerically) lost
    /// column rank, the minimizer is not unique.
    #[error("the least-squares matrix is rank deficient: |R[{column},{column}]| = {value:e} <= {tolerance:e}, numerical rank about {rank} of {p}; increase the input weight q_du (or q_u)")]
    RankDeficient {
        /// First column with a negligible pivot.
        column: usize,
        /// Its `|R_ii|`.
        value: f64,
        /// Threshold `max(m, p)·ε·max|R_jj|` (`m` of the system it stands for,
        /// [`LsqWorkspace::set_rank_rows`]).
        tolerance: f64,
        /// Number of pivots above the threshold.
        rank: usize,
        /// Number of unknowns.
        p: usize,
    },
    /// The factorization produced NaN or ±∞ (overflow).
    #[error("the least-squares solve overflowed (non-finite result): scale the problem or check the model")]
    NonFiniteResult,
}

/// Workspace of a Householder least-squares solve with `m` rows and `p ≤ m`
/// unknowns. Fill [`LsqWorkspace::matrix_mut`] and [`LsqWorkspace::rhs_mut`],
/// then call [`LsqWorkspace::solve`]; it overwrites both.
#[derive(Debug, Clone)]
pub struct LsqWorkspace {
    m: usize,
    p: usize,
    /// Row count in the rank test's tolerance (`m` unless set).
    rank_rows: usize,
    /// Column-major m×(p+1): `[𝒜 | b]`, overwritten by `R1`, reflectors, `[c1; c2]`.
    a: AlignedBuf,
    row_end: Vec<usize>,
    tau: Vec<f64>,
    x: Vec<f64>,
    /// The reflectors of one panel, explicit and interleaved (AVX2 kernels).
    vbuf: AlignedBuf,
}

/// The shape or profile given to [`LsqWorkspace::new`] is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LsqShapeError {
    /// `p == 0` or `p > m`.
    #[error("a least-squares system needs 1 <= unknowns <= rows, got {p} unknowns and {m} rows")]
    BadShape {
        /// Rows.
        m: usize,
        /// Unknowns.
        p: usize,
    },
    /// The profile is not a non-decreasing list of `p` ends with `c < end ≤ m`.
    #[error("bad profile at column {col}: row_end = {end} (must be > {col}, <= {m}, non-decreasing, one per column)")]
    BadProfile {
        /// Column.
        col: usize,
        /// Its declared end.
        end: usize,
        /// Rows.
        m: usize,
    },
}

impl LsqWorkspace {
    /// A dense workspace: `m` rows, `p` unknowns.
    pub fn new(m: usize, p: usize) -> Result<Self, LsqShapeError> {
        Self::with_profile(m, p, vec![m; p])
    }

    /// A workspace whose column `c` has zeros at rows `≥ row_end[c]`
    /// (non-decreasing; see the module documentation).
    pub fn with_profile(m: usize, p: usize, row_end: Vec<usize>) -> Result<Self, LsqShapeError> {
        if p == 0 || p > m {
            return Err(LsqShapeError::BadShape { m, p });
        }
        if row_end.len() != p {
            return Err(LsqShapeError::BadProfile {
                col: row_end.len().min(p),
                end: 0,
                m,
            });
        }
        let mut prev = 0;
        for (col, &end) in row_end.iter().enumerate() {
            if end <= col || end > m || end < prev {
                return Err(LsqShapeError::BadProfile { col, end, m });
            }
            prev = end;
        }
        Ok(Self {
            m,
            p,
            rank_rows: m,
            a: AlignedBuf::zeros(m * (p + 1)),
            row_end,
            tau: vec![0.0; p],
            x: vec![0.0; p],
            vbuf: AlignedBuf::zeros(VBUF_PER_ROW * PANEL * (m + 4)),
        })
    }

    /// Uses `rows` instead of `m` in the rank test's tolerance
    /// `max(rows, p)·ε·max|R_jj|`: for a system that stands for a taller one
    /// by an orthogonal transformation of its rows (same `R1`), so that both
    /// decide the rank alike.
    pub fn set_rank_rows(&mut self, rows: usize) {
        self.rank_rows = rows;
    }

    /// Rows `m`.
    pub fn rows(&self) -> usize {
        self.m
    }

    /// Unknowns `p`.
    pub fn cols(&self) -> usize {
        self.p
    }

    /// The profile: column `c` is zero at rows `≥ row_end()[c]`.
    pub fn row_end(&self) -> &[usize] {
        &self.row_end
    }

    /// `𝒜`, column-major m×p (column c is `[c·m, (c+1)·m)`). Entries outside
    /// the profile are ignored (treated as zero).
    pub fn matrix_mut(&mut self) -> &mut [f64] {
        let mp = self.m * self.p;
        &mut self.a[..mp]
    }

    /// `b`, length m.
    pub fn rhs_mut(&mut self) -> &mut [f64] {
        let mp = self.m * self.p;
        &mut self.a[mp..]
    }

    /// `𝒜` and `b` at once (split borrows).
    pub fn system_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        let mp = self.m * self.p;
        self.a.split_at_mut(mp)
    }

    /// The solution `ΔU` of the last successful [`LsqWorkspace::solve`].
    pub fn solution(&self) -> &[f64] {
        &self.x
    }

    /// After [`LsqWorkspace::solve`]: `c = Qᵀ b` (`[c1; c2]`, length m).
    pub fn transformed_rhs(&self) -> &[f64] {
        &self.a[self.m * self.p..]
    }

    /// After [`LsqWorkspace::solve`]: column `j < p` of `R1`, its rows
    /// `0..=j` (the rest is zero; the storage below holds reflectors).
    pub fn r_column(&self, j: usize) -> &[f64] {
        let j = j.min(self.p.saturating_sub(1));
        &self.a[j * self.m..j * self.m + j + 1]
    }

    /// After [`LsqWorkspace::solve`]: entry `(i, j)` of `R1`, `i ≤ j < p`.
    pub fn r(&self, i: usize, j: usize) -> f64 {
        if i <= j && j < self.p {
            self.a[j * self.m + i]
        } else {
            0.0
        }
    }

    /// Householder QR of `[𝒜 | b]` in place (Eq. (41)–(42)), back
    /// substitution `R1 ΔU = c1`, `J_min = ‖c2‖²`. Allocates nothing.
    pub fn solve(&mut self) -> Result<LsqInfo, LsqError> {
        let (m, p) = (self.m, self.p);
        // Finite input (inside the profile; b everywhere).
        if let Some((row, col)) = first_non_finite(&self.a, m, p, &self.row_end) {
            return Err(LsqError::NonFiniteInput { row, col, p });
        }
        let rmax = factor(
            &mut self.a,
            m,
            p,
            &self.row_end,
            &mut self.tau,
            &mut self.vbuf,
        );
        // Rank check on the diagonal of R1.
        let tol = (self.rank_rows.max(p) as f64) * f64::EPSILON * rmax;
        let rmin = (0..p).fold(f64::INFINITY, |r, c| r.min(self.a[c * m + c].abs()));
        if !rmax.is_finite() {
            return Err(LsqError::NonFiniteResult);
        }
        rank_test((0..p).map(|c| self.a[c * m + c].abs()), tol)?;
        let residual_sq = back_substitute(&self.a, m, p, &mut self.x);
        if !residual_sq.is_finite() || self.x.iter().any(|v| !v.is_finite()) {
            return Err(LsqError::NonFiniteResult);
        }
        Ok(LsqInfo {
            residual_sq,
            r_diag_ratio: rmax / rmin,
        })
    }
}

/// The rank test on the diagonal of `R1`: every `|R_ii|` (`diag`, in
/// column order) above `tol`, else the first column that is not, with the
/// numerical rank. Shared by the dense and the structured solver.
pub(crate) fn rank_test(diag: impl Iterator<Item = f64>, tol: f64) -> Result<(), LsqError> {
    let (mut rank, mut p, mut first_bad) = (0, 0, None);
    for (column, d) in diag.enumerate() {
        p += 1;
        if d > tol {
            rank += 1;
        } else if first_bad.is_none() {
            first_bad = Some((column, d));
        }
    }
    match first_bad {
        Some((column, value)) => Err(LsqError::RankDeficient {
            column,
            value,
            tolerance: tol,
            rank,
            p,
        }),
        None => Ok(()),
    }
}

/// Flops of [`LsqWorkspace::solve`] (factorization with `b`, back
/// substitution) for a profile, counting a multiply-add as 2 flops.
pub fn lsq_flops(p: usize, row_end: &[usize]) -> u64 {
    let mut f = 0u64;
    for (c, &end) in row_end.iter().enumerate().take(p) {
        let len = (end - c) as u64;
        f += 2 * len + 2 * len; // norm + scaling (≈)
        f += (p - c) as u64 * 4 * len; // dot + axpy on trailing columns and b
    }
    f + (p * p) as u64
}

/// Explicit AVX2+FMA kernels: blocked application of a panel's reflectors in
/// compact WY form, 4-wide vectors along the rows, two columns at a time.
#[cfg(target_arch = "x86_64")]
mod avx2;
mod factor;
mod householder;

#[cfg(test)]
mod tests {
    use super::factor::*;
    use super::householder::*;
    use super::*;
    use crate::control::solvers::simd::Avx2Fma;
    use nalgebra::{DMatrix, DVector};

    use crate::linalg::random::symmetric as rng;

    fn solve_dense(a: &DMatrix<f64>, b: &DVector<f64>) -> (Vec<f64>, LsqInfo) {
        let mut ws = LsqWorkspace::new(a.nrows(), a.ncols()).unwrap();
        ws.matrix_mut().copy_from_slice(a.as_slice());
        ws.rhs_mut().copy_from_slice(b.as_slice());
        let info = ws.solve().unwrap();
        (ws.solution().to_vec(), info)
    }

    #[test]
    fn equals_normal_equations_and_residual() {
        let mut seed = 11;
        for (m, p) in [(1, 1), (3, 1), (5, 5), (9, 4), (40, 17), (180, 60)] {
            let a = DMatrix::<f64>::from_fn(m, p, |_, _| rng(&mut seed));
            let b = DVector::<f64>::from_fn(m, |_, _| rng(&mut seed));
            let (x, info) = solve_dense(&a, &b);
            let x = DVector::from_vec(x);
            // Normal equations (brute force), well conditioned here.
            let ata = a.transpose() * &a;
            let xn = ata.cholesky().unwrap().solve(&(a.transpose() * &b));
            assert!(
                (&x - &xn).norm() <= 1e-11 * xn.norm().max(1.0),
                "m={m} p={p}"
            );
            // J_min = ‖c2‖² equals the residual computed directly.
            let r = &a * &x - &b;
            let j = r.norm_squared();
            assert!(
                (info.residual_sq - j).abs() <= 1e-12 * j.max(1e-300) + 1e-28,
                "m={m} p={p}: {} vs {j}",
                info.residual_sq
            );
            assert!(info.r_diag_ratio >= 1.0);
        }
    }

    #[test]
    fn profile_gives_the_dense_solution() {
        let mut seed = 5;
        let (m, p) = (30, 12);
        // Block upper-triangular profile: 3 rows per level, 1 column per level... grow by 5 rows per 2 columns.
        let row_end: Vec<usize> = (0..p).map(|c| (5 * (c / 2 + 1)).min(m)).collect();
        let a = DMatrix::<f64>::from_fn(
            m,
            p,
            |i, c| if i < row_end[c] { rng(&mut seed) } else { 0.0 },
        );
        let b = DVector::<f64>::from_fn(m, |_, _| rng(&mut seed));
        let (xd, infod) = solve_dense(&a, &b);
        let mut ws = LsqWorkspace::with_profile(m, p, row_end.clone()).unwrap();
        // Garbage outside the profile must be ignored.
        let mut garbage = a.clone();
        for c in 0..p {
            for i in row_end[c]..m {
                garbage[(i, c)] = 1e3 * rng(&mut seed);
            }
        }
        ws.matrix_mut().copy_from_slice(garbage.as_slice());
        ws.rhs_mut().copy_from_slice(b.as_slice());
        let info = ws.solve().unwrap();
        for (u, v) in ws.solution().iter().zip(&xd) {
            assert!((u - v).abs() <= 1e-12 * v.abs().max(1.0));
        }
        assert!((info.residual_sq - infod.residual_sq).abs() <= 1e-12 * infod.residual_sq);
        assert!(lsq_flops(p, &row_end) < lsq_flops(p, &vec![m; p]));
    }

    /// The portable kernel and the dispatched one (AVX2+FMA where present)
    /// factor alike, for dense and profiled shapes with all column remainders.
    #[test]
    fn portable_and_dispatched_kernels_agree() {
        let mut seed = 21;
        for (m, p, step) in [(7, 5, 0), (40, 13, 0), (90, 30, 9), (54, 18, 18)] {
            let row_end: Vec<usize> = if step == 0 {
                vec![m; p]
            } else {
                (0..p).map(|c| (step * (c / 3 + 1)).min(m)).collect()
            };
            let a: Vec<f64> = (0..m * (p + 1)).map(|_| rng(&mut seed)).collect();
            let (mut a1, mut a2) = (a.clone(), a);
            let (mut t1, mut t2) = (vec![0.0; p], vec![0.0; p]);
            let mut vbuf = vec![0.0; VBUF_PER_ROW * PANEL * (m + 4)];
            let r1 = factor_generic::<false>(None, &mut a1, m, p, &row_end, &mut t1, &mut vbuf);
            let r2 = factor(&mut a2, m, p, &row_end, &mut t2, &mut vbuf);
            assert!((r1 - r2).abs() <= 1e-13 * r1);
            for c in 0..=p {
                let end = if c < p { row_end[c] } else { m };
                for i in 0..end {
                    let (x, y) = (a1[c * m + i], a2[c * m + i]);
                    assert!(
                        (x - y).abs() <= 1e-11 * (1.0 + x.abs()),
                        "m={m} p={p} ({i},{c}): {x} vs {y}"
                    );
                }
            }
        }
    }

    /// Small multiples of 1/4: sums of their products are exact in any
    /// order, so differently ordered kernels must agree bit for bit.
    #[cfg(target_arch = "x86_64")]
    fn dyadic(seed: &mut u64) -> f64 {
        (rng(seed) * 8.0).round() / 4.0
    }

    /// The AVX2 dot product and scaling equal the portable loops on every
    /// length 0..=40 and around 70 (all vector/scalar tail combinations).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_dot_and_scale_equal_portable() {
        if Avx2Fma::detect().is_none() {
            eprintln!("SKIPPED avx_dot_and_scale_equal_portable: this CPU has no AVX2+FMA (the kernels are not used here)");
            return;
        }
        let mut seed = 31;
        for len in (0..=40).chain(64..=75) {
            let x: Vec<f64> = (0..len).map(|_| dyadic(&mut seed)).collect();
            let y: Vec<f64> = (0..len + 3).map(|_| dyadic(&mut seed)).collect();
            let portable = x.iter().zip(&y).fold(0.0, |s, (a, b)| s + a * b);
            // SAFETY: AVX2 and FMA detected above.
            let fast = unsafe { avx2::dot(&x, &y) };
            assert_eq!(portable.to_bits(), fast.to_bits(), "len {len}");
            // Rounded data: same result up to summation order.
            let xr: Vec<f64> = (0..len).map(|_| rng(&mut seed)).collect();
            let bound: f64 = xr.iter().zip(&y).map(|(a, b)| (a * b).abs()).sum();
            let portable = xr.iter().zip(&y).fold(0.0, |s, (a, b)| s + a * b);
            // SAFETY: as above.
            let fast = unsafe { avx2::dot(&xr, &y) };
            assert!((portable - fast).abs() <= 1e-15 * bound.max(f64::MIN_POSITIVE) * len as f64);
            let s = rng(&mut seed);
            let mut z = xr.clone();
            // SAFETY: as above.
            unsafe { avx2::scale(s, &mut z) };
            for (a, b) in z.iter().zip(&xr) {
                assert_eq!(a.to_bits(), (s * b).to_bits());
            }
        }
    }

    /// One reflector applied by the AVX2 block kernel (K = 1, column pairs
    /// and a single column) equals the portable `apply1`, and the AVX2 Gram
    /// entries of a panel equal the portable dot products, bit for bit on
    /// exact data, for row counts that leave every tail length.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_panel_kernels_equal_portable() {
        if Avx2Fma::detect().is_none() {
            eprintln!("SKIPPED avx_panel_kernels_equal_portable: this CPU has no AVX2+FMA (the kernels are not used here)");
            return;
        }
        let mut seed = 41;
        for m in [9usize, 12, 17, 70, 71, 72, 73, 74] {
            for (c0, k) in [(0usize, 1usize), (0, 6), (2, 8), (3, 5)] {
                if c0 + k > m {
                    continue;
                }
                for end in [c0 + k, c0 + k + 1, m - 1, m] {
                    if end < c0 + k || end > m {
                        continue;
                    }
                    let ncols = c0 + k + 3;
                    let a: Vec<f64> = (0..m * ncols).map(|_| dyadic(&mut seed)).collect();
                    let (left, right) = a.split_at(c0 * m + k * m);
                    // Gram of the panel c0..c0+k.
                    // SAFETY: AVX2 and FMA detected above; shapes as required.
                    let g = unsafe { avx2::gram(left, m, c0, c0 + k, end) };
                    assert_eq!(
                        g,
                        gram_portable(left, m, c0, c0 + k, end),
                        "m={m} c0={c0} k={k} end={end}"
                    );
                    // Reflector of column c0 applied to three trailing columns.
                    let mut t1 = [[0.0f64; PANEL]; PANEL];
                    t1[0][0] = 0.5;
                    let mut fast = right.to_vec();
                    let vt = &left[c0 * m + c0 + 1..c0 * m + end];
                    let vb: Vec<f64> = std::iter::once(1.0).chain(vt.iter().copied()).collect();
                    // SAFETY: as above.
                    unsafe { avx2::apply_block(&vb, m, 1, c0, end, m, &t1, &mut fast) };
                    let mut slow = right.to_vec();
                    for col in slow.chunks_exact_mut(m) {
                        apply1::<false>(0.5, vt, &mut col[c0..end]);
                    }
                    assert_eq!(fast, slow, "m={m} c0={c0} end={end}");
                }
            }
        }
    }

    /// The blocked AVX2 kernel, column layout and interleaved (packed)
    /// layout, applies `k` reflectors like `k` successive portable `apply1`
    /// calls (within rounding), and the two layouts agree bit for bit, for
    /// every `k`, every head length `(end − lo) mod 4`, short row ranges and
    /// an odd number of columns.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_block_layouts_agree_and_equal_sequential() {
        if Avx2Fma::detect().is_none() {
            eprintln!("SKIPPED avx_block_layouts_agree_and_equal_sequential: this CPU has no AVX2+FMA (the kernels are not used here)");
            return;
        }
        let mut seed = 51;
        let m = 40;
        for k in 1..=PANEL {
            for lo in [0usize, 3] {
                for len in [k, k + 1, k + 2, k + 3, 17, 18, 19, 20, 37 - lo] {
                    let end = lo + len;
                    if len < k || end > m {
                        continue;
                    }
                    // Reflectors: unit diagonal at row lo + r, random below.
                    let ld = m;
                    let mut vb = vec![0.0; PANEL * ld];
                    let mut tau = [0.0; PANEL];
                    for r in 0..k {
                        vb[r * ld + r] = 1.0;
                        for i in r + 1..len {
                            vb[r * ld + i] = 0.3 * rng(&mut seed);
                        }
                        let vv: f64 = vb[r * ld..r * ld + len].iter().map(|x| x * x).sum();
                        tau[r] = 2.0 / vv; // exact reflector: orthogonal H
                    }
                    let mut gram = [[0.0; PANEL]; PANEL];
                    for r in 0..k {
                        for j in 0..r {
                            gram[j][r] = (0..len).map(|i| vb[j * ld + i] * vb[r * ld + i]).sum();
                        }
                    }
                    let t = t_from_gram(k, &tau, &gram);
                    let ncols = 5;
                    let a: Vec<f64> = (0..m * ncols).map(|_| rng(&mut seed)).collect();
                    let mut slow = a.clone();
                    for col in slow.chunks_exact_mut(m) {
                        for r in 0..k {
                            let v = &vb[r * ld + r + 1..r * ld + len];
                            apply1::<false>(tau[r], v, &mut col[lo + r..end]);
                        }
                    }
                    let (mut col_layout, mut packed) = (a.clone(), a.clone());
                    let mut vpack = vec![f64::NAN; PANEL * (m + 4)];
                    // SAFETY: AVX2 and FMA detected above; shapes as required.
                    unsafe {
                        avx2::apply_block(&vb, ld, k, lo, end, m, &t, &mut col_layout);
                        avx2::apply_block_packed(
                            &vb,
                            ld,
                            k,
                            lo,
                            end,
                            m,
                            &t,
                            &mut packed,
                            &mut vpack,
                        );
                    }
                    assert_eq!(col_layout, packed, "k={k} lo={lo} len={len}");
                    for (i, (x, y)) in slow.iter().zip(&packed).enumerate() {
                        assert!(
                            (x - y).abs() <= 1e-13,
                            "k={k} lo={lo} len={len} at {i}: {x} vs {y}"
                        );
                        if i % m < lo || i % m >= end {
                            assert_eq!(y.to_bits(), a[i].to_bits(), "row outside lo..end touched");
                        }
                    }
                }
            }
        }
    }

    /// The dispatched finite check and back substitution equal the portable
    /// builds bit for bit.
    #[test]
    fn dispatched_check_and_back_substitution_equal_portable() {
        let mut seed = 61;
        for (m, p) in [(5, 3), (40, 13), (180, 60)] {
            let mut a: Vec<f64> = (0..m * (p + 1)).map(|_| rng(&mut seed)).collect();
            for c in 0..p {
                a[c * m + c] += 4.0_f64.copysign(a[c * m + c]);
            }
            let (mut x1, mut x2) = (vec![0.0; p], vec![0.0; p]);
            let j1 = back_substitute_generic(&a, m, p, &mut x1);
            let j2 = back_substitute(&a, m, p, &mut x2);
            assert_eq!(j1.to_bits(), j2.to_bits());
            assert_eq!(x1, x2);
            let row_end = vec![m; p];
            assert_eq!(first_non_finite(&a, m, p, &row_end), None);
            for (i, bad) in [
                (m * p - 1, f64::NAN),
                (3, f64::INFINITY),
                (m * (p + 1) - 1, -f64::INFINITY),
            ] {
                let mut b = a.clone();
                b[i] = bad;
                let want = Some((i % m, i / m));
                assert_eq!(first_non_finite_generic(&b, m, p, &row_end), want);
                assert_eq!(first_non_finite(&b, m, p, &row_end), want);
            }
        }
    }

    #[test]
    fn consistent_system_has_zero_residual_and_exact_solution() {
        let mut seed = 3;
        let (m, p) = (25, 8);
        let a = DMatrix::<f64>::from_fn(m, p, |_, _| rng(&mut seed));
        let x0 = DVector::<f64>::from_fn(p, |_, _| rng(&mut seed));
        let b = &a * &x0;
        let (x, info) = solve_dense(&a, &b);
        for (u, v) in x.iter().zip(x0.iter()) {
            assert!((u - v).abs() < 1e-13);
        }
        assert!(info.residual_sq < 1e-26);
    }

    #[test]
    fn reports_rank_loss_and_bad_input() {
        let (m, p) = (6, 3);
        let mut a = DMatrix::<f64>::from_fn(m, p, |i, j| (i + j) as f64);
        a.set_column(2, &(a.column(0) * 2.0)); // dependent
        let mut ws = LsqWorkspace::new(m, p).unwrap();
        ws.matrix_mut().copy_from_slice(a.as_slice());
        ws.rhs_mut().fill(1.0);
        assert!(matches!(
            ws.solve(),
            Err(LsqError::RankDeficient { column: 2, .. })
        ));
        ws.matrix_mut().fill(1.0);
        ws.rhs_mut()[4] = f64::NAN;
        assert_eq!(
            ws.solve(),
            Err(LsqError::NonFiniteInput {
                row: 4,
                col: 3,
                p: 3
            })
        );
        assert!(LsqWorkspace::new(2, 3).is_err());
        assert!(LsqWorkspace::with_profile(4, 2, vec![3, 2]).is_err());
        assert!(LsqWorkspace::with_profile(4, 2, vec![1, 4]).is_ok());
        assert!(LsqWorkspace::with_profile(4, 2, vec![0, 4]).is_err());
    }
}
