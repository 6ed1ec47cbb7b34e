//! The usual (positional) predictive controller of Eq. (43), the paper's
//! baseline: `min ‖Q_YW (F x_k + G U − W)‖² + ‖Q_U U‖²`, solved as the
//! least-squares system `[Q_YW G; Q_U] U = [Q_YW (W − F x_k); 0]` with
//! `F = [CA; …; CA^N]`, `G[j,l] = C A^{j−l} B`. It has no integrator and keeps
//! a steady offset under a model mismatch.

use super::core::{impl_controller, Core};
use super::settings::{MpcSettings, SettingsError};
use super::{ControllerKind, StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;

/// The usual MPC of Eq. (43). Allocation-free [`Algorithm::step`](super::Algorithm::step).
#[derive(Debug, Clone)]
pub struct UsualMpc {
    core: Core,
}

impl_controller!(UsualMpc, ControllerKind::Usual, Core, run_step);

impl UsualMpc {
    /// A controller for `n` joints (buffers sized once).
    pub fn new(n: usize, settings: &MpcSettings) -> Result<Self, SettingsError> {
        Ok(Self {
            core: Core::new(n, settings, ControllerKind::Usual)?,
        })
    }

    /// [`Algorithm::step`](super::Algorithm::step) of the usual algorithm.
    fn run_step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        w_k: &[f64],
        preview: &[f64],
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        let c = &mut self.core;
        c.prepare(model, x, w_k, preview, tau.len())?;
        if let Some(st) = c.backend.stage_mut() {
            // Stage-wise: z = [q; q̇], z_0 = x_k, target of q at stage j is w_{k+j}.
            st.z0.copy_from_slice(x);
            st.r.copy_from_slice(preview);
            c.fill_stage_model()?;
            let info = c.solve_structured()?;
            return c.finish(x, false, info, tau);
        }
        c.build_matrix();
        let (n, nh) = (c.n, c.nh);
        let rows = nh * n;
        // v1 = F x_k (positional prediction from the full state).
        Core::f_times(c.pred.f1().as_slice(), x, rows, &mut c.v1);
        let b = c.backend.dense_mut()?.lsq.rhs_mut();
        b.fill(0.0);
        for j in 1..=nh {
            let base = (nh - j) * 2 * n; // level N − j: [Q_YW rows; Q_U rows]
            let o = (j - 1) * n;
            for i in 0..n {
                b[base + i] = c.w_top[i] * (preview[o + i] - c.v1[o + i]);
            }
        }
        let info = c.solve()?;
        c.finish(x, false, info, tau)
    }
}
