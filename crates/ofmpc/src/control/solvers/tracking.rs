//! The incremental algorithms' two tracking row groups, halved by a constant
//! orthogonal transformation (dense solver).
//!
//! Both incremental algorithms weight the same predicted motion twice:
//! `Q_YW (G2 ΔU …)` or `Q_YW ((G2 + G3) ΔU …)` and `Q_ΔY (G1 ΔU …)`
//! (Eq. (37), (39)). The `G` are running sums of `G1` over block rows
//! (docs/guide/paper-notes.md, "Symbols"; prediction.rs):
//!
//! ```text
//! G2[j, l]      = Σ_{m ≤ j} G1[m, l]                 (S = S1, s(j, m) = 1)
//! G2[j, l] + G3[j, l] = Σ_{m ≤ j} (j − m + 1) G1[m, l]   (S = S1 + S3, s(j, m) = j − m + 1)
//! ```
//!
//! so `[Q_YW S G1; Q_ΔY G1]` is, for each output `i` (the weights are
//! diagonal and `S` acts on block rows only), the constant 2N×N matrix
//! `M_i = [q_yw,i S; q_Δy,i I_N]` times the N rows of `G1` that belong to
//! output `i`. A QL factorization `M_i = Q_i [L_i; 0]` (`Q_i` orthogonal 2N×2N,
//! `L_i` lower triangular N×N), computed once, turns those 2N rows into N:
//!
//! ```text
//! ‖M_i G1_i ΔU − b_i‖² = ‖L_i G1_i ΔU − c_i‖² + ‖d_i‖²,   [c_i; d_i] = Q_iᵀ b_i,
//! ```
//!
//! an orthogonal transformation of the rows of `𝒜` and `b`: the minimizer,
//! `J_min` (with `Σ ‖d_i‖²`) and `R1` are those of the paper's system, and
//! the condition number is untouched (no normal equations). `L_i` is *lower*
//! triangular so that `L_i G1_i` keeps `G1`'s block lower-triangular profile
//! ([`crate::control::mpc::core`]'s permuted layout then has 2 row groups per level
//! instead of 3: half the rows, about half the flops of the QR).

use nalgebra::DMatrix;

#[cfg(target_arch = "x86_64")]
use crate::control::solvers::simd::Avx2Fma;

/// The constant factors of the reduction for `n` outputs and horizon `N`,
/// and the per-step work buffer of the right-hand side.
#[derive(Debug, Clone)]
pub(crate) struct TrackingRows {
    n: usize,
    nh: usize,
    /// `diag(L_·[j][j'])` (zero for `j' > j`) as an n×n column-major block:
    /// the diagonal repeated in every column (`L_i[j][j']` at
    /// `(j·N + j')·n² + col·n + i`), so that a row-scaled block of `G1` is one
    /// elementwise product.
    lrep: Vec<f64>,
    /// The `G1` generator of the current step as N contiguous n×n blocks.
    gblk: Vec<f64>,
    /// One n×n block of `L G1` (joint counts without a fixed-size kernel).
    blks: Vec<f64>,
    /// Rows of `Q_iᵀ`: entry `(r, s)` at `(r·2N + s)·n + i`; rows `0..N` give
    /// `c_i`, rows `N..2N` give `d_i`.
    qt: Vec<f64>,
    /// The 2N·n right-hand side of the two tracking groups, filled by the
    /// controller: `[b_YW; b_ΔY]`, entry `(j, i)` of each group at `j·n + i`.
    pub b: Vec<f64>,
    /// `Q_iᵀ b_i` stacked like `b`.
    cd: Vec<f64>,
}

impl TrackingRows {
    /// The reduction for the first (`ramp = false`, `S = S1`) or the second
    /// (`ramp = true`, `S = S1 + S3`) algorithm with the diagonal square-root
    /// weights `q_yw`, `q_dy` (one per output) over `nh` block rows.
    pub(crate) fn new(q_yw: &[f64], q_dy: &[f64], nh: usize, ramp: bool) -> Self {
        let n = q_yw.len();
        let mut l = vec![0.0; nh * nh * n];
        let mut qt = vec![0.0; 4 * nh * nh * n];
        for i in 0..n {
            // M_i with its columns reversed (column k is block column N−1−k),
            // augmented by I so that the QR's Q is square (2N×2N): the first N
            // columns of the factorization are those of M_i J alone.
            let mut aug = DMatrix::<f64>::zeros(2 * nh, 3 * nh);
            for j in 0..nh {
                for mm in 0..=j {
                    let s = if ramp { (j - mm + 1) as f64 } else { 1.0 };
                    aug[(j, nh - 1 - mm)] = q_yw[i] * s;
                }
                aug[(nh + j, nh - 1 - j)] = q_dy[i];
            }
            for r in 0..2 * nh {
                aug[(r, nh + r)] = 1.0;
            }
            let qr = aug.qr();
            let (q, r) = (qr.q(), qr.r());
            // M_i J = Q [R_top; 0]  ⇒  M_i = Q diag(J, I) [J R_top J; 0].
            for j in 0..nh {
                for jp in 0..=j {
                    l[(j * nh + jp) * n + i] = r[(nh - 1 - j, nh - 1 - jp)];
                }
            }
            for row in 0..2 * nh {
                let src = if row < nh { nh - 1 - row } else { row };
                for s in 0..2 * nh {
                    qt[(row * 2 * nh + s) * n + i] = q[(s, src)];
                }
            }
        }
        let lrep = (0..nh * nh)
            .flat_map(|jj| {
                let row = l[jj * n..(jj + 1) * n].to_vec();
                (0..n).flat_map(move |_| row.clone())
            })
            .collect();
        Self {
            n,
            nh,
            lrep,
            gblk: vec![0.0; nh * n * n],
            blks: vec![0.0; n * n],
            qt,
            b: vec![0.0; 2 * nh * n],
            cd: vec![0.0; 2 * nh * n],
        }
    }

    /// The `f64` entries a reduction for `n` outputs and horizon `nh` holds
    /// (`None` on overflow), for the callers' size limits.
    pub(crate) fn entries(n: usize, nh: usize) -> Option<usize> {
        // lrep: N²n², qt: 4N²n, gblk: Nn², blks: n², b and cd: 4Nn.
        let nn = nh.checked_mul(nh)?;
        nn.checked_mul(n)?
            .checked_mul(n + 4)?
            .checked_add(nh.checked_mul(n)?.checked_mul(n + 4)?)?
            .checked_add(n.checked_mul(n)?)
    }

    /// `L_i[j][j']` for all outputs `i` (n entries: column 0 of the
    /// repeated block).
    #[cfg(test)]
    pub(crate) fn l_row(&self, j: usize, jp: usize) -> &[f64] {
        let o = (j * self.nh + jp) * self.n * self.n;
        &self.lrep[o..o + self.n]
    }

    /// Takes the `G1` generator of this step (N·n × n column-major, block `d`
    /// = `C A^d B`, [`crate::control::mpc::prediction::Predictions::g1_gen`]).
    fn load_g1(&mut self, g1_gen: &[f64]) {
        let (n, rows) = (self.n, self.nh * self.n);
        for (d, blk) in self.gblk.chunks_exact_mut(n * n).enumerate() {
            for (col, dst) in blk.chunks_exact_mut(n).enumerate() {
                dst.copy_from_slice(&g1_gen[col * rows + d * n..col * rows + d * n + n]);
            }
        }
    }

    /// Writes the reduced rows `L G1` and the `Q_ΔU` rows (diagonal `w_du`)
    /// into the m×p column-major `a` in the permuted layout of
    /// [`crate::control::mpc::core`]: level `t` (block row `j = N−1−t`, 0-based) holds `n`
    /// rows of `L G1` then `n` rows of `Q_ΔU`; column block `t'` is unknown
    /// `Δu_{k+N−1−t'}`; only levels `t ≤ t'` (the profile) are written.
    pub(crate) fn write_rows(&mut self, g1_gen: &[f64], w_du: &[f64], a: &mut [f64], m: usize) {
        self.load_g1(g1_gen);
        #[cfg(target_arch = "x86_64")]
        if let Some(token) = Avx2Fma::detect() {
            return self.write_rows_avx2(token, w_du, a, m);
        }
        self.write_rows_generic::<false>(w_du, a, m);
    }

    #[cfg(target_arch = "x86_64")]
    fn write_rows_avx2(&mut self, _token: Avx2Fma, w_du: &[f64], a: &mut [f64], m: usize) {
        #[target_feature(enable = "avx2,fma")]
        unsafe fn inner(t: &mut TrackingRows, w_du: &[f64], a: &mut [f64], m: usize) {
            t.write_rows_generic::<true>(w_du, a, m);
        }
        // SAFETY: the token proves that the CPU supports AVX2 and FMA, the
        // only requirement of `inner` (its body is safe code).
        unsafe { inner(self, w_du, a, m) }
    }

    /// [`TrackingRows::write_rows`] after [`TrackingRows::load_g1`]; block
    /// `(j, l)` of `L G1` is `Σ_{l ≤ j' ≤ j} diag(L_·[j][j']) G1[j' − l]`:
    /// elementwise products of contiguous n×n blocks, summed in registers for
    /// n = 4…7 and stored straight into the columns.
    #[inline(always)]
    fn write_rows_generic<const FMA: bool>(&mut self, w_du: &[f64], a: &mut [f64], m: usize) {
        let (n, nh) = (self.n, self.nh);
        let nn = n * n;
        for tc in 0..nh {
            let l = nh - 1 - tc;
            let cols = &mut a[tc * n * m..(tc + 1) * n * m];
            // The column block's levels 0..=tc: zeros (the Q_ΔU rows) in one
            // contiguous fill per column, then the blocks of L G1, then the
            // diagonal Q_ΔU entries.
            for column in cols.chunks_exact_mut(m) {
                column[..2 * n * (tc + 1)].fill(0.0);
            }
            for tl in 0..=tc {
                let j = nh - 1 - tl;
                let len = (j - l + 1) * nn;
                let lbase = (j * nh + l) * nn;
                let (lr, g) = (&self.lrep[lbase..lbase + len], &self.gblk[..len]);
                let off = tl * 2 * n;
                match n {
                    6 => sum_products_into::<6, 36, FMA>(lr, g, cols, m, off),
                    5 => sum_products_into::<5, 25, FMA>(lr, g, cols, m, off),
                    7 => sum_products_into::<7, 49, FMA>(lr, g, cols, m, off),
                    4 => sum_products_into::<4, 16, FMA>(lr, g, cols, m, off),
                    _ => {
                        let out = &mut self.blks[..nn];
                        out.fill(0.0);
                        for (lr, g) in lr.chunks_exact(nn).zip(g.chunks_exact(nn)) {
                            for ((o, x), y) in out.iter_mut().zip(lr).zip(g) {
                                *o += x * y;
                            }
                        }
                        for (column, src) in cols.chunks_exact_mut(m).zip(out.chunks_exact(n)) {
                            column[off..off + n].copy_from_slice(src);
                        }
                    }
                }
            }
            for (col, column) in cols.chunks_exact_mut(m).enumerate() {
                column[2 * n * tc + n + col] = w_du[col];
            }
        }
    }

    /// Transforms [`TrackingRows::b`]: afterwards [`TrackingRows::c`] gives
    /// `c_i[j]`; returns `Σ_i ‖d_i‖²` (the part of `J_min` the reduced system
    /// no longer holds).
    pub(crate) fn transform_rhs(&mut self) -> f64 {
        let (n, w) = (self.n, 2 * self.nh);
        for (row, out) in self.cd.chunks_exact_mut(n).enumerate() {
            let q_row = &self.qt[row * w * n..(row + 1) * w * n];
            match n {
                6 => sum_products::<6, false>(q_row, &self.b, out),
                _ => {
                    out.fill(0.0);
                    for (q, b) in q_row.chunks_exact(n).zip(self.b.chunks_exact(n)) {
                        for ((o, q), b) in out.iter_mut().zip(q).zip(b) {
                            *o += q * b;
                        }
                    }
                }
            }
        }
        self.cd[self.nh * n..].iter().map(|d| d * d).sum()
    }

    /// `c_i[j]` for all outputs `i` (after [`TrackingRows::transform_rhs`]).
    #[inline]
    pub(crate) fn c(&self, j: usize) -> &[f64] {
        &self.cd[j * self.n..(j + 1) * self.n]
    }
}

/// [`sum_products`] for an `N × N` column-major block (`NN = N²`), its
/// column `c` stored at `cols[c·m + off..][..N]`.
#[inline(always)]
fn sum_products_into<const N: usize, const NN: usize, const FMA: bool>(
    lr: &[f64],
    g: &[f64],
    cols: &mut [f64],
    m: usize,
    off: usize,
) {
    let acc = block_sum::<NN, FMA>(lr, g);
    for (c, src) in acc.chunks_exact(N).enumerate() {
        if let Some(dst) = cols
            .get_mut(c * m + off..)
            .and_then(|d| d.first_chunk_mut::<N>())
        {
            for (d, v) in dst.iter_mut().zip(src) {
                *d = *v;
            }
        }
    }
}

/// `out[..NN] = Σ_k lr_k ⊙ g_k` over the consecutive `NN`-blocks of `lr` and
/// `g` ([`block_sum`]).
#[inline(always)]
fn sum_products<const NN: usize, const FMA: bool>(lr: &[f64], g: &[f64], out: &mut [f64]) {
    out[..NN].copy_from_slice(&block_sum::<NN, FMA>(lr, g));
}

/// `Σ_k lr_k ⊙ g_k` over the consecutive `NN`-blocks of `lr` and `g`; the
/// sum stays in registers (fixed size). `FMA`: fused multiply-adds (only
/// where the CPU has them: the AVX2+FMA build).
#[inline(always)]
fn block_sum<const NN: usize, const FMA: bool>(lr: &[f64], g: &[f64]) -> [f64; NN] {
    let mut acc = [0.0f64; NN];
    for (x, y) in lr.chunks_exact(NN).zip(g.chunks_exact(NN)) {
        let (x, y): (&[f64; NN], &[f64; NN]) = match (x.try_into(), y.try_into()) {
            (Ok(x), Ok(y)) => (x, y),
            _ => continue,
        };
        for k in 0..NN {
            acc[k] = if FMA {
                x[k].mul_add(y[k], acc[k])
            } else {
                acc[k] + x[k] * y[k]
            };
        }
    }
    acc
}

/// The `f64` entries the dense solver holds for `n` joints and horizon `nh`:
/// the system `[𝒜 | b]` (2·N·n rows) and, for the incremental algorithms,
/// the tracking rows' constant factors ([`TrackingRows::entries`]); `None`
/// on overflow. [`crate::control::MpcSettings::validate_for_dof`] checks the same number.
pub(crate) fn dense_entries(n: usize, nh: usize, incremental: bool) -> Option<usize> {
    let p = nh.checked_mul(n)?;
    let system = p.checked_mul(2)?.checked_mul(p + 1)?;
    let extra = if incremental {
        TrackingRows::entries(n, nh)?
    } else {
        0
    };
    system.checked_add(extra)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;

    /// `M_i` as defined in the module docs (natural column order).
    fn m_i(q_yw: f64, q_dy: f64, nh: usize, ramp: bool) -> DMatrix<f64> {
        DMatrix::from_fn(2 * nh, nh, |r, c| {
            if r < nh {
                if c <= r {
                    q_yw * if ramp { (r - c + 1) as f64 } else { 1.0 }
                } else {
                    0.0
                }
            } else if r - nh == c {
                q_dy
            } else {
                0.0
            }
        })
    }

    /// The reduced rows written by `write_rows` (both paths: the register-held
    /// sums for n = 4…7 and the general loop for n = 2 and 13) equal `L_i G1_i`
    /// computed directly, in the permuted layout, with the `Q_ΔU` rows on the
    /// diagonal.
    #[test]
    fn written_rows_are_l_times_g1_in_the_permuted_layout() {
        let mut seed = 3u64;
        let mut rnd = move || crate::linalg::random::centered(&mut seed);
        for (n, nh, ramp) in [
            (2, 4, true),
            (6, 10, true),
            (6, 3, false),
            (7, 5, true),
            (13, 3, false),
        ] {
            let q_yw: Vec<f64> = (0..n).map(|_| 1.0 + rnd()).collect();
            let q_dy: Vec<f64> = (0..n).map(|_| 0.5 + rnd()).collect();
            let w_du: Vec<f64> = (0..n).map(|_| 0.1 + rnd().abs()).collect();
            let mut t = TrackingRows::new(&q_yw, &q_dy, nh, ramp);
            let p = nh * n;
            // G1 generator: N·n × n column-major, block d rows d·n..(d+1)·n.
            let g1: Vec<f64> = (0..p * n).map(|_| rnd()).collect();
            let gen = |d: usize, i: usize, col: usize| g1[col * p + d * n + i];
            let m = 2 * p;
            let mut a = vec![f64::NAN; m * p];
            t.write_rows(&g1, &w_du, &mut a, m);
            for tc in 0..nh {
                let l = nh - 1 - tc;
                for col in 0..n {
                    let column = &a[(tc * n + col) * m..(tc * n + col + 1) * m];
                    for tl in 0..=tc {
                        let j = nh - 1 - tl;
                        for i in 0..n {
                            let want: f64 = (l..=j)
                                .map(|jp| t.l_row(j, jp)[i] * gen(jp - l, i, col))
                                .sum();
                            let got = column[tl * 2 * n + i];
                            assert!(
                                (got - want).abs() <= 1e-13 * (1.0 + want.abs()),
                                "n {n} N {nh}: ({tl}, {i}) x ({tc}, {col}): {got} vs {want}"
                            );
                            let du = column[tl * 2 * n + n + i];
                            let want_du = if tl == tc && i == col { w_du[col] } else { 0.0 };
                            assert_eq!(du, want_du);
                        }
                    }
                }
            }
        }
    }

    /// `Q_iᵀ M_i = [L_i; 0]` with `Q_i` orthogonal and `L_i` lower
    /// triangular, and the transformed right-hand side keeps the norm.
    #[test]
    fn is_an_orthogonal_ql_factorization() {
        let (n, nh) = (3, 7);
        let q_yw = [1.0, 0.3, 0.0];
        let q_dy = [0.5, 0.0, 2.0];
        for ramp in [false, true] {
            let mut t = TrackingRows::new(&q_yw, &q_dy, nh, ramp);
            for i in 0..n {
                let q = DMatrix::from_fn(2 * nh, 2 * nh, |r, s| t.qt[(r * 2 * nh + s) * n + i]);
                let eye = DMatrix::<f64>::identity(2 * nh, 2 * nh);
                assert!((&q * q.transpose() - &eye).norm() < 1e-13);
                let lm = DMatrix::from_fn(
                    2 * nh,
                    nh,
                    |r, c| {
                        if r < nh {
                            t.l_row(r, c)[i]
                        } else {
                            0.0
                        }
                    },
                );
                for r in 0..nh {
                    for c in r + 1..nh {
                        assert_eq!(t.l_row(r, c)[i], 0.0);
                    }
                }
                let m = m_i(q_yw[i], q_dy[i], nh, ramp);
                let err = (&q * &m - &lm).norm();
                assert!(err < 1e-12 * (1.0 + m.norm()), "ramp {ramp} i {i}: {err:e}");
            }
            // ‖b‖² = ‖c‖² + ‖d‖² output by output.
            for (k, b) in t.b.iter_mut().enumerate() {
                *b = ((k * 37 % 11) as f64 - 5.0) * 0.3;
            }
            let b0 = t.b.clone();
            let d2 = t.transform_rhs();
            let c2: f64 = (0..nh).flat_map(|j| t.c(j).to_vec()).map(|c| c * c).sum();
            let b2 = DVector::from_vec(b0).norm_squared();
            assert!((c2 + d2 - b2).abs() < 1e-12 * b2);
        }
    }
}
