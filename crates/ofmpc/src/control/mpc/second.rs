//! The second incremental algorithm, Eq. (33)–(34) and (39): two integrators
//! (`u_k = u_{k−1} + Δu_k` and the aggregated error
//! `ē_k = ē_{k−1} + (w_k − y_k)`, Eq. (17)), cost
//! `Σ ‖Q_yw (ŷ_{k+j} − w_{k+j} − ê_{k+j−1})‖² + ‖Q_Δy Δŷ‖² + ‖Q_Δu Δu‖²`,
//! solved as
//!
//! ```text
//! [Q_YW (G2 + G3); Q_ΔY G1; Q_ΔU] ΔU =
//!     [Q_YW (W + W_s + F_I ē_k − (F_I + F_II) y_k − (F2 + F3) Δx_k); −Q_ΔY F1 Δx_k; 0].
//! ```
//!
//! It removes the steady error for constant and ramp references.

use crate::control::kind::ControllerKind;
use crate::control::mpc::core::{impl_controller, Core, StepTargets};
use crate::control::mpc::prediction::prefix_sums;
use crate::control::settings::{MpcSettings, SettingsError};
use crate::control::step::{StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;

/// The second algorithm, Eq. (34)/(39). Allocation-free [`Algorithm::step`](crate::control::Algorithm::step).
#[derive(Debug, Clone)]
pub struct SecondMpc {
    core: Core,
    ws: Vec<f64>,
}

impl_controller!(SecondMpc, ControllerKind::Second, Core, run_step);

impl SecondMpc {
    /// A controller for `n` joints (buffers sized once).
    pub fn new(n: usize, settings: &MpcSettings) -> Result<Self, SettingsError> {
        Ok(Self {
            core: Core::new(n, settings, ControllerKind::Second)?,
            ws: vec![0.0; n],
        })
    }

    /// [`Algorithm::step`](crate::control::Algorithm::step) of the second algorithm:
    /// [`Core::step_with`] with its targets ([`SecondTargets`]).
    fn run_step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        w_k: &[f64],
        preview: &[f64],
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        self.core.step_with(
            &mut SecondTargets { ws: &mut self.ws },
            model,
            (x, w_k, preview),
            tau,
        )
    }
}

/// The second algorithm's targets, Eq. (34)/(39): the aggregated error
/// `ē_k` joins the output's tracking (its running sum `W_s` in the stacked
/// form).
struct SecondTargets<'a> {
    /// `W_s` of Eq. (39), a work buffer of n values.
    ws: &'a mut [f64],
}

impl StepTargets for SecondTargets<'_> {
    const INCREMENTAL: bool = true;

    fn begin(&mut self, c: &mut Core, _x: &[f64], w_k: &[f64], preview: &[f64]) {
        let n = c.n;
        let y = &c.y_err;
        // Eq. (34): e_k = w_k − y_k, ē_k = ē_{k−1} + e_k (committed on success).
        for (((e, prev), w), yi) in c.ebar_new.iter_mut().zip(&c.ebar).zip(w_k).zip(y) {
            *e = prev + (w - yi);
        }
        if c.settings.friction_compensation {
            restart_in_hold(
                n,
                (w_k, y, preview),
                c.settings.hold_ebar_scale,
                &mut c.ebar_new,
            );
        }
    }

    fn stage_targets(
        &mut self,
        c: &mut Core,
        _x: &[f64],
        preview: &[f64],
    ) -> Result<(), StepFailure> {
        // Stage-wise: z = [s; Δq; y − y_k; Δq̇] with s_j = Σ_{i≤j}(ŷ_{k+i} −
        // w_{k+i}) − ē_k, so Q_YW s_j is the first row of Eq. (39):
        // z_0 = [−ē_k; Δq_k; 0; Δq̇_k], c_j = [y_k − w_{k+j+1}; 0; 0; 0]
        // (s⁺ = s + (y⁺ − y_k) + (y_k − w)), targets 0.
        let n = c.n;
        let y = &c.y_err;
        let st = c
            .backend
            .stage_mut()
            .ok_or(StepFailure::Internal("no stage-wise solver"))?;
        st.z0[..n]
            .iter_mut()
            .zip(&c.ebar_new)
            .for_each(|(z, e)| *z = -e);
        st.z0[n..2 * n].copy_from_slice(&c.dx[..n]);
        st.z0[2 * n..3 * n].fill(0.0);
        st.z0[3 * n..].copy_from_slice(&c.dx[n..]);
        for (cj, w) in st.c.chunks_exact_mut(4 * n).zip(preview.chunks_exact(n)) {
            for ((c, w), y) in cj[..n].iter_mut().zip(w).zip(y) {
                *c = y - w;
            }
        }
        Ok(())
    }

    fn dense_rhs(&mut self, c: &mut Core, _x: &[f64], preview: &[f64]) -> Result<(), StepFailure> {
        let (n, nh) = (c.n, c.nh);
        let rows = nh * n;
        let y = &c.y_err;
        // v1 = F1 Δx, v2 = (F2 + F3) Δx.
        Core::f_times(c.pred.f1().as_slice(), &c.dx, rows, &mut c.v1);
        // F2 Δx, F3 Δx by block running sums of F1 Δx (F2[j] = Σ_{i≤j} F1[i],
        // F3[j] = F3[j−1] + F2[j−1]).
        prefix_sums(n, &c.v1, &mut c.v2, Some(&mut c.v3));
        for (a, b) in c.v2.iter_mut().zip(&c.v3) {
            *a += b;
        }
        // W_s block j = Σ_{i<j} w_{k+i}: running sum.
        self.ws.fill(0.0);
        let b = &mut c.backend.tracking_mut()?.b;
        let (b_top, b_mid) = b.split_at_mut(rows);
        for j in 1..=nh {
            let o = (j - 1) * n;
            let jf = j as f64; // F_I + F_II has block j = j·I
            for i in 0..n {
                b_top[o + i] = c.w_top[i]
                    * (preview[o + i] + self.ws[i] + c.ebar_new[i] - jf * y[i] - c.v2[o + i]);
                b_mid[o + i] = -c.w_mid[i] * c.v1[o + i];
            }
            for (s, w) in self.ws.iter_mut().zip(&preview[o..o + n]) {
                *s += w;
            }
        }
        Ok(())
    }

    fn commit(&mut self, c: &mut Core) {
        c.commit_ebar();
    }
}

/// Friction (hold) rule of the aggregated error, on with
/// [`MpcSettings::friction_compensation`]: on a joint whose reference rests
/// over the whole horizon (`w_{k+j} = w_k`, `j = 1..N`, exactly), `ē_k`
/// restarts from the current error, `ē_k = w_k − y_k`, instead of carrying the
/// past sum.
///
/// Why: under Coulomb friction the sum of the past errors is what drives the
/// second algorithm's stick–slip hunting at rest (it keeps asking for the
/// integral to be paid back, i.e. an overshoot to the other side, where the
/// joint sticks again). The incremental input `u_k = u_{k−1} + Δu_k` alone
/// keeps the hold offset-free (as in the first algorithm: at an equilibrium
/// `ē_k = e_k` must vanish for `Δu_k = 0` to be optimal); while the reference
/// moves, `ē` is the paper's, so ramps stay offset-free.
///
/// `scale` ([`MpcSettings::hold_ebar_scale`], in `[0, 1]`): the restart is
/// `ē_k = scale·(w_k − y_k)`; 1 is the rule above exactly, 0 drops the
/// current error's second entry into the tracking rows (at rest the second
/// algorithm is then the first).
fn restart_in_hold(
    n: usize,
    (w_k, y, preview): (&[f64], &[f64], &[f64]),
    scale: f64,
    ebar: &mut [f64],
) {
    for (i, ((e, w), yi)) in ebar.iter_mut().zip(w_k).zip(y).enumerate() {
        if preview.chunks_exact(n).all(|p| p[i] == *w) {
            *e = if scale == 1.0 {
                w - yi
            } else {
                scale * (w - yi)
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::restart_in_hold;

    #[test]
    fn aggregated_error_restarts_only_where_the_reference_rests_over_the_horizon() {
        // Two joints, N = 3: joint 0 rests, joint 1 moves at the last step.
        let w = [1.0, 2.0];
        let y = [0.9, 1.5];
        let preview = [1.0, 2.0, 1.0, 2.0, 1.0, 2.1];
        let mut ebar = [5.0, 7.0];
        restart_in_hold(2, (&w, &y, &preview), 1.0, &mut ebar);
        assert!((ebar[0] - 0.1).abs() < 1e-15);
        assert_eq!(ebar[1], 7.0);
        // A factor scales the restart on the resting joint only.
        let mut ebar = [5.0, 7.0];
        restart_in_hold(2, (&w, &y, &preview), 0.5, &mut ebar);
        assert!((ebar[0] - 0.05).abs() < 1e-15);
        assert_eq!(ebar[1], 7.0);
        let mut ebar = [5.0, 7.0];
        restart_in_hold(2, (&w, &y, &preview), 0.0, &mut ebar);
        assert_eq!(ebar, [0.0, 7.0]);
    }
}
