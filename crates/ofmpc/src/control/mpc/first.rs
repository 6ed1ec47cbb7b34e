//! The first incremental algorithm, Eq. (30)–(32) and (37): one integrator
//! (`u_k = u_{k−1} + Δu_k`), cost
//! `Σ ‖Q_yw (ŷ − w)‖² + ‖Q_Δy Δŷ‖² + ‖Q_Δu Δu‖²`, solved as
//!
//! ```text
//! [Q_YW G2; Q_ΔY G1; Q_ΔU] ΔU = [Q_YW (W − F_I y_k − F2 Δx_k); −Q_ΔY F1 Δx_k; 0].
//! ```
//!
//! It removes the steady error for constant references.

use crate::control::kind::ControllerKind;
use crate::control::mpc::core::{impl_controller, Core, StepTargets};
use crate::control::mpc::prediction::prefix_sums;
use crate::control::settings::{MpcSettings, SettingsError};
use crate::control::step::{StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;

/// The first algorithm, Eq. (32)/(37). Allocation-free [`Algorithm::step`](crate::control::Algorithm::step).
#[derive(Debug, Clone)]
pub struct FirstMpc {
    core: Core,
}

impl_controller!(FirstMpc, ControllerKind::First, Core, run_step);

impl FirstMpc {
    /// A controller for `n` joints (buffers sized once).
    pub fn new(n: usize, settings: &MpcSettings) -> Result<Self, SettingsError> {
        Ok(Self {
            core: Core::new(n, settings, ControllerKind::First)?,
        })
    }

    /// [`Algorithm::step`](crate::control::Algorithm::step) of the first algorithm:
    /// [`Core::step_with`] with its targets ([`FirstTargets`]).
    fn run_step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        w_k: &[f64],
        preview: &[f64],
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        self.core
            .step_with(&mut FirstTargets, model, (x, w_k, preview), tau)
    }
}

/// The first algorithm's targets, Eq. (32)/(37): the output tracks `W`
/// relative to the measured `y_k`, the increments `Δq` are weighted.
struct FirstTargets;

impl StepTargets for FirstTargets {
    const INCREMENTAL: bool = true;

    fn stage_targets(
        &mut self,
        c: &mut Core,
        _x: &[f64],
        preview: &[f64],
    ) -> Result<(), StepFailure> {
        // Stage-wise: z = [y − y_k; Δq; Δq̇] (deviation from the measured
        // output, as W − F_I y_k in Eq. (37)), z_0 = [0; Δx_k]; targets:
        // w_{k+j} − y_k for the first block, 0 for Δq (Q_YW (ŷ − w), Q_ΔY Δŷ).
        let n = c.n;
        let st = c
            .backend
            .stage_mut()
            .ok_or(StepFailure::Internal("no stage-wise solver"))?;
        st.z0[..n].fill(0.0);
        st.z0[n..].copy_from_slice(&c.dx);
        for (r, w) in st.r.chunks_exact_mut(2 * n).zip(preview.chunks_exact(n)) {
            for ((r, w), y) in r[..n].iter_mut().zip(w).zip(&c.y_err) {
                *r = w - y;
            }
        }
        Ok(())
    }

    fn dense_rhs(&mut self, c: &mut Core, _x: &[f64], preview: &[f64]) -> Result<(), StepFailure> {
        let (n, nh) = (c.n, c.nh);
        let rows = nh * n;
        Core::f_times(c.pred.f1().as_slice(), &c.dx, rows, &mut c.v1);
        // F2 Δx: block running sums of F1 Δx (F2[j] = Σ_{i≤j} F1[i]).
        prefix_sums(n, &c.v1, &mut c.v2, None);
        let y = &c.y_err;
        let b = &mut c.backend.tracking_mut()?.b;
        let (b_top, b_mid) = b.split_at_mut(rows);
        for j in 0..nh {
            let o = j * n;
            for i in 0..n {
                // Eq. (37), first row: Q_YW (W − F_I y_k − F2 Δx_k)
                b_top[o + i] = c.w_top[i] * (preview[o + i] - y[i] - c.v2[o + i]);
                // second row: Q_ΔY (−F1 Δx_k); the third (Q_ΔU) is 0.
                b_mid[o + i] = -c.w_mid[i] * c.v1[o + i];
            }
        }
        Ok(())
    }
}
