//! Baseline: computed-torque control on the nominal model with PID on the
//! error and the reference's velocity and acceleration as feed-forward.
//!
//! ```text
//! τ_k = H(q_k) (a_ref,k + kp e_k + kd ė_k + ki z_k) + C(q_k, q̇_k) q̇_k + g(q_k),
//! e_k = w_k − q_k,   ė_k = v_ref,k − q̇_k,   z_{k+1} = z_k + Ts e_k
//! ```
//!
//! (Spong, Hutchinson & Vidyasagar, *Robot Modeling and Control*, §8.4,
//! with an integral term): with an exact model every joint's error is the
//! sampled double integrator of [`crate::control::baselines::baseline`], whose gains place a
//! triple pole at `e^(−ωn·Ts)`, `ωn` =
//! [`crate::control::BaselineSettings::ctc_bandwidth`] (default 150 rad/s);
//! `v_ref`, `a_ref` from the samples ([`crate::control::baselines::baseline`]). A payload the
//! model leaves out acts as an input disturbance that the integrator
//! removes at rest. With torque limits the torque is clipped and the clipped
//! joint's integral frozen (anti-windup).
//!
//! The stiffer hold (`ctc_hold_gain_scale`, issue 35): on a joint that holds
//! on the friction's stiff damper `b = F_c/v_s`
//! ([`crate::control::dead_zone::creeps_at_rest`]) the loop is
//! `b s² + M kp s + M ki = 0`, damped by `M kp / (2 √(M ki b))` (about 0.1 on
//! the real-arm preset's wrist, which then rings by 4–8 encoder counts);
//! `kp` × the factor there raises that damping in proportion.

use crate::control::baselines::baseline::{JointLawCore, Law};
use crate::control::kind::ControllerKind;
use crate::control::mpc::core::impl_controller;
use crate::control::settings::{
    bandwidths, hold_gain_scales, BaselineSettings, MpcSettings, SettingsError,
};

/// The computed-torque baseline. Allocation-free [`Algorithm::step`](crate::control::Algorithm::step).
#[derive(Debug, Clone)]
pub struct CtcController {
    core: JointLawCore,
}

impl_controller!(CtcController, ControllerKind::Ctc, JointLawCore);

impl CtcController {
    /// A controller for `n` joints with `baselines.ctc_bandwidth` and
    /// `baselines.ctc_hold_gain_scale`.
    pub fn new(
        n: usize,
        settings: &MpcSettings,
        baselines: &BaselineSettings,
    ) -> Result<Self, SettingsError> {
        let wn = bandwidths("ctc_bandwidth", &baselines.ctc_bandwidth, n)?;
        let mut core = JointLawCore::new(Law::Ctc, n, settings, &wn)?;
        core.set_hold_gain(hold_gain_scales(
            "ctc_hold_gain_scale",
            &baselines.ctc_hold_gain_scale,
            n,
        )?);
        Ok(Self { core })
    }
}
