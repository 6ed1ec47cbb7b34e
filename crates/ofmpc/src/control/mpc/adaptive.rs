//! Adaptive variants of the incremental algorithms: the first or second
//! algorithm whose robot model carries a payload identified online; and the
//! same for the computed-torque baseline (`ctc-adaptive`, the classic
//! adaptive robot controller: [`crate::control::baselines::ctc`] on the identified model).
//!
//! At every sample `k`, before the algorithm's own step, the payload
//! estimator ([`crate::ident::PayloadEstimator`]) takes the period
//! `[t_{k−1}, t_k]` — the measured states at both ends and the torque
//! `τ_{k−1}` this controller applied — updates `π̂` by recursive least squares
//! and writes the physically consistent estimate into the controller's model
//! ([`crate::robot::Robot::set_payload`] through
//! [`JointSpaceDynamics::robot_dynamics_mut`]). The algorithm then builds its
//! prediction model (Eq. (6)–(13)) and the torque `τ_k = H u_k + g`
//! (Eq. (15)) from that model. The integrators of the algorithm still remove
//! any remaining offset; the identification keeps the inertia ratio
//! `α = H_model/H_plant` near 1, inside the stability interval of the tuning
//! (`ofmpc analyze stability`).
//!
//! Assumes the torque the controller computes is the torque applied (no
//! saturation, no friction the model leaves out): those would bias `π̂`.

use crate::control::algorithm::Algorithm;
use crate::control::baselines::ctc::CtcController;
use crate::control::kind::ControllerKind;
use crate::control::mpc::first::FirstMpc;
use crate::control::mpc::second::SecondMpc;
use crate::control::settings::{BaselineSettings, MpcSettings, SettingsError};
use crate::control::step::{StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;
use crate::ident::{payload_of, PayloadEstimator, PayloadParams, RlsSettings};

/// The first or second algorithm with online payload identification.
pub struct AdaptiveMpc {
    kind: ControllerKind,
    inner: Box<dyn Algorithm + Send>,
    estimator: PayloadEstimator,
    x_prev: Vec<f64>,
    tau_prev: Vec<f64>,
    has_prev: bool,
    /// What the model carries, approaching the estimate (see [`MODEL_RATE`]).
    model_pi: PayloadParams,
}

/// Per sample, the model's payload moves this fraction of the way to the
/// estimate (a first-order filter, about 23 ms at Ts = 10 ms). The incremental
/// algorithms tolerate a model a little heavier than the plant only
/// (α ≤ 1.09 for the second with the paper's tuning) and a light one much
/// better (α ≥ 0.78): approached from below, an early overshoot of the
/// estimate (data from a fast transient) does not reach the model at once.
pub const MODEL_RATE: f64 = 0.35;

impl std::fmt::Debug for AdaptiveMpc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AdaptiveMpc")
            .field("kind", &self.kind)
            .field("mass_estimate", &self.estimator.rls().mass())
            .finish()
    }
}

impl AdaptiveMpc {
    /// `kind` must be [`ControllerKind::FirstAdaptive`],
    /// [`ControllerKind::SecondAdaptive`] or [`ControllerKind::CtcAdaptive`]
    /// (the plain kinds are taken as their adaptive variant; the usual MPC,
    /// the PID and the disturbance-observer MPC have none and are refused).
    /// `baselines` gives `ctc-adaptive` its bandwidth
    /// ([`BaselineSettings::ctc_bandwidth`]); the predictive kinds do not
    /// read it.
    pub fn new(
        kind: ControllerKind,
        n: usize,
        settings: &MpcSettings,
        baselines: &BaselineSettings,
    ) -> Result<Self, SettingsError> {
        Self::with_estimator(kind, n, settings, baselines, RlsSettings::default())
    }

    /// As [`Self::new`] with the estimator's tuning.
    pub fn with_estimator(
        kind: ControllerKind,
        n: usize,
        settings: &MpcSettings,
        baselines: &BaselineSettings,
        rls: RlsSettings,
    ) -> Result<Self, SettingsError> {
        let (kind, inner): (ControllerKind, Box<dyn Algorithm + Send>) = match kind {
            ControllerKind::First | ControllerKind::FirstAdaptive => (
                ControllerKind::FirstAdaptive,
                Box::new(FirstMpc::new(n, settings)?),
            ),
            ControllerKind::Second | ControllerKind::SecondAdaptive => (
                ControllerKind::SecondAdaptive,
                Box::new(SecondMpc::new(n, settings)?),
            ),
            ControllerKind::Ctc | ControllerKind::CtcAdaptive => (
                ControllerKind::CtcAdaptive,
                Box::new(CtcController::new(n, settings, baselines)?),
            ),
            ControllerKind::Usual | ControllerKind::Pid | ControllerKind::DobMpc => {
                return Err(SettingsError::NoAdaptiveVariant)
            }
        };
        let estimator = PayloadEstimator::new(n, rls, PayloadParams::zeros())
            .map_err(SettingsError::Estimator)?;
        Ok(Self {
            kind,
            inner,
            estimator,
            x_prev: vec![0.0; 2 * n],
            tau_prev: vec![0.0; n],
            has_prev: false,
            model_pi: PayloadParams::zeros(),
        })
    }

    /// The payload estimator (its current estimate, covariance, restarts).
    pub fn estimator(&self) -> &PayloadEstimator {
        &self.estimator
    }
}

impl Algorithm for AdaptiveMpc {
    fn kind(&self) -> ControllerKind {
        self.kind
    }
    fn dof(&self) -> usize {
        self.inner.dof()
    }
    fn horizon(&self) -> usize {
        self.inner.horizon()
    }
    fn settings(&self) -> &MpcSettings {
        self.inner.settings()
    }
    fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure> {
        self.inner.reset(x0)?;
        self.estimator.rls_mut().reset();
        self.has_prev = false;
        self.model_pi = PayloadParams::zeros();
        Ok(())
    }
    fn input(&self) -> &[f64] {
        self.inner.input()
    }
    fn increments(&self) -> &[f64] {
        self.inner.increments()
    }
    fn predicted_outputs(&mut self, out: &mut [f64]) -> bool {
        self.inner.predicted_outputs(out)
    }
    fn set_drive_model(
        &mut self,
        drives: &crate::control::drive_model::DriveModel,
    ) -> Result<(), SettingsError> {
        self.inner.set_drive_model(drives)
    }
    fn qp_status(&self) -> Option<crate::control::solvers::constrained::QpStatus> {
        self.inner.qp_status()
    }
    fn payload_estimate(&self) -> Option<f64> {
        Some(self.model_pi[0])
    }
    fn step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        input: &crate::control::step::StepInput<'_>,
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        let (x, w_k, preview) = (input.x, input.w_k, input.preview);
        let ts = self.inner.settings().ts;
        let saved_rls = *self.estimator.rls();
        let saved_pi = self.model_pi;
        let saved_payload;
        {
            let Some(rd) = model.robot_dynamics_mut() else {
                return Err(StepFailure::NoRigidBodyModel);
            };
            saved_payload = rd.robot().payload().copied();
            if self.has_prev
                && self
                    .estimator
                    .update(rd, &self.x_prev, x, &self.tau_prev, ts)
            {
                // A convex combination of two physical bodies is physical, so the
                // model should accept it; if it does not, the step is undone and says so.
                let target = self.estimator.rls().model_estimate();
                self.model_pi += (target - self.model_pi) * MODEL_RATE;
                if rd
                    .robot_mut()
                    .set_payload(payload_of(&self.model_pi))
                    .is_err()
                {
                    *self.estimator.rls_mut() = saved_rls;
                    self.model_pi = saved_pi;
                    return Err(StepFailure::PayloadRefused);
                }
            }
        }
        match self.inner.step(
            model,
            &crate::control::step::StepInput { x, w_k, preview },
            tau,
        ) {
            Ok(info) => {
                self.x_prev.copy_from_slice(x);
                self.tau_prev.copy_from_slice(tau);
                self.has_prev = true;
                Ok(info)
            }
            Err(e) => {
                *self.estimator.rls_mut() = saved_rls;
                self.model_pi = saved_pi;
                // The payload it had before this step, which it accepted then.
                if let Some(rd) = model.robot_dynamics_mut() {
                    if rd.robot_mut().set_payload(saved_payload).is_err() {
                        return Err(StepFailure::PayloadRefused);
                    }
                }
                Err(e)
            }
        }
    }
}
