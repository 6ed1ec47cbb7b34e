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

use super::dense::{axpy, dot};

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
        /// Threshold `max(m, p)·ε·max|R_jj|`.
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
    /// Column-major m×(p+1): `[𝒜 | b]`, overwritten by `R1`, reflectors, `[c1; c2]`.
    a: Vec<f64>,
    row_end: Vec<usize>,
    x: Vec<f64>,
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
            a: vec![0.0; m * (p + 1)],
            row_end,
            x: vec![0.0; p],
        })
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
        for c in 0..=p {
            let end = if c < p { self.row_end[c] } else { m };
            let col = &self.a[c * m..c * m + end];
            if let Some(row) = col.iter().position(|v| !v.is_finite()) {
                return Err(LsqError::NonFiniteInput { row, col: c, p });
            }
        }
        let mut rmax = 0.0f64;
        for c in 0..p {
            let end = self.row_end[c];
            let (left, right) = self.a.split_at_mut((c + 1) * m);
            let v = &mut left[c * m + c..c * m + end];
            // Reflector H = I − τ v vᵀ with v[0] = 1 mapping the column to β e1.
            let x0 = v[0];
            let sigma = dot(&v[1..], &v[1..]);
            let tau;
            if sigma == 0.0 {
                tau = 0.0; // already triangular in this column
            } else {
                let alpha = (x0 * x0 + sigma).sqrt();
                let beta = if x0 > 0.0 { -alpha } else { alpha };
                let v0 = x0 - beta;
                tau = (beta - x0) / beta;
                let inv = 1.0 / v0;
                v[1..].iter_mut().for_each(|e| *e *= inv);
                v[0] = beta;
            }
            rmax = rmax.max(v[0].abs());
            if tau != 0.0 {
                let vt = &v[1..];
                // Apply to the trailing columns c+1..p−1 and to b (column p).
                for col in right.chunks_exact_mut(m) {
                    let seg = &mut col[c..end];
                    let s = tau * (seg[0] + dot(vt, &seg[1..]));
                    seg[0] -= s;
                    axpy(-s, vt, &mut seg[1..]);
                }
            }
        }
        // Rank check on the diagonal of R1.
        let tol = (m.max(p) as f64) * f64::EPSILON * rmax;
        let mut rmin = f64::INFINITY;
        let mut first_bad = None;
        let mut rank = 0;
        for c in 0..p {
            let d = self.a[c * m + c].abs();
            rmin = rmin.min(d);
            if d > tol {
                rank += 1;
            } else if first_bad.is_none() {
                first_bad = Some((c, d));
            }
        }
        if !rmax.is_finite() {
            return Err(LsqError::NonFiniteResult);
        }
        if let Some((column, value)) = first_bad {
            return Err(LsqError::RankDeficient {
                column,
                value,
                tolerance: tol,
                rank,
                p,
            });
        }
        // Back substitution R1 x = c1, column-oriented.
        let (r, cvec) = self.a.split_at_mut(m * p);
        self.x.copy_from_slice(&cvec[..p]);
        for j in (0..p).rev() {
            let xj = self.x[j] / r[j * m + j];
            self.x[j] = xj;
            axpy(-xj, &r[j * m..j * m + j], &mut self.x[..j]);
        }
        let residual_sq = dot(&cvec[p..], &cvec[p..]);
        if !residual_sq.is_finite() || self.x.iter().any(|v| !v.is_finite()) {
            return Err(LsqError::NonFiniteResult);
        }
        Ok(LsqInfo {
            residual_sq,
            r_diag_ratio: rmax / rmin,
        })
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn rng(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

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
