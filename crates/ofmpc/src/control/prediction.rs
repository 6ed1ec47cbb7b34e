//! Equations of predictions, Eq. (20)–(29), and the positional ones of the
//! usual controller (43).
//!
//! Blocks (j = 1..N block row, l = 1..N block column; see NOTES.md):
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

use super::dense::gemm;
use super::zoh::Zoh;

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
        let n = zoh.dof();
        let nh = self.horizon;
        check_shape("(nx, nu) of the ZOH model", (self.nx, self.nu), (2 * n, n))?;
        check_shape("(ny, nu) of the ZOH model", (self.ny, self.nu), (n, n))?;
        let rows = nh * n;
        self.k.fill(0.0);
        // F1: left block identity per row block, right block K_j.
        self.f1.fill(0.0);
        for j in 0..nh {
            // C A^j B for d = j uses K_j (before update): g1 block j.
            // g1_j = Φ2 + K_j Φ1
            {
                let g = self.g1.as_mut_slice();
                for col in 0..n {
                    for i in 0..n {
                        g[col * rows + j * n + i] = zoh.phi2()[(i, col)];
                    }
                }
                for col in 0..n {
                    for m in 0..n {
                        let s = zoh.phi1()[(m, col)];
                        let km = &self.k.as_slice()[m * n..m * n + n];
                        let dst = &mut g[col * rows + j * n..col * rows + j * n + n];
                        super::dense::axpy(s, km, dst);
                    }
                }
            }
            // K_{j+1} = K_j E + Φ1
            self.k_next.copy_from(zoh.phi1());
            gemm(
                n,
                n,
                n,
                1.0,
                self.k.as_slice(),
                zoh.e().as_slice(),
                1.0,
                self.k_next.as_mut_slice(),
            );
            std::mem::swap(&mut self.k, &mut self.k_next);
            // F1[j+1] = [I, K_{j+1}]
            let f = self.f1.as_mut_slice();
            for i in 0..n {
                f[i * rows + j * n + i] = 1.0;
            }
            for col in 0..n {
                let src = &self.k.as_slice()[col * n..col * n + n];
                f[(n + col) * rows + j * n..(n + col) * rows + j * n + n].copy_from_slice(src);
            }
        }
        self.accumulate();
        Ok(())
    }

    /// F2, F3 from F1 and the G2, G3 generators from G1's.
    fn accumulate(&mut self) {
        let (ny, nh) = (self.ny, self.horizon);
        let rows = nh * ny;
        for (f1, f2, f3) in [
            (&self.f1, &mut self.f2, &mut self.f3),
            (&self.g1, &mut self.g2, &mut self.g3),
        ] {
            let cols = f1.ncols();
            let (s1, s2, s3) = (f1.as_slice(), f2.as_mut_slice(), f3.as_mut_slice());
            for col in 0..cols {
                let o = col * rows;
                for i in 0..ny {
                    s2[o + i] = s1[o + i];
                    s3[o + i] = 0.0;
                }
                for j in 1..nh {
                    for i in 0..ny {
                        let (cur, prev) = (o + j * ny + i, o + (j - 1) * ny + i);
                        s2[cur] = s2[prev] + s1[cur];
                        s3[cur] = s3[prev] + s2[prev];
                    }
                }
            }
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
