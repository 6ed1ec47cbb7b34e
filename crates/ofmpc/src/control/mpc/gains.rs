//! The first-stage feedback gain of the predictive controllers
//! ([`crate::control::MpcSettings::gains`]): `K = ∂τ_k/∂x_k` (n × 2n,
//! row-major) at the state `x_k` a step acted on, so that a faster loop can
//! apply `τ = τ_k + K (x − x_k)` between MPC samples (the linear-feedback
//! pattern of torque-controlled arms).
//!
//! The step's torque is `τ_k = H(q_k) u_k + g(q_k)` (Eq. (15)) with `u_k`
//! the stage-wise solve's first input (`u_{k−1} + Δu_k` for the incremental
//! algorithms). `K` has two parts:
//!
//! * `H K_u`, with `K_u = ∂u_k/∂x_k` from the structured solver's
//!   `∂v_0/∂z_0` ([`crate::control::solvers::structured`]) through the
//!   algorithm's map from `x_k` to its stage state and targets
//!   ([`map_stage_gain`]);
//! * `∂(H u + g)/∂q` at `u_k` held, by central differences of the model's
//!   terms (`2n` evaluations; `H` and `g` do not depend on `q̇`).
//!
//! What `K` leaves out is the ZOH model's own dependence on the state
//! (`f0 = −H⁻¹C` at `x_k`, frozen over the horizon): measured on the IRB 140
//! (tests/gains.rs) a first-order remainder of ≈ 5e-5 of `|K δx|`, against
//! 0.15–9.5 % without the second part.

use nalgebra::{DMatrix, DVector};

use crate::control::model_errors::TermsError;
use crate::dynamics::JointSpaceDynamics;

/// Relative step of the central differences of `H u + g` in `q`:
/// truncation ≈ 1e-10 and rounding ≈ ε/1e-5 ≈ 1e-11 of the derivative.
const FD_STEP: f64 = 1e-5;

/// Buffers of the gain, sized once.
#[derive(Debug, Clone)]
pub(crate) struct GainWork {
    n: usize,
    /// `K_u` (n × 2n, row-major).
    gain_u: Vec<f64>,
    /// `K` of the last step (n × 2n, row-major).
    gain: Vec<f64>,
    h: DMatrix<f64>,
    c: DMatrix<f64>,
    g: DVector<f64>,
    q: Vec<f64>,
    plus: Vec<f64>,
    minus: Vec<f64>,
}

impl GainWork {
    /// Buffers for `n` joints.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            gain_u: vec![0.0; 2 * n * n],
            gain: vec![0.0; 2 * n * n],
            h: DMatrix::zeros(n, n),
            c: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
            q: vec![0.0; n],
            plus: vec![0.0; n],
            minus: vec![0.0; n],
        }
    }

    /// `K` of the last [`GainWork::form`].
    pub fn gain(&self) -> &[f64] {
        &self.gain
    }

    /// Marks `K` as unusable (NaN): the model's terms next to the step's
    /// state were not finite.
    pub fn invalidate(&mut self) {
        self.gain.fill(f64::NAN);
    }

    /// Forms `K = H K_u + ∂(H u + g)/∂q` (module docs) from the solver's
    /// `kz = ∂v_0/∂z_0` (n × nz, row-major), the joints in the hold dead
    /// zone, the step's `H` (column-major) and its input `u`, at the state
    /// `x`. Allocates nothing.
    pub fn form(
        &mut self,
        (kz, hold): (&[f64], &[bool]),
        h: &DMatrix<f64>,
        u: &[f64],
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
    ) -> Result<(), TermsError> {
        let n = self.n;
        map_stage_gain(kz, hold, n, &mut self.gain_u);
        self.gain.fill(0.0);
        for (l, hcol) in h.as_slice().chunks_exact(n).enumerate() {
            let ku = &self.gain_u[l * 2 * n..(l + 1) * 2 * n];
            for (grow, hil) in self.gain.chunks_exact_mut(2 * n).zip(hcol) {
                crate::control::solvers::dense::axpy(*hil, ku, grow);
            }
        }
        self.add_torque_map_derivative(model, x, u)
    }

    /// Adds `∂(H u + g)/∂q_j` (u held) to column `j < n` of `K`, by central
    /// differences.
    fn add_torque_map_derivative(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        u: &[f64],
    ) -> Result<(), TermsError> {
        let n = self.n;
        let (q0, qd) = x.split_at(n);
        let mut terms = Terms {
            h: &mut self.h,
            c: &mut self.c,
            g: &mut self.g,
        };
        for j in 0..n {
            let step = FD_STEP * q0[j].abs().max(1.0);
            self.q.copy_from_slice(q0);
            self.q[j] = q0[j] + step;
            terms.torque(model, (&self.q, qd), u, &mut self.plus)?;
            self.q[j] = q0[j] - step;
            terms.torque(model, (&self.q, qd), u, &mut self.minus)?;
            let scale = 0.5 / step;
            for ((grow, p), m) in self
                .gain
                .chunks_exact_mut(2 * n)
                .zip(&self.plus)
                .zip(&self.minus)
            {
                grow[j] += (p - m) * scale;
            }
        }
        Ok(())
    }
}

/// Work buffers of one evaluation of the model's terms.
struct Terms<'a> {
    h: &'a mut DMatrix<f64>,
    c: &'a mut DMatrix<f64>,
    g: &'a mut DVector<f64>,
}

impl Terms<'_> {
    /// `H(q) u + g(q)` into `out`.
    fn torque(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        (q, qd): (&[f64], &[f64]),
        u: &[f64],
        out: &mut [f64],
    ) -> Result<(), TermsError> {
        let n = out.len();
        model.terms(q, qd, self.h, self.c, self.g);
        out.copy_from_slice(self.g.as_slice());
        for (&uj, hj) in u.iter().zip(self.h.as_slice().chunks_exact(n)) {
            crate::control::solvers::dense::axpy(uj, hj, out);
        }
        if let Some(index) = out.iter().position(|v| !v.is_finite()) {
            return Err(TermsError::NonFiniteTerm {
                term: "H u + g",
                index,
            });
        }
        Ok(())
    }
}

/// `K_u = ∂u_k/∂x_k` (n × 2n, row-major, into `ku`) from the solver's
/// `kz = ∂v_0/∂z_0` (n × nz, row-major), by the stage layout (`nz / n`
/// blocks, [`crate::control::mpc::core`]): usual `z_0 = x_k`; first
/// `z_0 = [0; Δx_k]` with targets `w − y_k` (a change of `y_k` acts as the
/// opposite change of the targets, i.e. as a change of the first block, an
/// integrator); second `z_0 = [−ē_k; Δq_k; 0; Δq̇_k]` with
/// `c_j = y_k − w` (a change of `y_k` enters `−ē_k` and acts on the affine
/// terms as a change of the third block). A joint in the hold dead zone
/// tracks `w_k` instead of `y_k`: its position enters through `Δq` alone.
pub(crate) fn map_stage_gain(kz: &[f64], hold: &[bool], n: usize, ku: &mut [f64]) {
    let nz = kz.len() / n;
    let blocks = nz / n;
    for (ku, kz) in ku.chunks_exact_mut(2 * n).zip(kz.chunks_exact(nz)) {
        let (kq, kqd) = ku.split_at_mut(n);
        kqd.copy_from_slice(&kz[(blocks - 1) * n..]);
        for (j, (k, held)) in kq.iter_mut().zip(hold).enumerate() {
            let (direct, through_y) = match blocks {
                3 => (kz[n + j], kz[j]),
                4 => (kz[n + j], kz[j] + kz[2 * n + j]),
                _ => (kz[j], 0.0),
            };
            *k = if *held { direct } else { direct + through_y };
        }
    }
}
