//! Equations of predictions, Eq. (20)–(29), and the positional ones of the
//! usual controller (43).
//!
//! Blocks (j = 1..N block row, l = 1..N block column; see docs/guide/paper-notes.md, "Symbols"):
//!
//! ```text
//! F1[j] = C A^j                      G1[j,l] = C A^{j-l} B                      (l ≤ j)
//! F2[j] = Σ_{i=1}^{j} C A^i          G2[j,l] = Σ_{m=l}^{j} C A^{m-l} B          (l ≤ j)
//! F3[j] = Σ_{i=1}^{j-1} (j-i) C A^i  G3[j,l] = Σ_{m=l}^{j-1} (j-m) C A^{m-l} B  (l ≤ j-1)
//! F_I[j] = I,  F_II[j] = (j-1) I,    W_s[j] = Σ_{i=1}^{j-1} w_{k+i}
//! ```
//!
//! The `G` are block lower-triangular Toeplitz: block `(j, l)` depends only on
//! the lag `d = j − l`. They are stored as their generators (block `d` of
//! [`Predictions::g1_gen`] is `G1[l+d, l]`), with
//! `g2_d = g2_{d−1} + g1_d` and `g3_d = g3_{d−1} + g2_{d−1}`, `g3_0 = 0`;
//! likewise `F2[j] = F2[j−1] + F1[j]`, `F3[j] = F3[j−1] + F2[j−1]`.
//!
//! The positional model (16) of the usual controller predicts
//! `Y = F x_k + G U` with `F = F1` and `G = G1` (the paper reuses the names).

use nalgebra::DMatrix;

use crate::control::mpc::zoh::Zoh;
use crate::control::solvers::dense::gemm;

/// Prediction matrices for a model with `nx` states, `nu` inputs, `ny` outputs
/// and horizon `N`, in buffers sized once. Updating allocates nothing.
#[derive(Debug, Clone)]
pub struct Predictions {
    nx: usize,
    nu: usize,
    ny: usize,
    horizon: usize,
    f1: DMatrix<f64>,
    f2: DMatrix<f64>,
    f3: DMatrix<f64>,
    g1: DMatrix<f64>,
    g2: DMatrix<f64>,
    g3: DMatrix<f64>,
    /// nx×nu: A^d B
    apb: DMatrix<f64>,
    apb_next: DMatrix<f64>,
    /// n×n work for the structured update (K_i of C A^i = [I, K_i]).
    k: DMatrix<f64>,
    k_next: DMatrix<f64>,
}

impl Predictions {
    /// Buffers for `nx` states, `nu` inputs, `ny` outputs, horizon `horizon`.
    pub fn new(nx: usize, nu: usize, ny: usize, horizon: usize) -> Self {
        let rows = horizon * ny;
        let half = nx / 2;
        Self {
            nx,
            nu,
            ny,
            horizon,
            f1: DMatrix::zeros(rows, nx),
            f2: DMatrix::zeros(rows, nx),
            f3: DMatrix::zeros(rows, nx),
            g1: DMatrix::zeros(rows, nu),
            g2: DMatrix::zeros(rows, nu),
            g3: DMatrix::zeros(rows, nu),
            apb: DMatrix::zeros(nx, nu),
            apb_next: DMatrix::zeros(nx, nu),
            k: DMatrix::zeros(half, half),
            k_next: DMatrix::zeros(half, half),
        }
    }

    /// Horizon `N`.
    pub fn horizon(&self) -> usize {
        self.horizon
    }

    /// Updates all predictions from a general discrete model `(A, B, C)`
    /// (nx×nx, nx×nu, ny×nx) by the recursions `C A^j = (C A^{j−1}) A` and
    /// `A^d B = A (A^{d−1} B)`.
    pub fn update_from_state_space(
        &mut self,
        a: &DMatrix<f64>,
        b: &DMatrix<f64>,
        c: &DMatrix<f64>,
    ) -> Result<(), PredictionError> {
        let (nx, nu, ny, nh) = (self.nx, self.nu, self.ny, self.horizon);
        check_shape("A", a.shape(), (nx, nx))?;
        check_shape("B", b.shape(), (nx, nu))?;
        check_shape("C", c.shape(), (ny, nx))?;
        // F1[j] = C A^j, row block j-1 of f1.
        for j in 0..nh {
            for col in 0..nx {
                for i in 0..ny {
                    let mut s = 0.0;
                    for m in 0..nx {
                        let prev = if j == 0 {
                            c[(i, m)]
                        } else {
                            self.f1[((j - 1) * ny + i, m)]
                        };
                        s += prev * a[(m, col)];
                    }
                    self.f1[(j * ny + i, col)] = s;
                }
            }
        }
        // G1 generator: block d = C A^d B.
        self.apb.copy_from(b);
        for d in 0..nh {
            if d > 0 {
                gemm(
                    nx,
                    nx,
                    nu,
                    1.0,
                    a.as_slice(),
                    self.apb.as_slice(),
                    0.0,
                    self.apb_next.as_mut_slice(),
                );
                std::mem::swap(&mut self.apb, &mut self.apb_next);
            }
            for col in 0..nu {
                for i in 0..ny {
                    let mut s = 0.0;
                    for m in 0..nx {
                        s += c[(i, m)] * self.apb[(m, col)];
                    }
                    self.g1[(d * ny + i, col)] = s;
                }
            }
        }
        self.accumulate();
        Ok(())
    }

    /// Updates all predictions from the ZOH model of Eq. (13) exploiting its
    /// structure `A = [[I, Φ1], [0, E]]`, `B = [[Φ2], [Φ1]]`, `C = [I, 0]`:
    /// `C A^j = [I, K_j]` with `K_j = K_{j−1} E + Φ1`, `K_0 = 0`, and
    /// `C A^d B = Φ2 + K_d Φ1`. Needs `nx = 2n`, `nu = ny = n`.
    pub fn update_from_zoh(&mut self, zoh: &Zoh) -> Result<(), PredictionError> {
        self.update_f1_and_g1_from_zoh(zoh)?;
        self.accumulate();
        Ok(())
    }

    /// The part of [`Predictions::update_from_zoh`] the controllers need:
    /// `F1` and the generator of `G1`. `F2`, `F3` and the generators of
    /// `G2`, `G3` are left as they were (the controllers form `F2 Δx`,
    /// `F3 Δx` from `F1 Δx` by the same running sums, see [`prefix_sums`], and
    /// `G2`, `G3` enter their systems through `G1`, see `tracking.rs`).
    pub(crate) fn update_f1_and_g1_from_zoh(&mut self, zoh: &Zoh) -> Result<(), PredictionError> {
        let n = zoh.dof();
        let nh = self.horizon;
        check_shape("(nx, nu) of the ZOH model", (self.nx, self.nu), (2 * n, n))?;
        check_shape("(ny, nu) of the ZOH model", (self.ny, self.nu), (n, n))?;
        let rows = nh * n;
        let (phi1, phi2, e) = (
            zoh.phi1().as_slice(),
            zoh.phi2().as_slice(),
            zoh.e().as_slice(),
        );
        let k = self.k.as_mut_slice();
        let k_next = self.k_next.as_mut_slice();
        let f = self.f1.as_mut_slice();
        let g1 = self.g1.as_mut_slice();
        // F1 = [F_I, K]: the left half is the constant block column of I.
        for (i, col) in f[..n * rows].chunks_exact_mut(rows).enumerate() {
            col.fill(0.0);
            for blk in col.chunks_exact_mut(n) {
                blk[i] = 1.0;
            }
        }
        // K_{j+1} = K_j E + Φ1 (K_0 = 0), stored as F1[j+1] = [I, K_{j+1}].
        k.copy_from_slice(phi1); // K_1
        for j in 0..nh {
            if j > 0 {
                k_next.copy_from_slice(phi1);
                gemm(n, n, n, 1.0, k, e, 1.0, k_next);
                k.copy_from_slice(k_next);
            }
            for col in 0..n {
                let o = (n + col) * rows + j * n;
                f[o..o + n].copy_from_slice(&k[col * n..col * n + n]);
            }
        }
        // g1_d = Φ2 + K_d Φ1 for all d at once: K_d (d ≥ 1) is block d−1 of
        // F1's right half, so each column is one long axpy per m.
        for col in 0..n {
            let gc = &mut g1[col * rows..col * rows + rows];
            for blk in gc.chunks_exact_mut(n) {
                blk.copy_from_slice(&phi2[col * n..col * n + n]);
            }
            for m in 0..n {
                let km = &f[(n + m) * rows..(n + m) * rows + rows - n];
                crate::control::solvers::dense::axpy(phi1[col * n + m], km, &mut gc[n..]);
            }
        }
        Ok(())
    }

    /// F2, F3 from F1 and the G2, G3 generators from G1's.
    fn accumulate(&mut self) {
        Self::running_sums(self.ny, self.horizon, &self.f1, &mut self.f2, &mut self.f3);
        Self::running_sums(self.ny, self.horizon, &self.g1, &mut self.g2, &mut self.g3);
    }

    /// Block running sums down the columns of `s1` (blocks of `ny` rows):
    /// `s2_j = s2_{j−1} + s1_j`, `s3_j = s3_{j−1} + s2_{j−1}`, `s3_0 = 0`.
    fn running_sums(
        ny: usize,
        nh: usize,
        f1: &DMatrix<f64>,
        f2: &mut DMatrix<f64>,
        f3: &mut DMatrix<f64>,
    ) {
        let rows = nh * ny;
        let (s1, s2, s3) = (f1.as_slice(), f2.as_mut_slice(), f3.as_mut_slice());
        for ((c1, c2), c3) in s1
            .chunks_exact(rows)
            .zip(s2.chunks_exact_mut(rows))
            .zip(s3.chunks_exact_mut(rows))
        {
            prefix_sums(ny, c1, c2, Some(c3));
        }
    }

    /// `F1 = [CA; CA²; …; CA^N]` (N·ny × nx), Eq. (23); also the positional `F`
    /// of the usual controller.
    pub fn f1(&self) -> &DMatrix<f64> {
        &self.f1
    }

    /// `F2`, block j = `Σ_{i=1}^{j} C A^i`, Eq. (26).
    pub fn f2(&self) -> &DMatrix<f64> {
        &self.f2
    }

    /// `F3`, block j = `Σ_{i=1}^{j-1} (j−i) C A^i`, Eq. (29).
    pub fn f3(&self) -> &DMatrix<f64> {
        &self.f3
    }

    /// Generator of `G1` (N·ny × nu): block d = `C A^d B`, the lag-d block of
    /// `G1` (Eq. (23)) and of the positional `G` of Eq. (43).
    pub fn g1_gen(&self) -> &DMatrix<f64> {
        &self.g1
    }

    /// Generator of `G2`: block d = `Σ_{e=0}^{d} C A^e B` (Eq. (26)).
    pub fn g2_gen(&self) -> &DMatrix<f64> {
        &self.g2
    }

    /// Generator of `G3`: block d = `Σ_{e=0}^{d-1} (d−e) C A^e B` (Eq. (29)).
    pub fn g3_gen(&self) -> &DMatrix<f64> {
        &self.g3
    }

    /// Assembles the full block lower-triangular Toeplitz matrix (N·ny × N·nu)
    /// of a generator into `out`: `out[j, l] = gen[j − l]` for `l ≤ j`, else 0.
    pub fn fill_toeplitz(
        &self,
        generator: &DMatrix<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), PredictionError> {
        let (ny, nu, nh) = (self.ny, self.nu, self.horizon);
        check_shape("generator", generator.shape(), (nh * ny, nu))?;
        check_shape("out", out.shape(), (nh * ny, nh * nu))?;
        out.fill(0.0);
        for l in 0..nh {
            for j in l..nh {
                let d = j - l;
                out.view_mut((j * ny, l * nu), (ny, nu))
                    .copy_from(&generator.view((d * ny, 0), (ny, nu)));
            }
        }
        Ok(())
    }
}

/// Block running sums of `s1` (blocks of `blk` values, over the common
/// length of `s1`, `s2` and `s3`): `s2_j = s2_{j−1} + s1_j`, and if given
/// `s3_j = s3_{j−1} + s2_{j−1}`, `s3_0 = 0`. This is how `F2`, `F3` follow
/// from `F1` (and `G2`, `G3` from `G1`), so also `F2 v`, `F3 v` from `F1 v`.
pub(crate) fn prefix_sums(blk: usize, s1: &[f64], s2: &mut [f64], s3: Option<&mut [f64]>) {
    let mut len = s1.len().min(s2.len());
    if let Some(s3) = s3.as_deref() {
        len = len.min(s3.len());
    }
    if blk == 0 || len < blk {
        return;
    }
    let (s1, s2) = (&s1[..len], &mut s2[..len]);
    s2[..blk].copy_from_slice(&s1[..blk]);
    for i in blk..len {
        s2[i] = s2[i - blk] + s1[i];
    }
    if let Some(s3) = s3 {
        let s3 = &mut s3[..len];
        s3[..blk].fill(0.0);
        for i in blk..len {
            s3[i] = s3[i - blk] + s2[i - blk];
        }
    }
}

/// A matrix or vector passed to the prediction builders has the wrong shape.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PredictionError {
    /// Shape (rows, cols) differs from what the builder was sized for.
    #[error("{what} has shape {got:?} but {expected:?} was expected: size it for the horizon and dimensions given to Predictions::new")]
    WrongShape {
        /// Which argument.
        what: &'static str,
        /// Expected (rows, cols).
        expected: (usize, usize),
        /// Given (rows, cols).
        got: (usize, usize),
    },
}

fn check_shape(
    what: &'static str,
    got: (usize, usize),
    expected: (usize, usize),
) -> Result<(), PredictionError> {
    if got == expected {
        Ok(())
    } else {
        Err(PredictionError::WrongShape {
            what,
            expected,
            got,
        })
    }
}

/// Work values [`predicted_outputs`] needs for `n` joints.
pub const fn predicted_outputs_work(n: usize) -> usize {
    5 * n
}

/// The outputs `ŷ_{k+1}, …, ŷ_{k+N}` (joint positions) a controller's ZOH model predicts for
/// its optimal `sequence` (N·n values, block `j` = `u_{k+j}` or `Δu_{k+j}`), into `out`
/// (N·n values, block `j` = `ŷ_{k+j+1}`), by the recursion of Eq. (13)
/// (`q⁺ = q + Φ1 v + Φ2 u`, `v⁺ = e^M v + Φ1 u`):
///
/// * positional (the usual MPC, Eq. (16) and (43); `y_k = None`): from `z_0 = x_k`,
///   `ŷ = q`;
/// * incremental (Eq. (20)–(29); `y_k = Some(q_k)`): from `z_0 = Δx_k = x_k − x_{k−1}`,
///   `ŷ_{k+j+1} = ŷ_{k+j} + Δq_{j+1}` from `ŷ_k = y_k` (`F_I y_k + F2 Δx_k + G2 ΔU`).
///
/// `work` holds `predicted_outputs_work``(n)` values. Allocates nothing.
pub fn predicted_outputs(
    zoh: &Zoh,
    z0: &[f64],
    y_k: Option<&[f64]>,
    sequence: &[f64],
    work: &mut [f64],
    out: &mut [f64],
) -> Result<(), PredictionError> {
    let n = zoh.dof();
    check_shape("z0", (z0.len(), 1), (2 * n, 1))?;
    if let Some(y) = y_k {
        check_shape("y_k", (y.len(), 1), (n, 1))?;
    }
    check_shape("out", (out.len(), 1), (sequence.len(), 1))?;
    if sequence.len().checked_rem(n) != Some(0) {
        return Err(PredictionError::WrongShape {
            what: "sequence (a multiple of n values)",
            expected: (n * (sequence.len() / n.max(1)), 1),
            got: (sequence.len(), 1),
        });
    }
    check_shape("work", (work.len(), 1), (predicted_outputs_work(n), 1))?;
    let (mut z, rest) = work.split_at_mut(2 * n);
    let (mut znext, y) = rest.split_at_mut(2 * n);
    z.copy_from_slice(z0);
    y.copy_from_slice(y_k.unwrap_or(&z0[..n]));
    let (phi1, phi2, e) = (zoh.phi1(), zoh.phi2(), zoh.e());
    for (u, o) in sequence.chunks_exact(n).zip(out.chunks_exact_mut(n)) {
        // q⁺ = q + Φ1 v + Φ2 u, v⁺ = e^M v + Φ1 u (Eq. (13)).
        for i in 0..n {
            let (mut dq, mut dv) = (0.0, 0.0);
            for j in 0..n {
                dq += phi1[(i, j)] * z[n + j] + phi2[(i, j)] * u[j];
                dv += e[(i, j)] * z[n + j] + phi1[(i, j)] * u[j];
            }
            znext[i] = z[i] + dq;
            znext[n + i] = dv;
        }
        std::mem::swap(&mut z, &mut znext);
        for i in 0..n {
            // y_{j+1} = y_j + Δq_{j+1} (incremental), or q_{j+1}.
            y[i] = match y_k {
                None => z[i],
                Some(_) => y[i] + z[i],
            };
        }
        o.copy_from_slice(y);
    }
    Ok(())
}

/// `F_I = [I; I; …; I]` (N·n × n), Eq. (25)/(28).
pub fn fill_f_i(n: usize, horizon: usize, out: &mut DMatrix<f64>) -> Result<(), PredictionError> {
    check_shape("F_I", out.shape(), (horizon * n, n))?;
    out.fill(0.0);
    for j in 0..horizon {
        for i in 0..n {
            out[(j * n + i, i)] = 1.0;
        }
    }
    Ok(())
}

/// `F_II = [0; I; 2I; …; (N−1)I]` (N·n × n), Eq. (28)/(29).
pub fn fill_f_ii(n: usize, horizon: usize, out: &mut DMatrix<f64>) -> Result<(), PredictionError> {
    check_shape("F_II", out.shape(), (horizon * n, n))?;
    out.fill(0.0);
    for j in 0..horizon {
        for i in 0..n {
            out[(j * n + i, i)] = j as f64;
        }
    }
    Ok(())
}

/// `W_s`, block j = `Σ_{i=1}^{j−1} w_{k+i}` (N·n values), Eq. (29), from the
/// preview `w_{k+1..k+N}` (flat, block j−1 = `w_{k+j}`, N·n values).
pub fn fill_w_s(n: usize, preview: &[f64], out: &mut [f64]) -> Result<(), PredictionError> {
    check_shape("W_s", (out.len(), 1), (preview.len(), 1))?;
    if preview.len().checked_rem(n) != Some(0) {
        return Err(PredictionError::WrongShape {
            what: "preview (a multiple of n values)",
            expected: (n * (preview.len() / n.max(1)), 1),
            got: (preview.len(), 1),
        });
    }
    let mut acc = 0.0;
    for i in 0..n {
        for (o, w) in out
            .iter_mut()
            .skip(i)
            .step_by(n)
            .zip(preview.iter().skip(i).step_by(n))
        {
            *o = acc;
            acc += w;
        }
        acc = 0.0;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The controllers' path (F1 and the G1 generator, then running sums of
    /// `F1 v`) reproduces the full update: the same `F1` and `G1`, and `F2 v`,
    /// `F3 v` of the accumulated matrices.
    #[test]
    fn generator_path_and_running_sums_match_the_full_update() {
        let n = 3;
        let nh = 7;
        let f0 = DMatrix::<f64>::from_fn(n, n, |i, j| 0.3 * (i as f64) - 0.7 * (j as f64) + 0.1);
        let mut zoh = Zoh::new(n);
        zoh.discretize(&f0, 0.05).unwrap();
        let mut full = Predictions::new(2 * n, n, n, nh);
        full.update_from_zoh(&zoh).unwrap();
        let mut part = Predictions::new(2 * n, n, n, nh);
        part.update_f1_and_g1_from_zoh(&zoh).unwrap();
        assert_eq!(full.f1(), part.f1());
        assert_eq!(full.g1_gen(), part.g1_gen());
        let v = nalgebra::DVector::<f64>::from_fn(2 * n, |i, _| (i as f64 * 0.9).sin());
        let f1v = full.f1() * &v;
        let (mut s2, mut s3) = (vec![0.0; nh * n], vec![0.0; nh * n]);
        prefix_sums(n, f1v.as_slice(), &mut s2, Some(&mut s3));
        let (f2v, f3v) = (full.f2() * &v, full.f3() * &v);
        for i in 0..nh * n {
            assert!((s2[i] - f2v[i]).abs() <= 1e-13 * (1.0 + f2v[i].abs()));
            assert!((s3[i] - f3v[i]).abs() <= 1e-13 * (1.0 + f3v[i].abs()));
        }
        // F3 block 1 is zero and F2 block 1 is F1 block 1.
        assert!(s3[..n].iter().all(|&x| x == 0.0));
        assert_eq!(&s2[..n], &f1v.as_slice()[..n]);
    }
}
