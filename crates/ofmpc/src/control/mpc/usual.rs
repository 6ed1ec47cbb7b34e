//! The usual (positional) predictive controller of Eq. (43), the paper's
//! baseline: `min ‖Q_YW (F x_k + G U − W)‖² + ‖Q_U U‖²`, solved as the
//! least-squares system `[Q_YW G; Q_U] U = [Q_YW (W − F x_k); 0]` with
//! `F = [CA; …; CA^N]`, `G[j,l] = C A^{j−l} B`. It has no integrator and keeps
//! a steady offset under a model mismatch.

use crate::control::kind::ControllerKind;
use crate::control::mpc::core::{impl_controller, Core, StepTargets};
use crate::control::settings::{MpcSettings, SettingsError};
use crate::control::step::{StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;

/// The usual MPC of Eq. (43). Allocation-free [`Algorithm::step`](crate::control::Algorithm::step).
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

    /// `Q_u` × `scale[i]` on the joints that hold on the friction's stiff
    /// damper ([`Core::set_hold_input_scale`]; `dob-mpc`'s stiffer hold).
    pub(crate) fn set_hold_input_scale(&mut self, scale: Vec<f64>) -> Result<(), SettingsError> {
        self.core.set_hold_input_scale(scale)
    }

    /// [`Algorithm::step`](crate::control::Algorithm::step) of the usual algorithm:
    /// [`Core::step_with`] with its targets ([`UsualTargets`]).
    fn run_step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        w_k: &[f64],
        preview: &[f64],
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        self.core
            .step_with(&mut UsualTargets, model, (x, w_k, preview), tau)
    }
}

/// The usual algorithm's targets, Eq. (43): the positional outputs track
/// `W` from the full state.
struct UsualTargets;

impl StepTargets for UsualTargets {
    const INCREMENTAL: bool = false;

    fn stage_targets(
        &mut self,
        c: &mut Core,
        x: &[f64],
        preview: &[f64],
    ) -> Result<(), StepFailure> {
        // Stage-wise: z = [q; q̇], z_0 = x_k, target of q at stage j is w_{k+j}.
        let st = c
            .backend
            .stage_mut()
            .ok_or(StepFailure::Internal("no stage-wise solver"))?;
        st.z0.copy_from_slice(x);
        st.r.copy_from_slice(preview);
        Ok(())
    }

    fn dense_rhs(&mut self, c: &mut Core, x: &[f64], preview: &[f64]) -> Result<(), StepFailure> {
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
        Ok(())
    }
}
