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
//! **With a position or velocity output** (`MpcSettings::output`, an
//! interface that closes its own joint loop) the torque the arm receives is
//! the drive's own (its loop on the vendor's model), not `τ_k`, so the
//! regression `τ_k = Y π` has no valid left-hand side — fed `τ_k`, the
//! estimate ran to the mass bound (1000 kg) through the simulated ABB EGM
//! and UR servoj interfaces. So:
//! * when the interface **reports the torque it applied** over each period
//!   ([`Algorithm::applied_torque`], `Controller::set_applied_torque`; the
//!   drives' joint torques or currents that UR RTDE, KUKA FRI or libfranka
//!   stream) the regression uses it instead of `τ_{k−1}`, and the model
//!   follows the estimate as with a torque output; the command then carries
//!   the payload to the drive as a torque feed-forward
//!   (`control/command.rs`, `StepOutput::tau_command`: the drive's loop on
//!   its nominal model would otherwise carry the load with its following
//!   error);
//! * without it, the identification is off, the model keeps its nominal
//!   payload and the adaptive kind runs as its base algorithm, to the bit,
//!   and reports no estimate ([`Algorithm::payload_estimate`] is `None`).
//!
//! **On a real arm** ([`RealArmIdentification`], on with the plant-facing
//! settings `delay_compensation`, `friction_compensation` or
//! `state_observer`, issue 35) the identification instead:
//! * learns from the raw measured positions (not the observer's prediction,
//!   which is the model's own output), delay-aligned: with a measurement
//!   `D` samples old, the positions `q_{m−2W}, q_{m−W}, q_m` (`m = k − D`,
//!   `W` samples spanning [`RealArmIdentification::window_s`]) give `q̇`,
//!   `q̈` at `m − W` by central differences over `W` periods, paired with the
//!   torques applied around it through the same filter ([`window_weight`];
//!   `½(τ_{m−2} + τ_{m−1})` for `W = 1`), minus the drives' friction
//!   estimate at that velocity; one sample in `W` is learnt from (at
//!   Ts = 10 ms `W = 1`: the differences over one period; no acceleration
//!   over 1 ms at 1 kHz, where one encoder count would be 6 rad/s²);
//! * only while the reference moves (excitation gating: at rest the data are
//!   quantization, noise and an unknown stiction; with
//!   [`RealArmIdentification::at_rest`] also at rest) and, per joint, only while
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
    /// The differences span `W = max(1, round(window_s / Ts))` samples
    /// (s): one encoder count `δ` is an acceleration error of `δ/(W·Ts)²`,
    /// so at high rates the regressor is built over several periods
    /// (10 ms: `W = 1` at Ts = 10 ms, `W = 10` at 1 kHz).
    pub window_s: f64,
    /// Largest distance of the payload's centre of mass from the flange (m)
    /// the model is given: a point mass further out is moved in along its
    /// direction (its mass kept). `0`: no bound (and the model's payload
    /// follows the estimate at the ideal plant's rate, 0.35 of the way per
    /// sample).
    pub max_com_m: f64,
    /// With `max_com_m > 0`: the time constant (s) with which the model's
    /// payload follows the estimate (a first-order filter on the samples
    /// learnt from), so that a burst of the estimate over a fast transient
    /// does not reach the model.
    pub model_time_s: f64,
    /// Also learn while the reference rests, from the joints whose speed is
    /// at least [`Self::min_joint_speed`] (default off: only while the
    /// reference moves).
    pub at_rest: bool,
    /// The model's point mass from the recursion's unconstrained estimate
    /// (mass clipped to `[0, max_mass_kg]`, first moments) instead of the
    /// projected one (default off; `MpcSettings::identification_raw_mass`).
    pub raw_mass: bool,
}

/// The weight of the torque held over the `j`-th period on either side of
/// the centre of a window of `w` periods (`j = 1..=w`): the central second
/// difference `(q(t+h) − 2q(t) + q(t−h))/h²`, `h = w·Ts`, is exactly the mean
/// of `q̈` under the triangle `(h − |s|)/h²`; these are that triangle's
/// integrals over the periods, so the torque passes through the same filter
/// as the acceleration (they sum to 1 over both sides; `½` each for `w = 1`).
pub(crate) fn window_weight(j: usize, w: usize) -> f64 {
    let (j, w) = (j as f64, w as f64);
    (2.0 * w - 2.0 * j + 1.0) / (2.0 * w * w)
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
            window_s: 0.01,
            max_com_m: 0.0,
            model_time_s: 0.5,
            at_rest: false,
            raw_mass: false,
        }
    }
}

/// Buffers of [`RealArmIdentification`] (sized once).
#[derive(Debug, Clone)]
struct RealArm {
    cfg: RealArmIdentification,
    /// The window in samples (`W`).
    window: usize,
    /// Per sample, the model moves this fraction of the way to `target`:
    /// [`MODEL_RATE`] at `W = 1`, else `1 − (1 − MODEL_RATE)^(1/W)` at every
    /// sample (the same time constant).
    model_rate: f64,
    /// The model's target at the last learnt sample.
    target: Option<PayloadParams>,
    /// The payload the tuning assumes ([`MpcSettings::model_payload_kg`], a
    /// point mass at the flange centre): the model's until the estimate is
    /// trusted, and its fallback.
    nominal: PayloadParams,
    /// The last `2W + 1` measured positions, ring.
    q_ring: Vec<f64>,
    measured: usize,
    /// The last `D + 2W` torques, ring.
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
    /// The identification runs on the controller's own torque (a torque
    /// output); off with a position or velocity output (module docs).
    identify: bool,
    /// Whether the drives' applied torque ([`Algorithm::applied_torque`],
    /// written where the identification reads the last period's torque)
    /// came for this step, and whether the interface has reported it since
    /// the reset: then the identification runs on it, also through a
    /// position or velocity output.
    applied_fresh: bool,
    reported: bool,
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
            identify: settings.output.is_torque(),
            applied_fresh: false,
            reported: false,
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
        let ts = self.inner.settings().ts;
        let window = if cfg.window_s.is_finite() && ts > 0.0 {
            ((cfg.window_s / ts).round() as usize).clamp(1, 1000)
        } else {
            1
        };
        let rls = RlsSettings {
            max_mass: cfg.max_mass_kg,
            change_threshold_nm: f64::MAX,
            sigma_torque: rls.sigma_torque.max(cfg.sigma_torque_nm),
            ..rls
        };
        self.estimator = PayloadEstimator::new(n, rls, PayloadParams::zeros())
            .map_err(SettingsError::Estimator)?;
        // The nominal model is the one built (zero unless the tuning centres
        // the model in a payload range).
        let nominal = point_mass(
            self.inner.settings().model_payload_kg,
            nalgebra::Vector3::zeros(),
        );
        self.model_pi = nominal;
        self.real_arm = Some(Box::new(RealArm {
            cfg,
            window,
            // With a bound on the centre of mass, the model follows the
            // estimate with the time constant `model_time_s`.
            model_rate: if cfg.max_com_m > 0.0 && cfg.model_time_s > 0.0 {
                1.0 - (-ts / cfg.model_time_s).exp()
            } else if window == 1 {
                MODEL_RATE
            } else {
                1.0 - (1.0 - MODEL_RATE).powf(1.0 / window as f64)
            },
            target: None,
            nominal,
            q_ring: vec![0.0; (2 * window + 1) * n],
            measured: 0,
            tau_ring: vec![0.0; (cfg.delay + 2 * window) * n],
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
        let (d, w) = (ra.cfg.delay, ra.window);
        let moving = preview.chunks_exact(n).any(|b| b != w_k);
        if !(moving || ra.cfg.at_rest)
            || ra.measured < 2 * w + 1
            || ra.steps < d + 2 * w
            || !ra.measured.is_multiple_of(w)
        {
            return false;
        }
        // Newest measurement q_m at slot (measured − 1) % (2W + 1).
        let q_slots = 2 * w + 1;
        let slot = |back: usize| ((ra.measured - 1 - back) % q_slots) * n;
        let (s0, s1, s2) = (slot(0), slot(w), slot(2 * w));
        let h = w as f64 * ts;
        for i in 0..n {
            let (qm, qm1, qm2) = (ra.q_ring[s0 + i], ra.q_ring[s1 + i], ra.q_ring[s2 + i]);
            let v = (qm - qm2) / (2.0 * h);
            ra.q[i] = qm1;
            ra.qd[i] = v;
            ra.qdd[i] = (qm - 2.0 * qm1 + qm2) / (h * h);
            let friction = crate::dynamics::friction::torque(
                ra.viscous[i],
                ra.coulomb[i],
                ra.coulomb_velocity,
                v,
            );
            ra.tau[i] = Self::window_torque(ra, i) - friction;
            ra.use_row[i] = v.abs() >= ra.cfg.min_joint_speed;
        }
        estimator.update_point(rd, &ra.q, &ra.qd, &ra.qdd, &ra.tau, &ra.use_row)
    }

    /// Joint `i`'s torque around the window's centre `c = m − W` through the
    /// acceleration's filter ([`window_weight`]): `τ_{c−j}` (held over
    /// `[c−j, c−j+1]`) and `τ_{c+j−1}` (over `[c+j−1, c+j]`), `j = 1..=W`;
    /// with `c = k − D − W` (`k` = steps), all within the ring's `D + 2W`.
    fn window_torque(ra: &RealArm, i: usize) -> f64 {
        let n = ra.q.len();
        let (d, w) = (ra.cfg.delay, ra.window);
        let slots = d + 2 * w;
        let c = ra.steps - d - w;
        let at = |t: usize| ra.tau_ring[(t % slots) * n + i];
        (1..=w).fold(0.0, |acc, j| {
            let wj = window_weight(j, w);
            acc + wj * at(c - j) + wj * at(c + j - 1)
        })
    }

    /// What the model should carry: the estimate; on a real arm (`cfg`) the
    /// nominal model (the payload the tuning assumes) until the mass is
    /// determined, then a point mass (the rotational inertia from delayed,
    /// quantized data is not to be trusted) with its centre of mass within
    /// `max_com_m` of the flange.
    fn model_target(
        rls: &crate::ident::PayloadRls,
        cfg: Option<(&RealArmIdentification, PayloadParams)>,
    ) -> PayloadParams {
        let p00 = rls.covariance()[(0, 0)];
        match cfg {
            Some((cfg, nominal))
                if p00.is_nan()
                    || p00.max(0.0).sqrt() >= cfg.trust_mass_sigma_kg
                    || rls.updates() < cfg.min_samples =>
            {
                nominal
            }
            Some((cfg, _)) if cfg.raw_mass => {
                bound_com(raw_point_mass(rls, cfg.max_mass_kg), cfg.max_com_m)
            }
            Some((cfg, _)) => bound_com(rls.point_mass_estimate(), cfg.max_com_m),
            None => rls.model_estimate(),
        }
    }

    /// The payload estimator (its current estimate, covariance, restarts).
    pub fn estimator(&self) -> &PayloadEstimator {
        &self.estimator
    }
}

/// The point mass of the recursion's unconstrained estimate: its mass
/// clipped to `[0, max_mass]`, its centre of mass `h/m` (first moments `h`);
/// nothing when the mass is not positive.
fn raw_point_mass(rls: &crate::ident::PayloadRls, max_mass: f64) -> PayloadParams {
    let raw = rls.raw_estimate();
    let m = raw[0].clamp(0.0, max_mass);
    if m.is_nan() || m <= 0.0 {
        return PayloadParams::zeros();
    }
    point_mass(m, nalgebra::Vector3::new(raw[1], raw[2], raw[3]) / raw[0])
}

/// The point mass `pi` (mass, first moments, the inertia of a point) with
/// its centre of mass moved in to at most `r` from the flange along its
/// direction; unchanged when `r ≤ 0`, the mass is not positive or it lies
/// within `r`.
fn bound_com(pi: PayloadParams, r: f64) -> PayloadParams {
    let m = pi[0];
    let h = nalgebra::Vector3::new(pi[1], pi[2], pi[3]);
    if !(r > 0.0 && m > 0.0) || h.norm() <= m * r {
        return pi;
    }
    point_mass(m, h * (r / h.norm()))
}

/// The parameters of a point mass `m` at `c` from the flange: first moments `m c`, inertia
/// about the flange `m (|c|² 1 − c cᵀ)` (xx, xy, xz, yy, yz, zz).
fn point_mass(m: f64, c: nalgebra::Vector3<f64>) -> PayloadParams {
    let i_o = (nalgebra::Matrix3::identity() * c.norm_squared() - c * c.transpose()) * m;
    let hc = c * m;
    let mut out = PayloadParams::zeros();
    out[0] = m;
    for (k, v) in [
        hc.x,
        hc.y,
        hc.z,
        i_o[(0, 0)],
        i_o[(0, 1)],
        i_o[(0, 2)],
        i_o[(1, 1)],
        i_o[(1, 2)],
        i_o[(2, 2)],
    ]
    .into_iter()
    .enumerate()
    {
        out[k + 1] = v;
    }
    out
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
        self.applied_fresh = false;
        self.reported = false;
        self.model_pi = PayloadParams::zeros();
        if let Some(ra) = self.real_arm.as_deref_mut() {
            // The model the run starts with: the nominal one (built so).
            self.model_pi = ra.nominal;
            ra.measured = 0;
            ra.steps = 0;
            ra.tau_ring.fill(0.0);
            ra.target = None;
        }
        Ok(())
    }
    fn measurement(&mut self, y: &[f64]) {
        if let Some(ra) = self.real_arm.as_deref_mut() {
            let n = ra.q.len();
            if y.len() >= n && y[..n].iter().all(|v| v.is_finite()) {
                let s = (ra.measured % (2 * ra.window + 1)) * n;
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
    fn first_stage_gain(&mut self, gain: &mut [f64]) -> bool {
        self.inner.first_stage_gain(gain)
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
    fn set_step_clock(&mut self, start: std::time::Instant, reserve_us: f64) {
        self.inner.set_step_clock(start, reserve_us)
    }
    fn qp_end(&self) -> Option<std::time::Instant> {
        self.inner.qp_end()
    }
    fn payload_estimate(&self) -> Option<f64> {
        (self.identify || self.reported).then_some(self.model_pi[0])
    }
    fn applied_torque(&mut self, tau: &[f64]) {
        if tau.len() == self.tau_prev.len() && tau.iter().all(|v| v.is_finite()) {
            // The torque of the period that just ended, `[t_{k−1}, t_k]`,
            // in place of the controller's own `τ_{k−1}` where the
            // identification reads it: `tau_prev`, and the real arm's ring
            // slot of the last step.
            self.tau_prev.copy_from_slice(tau);
            if let Some(ra) = self.real_arm.as_deref_mut().filter(|ra| ra.steps > 0) {
                let n = tau.len();
                let s = ((ra.steps - 1) % (ra.cfg.delay + 2 * ra.window)) * n;
                ra.tau_ring[s..s + n].copy_from_slice(tau);
            }
            self.applied_fresh = true;
            self.reported = true;
        }
    }
    fn step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        input: &crate::control::step::StepInput<'_>,
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        // With the drives' applied torque for this period, the regression
        // uses it (the torque the arm received); without it, only a torque
        // output identifies (from its own `τ_{k−1}`).
        let from_drive = std::mem::take(&mut self.applied_fresh);
        if !(self.identify || self.reported) {
            return self.inner.step(model, input, tau);
        }
        let learn = self.identify || from_drive;
        let (x, w_k, preview) = (input.x, input.w_k, input.preview);
        let ts = self.inner.settings().ts;
        let saved_rls = *self.estimator.rls();
        let saved_pi = self.model_pi;
        let saved_target = self.real_arm.as_deref().and_then(|ra| ra.target);
        let saved_payload;
        {
            let Some(rd) = model.robot_dynamics_mut() else {
                return Err(StepFailure::NoRigidBodyModel);
            };
            saved_payload = rd.robot().payload().copied();
            let learnt = learn
                && match self.real_arm.as_deref_mut() {
                    Some(ra) => Self::learn_real_arm(ra, &mut self.estimator, rd, w_k, preview, ts),
                    None => {
                        self.has_prev
                            && self
                                .estimator
                                .update(rd, &self.x_prev, x, &self.tau_prev, ts)
                    }
                };
            let target = match self.real_arm.as_deref_mut() {
                Some(ra) => {
                    // W > 1: the model follows the last target at every sample
                    // (the same time constant as per learnt sample at W = 1,
                    // without a step every W samples).
                    if learnt {
                        ra.target = Some(Self::model_target(
                            self.estimator.rls(),
                            Some((&ra.cfg, ra.nominal)),
                        ));
                    }
                    ra.target.filter(|_| learnt || ra.window > 1)
                }
                None => learnt.then(|| Self::model_target(self.estimator.rls(), None)),
            };
            if let Some(target) = target {
                let rate = self
                    .real_arm
                    .as_deref()
                    .map_or(MODEL_RATE, |ra| ra.model_rate);
                // A convex combination of two physical bodies is physical, so the
                // model should accept it; if it does not, the step is undone and says so.
                self.model_pi += (target - self.model_pi) * rate;
                if rd
                    .robot_mut()
                    .set_payload(payload_of(&self.model_pi))
                    .is_err()
                {
                    *self.estimator.rls_mut() = saved_rls;
                    self.model_pi = saved_pi;
                    if let Some(ra) = self.real_arm.as_deref_mut() {
                        ra.target = saved_target;
                    }
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
                    let s = (ra.steps % (ra.cfg.delay + 2 * ra.window)) * n;
                    ra.tau_ring[s..s + n].copy_from_slice(tau);
                    ra.steps += 1;
                }
                Ok(info)
            }
            Err(e) => {
                *self.estimator.rls_mut() = saved_rls;
                self.model_pi = saved_pi;
                if let Some(ra) = self.real_arm.as_deref_mut() {
                    ra.target = saved_target;
                }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// On a unit mass driven by torques held over each period, the second
    /// difference over `W` periods divided by `(W·Ts)²` equals the torques
    /// through the window's weights, exactly (the identification's two sides
    /// pass through the same filter); the weights sum to 1 and are `½` at
    /// `W = 1` (the 10 ms algorithm).
    #[test]
    fn the_window_weights_are_the_second_difference_of_a_double_integrator() {
        assert_eq!(window_weight(1, 1), 0.5);
        let ts = 1e-3;
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 200.0 - 100.0
        };
        for w in 1..=15 {
            let sum: f64 = (1..=w).map(|j| 2.0 * window_weight(j, w)).sum();
            assert!((sum - 1.0).abs() < 1e-14, "W = {w}: {sum}");
            let tau: Vec<f64> = (0..2 * w).map(|_| next()).collect();
            // Exact positions at the period boundaries from rest-free start.
            let (mut q, mut v) = (vec![0.3], 0.7);
            for &t in &tau {
                let last = *q.last().unwrap();
                q.push(last + v * ts + 0.5 * t * ts * ts);
                v += t * ts;
            }
            let h = w as f64 * ts;
            let second = (q[2 * w] - 2.0 * q[w] + q[0]) / (h * h);
            // Centre c = W: τ_{c−j} and τ_{c+j−1}.
            let filtered: f64 = (1..=w)
                .map(|j| window_weight(j, w) * (tau[w - j] + tau[w + j - 1]))
                .sum();
            assert!(
                (second - filtered).abs() < 1e-6 * (1.0 + filtered.abs()),
                "W = {w}: {second} vs {filtered}"
            );
        }
    }

    #[test]
    fn the_centre_of_mass_is_moved_in_to_the_bound_with_its_mass() {
        // 0.5 kg at c = (0.3, 0, 0.4) m (|c| = 0.5) as a point mass.
        let c = nalgebra::Vector3::<f64>::new(0.3, 0.0, 0.4);
        let pi = point_mass(0.5, c);
        assert_eq!([pi[1], pi[2], pi[3]], [0.15, 0.0, 0.2]);
        let b = bound_com(pi, 0.2);
        assert_eq!(b[0], 0.5);
        let h = nalgebra::Vector3::new(b[1], b[2], b[3]);
        assert!((h.norm() / 0.5 - 0.2).abs() < 1e-12);
        assert!((h.normalize() - c.normalize()).norm() < 1e-12);
        // The inertia of the moved point: m (|c'|² − c'_x²) about x.
        let cx = 0.2 * 0.6;
        assert!((b[4] - 0.5 * (0.04 - cx * cx)).abs() < 1e-12);
        // Within the bound, no bound, or no mass: unchanged.
        assert_eq!(bound_com(pi, 0.6), pi);
        assert_eq!(bound_com(pi, 0.0), pi);
        let mut empty = pi;
        empty[0] = 0.0;
        assert_eq!(bound_com(empty, 0.2), empty);
    }
}
