//! Numeric inverse kinematics by damped least squares (Levenberg–Marquardt).
//!
//! For robots without a closed-form solver. Each iteration linearises the pose
//! error `e(q) = [p* − p(q); log(R*·R(q)ᵀ)]` with the geometric Jacobian `J` and
//! takes the damped Gauss–Newton step `(JᵀJ + λI) δ = Jᵀe`, clamped into the
//! joint limits. The damping λ adapts with the gain ratio ρ = actual / predicted
//! cost reduction (Nielsen's rule: λ ← λ·max(1/3, 1 − (2ρ − 1)³) after a successful
//! step, λ ← λ·ν, ν ← 2ν after a rejected one), so the method behaves like
//! Gauss–Newton near a regular solution (fast convergence) and like damped gradient
//! descent near singularities or far from the target. The cost adds position (m)
//! and rotation (rad) errors unweighted, which suits arms of about a metre.

use nalgebra::{DMatrix, DVector, Isometry3};

use super::{pose_error, pose_is_finite, ForwardKinematics, IkError};
use crate::linalg;

/// Settings of [`NumericIk`]; each field's default is given in its doc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NumericIkSettings {
    /// Maximum number of iterations (one trial step each). Default 100.
    pub max_iterations: usize,
    /// Converged when the position error is at most this (m). Default 1e-10.
    pub position_tolerance: f64,
    /// … and the orientation error is at most this (rad). Default 1e-10.
    pub orientation_tolerance: f64,
    /// Initial damping relative to the largest diagonal entry of JᵀJ. Default 1e-3.
    pub initial_damping: f64,
    /// Smallest damping λ (absolute); keeps JᵀJ + λI positive definite at a
    /// singularity. Default 1e-12.
    pub min_damping: f64,
    /// The solver gives up when λ exceeds this (absolute): no step decreases the
    /// error any more. Default 1e10.
    pub max_damping: f64,
}

impl Default for NumericIkSettings {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            position_tolerance: 1e-10,
            orientation_tolerance: 1e-10,
            initial_damping: 1e-3,
            min_damping: 1e-12,
            max_damping: 1e10,
        }
    }
}

impl NumericIkSettings {
    /// Checks that tolerances and damping values are finite and positive and that
    /// `min_damping < max_damping`.
    pub fn validate(&self) -> Result<(), IkError> {
        let checks = [
            ("position_tolerance", self.position_tolerance),
            ("orientation_tolerance", self.orientation_tolerance),
            ("initial_damping", self.initial_damping),
            ("min_damping", self.min_damping),
            ("max_damping", self.max_damping),
        ];
        for (name, value) in checks {
            if !(value.is_finite() && value > 0.0) {
                return Err(IkError::InvalidParameter {
                    name,
                    value,
                    requirement: "must be finite and positive",
                });
            }
        }
        if self.min_damping >= self.max_damping {
            return Err(IkError::InvalidParameter {
                name: "min_damping",
                value: self.min_damping,
                requirement: "must be smaller than max_damping",
            });
        }
        Ok(())
    }
}

/// Outcome of a converged [`NumericIk::solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NumericIkReport {
    /// Iterations performed (0 when the seed already met the tolerances).
    pub iterations: usize,
    /// Final position error (m).
    pub position_error: f64,
    /// Final orientation error (rad).
    pub orientation_error: f64,
}

/// Damped-least-squares IK for an n-joint robot; all buffers are sized in
/// [`NumericIk::new`], [`NumericIk::solve`] allocates nothing.
#[derive(Debug, Clone)]
pub struct NumericIk {
    n: usize,
    settings: NumericIkSettings,
    lower: Vec<f64>,
    upper: Vec<f64>,
    jac: DMatrix<f64>,
    jtj: DMatrix<f64>,
    sys: DMatrix<f64>,
    err: DVector<f64>,
    grad: DVector<f64>,
    step: DVector<f64>,
    jtj_step: DVector<f64>,
    q: Vec<f64>,
    trial: Vec<f64>,
}

/// Solves `a x = b` for symmetric positive definite `a` by an in-place Cholesky
/// factorisation ([`crate::linalg`]; the lower triangle of `a` is overwritten with L,
/// `b` with x). Returns false (and leaves garbage) if `a` is not numerically positive
/// definite.
fn cholesky_solve_in_place(a: &mut DMatrix<f64>, b: &mut DVector<f64>) -> bool {
    let n = a.nrows();
    if linalg::cholesky_in_place(n, n, a.as_mut_slice()).is_err() {
        return false;
    }
    linalg::cholesky_solve_in_place(n, n, a.as_slice(), b.as_mut_slice());
    true
}

impl NumericIk {
    /// IK for `n` joints with limits `lower`/`upper` (rad; ±∞ allowed for
    /// unbounded joints). Errors: wrong lengths, NaN or inverted limits, invalid
    /// settings.
    pub fn new(
        n: usize,
        lower: &[f64],
        upper: &[f64],
        settings: NumericIkSettings,
    ) -> Result<Self, IkError> {
        settings.validate()?;
        if n == 0 {
            return Err(IkError::DimensionMismatch {
                what: "robot (number of joints)",
                expected: 1,
                got: 0,
            });
        }
        for (what, v) in [("lower limits", lower), ("upper limits", upper)] {
            if v.len() != n {
                return Err(IkError::DimensionMismatch {
                    what,
                    expected: n,
                    got: v.len(),
                });
            }
        }
        for (i, (&l, &u)) in lower.iter().zip(upper).enumerate() {
            if l.is_nan() || u.is_nan() || l > u || l == f64::INFINITY || u == f64::NEG_INFINITY {
                return Err(IkError::InvalidLimits {
                    joint: i + 1,
                    lower: l,
                    upper: u,
                });
            }
        }
        Ok(Self {
            n,
            settings,
            lower: lower.to_vec(),
            upper: upper.to_vec(),
            jac: DMatrix::zeros(6, n),
            jtj: DMatrix::zeros(n, n),
            sys: DMatrix::zeros(n, n),
            err: DVector::zeros(6),
            grad: DVector::zeros(n),
            step: DVector::zeros(n),
            jtj_step: DVector::zeros(n),
            q: vec![0.0; n],
            trial: vec![0.0; n],
        })
    }

    /// The settings in use.
    pub fn settings(&self) -> &NumericIkSettings {
        &self.settings
    }

    /// Moves `q` (in: seed, typically the previous sample; out: solution) until the
    /// flange of `fk` reaches `target` within the tolerances. The seed is first
    /// clamped into the joint limits; every iterate stays inside them.
    ///
    /// Errors: [`IkError::DimensionMismatch`] (q or model size), [`IkError::NonFinite`]
    /// (target, seed, or the model's pose/Jacobian) — `q` is then unchanged;
    /// [`IkError::NotConverged`] when the iteration limit is reached or no step
    /// reduces the error (unreachable pose, limits in the way) — `q` then holds the
    /// best iterate found.
    pub fn solve<F: ForwardKinematics + ?Sized>(
        &mut self,
        fk: &mut F,
        target: &Isometry3<f64>,
        q: &mut [f64],
    ) -> Result<NumericIkReport, IkError> {
        self.check_inputs(&*fk, target, q)?;
        let s = self.settings;
        let mut st = self.start(fk, target, q)?;
        let mut iterations = 0;
        let converged =
            |ep: f64, er: f64| ep <= s.position_tolerance && er <= s.orientation_tolerance;

        while !converged(st.ep.norm(), st.er.norm()) && iterations < s.max_iterations {
            iterations += 1;
            if st.need_jacobian {
                self.update_jacobian(fk, &mut st)?;
            }
            if !self.try_step(fk, target, &mut st) {
                st.lambda *= st.nu;
                st.nu *= 2.0;
                if st.lambda > s.max_damping {
                    break;
                }
            }
        }
        q.copy_from_slice(&self.q);
        let (pe, oe) = (st.ep.norm(), st.er.norm());
        if converged(pe, oe) {
            Ok(NumericIkReport {
                iterations,
                position_error: pe,
                orientation_error: oe,
            })
        } else {
            Err(IkError::NotConverged {
                iterations,
                position_error: pe,
                orientation_error: oe,
            })
        }
    }

    /// Checks the sizes of `q` and of the model, and that the target and the seed are
    /// finite.
    fn check_inputs<F: ForwardKinematics + ?Sized>(
        &self,
        fk: &F,
        target: &Isometry3<f64>,
        q: &[f64],
    ) -> Result<(), IkError> {
        let n = self.n;
        if q.len() != n {
            return Err(IkError::DimensionMismatch {
                what: "joint vector",
                expected: n,
                got: q.len(),
            });
        }
        if fk.dof() != n {
            return Err(IkError::DimensionMismatch {
                what: "robot model",
                expected: n,
                got: fk.dof(),
            });
        }
        if !pose_is_finite(target) {
            return Err(IkError::NonFinite {
                what: "target pose",
            });
        }
        if !q.iter().all(|x| x.is_finite()) {
            return Err(IkError::NonFinite {
                what: "seed joint vector",
            });
        }
        Ok(())
    }

    /// Clamps the seed `q` into the joint limits as the first iterate and evaluates its
    /// pose error; the damping is set at the first Jacobian.
    fn start<F: ForwardKinematics + ?Sized>(
        &mut self,
        fk: &mut F,
        target: &Isometry3<f64>,
        q: &[f64],
    ) -> Result<LmState, IkError> {
        for (((x, &seed), &lo), &hi) in self.q.iter_mut().zip(q).zip(&self.lower).zip(&self.upper) {
            *x = seed.clamp(lo, hi);
        }
        let pose = fk.flange_pose(&self.q);
        let (ep, er) = pose_error(target, &pose);
        if !(ep.iter().chain(er.iter()).all(|x| x.is_finite())) {
            return Err(IkError::NonFinite {
                what: "forward kinematics at the seed",
            });
        }
        let cost = 0.5 * (ep.norm_squared() + er.norm_squared());
        Ok(LmState {
            ep,
            er,
            cost,
            lambda: f64::NAN, // set from JᵀJ at the first Jacobian
            nu: 2.0,
            need_jacobian: true,
        })
    }

    /// Evaluates the flange Jacobian `J` at the current iterate, `JᵀJ` and the gradient
    /// `Jᵀe`; the first time, sets the damping `λ = max(initial_damping · max diag JᵀJ,
    /// min_damping)`.
    fn update_jacobian<F: ForwardKinematics + ?Sized>(
        &mut self,
        fk: &mut F,
        st: &mut LmState,
    ) -> Result<(), IkError> {
        let (n, s) = (self.n, self.settings);
        fk.flange_jacobian(&self.q, &mut self.jac);
        if self.jac.shape() != (6, n) || !self.jac.iter().all(|x| x.is_finite()) {
            return Err(IkError::NonFinite {
                what: "flange Jacobian (or its shape)",
            });
        }
        self.jtj.gemm_tr(1.0, &self.jac, &self.jac, 0.0);
        self.err.fixed_rows_mut::<3>(0).copy_from(&st.ep);
        self.err.fixed_rows_mut::<3>(3).copy_from(&st.er);
        self.grad.gemv_tr(1.0, &self.jac, &self.err, 0.0);
        if st.lambda.is_nan() {
            let max_diag = (0..n).map(|i| self.jtj[(i, i)]).fold(0.0, f64::max);
            st.lambda = (s.initial_damping * max_diag).max(s.min_damping);
        }
        st.need_jacobian = false;
        Ok(())
    }

    /// One damped step: solves `(JᵀJ + λI) δ = Jᵀe`, clamps the trial point into the joint
    /// limits and accepts it if it lowers `½|e|²`, updating `λ` from the ratio of actual to
    /// predicted reduction (Nielsen's rule). Returns whether the step was accepted.
    fn try_step<F: ForwardKinematics + ?Sized>(
        &mut self,
        fk: &mut F,
        target: &Isometry3<f64>,
        st: &mut LmState,
    ) -> bool {
        let (n, s) = (self.n, self.settings);
        // (JᵀJ + λI) δ = Jᵀe
        self.sys.copy_from(&self.jtj);
        for i in 0..n {
            self.sys[(i, i)] += st.lambda;
        }
        self.step.copy_from(&self.grad);
        if !cholesky_solve_in_place(&mut self.sys, &mut self.step) {
            return false;
        }
        for i in 0..n {
            self.trial[i] = (self.q[i] + self.step[i]).clamp(self.lower[i], self.upper[i]);
            self.step[i] = self.trial[i] - self.q[i];
        }
        // Predicted reduction of ½|e|² for the (clamped) step δ:
        // δᵀJᵀe − ½ δᵀJᵀJδ.
        self.jtj_step.gemv(1.0, &self.jtj, &self.step, 0.0);
        let predicted = self.step.dot(&self.grad) - 0.5 * self.step.dot(&self.jtj_step);
        let pose = fk.flange_pose(&self.trial);
        let (tp, tr) = pose_error(target, &pose);
        let trial_cost = 0.5 * (tp.norm_squared() + tr.norm_squared());
        if !(trial_cost.is_finite() && trial_cost < st.cost) {
            return false;
        }
        if predicted > 0.0 {
            let rho = (st.cost - trial_cost) / predicted;
            st.lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
            st.lambda = st.lambda.max(s.min_damping);
        }
        st.nu = 2.0;
        self.q.copy_from_slice(&self.trial);
        (st.ep, st.er, st.cost) = (tp, tr, trial_cost);
        st.need_jacobian = true;
        true
    }
}

/// State of the damped least-squares (Levenberg–Marquardt) iteration of
/// [`NumericIk::solve`].
struct LmState {
    /// Position error of the current iterate.
    ep: nalgebra::Vector3<f64>,
    /// Orientation error (rotation vector) of the current iterate.
    er: nalgebra::Vector3<f64>,
    /// `½|e|²` of the current iterate.
    cost: f64,
    /// Damping `λ` (NaN until the first Jacobian).
    lambda: f64,
    /// Growth factor of `λ` after a rejected step.
    nu: f64,
    /// The iterate moved since the last Jacobian.
    need_jacobian: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_spd_system_and_rejects_indefinite() {
        // A = BᵀB + I for a fixed B; x known.
        let b = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.5, -0.3, 0.7, 1.1, 0.2, -0.4, 0.9]);
        let a = b.transpose() * &b + DMatrix::identity(3, 3);
        let x = DVector::from_vec(vec![0.3, -1.2, 2.5]);
        let mut rhs = &a * &x;
        let mut f = a.clone();
        assert!(cholesky_solve_in_place(&mut f, &mut rhs));
        assert!((rhs - x).norm() < 1e-14);
        let mut indef = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let mut r = DVector::from_vec(vec![1.0, 1.0]);
        assert!(!cholesky_solve_in_place(&mut indef, &mut r));
    }

    #[test]
    fn new_rejects_bad_input() {
        let s = NumericIkSettings::default();
        assert!(matches!(
            NumericIk::new(2, &[0.0], &[1.0, 1.0], s),
            Err(IkError::DimensionMismatch { .. })
        ));
        assert!(matches!(
            NumericIk::new(2, &[0.0, 2.0], &[1.0, 1.0], s),
            Err(IkError::InvalidLimits { joint: 2, .. })
        ));
        let bad = NumericIkSettings {
            position_tolerance: -1.0,
            ..s
        };
        assert!(matches!(
            NumericIk::new(1, &[0.0], &[1.0], bad),
            Err(IkError::InvalidParameter {
                name: "position_tolerance",
                ..
            })
        ));
        assert!(NumericIk::new(1, &[f64::NEG_INFINITY], &[f64::INFINITY], s).is_ok());
    }
}
