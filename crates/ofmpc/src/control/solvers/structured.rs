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
//! coordinates come first, see [`crate::control::mpc::core`]).
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
//!
//! # Converged stages
//!
//! The model and the weights are frozen over the horizon, so the factor
//! `L_j` depends on `N − j` only and converges as the recursion moves away
//! from the end of the horizon (geometrically, at the rate of the closed
//! loop: measured on the IRB 140, to rounding level within ≈ 15 stages at
//! `Ts` = 10 ms and ≈ 80 at 1 ms). Stage `j`'s reflectors are a function of
//! `L_{j+1}` alone; once two consecutive stages leave `L` unchanged to
//! [`CONVERGED_RTOL`], every earlier stage `j ≥ 1` would factorize the same
//! matrix: the recursion keeps that stage's orthogonal transformation, as
//! the linear map `M` from the stage's right-hand side inputs
//! `[D r_j; l_{j+1} − L c_j]` to its outputs `[ρ_j; l_j; e_j]` (formed by
//! carrying the inputs' unit vectors as extra columns through the stage's
//! reflections, from the stage after the first unchanged one), and runs the earlier
//! stages as one product with `M` each (`O((nu + nz + nq)·(nq + nz))` flops
//! instead of `O((nu + nz)²·nz)`). Stage 0 is always factorized in full.

use crate::control::solvers::simd::{AlignedBuf, Avx2Fma};

/// Largest change of `L` between consecutive stages, relative to `max|L|`,
/// at which the recursion counts as converged: 1e-12, far below the
/// solver's accuracy target (1e-9 against the dense QR) and above the
/// rounding noise of the recursion (measured 2–5e-16 once converged).
///
/// Measured on the IRB 140, second algorithm (ΔU against the dense QR,
/// relative; a few states of the paper's path): Ts = 1 ms, N = 100:
/// 1.1e-11 with 32 ε, 1.7e-11 with 1e-12, 2.0e-10 with 1e-11; N = 200:
/// 1.5e-10 / 1.6e-10 / 6.6e-10. Against 32 ε it factorizes 16 instead of
/// 18 stages at Ts = 10 ms (step at N = 100: 95 → 86 µs) and 66 instead of
/// 78 at 1 ms (the 1 kHz paper run: median 332 → 285 µs, tracking unchanged
/// to 12 digits).
pub(crate) const CONVERGED_RTOL: f64 = 1e-12;

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
    /// Only the first `c_rows` entries of every `c_j` may be non-zero (0: all
    /// `c_j` are zero and are skipped; the second algorithm's `c_j` has its
    /// `n` tracking entries only): `L c_j` then needs the first `c_rows` rows
    /// of the upper-triangular `L` alone.
    pub c_rows: usize,
    /// Initial state `z_0` (nz).
    pub z0: Vec<f64>,
    /// Stacked stage matrix, row-major: `ld = nu + nq + nz` rows of
    /// `nu + nz + 1` columns (row operations are contiguous), padded with
    /// zeros to `cs`, a multiple of 8 (the reflections then run on whole
    /// 8-wide blocks, none on a scalar tail), then `nq + nz` columns (padded
    /// to a multiple of 8) that carry the unit vectors of the right-hand
    /// side's inputs when a stage is about to converge. Row stride `ms`.
    m: AlignedBuf,
    ld: usize,
    cs: usize,
    ms: usize,
    /// `[B A 0]` row-major (nz rows, stride `cs`, zero from column nu + nz).
    ba: AlignedBuf,
    /// Current `L` (nz×nz row-major, upper triangular) and `l`.
    l_mat: AlignedBuf,
    l_vec: Vec<f64>,
    /// Householder work: the reflector vector and `vᵀM`.
    hv: AlignedBuf,
    hw: AlignedBuf,
    /// Per stage `j`: the `nu` rows `[R_vv R_vz ρ]`, row-major
    /// nu × (nu + nz + 1).
    vrows: AlignedBuf,
    /// Forward pass: current and next state.
    z: Vec<f64>,
    z_next: Vec<f64>,
    /// The solution `v_0, …, v_{N−1}` (N·nu, natural order).
    sol: Vec<f64>,
    /// Reuse the factorization of converged stages (on by default; off
    /// factorizes every stage, for tests).
    pub reuse_converged: bool,
    /// With a constraint head ([`StageLq::set_head`]): the first `nc` stages
    /// are condensed on demand; the cost-to-go `(L, l)` from stage `nc` is
    /// kept by each solve.
    head: usize,
    kept_l: Vec<f64>,
    kept_lvec: Vec<f64>,
    /// Condensing work: `∂z_j/∂v` (nz × nc·nu, column-major) and the affine
    /// part of `z_j`, for the current and the next stage.
    zs: Vec<f64>,
    zs_next: Vec<f64>,
    za: Vec<f64>,
    za_next: Vec<f64>,
    /// Right-hand side column of a reused stage (`ld` rows, padded to a
    /// multiple of 8).
    bvec: AlignedBuf,
    /// The converged stage's map `M` (ld × (nq + nz), column-major, column
    /// stride `ld` rounded up to a multiple of 8, zero padding) and its
    /// input `[D r_j; l_{j+1} − L c_j]`.
    mmap: AlignedBuf,
    bin: Vec<f64>,
    /// With [`StageLq::enable_gain`]: the first stage's feedback gain
    /// `K = ∂v_0/∂z_0` (nu × nz, row-major) of the last solve; empty
    /// otherwise (the first stage then carries no extra columns).
    gain: Vec<f64>,
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
    /// Stages factorized in full (the others reused a converged stage).
    pub factorized_stages: usize,
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
        let cs = cols.next_multiple_of(8);
        let ms = cs + (nq + nz).next_multiple_of(8);
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
            c_rows: 0,
            z0: vec![0.0; nz],
            m: AlignedBuf::zeros(ld * ms),
            ld,
            cs,
            ms,
            ba: AlignedBuf::zeros(nz * cols.next_multiple_of(8)),
            hv: AlignedBuf::zeros(ld),
            hw: AlignedBuf::zeros(ms),
            l_mat: AlignedBuf::zeros(nz * nz),
            l_vec: vec![0.0; nz],
            vrows: AlignedBuf::zeros(nh * nu * cols),
            z: vec![0.0; nz],
            z_next: vec![0.0; nz],
            sol: vec![0.0; nh * nu],
            reuse_converged: true,
            head: 0,
            kept_l: Vec::new(),
            kept_lvec: Vec::new(),
            zs: Vec::new(),
            zs_next: Vec::new(),
            za: Vec::new(),
            za_next: Vec::new(),
            bvec: AlignedBuf::zeros(ld.next_multiple_of(8)),
            mmap: AlignedBuf::zeros(ld.next_multiple_of(8) * (nq + nz)),
            bin: vec![0.0; nq + nz],
            gain: Vec::new(),
        }
    }

    /// Makes every solve also form the first stage's feedback gain
    /// [`StageLq::first_stage_gain`] (nu·nz values, sized here once). The
    /// first stage then carries the `nz` columns `L_1 A` through its
    /// reflections (`R_vz`, which the stage otherwise folds into its
    /// right-hand side with `z_0`); the solution is unchanged.
    pub fn enable_gain(&mut self) {
        self.gain = vec![0.0; self.nu * self.nz];
    }

    /// `K = ∂v_0/∂z_0 = −R_vv⁻¹ R_vz` of the last solve (nu × nz, row-major):
    /// the stage-0 input is `v_0 = R_vv⁻¹(ρ_0 − R_vz z_0)`, so for a change
    /// `δz_0` of the initial state alone (same `A`, `B`, `c_j`, targets)
    /// `v_0` changes by exactly `K δz_0`. Empty unless
    /// [`StageLq::enable_gain`] was called.
    pub fn first_stage_gain(&self) -> &[f64] {
        &self.gain
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
        let (nu, nz, nq, nh) = (self.nu, self.nz, self.nq, self.nh);
        let cols = nu + nz + 1;
        let cs = self.cs;
        let rhs = nu + nz;
        // [B A] row-major.
        for (i, row) in self.ba.chunks_exact_mut(cs).enumerate() {
            for (c, v) in row[..nu].iter_mut().enumerate() {
                *v = self.b[c * nz + i];
            }
            for (c, v) in row[nu..rhs].iter_mut().enumerate() {
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
        if self.head == nh {
            self.keep_cost_to_go();
        }
        let mut acc = 0.0;
        let (mut dmax, mut dmin) = (0.0f64, f64::INFINITY);
        // Consecutive stages that left L unchanged; the stage whose
        // reflectors the remaining stages reuse.
        let mut streak = 0;
        let mut converged: Option<usize> = None;
        let mut factorized = 0;
        for j in (0..nh).rev() {
            if j == 0 {
                factorized += 1;
                acc += self.first_stage();
            } else if let Some(src) = converged {
                acc += self.reused_stage(j, src);
                if !(acc.is_finite() && self.l_vec.iter().all(|v| v.is_finite())) {
                    return Err(StageError::NonFinite);
                }
                if j == self.head {
                    self.keep_cost_to_go();
                }
                continue;
            } else {
                factorized += 1;
                acc += self.full_stage(j, &mut streak, &mut converged);
                if j == self.head {
                    self.keep_cost_to_go();
                }
            }
            // [R_vv R_vz ρ] of this stage (in vrows).
            let dst = &self.vrows[j * nu * cols..(j + 1) * nu * cols];
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
                factorized_stages: factorized,
            });
        }
        self.forward_pass();
        if !self.sol.iter().all(|v| v.is_finite()) {
            return Err(StageError::NonFinite);
        }
        Ok(StageInfo {
            residual_sq: acc,
            r_diag_ratio: dmax / dmin,
            r_max: dmax,
            factorized_stages: factorized,
        })
    }

    /// Sizes the constraint head: the first `nc` stages (`1 ≤ nc ≤ nh`) can
    /// be condensed by [`StageLq::condense_head`] after each solve. Allocates.
    pub fn set_head(&mut self, nc: usize) {
        let nc = nc.clamp(1, self.nh.max(1));
        let (nu, nz) = (self.nu, self.nz);
        self.head = nc;
        self.kept_l = vec![0.0; nz * nz];
        self.kept_lvec = vec![0.0; nz];
        self.zs = vec![0.0; nz * nc * nu];
        self.zs_next = vec![0.0; nz * nc * nu];
        self.za = vec![0.0; nz];
        self.za_next = vec![0.0; nz];
    }

    /// Rows and columns of the condensed head problem (`m`, `p`).
    pub fn head_dims(nu: usize, nz: usize, nq: usize, nc: usize) -> (usize, usize) {
        (nc * nu + (nc - 1) * nq + nz, nc * nu)
    }

    fn keep_cost_to_go(&mut self) {
        if self.kept_l.len() == self.l_mat.len() {
            self.kept_l.copy_from_slice(&self.l_mat);
            self.kept_lvec.copy_from_slice(&self.l_vec);
        }
    }

    /// After a solve: the least-squares problem of the first `nc` inputs
    /// with the rest of the horizon optimized out, written into `a` (m × p,
    /// column-major, `(m, p)` = [`StageLq::head_dims`]) and `b`:
    ///
    /// ```text
    /// min Σ_{j<nc} ‖R v_j‖² + Σ_{1≤j<nc} ‖D (S z_j − r_j)‖² + ‖L_nc z_nc − l_nc‖²
    /// ```
    ///
    /// (the cost-to-go from stage `nc` is the recursion's own factor), with
    /// `z_j` eliminated. Its unknowns are laid out as the dense system's:
    /// block `nc − 1 − j` is `v_j`. Its minimizer is the structured
    /// solution's `v_0 … v_{nc−1}`; with constraints on those inputs only,
    /// it is the whole constrained problem. Allocation-free.
    pub fn condense_head(&mut self, a: &mut [f64], b: &mut [f64]) {
        let (nu, nz, nq, nc) = (self.nu, self.nz, self.nq, self.head);
        if nc == 0 {
            return;
        }
        let (m, p) = Self::head_dims(nu, nz, nq, nc);
        if a.len() < m * p || b.len() < m {
            return;
        }
        a[..m * p].fill(0.0);
        b[..m].fill(0.0);
        let col = |j: usize, i: usize| (nc - 1 - j) * nu + i;
        for j in 0..nc {
            for i in 0..nu {
                a[col(j, i) * m + j * nu + i] = self.rd[i];
            }
        }
        self.zs.fill(0.0);
        self.za.copy_from_slice(&self.z0);
        for j in 0..nc {
            // z_{j+1} = A z_j + B v_j + c_j.
            self.zs_next.fill(0.0);
            for (out, zc) in self
                .zs_next
                .chunks_exact_mut(nz)
                .zip(self.zs.chunks_exact(nz))
            {
                accumulate_rows(out, zc, &self.a, nz, 0);
            }
            for i in 0..nu {
                let c = col(j, i);
                self.zs_next[c * nz..(c + 1) * nz].copy_from_slice(&self.b[i * nz..(i + 1) * nz]);
            }
            if self.c_rows == 0 {
                self.za_next.fill(0.0);
            } else {
                self.za_next.copy_from_slice(&self.c[j * nz..(j + 1) * nz]);
            }
            accumulate_rows(&mut self.za_next, &self.za, &self.a, nz, 0);
            std::mem::swap(&mut self.zs, &mut self.zs_next);
            std::mem::swap(&mut self.za, &mut self.za_next);
            let t = j + 1;
            if t < nc {
                // D (S z_t − r_t): r_t is target block t − 1.
                let base = nc * nu + (t - 1) * nq;
                for i in 0..nq {
                    let q = self.qd[i];
                    for c in 0..p {
                        a[c * m + base + i] = q * self.zs[c * nz + i];
                    }
                    b[base + i] = q * (self.r[(t - 1) * nq + i] - self.za[i]);
                }
            } else {
                // ‖L z_nc − l‖, L upper triangular (row-major).
                let base = nc * nu + (nc - 1) * nq;
                for i in 0..nz {
                    let lrow = &self.kept_l[i * nz + i..(i + 1) * nz];
                    for c in 0..p {
                        a[c * m + base + i] = dot(lrow, &self.zs[c * nz + i..(c + 1) * nz]);
                    }
                    b[base + i] = self.kept_lvec[i] - dot(lrow, &self.za[i..]);
                }
            }
        }
    }

    /// Stage `j ≥ 1` factorized in full: the stacked matrix, its Householder
    /// QR, `L_j`, `l_j`, `[R_vv R_vz ρ]` into `vrows`; counts the stages that
    /// left `L` unchanged (`streak`) and, when a stage repeats the previous
    /// one, sets `converged` and the map `M`. Returns `‖e_j‖²`.
    #[inline(always)]
    fn full_stage(&mut self, j: usize, streak: &mut usize, converged: &mut Option<usize>) -> f64 {
        let (nu, nz, nq) = (self.nu, self.nz, self.nq);
        let cols = nu + nz + 1;
        let (cs, ms) = (self.cs, self.ms);
        let rhs = nu + nz;
        let top = nu + nq;
        // One stage after an unchanged L, this stage probably repeats
        // it: carry the unit vectors of the right-hand side's inputs
        // through its reflections (columns cs.., the map M).
        let extend = self.reuse_converged && *streak >= 1 && j > 1;
        let width = if extend { ms } else { cs };
        let active = self.stack_stage(j, extend);
        let m = &mut self.m;
        // Householder on the columns with a diagonal pivot row.
        for k in 0..top {
            householder_rows(
                m,
                (ms, width),
                k,
                (k, top, top + active),
                &mut self.hv,
                &mut self.hw,
            );
        }
        // The remaining z columns: pivot k is dense row k − top, at row k
        // (nothing below it to annihilate from row top + active on).
        for k in (top..nu + nz).take_while(|k| k + 1 < top + active) {
            householder_rows(
                m,
                (ms, width),
                k,
                (k, k + 1, top + active),
                &mut self.hv,
                &mut self.hw,
            );
        }
        self.take_factor(j, extend, streak, converged);
        // Rows below the pivots: residual only.
        let mut acc = 0.0;
        for row in nu + nz..top + nz {
            let e = self.m[row * ms + rhs];
            acc += e * e;
        }
        // Keep [R_vv R_vz ρ] of this stage.
        let dst = &mut self.vrows[j * nu * cols..(j + 1) * nu * cols];
        for (d, row) in dst.chunks_exact_mut(cols).zip(self.m.chunks_exact(ms)) {
            d.copy_from_slice(&row[..cols]);
        }
        acc
    }

    /// The stacked matrix of stage `j ≥ 1` into `m`: the diagonal rows
    /// `[R_d; Q_d | Q_d r_j]`, the dense rows
    /// `Σ_{k ≥ i} L[i,k] [B A | −c_j][k]` with `l_{j+1}`, and with `extend`
    /// the unit columns that carry the map `M`. Returns how many dense rows
    /// are non-zero (at the last stage `L_N = [D S; 0]`: its first `nq`).
    #[inline(always)]
    fn stack_stage(&mut self, j: usize, extend: bool) -> usize {
        let (nu, nz, nq) = (self.nu, self.nz, self.nq);
        let (cs, ms) = (self.cs, self.ms);
        let rhs = nu + nz;
        // Rows of the diagonal part.
        let top = nu + nq;
        let m = &mut self.m;
        m[..top * ms].fill(0.0);
        for i in 0..nu {
            m[i * ms + i] = self.rd[i];
        }
        for i in 0..nq {
            let q = self.qd[i];
            let row = &mut m[(nu + i) * ms..(nu + i + 1) * ms];
            row[nu + i] = q;
            row[rhs] = q * self.r[(j - 1) * nq + i];
        }
        // Dense rows: row i = Σ_{k ≥ i} L[i,k] [B A | −c_j][k] and l_{j+1}.
        // At the last stage L_N = [D S; 0]: only its first nq rows are
        // non-zero, the reflections skip the others.
        let active = if j + 1 == self.nh && !extend {
            nq.min(nz)
        } else {
            nz
        };
        let cj = &self.c[j * nz..(j + 1) * nz];
        for (i, (row, lrow)) in m[top * ms..(top + nz) * ms]
            .chunks_exact_mut(ms)
            .zip(self.l_mat.chunks_exact(nz))
            .enumerate()
        {
            row.fill(0.0);
            if i >= active {
                continue;
            }
            let li = &lrow[i..];
            accumulate_rows(&mut row[..cs], li, &self.ba[i * cs..], cs, 0);
            row[rhs] = if i >= self.c_rows {
                self.l_vec[i]
            } else {
                let k = self.c_rows;
                self.l_vec[i] - dot(&lrow[i..k], &cj[i..k])
            };
        }
        if extend {
            // Input i of the right-hand side is row nu + i.
            for i in 0..nq + nz {
                m[(nu + i) * ms + cs + i] = 1.0;
            }
        }
        active
    }

    /// After stage `j`'s reflections: `L_j` and `l_j` from the triangular
    /// rows, the streak of stages that left `L` unchanged (to
    /// [`CONVERGED_RTOL`]), and with `extend` and a repeat, the map `M`
    /// (`converged = Some(j)`).
    #[inline(always)]
    fn take_factor(
        &mut self,
        j: usize,
        extend: bool,
        streak: &mut usize,
        converged: &mut Option<usize>,
    ) {
        let (nu, nz, ld) = (self.nu, self.nz, self.ld);
        let (cs, ms) = (self.cs, self.ms);
        let rhs = nu + nz;
        let m = &self.m;
        // L_j: row c is row nu + c from column nu + c on; how much it
        // moved from L_{j+1}.
        let (mut change, mut size) = (0.0f64, 0.0f64);
        for (c, lrow) in self.l_mat.chunks_exact_mut(nz).enumerate() {
            let row = &m[(nu + c) * ms..(nu + c + 1) * ms];
            lrow[..c].fill(0.0);
            for (old, new) in lrow[c..].iter_mut().zip(&row[nu + c..rhs]) {
                change = change.max((*old - new).abs());
                size = size.max(new.abs());
                *old = *new;
            }
            self.l_vec[c] = row[rhs];
        }
        *streak = if change <= CONVERGED_RTOL * size {
            *streak + 1
        } else {
            0
        };
        if extend && *streak >= 2 {
            // M (column-major, stride lds) from the carried columns.
            let lds = self.bvec.len();
            for (i, col) in self.mmap.chunks_exact_mut(lds).enumerate() {
                for (r, o) in col[..ld].iter_mut().enumerate() {
                    *o = m[r * ms + cs + i];
                }
            }
            *converged = Some(j);
        }
    }

    /// Stage 0, where `z_0` is known: the least-squares problem in `v_0`
    /// alone, `min ‖R v‖² + ‖L_1 B v − (l_1 − L_1 (A z_0 + c_0))‖²`, by the
    /// Householder QR of `[R; L_1 B]` with that right-hand side (columns
    /// `0..nu` and `nu` of the stacked matrix, 8-wide blocks). Stores
    /// `[R_vv 0 ρ_0]` (the `z_0` term is in `ρ_0`) and returns `‖e_0‖²`.
    #[inline(always)]
    fn first_stage(&mut self) -> f64 {
        let (nu, nz) = (self.nu, self.nz);
        let cols = nu + nz + 1;
        let (cs, ms) = (self.cs, self.ms);
        // With the gain: the columns L_1 A (R_vz after the reflections) right
        // of the right-hand side.
        let gz = if self.gain.is_empty() { 0 } else { nz };
        let width = (nu + 1 + gz).next_multiple_of(8);
        // t = A z_0 + c_0 (z_next as work).
        if self.c_rows == 0 {
            self.z_next.fill(0.0);
        } else {
            self.z_next.copy_from_slice(&self.c[..nz]);
        }
        accumulate_rows(&mut self.z_next, &self.z0, &self.a, nz, 0);
        let m = &mut self.m;
        for (i, row) in m[..(nu + nz) * ms].chunks_exact_mut(ms).enumerate() {
            row[..width].fill(0.0);
            if i < nu {
                row[i] = self.rd[i];
            }
        }
        for (i, (row, lrow)) in m[nu * ms..(nu + nz) * ms]
            .chunks_exact_mut(ms)
            .zip(self.l_mat.chunks_exact(nz))
            .enumerate()
        {
            let li = &lrow[i..];
            // [B A] rows hold B in their first nu columns.
            let pw = if gz == 0 { width } else { cs };
            let prod = &mut self.hw[..pw];
            prod.fill(0.0);
            accumulate_rows(prod, li, &self.ba[i * cs..], cs, 0);
            row[..nu].copy_from_slice(&prod[..nu]);
            row[nu] = self.l_vec[i] - dot(li, &self.z_next[i..]);
            row[nu + 1..nu + 1 + gz].copy_from_slice(&prod[nu..nu + gz]);
        }
        for k in 0..nu {
            householder_rows(
                m,
                (ms, width),
                k,
                (k, nu, nu + nz),
                &mut self.hv,
                &mut self.hw,
            );
        }
        let acc: f64 = m[nu * ms..(nu + nz) * ms]
            .chunks_exact(ms)
            .map(|row| row[nu] * row[nu])
            .sum();
        let dst = &mut self.vrows[..nu * cols];
        for (d, row) in dst.chunks_exact_mut(cols).zip(m.chunks_exact(ms)) {
            d[..nu].copy_from_slice(&row[..nu]);
            d[nu..nu + nz].fill(0.0);
            d[nu + nz] = row[nu];
        }
        if gz > 0 {
            gain_from_rows(&mut self.gain, &self.m[..nu * ms], ms, nu, nz);
        }
        acc
    }

    /// `v_j = R_vv⁻¹(ρ_j − R_vz z_j)`, `z_{j+1} = A z_j + B v_j + c_j` from
    /// `z_0`, into `sol`.
    #[inline(always)]
    fn forward_pass(&mut self) {
        let (nu, nz, nh) = (self.nu, self.nz, self.nh);
        let cols = nu + nz + 1;
        let rhs = nu + nz;
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
                if self.c_rows == 0 {
                    self.z_next.fill(0.0);
                } else {
                    self.z_next.copy_from_slice(&self.c[j * nz..(j + 1) * nz]);
                }
                // Column-major A, B: sums of scaled columns in registers.
                accumulate_rows(&mut self.z_next, &self.z, &self.a, nz, 0);
                accumulate_rows(&mut self.z_next, v, &self.b, nz, 0);
                std::mem::swap(&mut self.z, &mut self.z_next);
            }
        }
    }

    /// Stage `j ≥ 1` with the factorization of the converged stage `src`
    /// (its map in `mmap`, its `[R_vv R_vz]` in `vrows`): forms the stage's
    /// right-hand side inputs, multiplies them by `M`, updates `l` and
    /// stores `ρ_j`. Returns `‖e_j‖²`.
    #[inline(always)]
    fn reused_stage(&mut self, j: usize, src: usize) -> f64 {
        let (nu, nz, nq, ld) = (self.nu, self.nz, self.nq, self.ld);
        let cols = nu + nz + 1;
        let rhs = nu + nz;
        let (dr, lc) = self.bin.split_at_mut(nq);
        for ((o, q), r) in dr.iter_mut().zip(&self.qd).zip(&self.r[(j - 1) * nq..]) {
            *o = q * r;
        }
        let cj = &self.c[j * nz..(j + 1) * nz];
        for (i, (o, lrow)) in lc.iter_mut().zip(self.l_mat.chunks_exact(nz)).enumerate() {
            *o = if i >= self.c_rows {
                self.l_vec[i]
            } else {
                let k = self.c_rows;
                self.l_vec[i] - dot(&lrow[i..k], &cj[i..k])
            };
        }
        let out = &mut self.bvec;
        out.fill(0.0);
        // M·input: the same kernel as a sum of scaled rows (columns of M).
        let lds = out.len();
        accumulate_rows(out, &self.bin, &self.mmap, lds, 0);
        self.l_vec.copy_from_slice(&out[nu..nu + nz]);
        let e: f64 = out[nu + nz..ld].iter().map(|x| x * x).sum();
        let (done, rest) = self.vrows.split_at_mut(src * nu * cols);
        let dst = &mut done[j * nu * cols..(j + 1) * nu * cols];
        dst.copy_from_slice(&rest[..nu * cols]);
        for (i, row) in dst.chunks_exact_mut(cols).enumerate() {
            row[rhs] = out[i];
        }
        e
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

/// `K = −R_vv⁻¹ G` (nu × nz, row-major, into `k`) from the first stage's
/// reflected rows `m` (row stride `ms`): `R_vv` (upper triangular) in
/// columns `0..nu`, `G = R_vz` in columns `nu + 1..nu + 1 + nz`.
fn gain_from_rows(k: &mut [f64], m: &[f64], ms: usize, nu: usize, nz: usize) {
    for i in (0..nu).rev() {
        let (done, rest) = k.split_at_mut((i + 1) * nz);
        let ki = &mut done[i * nz..];
        let row = &m[i * ms..(i + 1) * ms];
        for (kc, g) in ki.iter_mut().zip(&row[nu + 1..nu + 1 + nz]) {
            *kc = -g;
        }
        for (r, kr) in row[i + 1..nu].iter().zip(rest.chunks_exact(nz)) {
            for (kc, x) in ki.iter_mut().zip(kr) {
                *kc -= r * x;
            }
        }
        let d = row[i];
        for kc in ki.iter_mut() {
            *kc /= d;
        }
    }
}

/// One Householder reflection of the stacked matrix `m` (row-major, row
/// stride `ms`; columns up to `width`, a multiple of 8, take part):
/// annihilates column `k` in rows `lo..hi` against the pivot row `p`
/// (`p < lo`; every other row is zero in column `k` by structure), and
/// applies it to the columns right of `k` by contiguous row operations.
/// Leaves `β` at `(p, k)` and the reflector's vector (scaled to a unit pivot
/// entry) in rows `lo..hi` of column `k`. `hv` (≥ hi − lo) and `hw`
/// (≥ width) are work.
///
/// The update runs on whole 8-wide blocks from the block holding column
/// `k + 1`: the entries of `w` left of `k + 1` are set to zero, which leaves
/// those columns exactly unchanged.
#[inline(always)]
fn householder_rows(
    m: &mut [f64],
    (ms, width): (usize, usize),
    k: usize,
    (p, lo, hi): (usize, usize, usize),
    hv: &mut [f64],
    hw: &mut [f64],
) {
    let len = hi - lo;
    let v = &mut hv[..len];
    for (x, row) in v.iter_mut().zip(m[lo * ms..hi * ms].chunks_exact(ms)) {
        *x = row[k];
    }
    let sigma = dot(v, v);
    if sigma == 0.0 {
        return;
    }
    let alpha = m[p * ms + k];
    let norm = (alpha * alpha + sigma).sqrt();
    let beta = if alpha >= 0.0 { -norm } else { norm };
    let scale = 1.0 / (alpha - beta);
    for x in v.iter_mut() {
        *x *= scale;
    }
    let tau = (beta - alpha) / beta;
    let c0 = (k + 1) / 8 * 8;
    let w = &mut hw[..width - c0];
    let (upper, lower) = m.split_at_mut(lo * ms);
    let prow = &mut upper[p * ms..(p + 1) * ms];
    // w = τ (M[p, c0..] + Σ v_i M[i, c0..]), zero left of column k + 1.
    w.copy_from_slice(&prow[c0..width]);
    let lower = &mut lower[..len * ms];
    accumulate_rows(w, v, lower, ms, c0);
    for o in w.iter_mut() {
        *o *= tau;
    }
    w[..k + 1 - c0].fill(0.0);
    prow[k] = beta;
    for (o, x) in prow[c0..width].iter_mut().zip(w.iter()) {
        *o -= x;
    }
    subtract_rank1(lower, ms, c0, v, w);
    for (vi, row) in v.iter().zip(lower.chunks_exact_mut(ms)) {
        row[k] = *vi;
    }
}

/// `m[i·cols + off + c] −= v[i]·w[c]` for every row `i < v.len()` and
/// `c < w.len()` (a multiple of 8): blocks of 32 or 8 columns of `w` held in
/// registers across the rows.
#[inline(always)]
fn subtract_rank1(m: &mut [f64], cols: usize, off: usize, v: &[f64], w: &[f64]) {
    let len = w.len();
    let mut c0 = 0;
    while c0 + 32 <= len {
        subtract_block::<32>(m, cols, off + c0, v, &w[c0..c0 + 32]);
        c0 += 32;
    }
    while c0 + 8 <= len {
        subtract_block::<8>(m, cols, off + c0, v, &w[c0..c0 + 8]);
        c0 += 8;
    }
    debug_assert_eq!(c0, len);
}

#[inline(always)]
fn subtract_block<const W: usize>(m: &mut [f64], cols: usize, off: usize, v: &[f64], w: &[f64]) {
    let mut wb = [0.0f64; W];
    wb.copy_from_slice(&w[..W]);
    for (i, &vi) in v.iter().enumerate() {
        let Some(seg) = m
            .get_mut(i * cols + off..)
            .and_then(|r| r.first_chunk_mut::<W>())
        else {
            return;
        };
        for l in 0..W {
            seg[l] -= vi * wb[l];
        }
    }
}

/// `w[c] += Σ_i v[i]·m[i·cols + off + c]` for `c < w.len()`: a sum of
/// scaled rows, up to 32 columns at a time in registers (independent
/// accumulation chains; no round trip of `w` through memory per row).
#[inline(always)]
fn accumulate_rows(w: &mut [f64], v: &[f64], m: &[f64], cols: usize, off: usize) {
    let len = w.len();
    let mut c0 = 0;
    while c0 + 32 <= len {
        accumulate_block::<32>(&mut w[c0..c0 + 32], v, m, cols, off + c0);
        c0 += 32;
    }
    if c0 + 16 <= len {
        accumulate_block::<16>(&mut w[c0..c0 + 16], v, m, cols, off + c0);
        c0 += 16;
    }
    while c0 + 8 <= len {
        accumulate_block::<8>(&mut w[c0..c0 + 8], v, m, cols, off + c0);
        c0 += 8;
    }
    if c0 < len {
        let rest = len - c0;
        let mut acc = [0.0f64; 8];
        acc[..rest].copy_from_slice(&w[c0..]);
        for (&vi, row) in v.iter().zip(m.chunks(cols)) {
            for (a, x) in acc[..rest].iter_mut().zip(&row[off + c0..off + len]) {
                *a += vi * x;
            }
        }
        w[c0..].copy_from_slice(&acc[..rest]);
    }
}

/// `w[c] += Σ_i v[i]·m[i·cols + off + c]` for a block of `W` columns.
#[inline(always)]
fn accumulate_block<const W: usize>(w: &mut [f64], v: &[f64], m: &[f64], cols: usize, off: usize) {
    let mut acc = [0.0f64; W];
    acc.copy_from_slice(&w[..W]);
    for (i, &vi) in v.iter().enumerate() {
        let Some(seg) = m.get(i * cols + off..).and_then(|r| r.first_chunk::<W>()) else {
            break;
        };
        for l in 0..W {
            acc[l] += vi * seg[l];
        }
    }
    w[..W].copy_from_slice(&acc);
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

    use crate::linalg::random::symmetric as rng;

    fn random_problem(nu: usize, nz: usize, nq: usize, nh: usize, seed: &mut u64) -> StageLq {
        let mut st = StageLq::new(nu, nz, nq, nh);
        for v in st.a.iter_mut().chain(&mut st.b).chain(&mut st.r) {
            *v = rng(seed);
        }
        for v in st.c.iter_mut().chain(&mut st.z0) {
            *v = rng(seed);
        }
        st.c_rows = nz;
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

    /// The first stage's gain is `∂v_0/∂z_0` of the brute-force minimizer
    /// (the solution is linear in `z_0`: compared column by column against
    /// `(v_0(z_0 + e_c) − v_0(z_0))`), and enabling it leaves the solution
    /// bit-identical, with and without the reuse of converged stages.
    #[test]
    fn first_stage_gain_is_the_derivative_of_the_first_input() {
        let mut seed = 11;
        for (nu, nz, nq, nh) in [(1, 1, 1, 1), (2, 3, 2, 4), (3, 5, 2, 6), (2, 8, 4, 30)] {
            let plain = random_problem(nu, nz, nq, nh, &mut seed);
            for reuse in [false, true] {
                let mut a = plain.clone();
                a.reuse_converged = reuse;
                let mut g = a.clone();
                g.enable_gain();
                a.solve_portable().unwrap();
                g.solve_portable().unwrap();
                assert_eq!(a.solution(), g.solution(), "solution changed");
                let k = g.first_stage_gain().to_vec();
                assert_eq!(k.len(), nu * nz);
                // Brute force on the short horizons; the solver itself (whose
                // solution is checked against brute force above) on the
                // long one, where the SVD of A^30 loses digits.
                let first = |p: &StageLq| {
                    if nh <= 6 {
                        brute(p).0
                    } else {
                        let mut p = p.clone();
                        p.solve_portable().unwrap();
                        p.solution().to_vec()
                    }
                };
                let v0 = first(&plain);
                for c in 0..nz {
                    let mut p = plain.clone();
                    p.z0[c] += 1.0;
                    let v1 = first(&p);
                    for i in 0..nu {
                        let want = v1[i] - v0[i];
                        let got = k[i * nz + c];
                        let scale = want.abs().max(1e-3);
                        assert!(
                            (got - want).abs() <= 1e-8 * scale,
                            "{nu} {nz} {i} {c}: {got} vs {want}"
                        );
                    }
                }
            }
        }
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

    /// A long horizon on a contracting system: the recursion converges, the
    /// earlier stages reuse the converged factorization, and the solution
    /// equals both the stage-by-stage factorization and brute force.
    #[test]
    fn converged_stages_reuse_the_factorization_exactly() {
        let mut seed = 17;
        for (nu, nz, nq, nh, c_zero) in [
            (2, 4, 2, 60, false),
            (3, 6, 3, 80, true),
            (6, 24, 12, 40, false),
        ] {
            let mut st = random_problem(nu, nz, nq, nh, &mut seed);
            // Contracting A (spectral radius ≤ 0.6): fast convergence.
            let a = DMatrix::from_column_slice(nz, nz, &st.a);
            let norm = a.norm();
            for v in st.a.iter_mut() {
                *v *= 0.6 / norm;
            }
            if c_zero {
                st.c.fill(0.0);
                st.c_rows = 0;
            }
            let mut full = st.clone();
            full.reuse_converged = false;
            let reused = st.solve().unwrap();
            let every = full.solve().unwrap();
            assert_eq!(every.factorized_stages, nh);
            assert!(
                reused.factorized_stages < nh / 2,
                "{nu} {nz} {nh}: {} stages factorized",
                reused.factorized_stages
            );
            let scale = full.solution().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let diff = st
                .solution()
                .iter()
                .zip(full.solution())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                diff <= 1e-12 * scale,
                "reuse vs full: {diff:e} (scale {scale:e})"
            );
            assert!((reused.residual_sq - every.residual_sq).abs() <= 1e-12 * every.residual_sq);
            assert!((reused.r_diag_ratio / every.r_diag_ratio - 1.0).abs() <= 1e-12);
            if nh <= 60 {
                let (x, _) = brute(&st);
                let diff = st
                    .solution()
                    .iter()
                    .zip(&x)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(diff <= 1e-9 * scale, "reuse vs brute force: {diff:e}");
            }
        }
    }

    /// The condensed head (first nc inputs, the rest optimized out by the
    /// recursion's cost-to-go) has the structured solution's first inputs as
    /// its least-squares minimizer, with and without converged-stage reuse.
    #[test]
    fn the_condensed_head_has_the_same_minimizer() {
        let mut seed = 29;
        for (nu, nz, nq, nh, nc, contract) in [
            (2, 4, 2, 8, 3, false),
            (3, 6, 3, 6, 6, false),
            (6, 24, 12, 40, 5, true),
        ] {
            let mut st = random_problem(nu, nz, nq, nh, &mut seed);
            if contract {
                let norm = DMatrix::from_column_slice(nz, nz, &st.a).norm();
                for v in st.a.iter_mut() {
                    *v *= 0.6 / norm;
                }
            }
            st.set_head(nc);
            st.solve().unwrap();
            let (m, p) = StageLq::head_dims(nu, nz, nq, nc);
            let (mut a, mut b) = (vec![0.0; m * p], vec![0.0; m]);
            st.condense_head(&mut a, &mut b);
            let am = DMatrix::from_column_slice(m, p, &a);
            let x = am
                .clone()
                .svd(true, true)
                .solve(&DVector::from_column_slice(&b), 1e-14)
                .unwrap();
            let scale = st.solution().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for j in 0..nc {
                for i in 0..nu {
                    let got = x[(nc - 1 - j) * nu + i];
                    let want = st.solution()[j * nu + i];
                    assert!(
                        (got - want).abs() <= 1e-9 * scale,
                        "{nu} {nz} {nh} {nc}: v_{j}[{i}] {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn avx2_build_equals_portable_build() {
        let Some(token) = Avx2Fma::detect() else {
            eprintln!("SKIPPED avx2_build_equals_portable_build: this CPU has no AVX2+FMA");
            return;
        };
        let mut seed = 9;
        for (nu, nz, nq, nh) in [
            (6, 24, 12, 10),
            (2, 3, 2, 4),
            (6, 18, 12, 7),
            (6, 24, 12, 40),
        ] {
            let mut st = random_problem(nu, nz, nq, nh, &mut seed);
            let mut st2 = st.clone();
            let a = st.solve_portable().unwrap();
            let b = st2.solve_avx2(token).unwrap();
            assert_eq!(a, b);
            assert_eq!(st.solution(), st2.solution());
        }
    }
}
