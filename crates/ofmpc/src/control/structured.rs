//! Structured least squares: the controllers' problem as a stage-wise
//! linear-quadratic problem, solved by a square-root (QR) Riccati recursion
//! whose cost grows linearly in the horizon `N`.
//!
//! The model is frozen over the horizon, so every controller's system
//! `𝒜 ΔU = b` (Eq. (37), (39), (43)) is the condensed form of
//!
//! ```text
//! min Σ_{j=0}^{N−1} ‖R v_j‖² + Σ_{j=1}^{N} ‖D (S z_j − r_j)‖²,
//! z_{j+1} = A z_j + B v_j + c_j,   z_0 given,
//! ```
//!
//! with an augmented state `z` (nz), the stage input `v_j` (nu: `Δu_{k+j}` or
//! `u_{k+j}`), diagonal `R > 0` and `D ≥ 0`, and `S` selecting the first `nq`
//! entries of `z` (each controller orders its state so that the weighted
//! coordinates come first, see [`super::core`]).
//!
//! # Square-root recursion (Householder, no normal equations)
//!
//! The cost-to-go from stage `j` is `‖L_j z_j − l_j‖² + ρ_j` with `L_j`
//! upper triangular (nz×nz). Starting from `L_N = [D S; 0]`, `l_N = [D r_N; 0]`,
//! stage `j = N−1, …, 0` factorizes by Householder QR
//!
//! ```text
//!  columns:        v_j          z_j            rhs
//!             [ R             0        |   0               ]   nu rows (diagonal)
//!             [ 0             D S      |   D r_j           ]   nq rows (diagonal; none at j = 0)
//!             [ L_{j+1} B     L_{j+1} A |   l_{j+1} − L_{j+1} c_j ]   nz dense rows
//!   = Q [ R_vv   R_vz | ρ_j ]
//!       [ 0      L_j  | l_j ]
//!       [ 0      0    | e_j ]
//! ```
//!
//! so that `v_j = R_vv⁻¹(ρ_j − R_vz z_j)` (forward pass) and `ρ_{j} =
//! ρ_{j+1} + ‖e_j‖²`. The top rows of the stacked matrix are diagonal, so the
//! reflector of each of their columns touches its pivot row and the `nz`
//! dense rows only. This is a Householder QR of `𝒜` itself with its unknowns
//! in the order `v_{N−1}, …, v_0` (the order of the dense solver), applied
//! stage by stage: the condition number is not squared, `|R_ii|` and
//! `J_min = ρ_0 + ‖e_0‖²` equal those of the dense QR up to rounding.
//!
//! Flops per stage: `O((nu + nz)²·nz)`, independent of `N`.

use super::simd::Avx2Fma;

/// The stage-wise problem and its square-root Riccati workspace, sized once.
#[derive(Debug, Clone)]
pub(crate) struct StageLq {
    pub nu: usize,
    pub nz: usize,
    pub nq: usize,
    pub nh: usize,
    /// `A` (nz×nz, column-major).
    pub a: Vec<f64>,
    /// `B` (nz×nu, column-major).
    pub b: Vec<f64>,
    /// Diagonal of `R` (nu), all > 0.
    pub rd: Vec<f64>,
    /// Diagonal of `D` (nq), all ≥ 0.
    pub qd: Vec<f64>,
    /// Targets `r_j`, j = 1..N: block `j − 1` (nq values each).
    pub r: Vec<f64>,
    /// Affine terms `c_j`, j = 0..N−1: block `j` (nz values each).
    pub c: Vec<f64>,
    /// Whether the `c_j` are all zero (skips `L c`).
    pub c_zero: bool,
    /// Initial state `z_0` (nz).
    pub z0: Vec<f64>,
    /// Stacked stage matrix, row-major: `ld = nu + nq + nz` rows of
    /// `nu + nz + 1` columns (row operations are contiguous).
    m: Vec<f64>,
    ld: usize,
    /// `[B A]` row-major (nz × (nu + nz)).
    ba: Vec<f64>,
    /// Current `L` (nz×nz row-major, upper triangular) and `l`.
    l_mat: Vec<f64>,
    l_vec: Vec<f64>,
    /// Householder work: the reflector vector and `vᵀM`.
    hv: Vec<f64>,
    hw: Vec<f64>,
    /// Per stage `j`: the `nu` rows `[R_vv R_vz ρ]`, row-major
    /// nu × (nu + nz + 1).
    vrows: Vec<f64>,
    /// Forward pass: current and next state.
    z: Vec<f64>,
    z_next: Vec<f64>,
    /// The solution `v_0, …, v_{N−1}` (N·nu, natural order).
    sol: Vec<f64>,
}

/// Outcome of one structured solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StageInfo {
    /// `J_min` of the condensed system.
    pub residual_sq: f64,
    /// `max|R_ii| / min|R_ii|` over the diagonal blocks `R_vv`.
    pub r_diag_ratio: f64,
    /// `max|R_ii|`.
    pub r_max: f64,
}

/// Why a structured solve failed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum StageError {
    /// A number became NaN or infinite.
    NonFinite,
}

impl StageLq {
    /// Buffers for `nu` inputs, `nz` states of which the first `nq` are
    /// weighted, horizon `nh`.
    pub fn new(nu: usize, nz: usize, nq: usize, nh: usize) -> Self {
        let ld = nu + nq + nz;
        let cols = nu + nz + 1;
        Self {
            nu,
            nz,
            nq,
            nh,
            a: vec![0.0; nz * nz],
            b: vec![0.0; nz * nu],
            rd: vec![0.0; nu],
            qd: vec![0.0; nq],
            r: vec![0.0; nh * nq],
            c: vec![0.0; nh * nz],
            c_zero: true,
            z0: vec![0.0; nz],
            m: vec![0.0; ld * cols],
            ld,
            ba: vec![0.0; nz * (nu + nz)],
            hv: vec![0.0; ld],
            hw: vec![0.0; cols],
            l_mat: vec![0.0; nz * nz],
            l_vec: vec![0.0; nz],
            vrows: vec![0.0; nh * nu * cols],
            z: vec![0.0; nz],
            z_next: vec![0.0; nz],
            sol: vec![0.0; nh * nu],
        }
    }

    /// The solution `v_0, …, v_{N−1}` of the last successful solve.
    pub fn solution(&self) -> &[f64] {
        &self.sol
    }

    /// Backward square-root recursion and forward pass. Allocates nothing.
    /// Runs the same code compiled for AVX2 when the CPU has it (the
    /// partial sums are the same, so is the result).
    pub fn solve(&mut self) -> Result<StageInfo, StageError> {
        match Avx2Fma::detect() {
            Some(token) => self.solve_avx2(token),
            None => self.solve_portable(),
        }
    }

    /// [`StageLq::solve`] compiled for the baseline target.
    pub fn solve_portable(&mut self) -> Result<StageInfo, StageError> {
        self.solve_impl()
    }

    /// [`StageLq::solve`] compiled with AVX2 and FMA enabled; the token proves
    /// the CPU runs them.
    pub fn solve_avx2(&mut self, token: Avx2Fma) -> Result<StageInfo, StageError> {
        let _proof = token;
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: an `Avx2Fma` exists only when the CPU supports AVX2 and
            // FMA (`Avx2Fma::detect`), the features `solve_avx2_unchecked`
            // enables.
            unsafe { self.solve_avx2_unchecked() }
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.solve_impl()
    }

    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn solve_avx2_unchecked(&mut self) -> Result<StageInfo, StageError> {
        self.solve_impl()
    }

    #[inline(always)]
    fn solve_impl(&mut self) -> Result<StageInfo, StageError> {
        let (nu, nz, nq, nh, ld) = (self.nu, self.nz, self.nq, self.nh, self.ld);
        let cols = nu + nz + 1;
        let rhs = nu + nz;
        // [B A] row-major.
        for (i, row) in self.ba.chunks_exact_mut(nu + nz).enumerate() {
            for (c, v) in row[..nu].iter_mut().enumerate() {
                *v = self.b[c * nz + i];
            }
            for (c, v) in row[nu..].iter_mut().enumerate() {
                *v = self.a[c * nz + i];
            }
        }
        // L_N = [D S; 0], l_N = [D r_N; 0].
        self.l_mat.fill(0.0);
        self.l_vec.fill(0.0);
        for i in 0..nq {
            self.l_mat[i * nz + i] = self.qd[i];
            self.l_vec[i] = self.qd[i] * self.r[(nh - 1) * nq + i];
        }
        let mut acc = 0.0;
        let (mut dmax, mut dmin) = (0.0f64, f64::INFINITY);
        for j in (0..nh).rev() {
            // Rows of the diagonal part: nu (+ nq for j ≥ 1).
            let top = if j == 0 { nu } else { nu + nq };
            let m = &mut self.m;
            m[..top * cols].fill(0.0);
            for i in 0..nu {
                m[i * cols + i] = self.rd[i];
            }
            if j > 0 {
                for i in 0..nq {
                    let q = self.qd[i];
                    let row = &mut m[(nu + i) * cols..(nu + i + 1) * cols];
                    row[nu + i] = q;
                    row[rhs] = q * self.r[(j - 1) * nq + i];
                }
            }
            // Dense rows: row i = Σ_{k ≥ i} L[i,k] [B A | −c_j][k] and l_{j+1}.
            let cj = &self.c[j * nz..(j + 1) * nz];
            for (i, (row, lrow)) in m[top * cols..(top + nz) * cols]
                .chunks_exact_mut(cols)
                .zip(self.l_mat.chunks_exact(nz))
                .enumerate()
            {
                let (out, last) = row.split_at_mut(rhs);
                out.fill(0.0);
                let li = &lrow[i..];
                accumulate_rows(out, li, &self.ba[i * (nu + nz)..], nu + nz, 0);
                let lc = if self.c_zero { 0.0 } else { dot(li, &cj[i..]) };
                last[0] = if self.c_zero {
                    self.l_vec[i]
                } else {
                    self.l_vec[i] - lc
                };
            }
            // Householder on the columns with a diagonal pivot row.
            for k in 0..top {
                householder_rows(m, cols, k, k, top, top + nz, &mut self.hv, &mut self.hw);
            }
            if j > 0 {
                // The remaining z columns: pivot k is dense row k − top, at row k.
                for k in top..nu + nz {
                    householder_rows(m, cols, k, k, k + 1, top + nz, &mut self.hv, &mut self.hw);
                }
                // L_j: row c is row nu + c from column nu + c on.
                for (c, lrow) in self.l_mat.chunks_exact_mut(nz).enumerate() {
                    let row = &m[(nu + c) * cols..(nu + c + 1) * cols];
                    lrow[..c].fill(0.0);
                    lrow[c..].copy_from_slice(&row[nu + c..rhs]);
                    self.l_vec[c] = row[rhs];
                }
                // Rows below the pivots: residual only.
                for row in nu + nz..top + nz {
                    let e = m[row * cols + rhs];
                    acc += e * e;
                }
            } else {
                // j = 0: z_0 is known, the remaining rows are residual.
                for row in m[top * cols..(top + nz) * cols].chunks_exact(cols) {
                    let e = dot(&row[nu..rhs], &self.z0) - row[rhs];
                    acc += e * e;
                }
            }
            // Keep [R_vv R_vz ρ] of this stage.
            let dst = &mut self.vrows[j * nu * cols..(j + 1) * nu * cols];
            dst.copy_from_slice(&m[..nu * cols]);
            for i in 0..nu {
                let d = dst[i * cols + i].abs();
                dmax = dmax.max(d);
                dmin = dmin.min(d);
            }
            if !(acc.is_finite() && self.l_mat.iter().all(|v| v.is_finite())) {
                return Err(StageError::NonFinite);
            }
        }
        if !dmax.is_finite() {
            return Err(StageError::NonFinite);
        }
        if dmin == 0.0 {
            // Zero pivot: the caller's rank test reports it.
            return Ok(StageInfo {
                residual_sq: acc,
                r_diag_ratio: dmax / dmin,
                r_max: dmax,
            });
        }
        let _ = ld;
        // Forward pass.
        self.z.copy_from_slice(&self.z0);
        for j in 0..nh {
            let vr = &self.vrows[j * nu * cols..(j + 1) * nu * cols];
            let v = &mut self.sol[j * nu..(j + 1) * nu];
            // Back substitution: R_vv v = ρ − R_vz z (R_vv upper triangular).
            for i in (0..nu).rev() {
                let row = &vr[i * cols..(i + 1) * cols];
                let mut s = row[rhs] - dot(&row[nu..rhs], &self.z);
                for (r, vk) in row[i + 1..nu].iter().zip(&v[i + 1..]) {
                    s -= r * vk;
                }
                v[i] = s / row[i];
            }
            if j + 1 < nh {
                // z_{j+1} = A z_j + B v_j + c_j
                if self.c_zero {
                    self.z_next.fill(0.0);
                } else {
                    self.z_next.copy_from_slice(&self.c[j * nz..(j + 1) * nz]);
                }
                for (col, zc) in self.a.chunks_exact(nz).zip(&self.z) {
                    if *zc != 0.0 {
                        for (o, a) in self.z_next.iter_mut().zip(col) {
                            *o += a * zc;
                        }
                    }
                }
                for (col, vc) in self.b.chunks_exact(nz).zip(v.iter()) {
                    for (o, b) in self.z_next.iter_mut().zip(col) {
                        *o += b * vc;
                    }
                }
                std::mem::swap(&mut self.z, &mut self.z_next);
            }
        }
        if !self.sol.iter().all(|v| v.is_finite()) {
            return Err(StageError::NonFinite);
        }
        Ok(StageInfo {
            residual_sq: acc,
            r_diag_ratio: dmax / dmin,
            r_max: dmax,
        })
    }

    /// `|R_ii|` of the last solve in the column order of the dense system
    /// (`v_{N−1}` first).
    pub fn r_diagonal_dense_order(&self) -> impl Iterator<Item = f64> + '_ {
        let (nu, cols) = (self.nu, self.nu + self.nz + 1);
        self.vrows
            .chunks_exact(nu * cols)
            .rev()
            .flat_map(move |v| (0..nu).map(move |i| v[i * cols + i].abs()))
    }
}

/// One Householder reflection of the stacked matrix `m` (row-major, `cols`
/// columns): annihilates column `k` in rows `lo..hi` against the pivot row
/// `p` (`p < lo`; every other row is zero in column `k` by structure), and
/// applies it to columns `k+1..cols` by contiguous row operations. Leaves
/// `β` at `(p, k)` and zeros in rows `lo..hi` of column `k`. `hv` (≥ hi − lo)
/// and `hw` (≥ cols) are work.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn householder_rows(
    m: &mut [f64],
    cols: usize,
    k: usize,
    p: usize,
    lo: usize,
    hi: usize,
    hv: &mut [f64],
    hw: &mut [f64],
) {
    let len = hi - lo;
    let v = &mut hv[..len];
    for (x, row) in v.iter_mut().zip(m[lo * cols..hi * cols].chunks_exact(cols)) {
        *x = row[k];
    }
    let sigma = dot(v, v);
    if sigma == 0.0 {
        return;
    }
    let alpha = m[p * cols + k];
    let norm = (alpha * alpha + sigma).sqrt();
    let beta = if alpha >= 0.0 { -norm } else { norm };
    let scale = 1.0 / (alpha - beta);
    for x in v.iter_mut() {
        *x *= scale;
    }
    let tau = (beta - alpha) / beta;
    let w = &mut hw[..cols - k - 1];
    let (upper, lower) = m.split_at_mut(lo * cols);
    let prow = &mut upper[p * cols..(p + 1) * cols];
    prow[k] = beta;
    // w = M[p, k+1..] + Σ v_i M[i, k+1..]
    w.copy_from_slice(&prow[k + 1..]);
    let lower = &mut lower[..len * cols];
    accumulate_rows(w, v, lower, cols, k + 1);
    for o in w.iter_mut() {
        *o *= tau;
    }
    for (o, x) in prow[k + 1..].iter_mut().zip(w.iter()) {
        *o -= x;
    }
    for (vi, row) in v.iter().zip(lower.chunks_exact_mut(cols)) {
        row[k] = 0.0;
        for (o, x) in row[k + 1..].iter_mut().zip(w.iter()) {
            *o -= vi * x;
        }
    }
}

/// `w[c] += Σ_i v[i]·m[i·cols + off + c]` for `c < w.len()`: a sum of
/// scaled rows, eight columns at a time in registers (no round trip of `w`
/// through memory per row).
#[inline(always)]
fn accumulate_rows(w: &mut [f64], v: &[f64], m: &[f64], cols: usize, off: usize) {
    const W: usize = 8;
    let len = w.len();
    let mut c0 = 0;
    while c0 + W <= len {
        let mut acc = [0.0f64; W];
        acc.copy_from_slice(&w[c0..c0 + W]);
        for (&vi, row) in v.iter().zip(m.chunks(cols)) {
            let seg = &row[off + c0..off + c0 + W];
            for l in 0..W {
                acc[l] += vi * seg[l];
            }
        }
        w[c0..c0 + W].copy_from_slice(&acc);
        c0 += W;
    }
    if c0 < len {
        let rest = len - c0;
        let mut acc = [0.0f64; W];
        acc[..rest].copy_from_slice(&w[c0..]);
        for (&vi, row) in v.iter().zip(m.chunks(cols)) {
            for (a, x) in acc[..rest].iter_mut().zip(&row[off + c0..off + len]) {
                *a += vi * x;
            }
        }
        w[c0..].copy_from_slice(&acc[..rest]);
    }
}

/// `xᵀy` with four independent partial sums (so that it vectorizes).
#[inline(always)]
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let len = x.len().min(y.len());
    let (x, y) = (&x[..len], &y[..len]);
    let mut acc = [0.0f64; 4];
    let (cx, cy) = (x.chunks_exact(4), y.chunks_exact(4));
    let (rx, ry) = (cx.remainder(), cy.remainder());
    for (a, b) in cx.zip(cy) {
        for l in 0..4 {
            acc[l] += a[l] * b[l];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (a, b) in rx.iter().zip(ry) {
        s += a * b;
    }
    s
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

    fn random_problem(nu: usize, nz: usize, nq: usize, nh: usize, seed: &mut u64) -> StageLq {
        let mut st = StageLq::new(nu, nz, nq, nh);
        for v in st.a.iter_mut().chain(&mut st.b).chain(&mut st.r) {
            *v = rng(seed);
        }
        for v in st.c.iter_mut().chain(&mut st.z0) {
            *v = rng(seed);
        }
        st.c_zero = false;
        for v in st.rd.iter_mut() {
            *v = 0.1 + rng(seed).abs();
        }
        for v in st.qd.iter_mut() {
            *v = rng(seed).abs();
        }
        st
    }

    /// The condensed problem built by brute force: unknowns v_0..v_{N−1},
    /// states eliminated by z_{j} = A^j z_0 + Σ A^{j−1−i}(B v_i + c_i); solved
    /// by SVD.
    fn brute(st: &StageLq) -> (Vec<f64>, f64) {
        let (nu, nz, nq, nh) = (st.nu, st.nz, st.nq, st.nh);
        let a = DMatrix::from_column_slice(nz, nz, &st.a);
        let b = DMatrix::from_column_slice(nz, nu, &st.b);
        let p = nh * nu;
        let rows = p + nh * nq;
        let mut m = DMatrix::<f64>::zeros(rows, p);
        let mut rhs = DVector::<f64>::zeros(rows);
        for i in 0..p {
            m[(i, i)] = st.rd[i % nu];
        }
        // z_j = Z_j [v; 1]: affine in v.
        let mut zv = DMatrix::<f64>::zeros(nz, p);
        let mut z1 = DVector::from_column_slice(&st.z0);
        for j in 1..=nh {
            let c = DVector::from_column_slice(&st.c[(j - 1) * nz..j * nz]);
            zv = &a * zv;
            zv.view_mut((0, (j - 1) * nu), (nz, nu)).copy_from(&b);
            z1 = &a * z1 + c;
            for i in 0..nq {
                let row = p + (j - 1) * nq + i;
                for col in 0..p {
                    m[(row, col)] = st.qd[i] * zv[(i, col)];
                }
                rhs[row] = st.qd[i] * (st.r[(j - 1) * nq + i] - z1[i]);
            }
        }
        let x = m.clone().svd(true, true).solve(&rhs, 1e-14).unwrap();
        let res = (&m * &x - &rhs).norm_squared();
        (x.as_slice().to_vec(), res)
    }

    #[test]
    fn square_root_recursion_equals_brute_force_least_squares() {
        let mut seed = 3;
        for (nu, nz, nq, nh) in [(1, 1, 1, 1), (2, 3, 2, 4), (3, 5, 2, 6), (2, 4, 4, 9)] {
            let mut st = random_problem(nu, nz, nq, nh, &mut seed);
            let info = st.solve_portable().unwrap();
            let (x, res) = brute(&st);
            let diff = st
                .solution()
                .iter()
                .zip(&x)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(diff <= 1e-10 * scale, "{nu} {nz} {nq} {nh}: {diff:e}");
            assert!(
                (info.residual_sq - res).abs() <= 1e-10 * res.max(1e-300),
                "J_min {} vs {res}",
                info.residual_sq
            );
        }
    }

    #[test]
    fn avx2_build_equals_portable_build() {
        let Some(token) = Avx2Fma::detect() else {
            eprintln!("SKIPPED avx2_build_equals_portable_build: this CPU has no AVX2+FMA");
            return;
        };
        let mut seed = 9;
        for (nu, nz, nq, nh) in [(6, 24, 12, 10), (2, 3, 2, 4), (6, 18, 12, 7)] {
            let mut st = random_problem(nu, nz, nq, nh, &mut seed);
            let mut st2 = st.clone();
            let a = st.solve_portable().unwrap();
            let b = st2.solve_avx2(token).unwrap();
            assert_eq!(a, b);
            assert_eq!(st.solution(), st2.solution());
        }
    }
}
