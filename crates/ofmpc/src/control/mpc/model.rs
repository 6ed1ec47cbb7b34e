//! The linear-like time-varying model of Section II: `f0 = −H⁻¹C` (Eq. (6)),
//! `u = H⁻¹(τ − g)` (Eq. (7)), the state-space form (9)–(12) and the way back
//! to torques `τ = H u + g` (Eq. (15)).

use nalgebra::{DMatrix, DVector};

use crate::control::model_errors::TermsError;
use crate::dynamics::JointSpaceDynamics;
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place_dot};

/// The terms `H, C, g` of one sample and the derived `f0 = −H⁻¹C`, in
/// preallocated n×n buffers. [`LinearLikeModel::update`] allocates nothing.
#[derive(Debug, Clone)]
pub struct LinearLikeModel {
    n: usize,
    h: DMatrix<f64>,
    c: DMatrix<f64>,
    g: DVector<f64>,
    /// Cholesky factor `L` (lower triangle used), `H = L Lᵀ`.
    chol: DMatrix<f64>,
    f0: DMatrix<f64>,
}

impl LinearLikeModel {
    /// Buffers for an `n`-joint robot.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            h: DMatrix::zeros(n, n),
            c: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
            chol: DMatrix::zeros(n, n),
            f0: DMatrix::zeros(n, n),
        }
    }

    /// Number of joints `n`.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Evaluates `H, C, g` at `(q, q̇)` and computes `f0 = −H⁻¹C` (Eq. (6),
    /// with `½Ḣ + S = C`, the Christoffel Coriolis matrix) through an in-place
    /// Cholesky factorization of `H`. `q` and `qd` must have `n` entries.
    pub fn update(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        q: &[f64],
        qd: &[f64],
    ) -> Result<(), TermsError> {
        if model.dof() != self.n {
            return Err(TermsError::DofMismatch {
                expected: self.n,
                got: model.dof(),
            });
        }
        check_len("q", q.len(), self.n)?;
        check_len("qd", qd.len(), self.n)?;
        model.terms(q, qd, &mut self.h, &mut self.c, &mut self.g);
        self.set_f0_from_terms()
    }

    /// Sets `H, C, g` directly (n×n, n×n, n) and computes `f0`. Allocation-free.
    /// For tests and callers that evaluate the model themselves.
    pub fn set_terms(
        &mut self,
        h: &DMatrix<f64>,
        c: &DMatrix<f64>,
        g: &DVector<f64>,
    ) -> Result<(), TermsError> {
        let n = self.n;
        for (what, shape, want) in [
            ("H", h.shape(), (n, n)),
            ("C", c.shape(), (n, n)),
            ("g", (g.len(), 1), (n, 1)),
        ] {
            if shape != want {
                return Err(TermsError::WrongLength {
                    what,
                    expected: want.0 * want.1,
                    got: shape.0 * shape.1,
                });
            }
        }
        self.h.copy_from(h);
        self.c.copy_from(c);
        self.g.copy_from(g);
        self.set_f0_from_terms()
    }

    fn set_f0_from_terms(&mut self) -> Result<(), TermsError> {
        for (term, s) in [
            ("H", self.h.as_slice()),
            ("C", self.c.as_slice()),
            ("g", self.g.as_slice()),
        ] {
            if let Some(index) = s.iter().position(|v| !v.is_finite()) {
                return Err(TermsError::NonFiniteTerm { term, index });
            }
        }
        let n = self.n;
        self.chol.as_mut_slice()[..n * n].copy_from_slice(&self.h.as_slice()[..n * n]);
        cholesky_in_place(n, n, self.chol.as_mut_slice()).map_err(|e| {
            TermsError::InertiaNotPositiveDefinite {
                pivot: e.pivot,
                value: e.value,
            }
        })?;
        // f0 = −H⁻¹ C: solve L Lᵀ f0 = −C column by column.
        self.f0.copy_from(&self.c);
        let l = self.chol.as_slice();
        for col in self.f0.as_mut_slice().chunks_exact_mut(n) {
            col.iter_mut().for_each(|v| *v = -*v);
            cholesky_solve_in_place_dot(n, n, l, col);
        }
        Ok(())
    }

    /// `f0 = −H⁻¹C` of the last update (Eq. (6)).
    pub fn f0(&self) -> &DMatrix<f64> {
        &self.f0
    }

    /// Inertia `H` of the last update (with armature).
    pub fn h(&self) -> &DMatrix<f64> {
        &self.h
    }

    /// Coriolis matrix `C` of the last update.
    pub fn c(&self) -> &DMatrix<f64> {
        &self.c
    }

    /// Gravity `g` of the last update.
    pub fn g(&self) -> &DVector<f64> {
        &self.g
    }

    /// Torques from the acceleration-like input: `τ = H u + g` (Eq. (15)),
    /// with the `H`, `g` of the last update. Slices of length `n`.
    pub fn torque(&self, u: &[f64], tau: &mut [f64]) -> Result<(), TermsError> {
        let n = self.n;
        check_len("u", u.len(), n)?;
        check_len("tau", tau.len(), n)?;
        tau.copy_from_slice(self.g.as_slice());
        for (&uj, hj) in u.iter().zip(self.h.as_slice().chunks_exact(n.max(1))) {
            crate::control::solvers::dense::axpy(uj, hj, tau);
        }
        Ok(())
    }

    /// The input `u = H⁻¹(τ − g)` of Eq. (7) for given torques (inverse of
    /// [`LinearLikeModel::torque`]). Slices of length `n`.
    pub fn input_from_torque(&self, tau: &[f64], u: &mut [f64]) -> Result<(), TermsError> {
        check_len("tau", tau.len(), self.n)?;
        check_len("u", u.len(), self.n)?;
        for ((ui, ti), gi) in u.iter_mut().zip(tau).zip(self.g.iter()) {
            *ui = ti - gi;
        }
        cholesky_solve_in_place_dot(self.n, self.n, self.chol.as_slice(), u);
        Ok(())
    }
}

impl LinearLikeModel {
    /// `b ← H⁻¹ b` with the Cholesky factor of the last update (`n` values;
    /// a shorter or longer slice is left as it is). Allocation-free.
    /// Adds a known torque `f` to `g` (a bias the drives must overcome, e.g.
    /// friction), so that `τ = H u + g + f`. Allocation-free.
    pub(crate) fn add_bias_torque(&mut self, f: &[f64]) -> Result<(), TermsError> {
        check_len("f", f.len(), self.n)?;
        for (g, fi) in self.g.iter_mut().zip(f) {
            *g += fi;
        }
        Ok(())
    }

    pub(crate) fn solve_h_in_place(&self, b: &mut [f64]) {
        if b.len() == self.n {
            cholesky_solve_in_place_dot(self.n, self.n, self.chol.as_slice(), b);
        }
    }
}

fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), TermsError> {
    if got == expected {
        Ok(())
    } else {
        Err(TermsError::WrongLength {
            what,
            expected,
            got,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::linalg::random::spd_matrix as spd;

    #[test]
    fn f0_is_minus_h_inverse_c_and_torque_roundtrips() {
        for n in [1, 2, 6, 7] {
            let h = spd(n, 3 + n as u64);
            let c = DMatrix::<f64>::from_fn(n, n, |i, j| (i as f64 - 2.0 * j as f64) * 0.3);
            let g = DVector::<f64>::from_fn(n, |i, _| i as f64 - 1.5);
            let mut m = LinearLikeModel::new(n);
            m.set_terms(&h, &c, &g).unwrap();
            let want = -h.clone().lu().solve(&c).unwrap();
            assert!((m.f0() - &want).norm() <= 1e-12 * want.norm().max(1.0));
            // τ = H u + g and back.
            let u: Vec<f64> = (0..n).map(|i| 0.3 * i as f64 - 0.7).collect();
            let mut tau = vec![0.0; n];
            m.torque(&u, &mut tau).unwrap();
            let want_tau = &h * DVector::from_column_slice(&u) + &g;
            assert!((DVector::from_column_slice(&tau) - want_tau).norm() < 1e-12);
            let mut u2 = vec![0.0; n];
            m.input_from_torque(&tau, &mut u2).unwrap();
            assert!(m.torque(&u[..n - 1], &mut tau).is_err());
            for (a, b) in u.iter().zip(&u2) {
                assert!((a - b).abs() < 1e-10);
            }
        }
    }

    #[test]
    fn rejects_indefinite_and_non_finite_inertia() {
        let mut m = LinearLikeModel::new(2);
        let c = DMatrix::zeros(2, 2);
        let g = DVector::zeros(2);
        let h = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(matches!(
            m.set_terms(&h, &c, &g),
            Err(TermsError::InertiaNotPositiveDefinite { pivot: 1, .. })
        ));
        let h = DMatrix::from_row_slice(2, 2, &[1.0, f64::NAN, f64::NAN, 1.0]);
        assert!(matches!(
            m.set_terms(&h, &c, &g),
            Err(TermsError::NonFiniteTerm { term: "H", .. })
        ));
    }
}
