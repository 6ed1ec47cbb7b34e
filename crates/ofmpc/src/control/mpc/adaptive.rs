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
//!
//! **On a real arm** ([`RealArmIdentification`], on with the plant-facing
//! settings `delay_compensation`, `friction_compensation` or
//! `state_observer`, issue 35) the identification instead:
//! * learns from the raw measured positions (not the observer's prediction,
//!   which is the model's own output), delay-aligned: with a measurement
//!   `D` samples old, the positions `q_{m−2}, q_{m−1}, q_m` (`m = k − D`) give
//!   `q̇`, `q̈` at `m − 1` by central differences, paired with the torques
//!   `½(τ_{m−2} + τ_{m−1})` applied around it, minus the drives' friction
//!   estimate at that velocity;
//! * only while the reference moves (excitation gating: at rest the data are
//!   quantization, noise and an unknown stiction) and, per joint, only while
//!   the joint slides (`|q̇_i| ≥` [`RealArmIdentification::min_joint_speed`]:
//!   there the friction is the estimate's ±20 %, at rest anything up to `F_c`);
//! * bounds the mass to [`RealArmIdentification::max_mass_kg`] (a multiple of
//!   the rated payload), never restarts the covariance (friction would trip
//!   the change detector at every reversal; the trace stays bounded by the
//!   prior's), and
//! * falls back to the nominal model while the mass's standard deviation is
//!   above [`RealArmIdentification::trust_mass_sigma_kg`] or fewer than
//!   [`RealArmIdentification::min_samples`] samples were learnt from, and
//!   gives the model a point mass (mass and centre of mass; the rotational
//!   inertia from delayed, quantized data would make a light wrist's model
//!   many times heavier than the plant).

use crate::control::algorithm::Algorithm;
use crate::control::baselines::ctc::CtcController;
use crate::control::kind::ControllerKind;
use crate::control::mpc::first::FirstMpc;
use crate::control::mpc::second::SecondMpc;
use crate::control::settings::{BaselineSettings, MpcSettings, SettingsError};
use crate::control::step::{StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;
use crate::ident::{payload_of, PayloadEstimator, PayloadParams, RlsSettings};

/// The identification for a real arm (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RealArmIdentification {
    /// Samples by which the measurement lags the control (`D`).
    pub delay: usize,
    /// Upper bound of the payload mass (kg).
    pub max_mass_kg: f64,
    /// A joint's row is used only while its speed is at least this (rad/s).
    pub min_joint_speed: f64,
    /// The model carries the estimate only once the mass's standard
    /// deviation is below this (kg); before, the nominal model.
    pub trust_mass_sigma_kg: f64,
    /// ... and only after this many samples learnt from.
    pub min_samples: u64,
    /// Torque noise standard deviation assumed per joint (N·m): the
    /// quantization's acceleration noise and the friction estimate's error,
    /// at least (the estimator's own is the ideal plant's).
    pub sigma_torque_nm: f64,
}

impl Default for RealArmIdentification {
    fn default() -> Self {
        Self {
            delay: 0,
            max_mass_kg: 1e3,
            min_joint_speed: 0.02,
            trust_mass_sigma_kg: 0.5,
            min_samples: 100,
            sigma_torque_nm: 1.0,
        }
    }
}

/// Buffers of [`RealArmIdentification`] (sized once).
#[derive(Debug, Clone)]
struct RealArm {
    cfg: RealArmIdentification,
    /// The last three measured positions, ring (3n).
    q_ring: Vec<f64>,
    measured: usize,
    /// The last `D + 2` torques, ring.
    tau_ring: Vec<f64>,
    steps: usize,
    coulomb: Vec<f64>,
    viscous: Vec<f64>,
    coulomb_velocity: f64,
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    tau: Vec<f64>,
    use_row: Vec<bool>,
}

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
    real_arm: Option<Box<RealArm>>,
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
            real_arm: None,
        })
    }

    /// Switches to the identification for a real arm (module docs): raw,
    /// delay-aligned, excitation-gated measurements, a bounded mass, no
    /// covariance restarts, the nominal model until the estimate is
    /// trusted. `rls` is the estimator's tuning (its mass bound and change
    /// threshold are replaced). Allocates; call before a run.
    pub fn set_real_arm(
        &mut self,
        cfg: RealArmIdentification,
        rls: RlsSettings,
    ) -> Result<(), SettingsError> {
        let n = self.inner.dof();
        let rls = RlsSettings {
            max_mass: cfg.max_mass_kg,
            change_threshold_nm: f64::MAX,
            sigma_torque: rls.sigma_torque.max(cfg.sigma_torque_nm),
            ..rls
        };
        self.estimator = PayloadEstimator::new(n, rls, PayloadParams::zeros())
            .map_err(SettingsError::Estimator)?;
        self.real_arm = Some(Box::new(RealArm {
            cfg,
            q_ring: vec![0.0; 3 * n],
            measured: 0,
            tau_ring: vec![0.0; (cfg.delay + 2) * n],
            steps: 0,
            coulomb: vec![0.0; n],
            viscous: vec![0.0; n],
            coulomb_velocity: crate::dynamics::friction::DEFAULT_COULOMB_VELOCITY,
            q: vec![0.0; n],
            qd: vec![0.0; n],
            qdd: vec![0.0; n],
            tau: vec![0.0; n],
            use_row: vec![false; n],
        }));
        Ok(())
    }

    /// The real-arm identification's sample (module docs): returns whether
    /// the estimator learnt.
    fn learn_real_arm(
        ra: &mut RealArm,
        estimator: &mut PayloadEstimator,
        rd: &mut crate::dynamics::RobotDynamics,
        w_k: &[f64],
        preview: &[f64],
        ts: f64,
    ) -> bool {
        let n = ra.q.len();
        let d = ra.cfg.delay;
        let moving = preview.chunks_exact(n).any(|b| b != w_k);
        if !moving || ra.measured < 3 || ra.steps < d + 2 {
            return false;
        }
        // Newest measurement q_m at slot (measured − 1) % 3.
        let slot = |back: usize| ((ra.measured - 1 - back) % 3) * n;
        let (s0, s1, s2) = (slot(0), slot(1), slot(2));
        let slots = d + 2;
        // τ_{m−1} = τ_{k−D−1}, τ_{m−2} = τ_{k−D−2}; k = steps.
        let t1 = ((ra.steps - d - 1) % slots) * n;
        let t2 = ((ra.steps - d - 2) % slots) * n;
        for i in 0..n {
            let (qm, qm1, qm2) = (ra.q_ring[s0 + i], ra.q_ring[s1 + i], ra.q_ring[s2 + i]);
            let v = (qm - qm2) / (2.0 * ts);
            ra.q[i] = qm1;
            ra.qd[i] = v;
            ra.qdd[i] = (qm - 2.0 * qm1 + qm2) / (ts * ts);
            let friction = crate::dynamics::friction::torque(
                ra.viscous[i],
                ra.coulomb[i],
                ra.coulomb_velocity,
                v,
            );
            ra.tau[i] = 0.5 * (ra.tau_ring[t1 + i] + ra.tau_ring[t2 + i]) - friction;
            ra.use_row[i] = v.abs() >= ra.cfg.min_joint_speed;
        }
        estimator.update_point(rd, &ra.q, &ra.qd, &ra.qdd, &ra.tau, &ra.use_row)
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
        if let Some(ra) = self.real_arm.as_deref_mut() {
            ra.measured = 0;
            ra.steps = 0;
            ra.tau_ring.fill(0.0);
        }
        Ok(())
    }
    fn measurement(&mut self, y: &[f64]) {
        if let Some(ra) = self.real_arm.as_deref_mut() {
            let n = ra.q.len();
            if y.len() >= n && y[..n].iter().all(|v| v.is_finite()) {
                let s = (ra.measured % 3) * n;
                ra.q_ring[s..s + n].copy_from_slice(&y[..n]);
                ra.measured += 1;
            }
        }
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
        self.inner.set_drive_model(drives)?;
        if let Some(ra) = self.real_arm.as_deref_mut() {
            if drives.coulomb_nm.len() == ra.q.len() && drives.viscous_nms.len() == ra.q.len() {
                ra.coulomb.copy_from_slice(&drives.coulomb_nm);
                ra.viscous.copy_from_slice(&drives.viscous_nms);
                ra.coulomb_velocity = drives.coulomb_velocity_rad_s;
            }
        }
        Ok(())
    }
    fn qp_status(&self) -> Option<crate::control::solvers::constrained::QpStatus> {
        self.inner.qp_status()
    }
    fn model_time(&self) -> Option<std::time::Duration> {
        self.inner.model_time()
    }
    fn set_check_budget(&mut self, checks: Option<u32>) {
        self.inner.set_check_budget(checks)
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
            let learnt = match self.real_arm.as_deref_mut() {
                Some(ra) => Self::learn_real_arm(ra, &mut self.estimator, rd, w_k, preview, ts),
                None => {
                    self.has_prev
                        && self
                            .estimator
                            .update(rd, &self.x_prev, x, &self.tau_prev, ts)
                }
            };
            if learnt {
                // A convex combination of two physical bodies is physical, so the
                // model should accept it; if it does not, the step is undone and says so.
                let rls = self.estimator.rls();
                let target = match self.real_arm.as_deref() {
                    // Fallback: the nominal model until the mass is determined.
                    Some(ra)
                        if rls.covariance()[(0, 0)].is_nan()
                            || rls.covariance()[(0, 0)].max(0.0).sqrt()
                                >= ra.cfg.trust_mass_sigma_kg
                            || rls.updates() < ra.cfg.min_samples =>
                    {
                        PayloadParams::zeros()
                    }
                    // A point mass: the rotational inertia from delayed,
                    // quantized data is not to be trusted.
                    Some(_) => rls.point_mass_estimate(),
                    None => rls.model_estimate(),
                };
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
                if let Some(ra) = self.real_arm.as_deref_mut() {
                    let n = ra.q.len();
                    let s = (ra.steps % (ra.cfg.delay + 2)) * n;
                    ra.tau_ring[s..s + n].copy_from_slice(tau);
                    ra.steps += 1;
                }
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
