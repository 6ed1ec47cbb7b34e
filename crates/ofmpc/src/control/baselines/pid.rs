//! Baseline: independent joint PID with gravity compensation and velocity
//! feed-forward, the controller the paper's introduction names.
//!
//! ```text
//! τ_k = g(q_k) + D (kp e_k + kd ė_k + ki z_k),   D = diag(H_11(q_0), …, H_nn(q_0)),
//! e_k = w_k − q_k,   ė_k = v_ref,k − q̇_k,   z_{k+1} = z_k + Ts e_k,
//! ```
//!
//! with the nominal model's gravity at the measured `q_k`, its inertia's
//! diagonal at the start pose `q_0` (the state of the last
//! [`Algorithm::reset`](crate::control::Algorithm::reset)), the reference velocity
//! of [`crate::control::baselines::baseline`] (module docs) and the gains of a discrete triple
//! pole at `e^(−ωn·Ts)` ([`crate::control::baselines::baseline`]), `ωn` =
//! [`crate::control::BaselineSettings::pid_bandwidth`] (default 60 rad/s). No
//! acceleration feed-forward and no coupling: the inertia the law leaves out
//! (off-diagonal, pose-dependent, the payload's) is a disturbance its
//! integrator removes at rest. With torque limits the torque is clipped
//! and the clipped joint's integral frozen (anti-windup).

use crate::control::baselines::baseline::{JointLawCore, Law};
use crate::control::kind::ControllerKind;
use crate::control::mpc::core::impl_controller;
use crate::control::settings::{bandwidths, BaselineSettings, MpcSettings, SettingsError};

/// The PID baseline. Allocation-free [`Algorithm::step`](crate::control::Algorithm::step).
#[derive(Debug, Clone)]
pub struct PidController {
    core: JointLawCore,
}

impl_controller!(PidController, ControllerKind::Pid, JointLawCore);

impl PidController {
    /// A controller for `n` joints with `baselines.pid_bandwidth` (and
    /// `settings.ts`, `settings.horizon` for the preview it reads).
    pub fn new(
        n: usize,
        settings: &MpcSettings,
        baselines: &BaselineSettings,
    ) -> Result<Self, SettingsError> {
        let wn = bandwidths("pid_bandwidth", &baselines.pid_bandwidth, n)?;
        Ok(Self {
            core: JointLawCore::new(Law::Pid, n, settings, &wn)?,
        })
    }
}
