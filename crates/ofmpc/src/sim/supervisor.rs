//! Supervision of the closed loop: a plausibility check of each measurement
//! and a safe stop (decelerate on a torque-limited braking law, then hold).
//!
//! Plausibility, per joint, against the last accepted measurement `(q_a, q̇_a)`
//! `m` samples ago:
//! * a position jump `|y − (q_a + q̇_a τ + ½ q̈_a τ²)|` (`τ = m Ts`, `q̈_a` the
//!   last accepted velocity change per time) beyond a tenth of what the speed
//!   limit allows in those samples (`0.1 · v_max · τ`) is rejected: the loop
//!   uses the prediction instead, unless the raw sample agrees with the
//!   previous raw one (`|y − (y₋₁ + q̇₋₁ Ts)|` within the same bound: the
//!   motion is real and the prediction was off); more than [`MAX_REJECTED`]
//!   rejections in a row make the measurement implausible;
//! * a velocity off its prediction `q̇_a + q̈_a τ` by more than `0.1 · v_max`
//!   per sample is rejected (the prediction is used), unless it explains the
//!   accepted position better than the prediction does
//!   (`|y − q_a − ½(q̇_a + q̇) τ|` no larger with the measured velocity than
//!   with the predicted one): friction can stop or release a light joint
//!   within a sample, faster than the constant-acceleration prediction
//!   allows, and handing the controller the prediction then (a joint still
//!   moving, as it stuck) makes it brake against a motion that is not there;
//! * a position that does not change at all for [`FROZEN_SAMPLES`] samples
//!   while the joint moves (`|q̇_a| Ts ≥` [`MOVING_STEP_RAD`]) is a frozen
//!   encoder.
//!
//! The safe stop (category-1-like): each joint brakes towards
//! `q_stop = q + q̇ T_b` (where `a = −q̇/T_b` would stop it) and holds there,
//! `a = −(q − q_stop)/T_b² − 2 q̇/T_b` (critically damped), `τ = H a + C q̇ + g`
//! of the controller's model clamped to the drives' limits. A joint whose
//! encoder is frozen is dead-reckoned through the model from its last good
//! measurement under the torques applied since.

use super::format::angle_text;
use super::repair::model_accel;
use crate::control::{LinearLikeModel, StepFailure};
use crate::dynamics::JointSpaceDynamics;
use std::fmt;

/// Rejections in a row after which a measurement is implausible.
pub const MAX_REJECTED: usize = 3;
/// Samples without any change of a moving joint's position: a frozen encoder.
pub const FROZEN_SAMPLES: usize = 3;
/// Expected motion per sample (rad) above which a joint counts as moving.
pub const MOVING_STEP_RAD: f64 = 1e-5;
/// Speed below which a joint is at rest (rad/s).
pub const REST_SPEED: f64 = 1e-3;
/// Braking time constant `T_b` (s).
pub const BRAKE_TIME: f64 = 0.03;
/// The look-back of the growth rule ([`DivergenceRule::Growth`], s): the
/// error now is compared with the largest error between `2·W` and `W` ago.
pub const GROWTH_WINDOW_S: f64 = 0.5;
/// The growth factor of the growth rule: an error (beyond the floor) at
/// least this many times the largest error of the look-back window grows.
pub const GROWTH_FACTOR: f64 = 4.0;
/// A joint error beyond this (rad, half a turn) is a divergence under the
/// growth rule whatever its history: no stable tracking controller holds an
/// offset of half a turn.
pub const GROWTH_CEILING_RAD: f64 = std::f64::consts::PI;

/// How the loop judges a run unstable ("diverged").
///
/// An offset is a result, divergence is growth: a stable controller whose
/// model misses a heavy payload (the usual MPC) settles at a large steady
/// offset, which must complete and be reported, while an unstable loop's
/// error grows geometrically (the spectral radius of its linearisation is
/// above 1; `analysis::stability`). With `ε_k = max_i |w_i − q_i|` (the true
/// joint error at sample `k`) and the floor `f` = the divergence threshold:
/// * [`DivergenceRule::Growth`] (the default): diverged when `ε_k > f` and
///   either `ε_k ≥` `GROWTH_FACTOR` `· max{ε_j : k − 2M ≤ j < k − M}`
///   (`M` = `GROWTH_WINDOW_S``/Ts` samples, or half the samples so far at
///   the start of a run, not before `M/2` samples: the error quadrupled
///   within a second), or a joint
///   is beyond its position limits, or `ε_k >` `GROWTH_CEILING_RAD`. A
///   step disturbance at the start (a payload that sags the arm within
///   0.1–0.3 s) rises by less than the factor against the look-back, an
///   instability keeps growing (the paper's unstable runs grow 2–4× per
///   0.1 s). A payload picked up mid-path that moves a small error beyond
///   the floor within a second reads as growth (a limit of the rule).
/// * [`DivergenceRule::Threshold`]: diverged when `ε_k > f` (the rule of
///   earlier versions; a scenario that sets `divergence_threshold_rad`
///   without `divergence` gets it).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DivergenceRule {
    /// Growth beyond the threshold as a floor (above).
    #[default]
    Growth,
    /// The threshold alone.
    Threshold,
}

impl DivergenceRule {
    /// `"growth"` or `"threshold"`.
    pub fn name(self) -> &'static str {
        match self {
            DivergenceRule::Growth => "growth",
            DivergenceRule::Threshold => "threshold",
        }
    }
}

/// Why the loop stopped the robot.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum StopReason {
    /// A joint error passed the divergence threshold.
    Diverged {
        /// 0-based joint.
        joint: usize,
        /// The error (rad).
        error_rad: f64,
    },
    /// A joint error passed the safety limit (`max_joint_error_rad`).
    JointErrorLimit {
        /// 0-based joint.
        joint: usize,
        /// The error (rad), of the state the controller was given.
        error_rad: f64,
        /// The limit (rad).
        limit_rad: f64,
    },
    /// A controller step failed.
    ControllerFailed(StepFailure),
    /// A joint's measurement kept jumping beyond the plausible.
    ImplausibleMeasurement {
        /// 0-based joint.
        joint: usize,
        /// The jump from the prediction (rad).
        jump_rad: f64,
        /// The tolerance (rad).
        tolerance_rad: f64,
    },
    /// A moving joint's encoder stopped changing.
    FrozenEncoder {
        /// 0-based joint.
        joint: usize,
    },
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StopReason::Diverged { joint, error_rad } => write!(
                f,
                "the error of joint {} reached {} rad (divergence)",
                joint + 1,
                angle_text(*error_rad)
            ),
            StopReason::JointErrorLimit {
                joint,
                error_rad,
                limit_rad,
            } => write!(
                f,
                "the error of joint {} reached {} rad, beyond the safety limit of {limit_rad} rad",
                joint + 1,
                angle_text(*error_rad)
            ),
            StopReason::ControllerFailed(e) => write!(f, "the controller step failed: {e}"),
            StopReason::ImplausibleMeasurement {
                joint,
                jump_rad,
                tolerance_rad,
            } => write!(
                f,
                "the measurement of joint {} jumped {jump_rad:.3e} rad from its prediction, beyond {tolerance_rad:.3e} rad, {} samples in a row",
                joint + 1,
                MAX_REJECTED + 1
            ),
            StopReason::FrozenEncoder { joint } => write!(
                f,
                "the encoder of joint {} stopped changing while the joint moved",
                joint + 1
            ),
        }
    }
}

/// The plausibility check of the measurements (module docs).
#[derive(Debug, Clone)]
pub struct Plausibility {
    n: usize,
    /// The control period (s).
    ts: f64,
    vmax: Vec<f64>,
    q_a: Vec<f64>,
    v_a: Vec<f64>,
    acc_a: Vec<f64>,
    m: Vec<usize>,
    rejected: Vec<usize>,
    frozen: Vec<usize>,
    prev_raw: Vec<f64>,
    prev_raw_v: Vec<f64>,
    /// Rejected samples so far (positions and velocities).
    pub rejections: usize,
}

impl Plausibility {
    /// A check for joints with these speed limits (`vmax`, n values; an
    /// infinite limit turns the check off for that joint), starting from
    /// the accepted state `x0` (2n), one reading per control period `ts` (s).
    pub fn new(vmax: &[f64], x0: &[f64], ts: f64) -> Self {
        let n = vmax.len();
        Self {
            n,
            ts,
            vmax: vmax.to_vec(),
            q_a: x0[..n].to_vec(),
            v_a: x0[n..2 * n].to_vec(),
            acc_a: vec![0.0; n],
            m: vec![1; n],
            rejected: vec![0; n],
            frozen: vec![0; n],
            prev_raw: x0[..n].to_vec(),
            prev_raw_v: x0[n..2 * n].to_vec(),
            rejections: 0,
        }
    }

    /// Starts over from the accepted state `x0` (2n) with no rejection
    /// counted; allocates nothing.
    pub fn reset(&mut self, x0: &[f64]) {
        let n = self.n;
        self.q_a.copy_from_slice(&x0[..n]);
        self.v_a.copy_from_slice(&x0[n..2 * n]);
        self.acc_a.fill(0.0);
        self.m.fill(1);
        self.rejected.fill(0);
        self.frozen.fill(0);
        self.prev_raw.copy_from_slice(&x0[..n]);
        self.prev_raw_v.copy_from_slice(&x0[n..2 * n]);
        self.rejections = 0;
    }

    /// Checks `x` (2n), replaces rejected values by their predictions, and
    /// says when the measurement cannot be trusted any more.
    pub fn check(&mut self, x: &mut [f64]) -> Option<StopReason> {
        let (n, ts) = (self.n, self.ts);
        let mut reason = None;
        for i in 0..n {
            let (raw_q, raw_v) = (x[i], x[n + i]);
            let moving = self.v_a[i].abs() * ts >= MOVING_STEP_RAD;
            if raw_q.to_bits() == self.prev_raw[i].to_bits() && moving {
                self.frozen[i] += 1;
            } else {
                self.frozen[i] = 0;
            }
            let prev_raw = self.prev_raw[i];
            let prev_raw_v = self.prev_raw_v[i];
            self.prev_raw[i] = raw_q;
            self.prev_raw_v[i] = raw_v;
            if self.frozen[i] >= FROZEN_SAMPLES && reason.is_none() {
                reason = Some(StopReason::FrozenEncoder { joint: i });
            }
            if !self.vmax[i].is_finite() {
                self.q_a[i] = raw_q;
                self.v_a[i] = raw_v;
                continue;
            }
            let steps = self.m[i] as f64;
            let dt = ts * steps;
            let pred = self.q_a[i] + self.v_a[i] * dt + 0.5 * self.acc_a[i] * dt * dt;
            let v_pred = self.v_a[i] + self.acc_a[i] * dt;
            let tol = 0.1 * self.vmax[i] * dt;
            let jump = (raw_q - pred).abs();
            // After a rejection, two raw samples that agree with each other
            // (the motion is real, the prediction was off) are accepted.
            let consistent = self.rejected[i] > 0
                && (raw_q - (prev_raw + prev_raw_v * ts)).abs() <= 0.1 * self.vmax[i] * ts;
            if (jump > tol || jump.is_nan()) && !consistent {
                self.rejections += 1;
                self.rejected[i] += 1;
                self.m[i] += 1;
                x[i] = pred;
                x[n + i] = v_pred;
                if self.rejected[i] > MAX_REJECTED && reason.is_none() {
                    reason = Some(StopReason::ImplausibleMeasurement {
                        joint: i,
                        jump_rad: jump,
                        tolerance_rad: tol,
                    });
                }
                continue;
            }
            self.rejected[i] = 0;
            self.m[i] = 1;
            let q_a_old = self.q_a[i];
            self.q_a[i] = raw_q;
            // A velocity off its prediction is still real when it explains
            // the accepted position better than the prediction does
            // (trapezoid over the interval): a joint that friction stops
            // (or releases) within a sample changes its velocity faster
            // than the constant-acceleration prediction allows.
            let explains = |v: f64| (raw_q - q_a_old - 0.5 * (self.v_a[i] + v) * dt).abs();
            if consistent
                || (raw_v - v_pred).abs() <= 0.1 * self.vmax[i] * steps
                || explains(raw_v) <= explains(v_pred)
            {
                self.acc_a[i] = (raw_v - self.v_a[i]) / dt;
                self.v_a[i] = raw_v;
            } else {
                // Keep the motion predicted from the last accepted velocity.
                self.rejections += 1;
                x[n + i] = v_pred;
                self.v_a[i] = v_pred;
            }
        }
        reason
    }
}

/// The safe stop's state (module docs). Sized once before the loop
/// ([`SafeStop::new`]); [`SafeStop::begin`] and [`SafeStop::step`] allocate
/// nothing.
#[derive(Debug, Clone)]
pub struct SafeStop {
    n: usize,
    /// The control period (s).
    ts: f64,
    tau_max: Vec<f64>,
    model: LinearLikeModel,
    q: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    /// Where the joints are held (capacity n; empty until the first stop sample).
    hold: Vec<f64>,
    dead_reckoned: Vec<bool>,
    last_raw: Vec<f64>,
    w: Vec<f64>,
    /// The torque of the previous stop sample (dead reckoning).
    tau_prev: Vec<f64>,
    /// Position and velocity of the replay of a frozen joint ([`SafeStop::begin`]).
    replay_q: Vec<f64>,
    replay_v: Vec<f64>,
    /// The stop's own braking trajectory for a position or velocity
    /// interface ([`SafeStop::command`]): its position and velocity at the
    /// current sample.
    path_q: Vec<f64>,
    path_v: Vec<f64>,
    /// The trajectory was started at this stop's first state and not yet
    /// advanced.
    path_fresh: bool,
}

/// The critically damped braking law `ë = −ω²e − 2ωė` from `e(0) = e0`,
/// `ė(0) = v0` at time `t`: `e = (A + Bt)e^{−ωt}` with `A = e0`,
/// `B = v0 + ωe0`; returns `(e, ė, ë)`.
fn critically_damped(e0: f64, v0: f64, w: f64, t: f64) -> (f64, f64, f64) {
    let (a, b) = (e0, v0 + w * e0);
    let decay = (-w * t).exp();
    let e = a + b * t;
    (
        e * decay,
        (b - w * e) * decay,
        (w * w * e - 2.0 * w * b) * decay,
    )
}

impl SafeStop {
    /// A stop law for drives with these torque limits (n of them), one
    /// torque per control period `ts` (s).
    pub fn new(tau_max: &[f64], ts: f64) -> Self {
        let n = tau_max.len();
        Self {
            n,
            ts,
            tau_max: tau_max.to_vec(),
            model: LinearLikeModel::new(n),
            q: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
            hold: Vec::with_capacity(n),
            dead_reckoned: vec![false; n],
            last_raw: vec![0.0; n],
            w: vec![0.0; n],
            tau_prev: vec![0.0; n],
            replay_q: vec![0.0; n],
            replay_v: vec![0.0; n],
            path_q: vec![0.0; n],
            path_v: vec![0.0; n],
            path_fresh: true,
        }
    }

    /// For an interface that takes positions (`[mpc] output =
    /// "position_velocity"` or `"velocity"`): the stop's braking trajectory
    /// `lead_s` after the current sample, into `q`, `qd`, `qdd` (n each) —
    /// the law of [`Self::step`] (critically damped, time constant
    /// [`BRAKE_TIME`], to where the braking started plus its run-out) run on
    /// the stop's own trajectory from the state the stop began at, not on
    /// the measurement: a decelerating, then holding, position the drive's
    /// own loop follows (a torque it would ignore stops nothing). Allocates
    /// nothing.
    pub fn command(&self, lead_s: f64, cmd: [&mut [f64]; 3]) {
        let w = 1.0 / BRAKE_TIME;
        let [q, qd, qdd] = cmd;
        for i in 0..self.n {
            let hold = self.hold_of(i);
            let (e, v, a) = critically_damped(self.path_q[i] - hold, self.path_v[i], w, lead_s);
            q[i] = hold + e;
            qd[i] = v;
            qdd[i] = a;
        }
    }

    /// Where joint `i` is held: the hold once the stop has taken its first
    /// sample, before it the trajectory's own run-out.
    fn hold_of(&self, i: usize) -> f64 {
        match self.hold.get(i) {
            Some(h) => *h,
            None => self.path_q[i] + self.path_v[i] * BRAKE_TIME,
        }
    }

    /// Moves the braking trajectory of [`Self::command`] one period on
    /// (not at the stop's first sample, which is the state it began at).
    fn advance_path(&mut self) {
        if std::mem::take(&mut self.path_fresh) {
            return;
        }
        let w = 1.0 / BRAKE_TIME;
        for i in 0..self.n {
            let hold = self.hold_of(i);
            let (e, v, _) = critically_damped(self.path_q[i] - hold, self.path_v[i], w, self.ts);
            self.path_q[i] = hold + e;
            self.path_v[i] = v;
        }
    }

    /// Starts a stop from the measured state `x` (2n). A joint in `frozen` is
    /// dead-reckoned until its measurement changes again, starting from the
    /// replay of `last_good` (the state measured before the freeze) under the
    /// torques applied since (`torques`, n each, oldest first) through the
    /// model.
    pub fn begin(
        &mut self,
        x: &[f64],
        frozen: Option<(usize, &[f64], &[f64])>,
        model: &mut dyn JointSpaceDynamics,
    ) {
        let (n, ts) = (self.n, self.ts);
        self.q.copy_from_slice(&x[..n]);
        self.v.copy_from_slice(&x[n..2 * n]);
        self.a.fill(0.0);
        self.hold.clear();
        self.dead_reckoned.fill(false);
        self.last_raw.copy_from_slice(&x[..n]);
        self.w.fill(0.0);
        self.tau_prev.fill(0.0);
        if let Some((j, last_good, torques)) = frozen {
            self.dead_reckoned[j] = true;
            let (rq, rv) = (&mut self.replay_q, &mut self.replay_v);
            rq.copy_from_slice(&last_good[..n]);
            rv.copy_from_slice(&last_good[n..2 * n]);
            for tau in torques.chunks_exact(n) {
                if model_accel(&mut self.model, model, rq, rv, tau, &mut self.a).is_err() {
                    break;
                }
                for i in 0..n {
                    rq[i] += rv[i] * ts + 0.5 * self.a[i] * ts * ts;
                    rv[i] += self.a[i] * ts;
                }
            }
            self.q[j] = rq[j];
            self.v[j] = rv[j];
            self.a.fill(0.0);
        }
        self.path_q.copy_from_slice(&self.q);
        self.path_v.copy_from_slice(&self.v);
        self.path_fresh = true;
    }

    /// One sample of the stop: `raw` is the measurement (frozen encoders are
    /// recognised on it), `x` the state to brake (the observer's estimate
    /// when there is one, else `raw`); writes the braking or holding torque
    /// into `tau`.
    pub fn step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        raw: &[f64],
        x: &[f64],
        tau: &mut [f64],
    ) -> Result<(), StepFailure> {
        self.track(model, raw, x)?;
        let n = self.n;
        // Brake towards where the braking started plus its run-out, then
        // hold there: a = −ω²(q − q_stop) − 2ω q̇ (critically damped).
        if self.hold.is_empty() {
            // Within its capacity: no allocation.
            let (q, v) = (&self.q, &self.v);
            self.hold
                .extend(q.iter().zip(v).map(|(q, v)| q + v * BRAKE_TIME));
        }
        self.advance_path();
        let w = 1.0 / BRAKE_TIME;
        for i in 0..n {
            self.a[i] = -w * w * (self.q[i] - self.hold[i]) - 2.0 * w * self.v[i];
        }
        // τ = H a + C q̇ + g = H (a − f0 q̇) + g (f0 = −H⁻¹C, Eq. (6)).
        self.model.update(model, &self.q, &self.v)?;
        let f0 = self.model.f0().as_slice();
        for r in 0..n {
            let mut s = self.a[r];
            for c in 0..n {
                s -= f0[c * n + r] * self.v[c];
            }
            self.w[r] = s;
        }
        let h = self.model.h().as_slice();
        let g = self.model.g().as_slice();
        for (r, t) in tau.iter_mut().enumerate() {
            let mut s = g[r];
            for c in 0..n {
                s += h[c * n + r] * self.w[c];
            }
            let lim = self.tau_max[r];
            *t = if lim.is_finite() {
                s.clamp(-lim, lim)
            } else {
                s
            };
        }
        self.tau_prev.copy_from_slice(tau);
        Ok(())
    }

    /// The state the stop law acts on, from the raw reading `raw` and the
    /// state `x` (2n each): `x`, except for a joint whose encoder froze,
    /// dead-reckoned through the model under the last torque until its
    /// reading changes again (then the hold moves to where it really is).
    fn track(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        raw: &[f64],
        x: &[f64],
    ) -> Result<(), StepFailure> {
        let (n, ts) = (self.n, self.ts);
        if self.dead_reckoned.iter().any(|d| *d) {
            // The acceleration the last torque gave, by the model.
            model_accel(
                &mut self.model,
                model,
                &self.q,
                &self.v,
                &self.tau_prev,
                &mut self.w,
            )?;
        }
        for i in 0..n {
            if self.dead_reckoned[i] && raw[i].to_bits() != self.last_raw[i].to_bits() {
                // The encoder is back: hold where the joint really is.
                self.dead_reckoned[i] = false;
                if !self.hold.is_empty() {
                    self.hold[i] = x[i] + x[n + i] * BRAKE_TIME;
                }
            }
            self.last_raw[i] = raw[i];
            if self.dead_reckoned[i] {
                self.q[i] += self.v[i] * ts + 0.5 * self.w[i] * ts * ts;
                self.v[i] += self.w[i] * ts;
            } else {
                self.q[i] = x[i];
                self.v[i] = x[n + i];
            }
        }
        Ok(())
    }
}

/// What the [`Supervisor`] does: the divergence threshold it judges the
/// run by, and the checks and the stop it may apply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupervisorSettings {
    /// A joint error (reference − true position) beyond this (rad) is a
    /// divergence (with [`DivergenceRule::Growth`]: when it also grows): a
    /// safe stop with [`Self::safe_stop`], else the run ends.
    pub divergence_threshold_rad: f64,
    /// How a divergence is recognised ([`DivergenceRule`]).
    pub divergence: DivergenceRule,
    /// Check each measurement (`Plausibility`) and replace rejected values
    /// by predictions.
    pub plausibility_check: bool,
    /// Stop safely (`SafeStop`) on a divergence, a failed controller step
    /// or an implausible measurement, instead of ending the run.
    pub safe_stop: bool,
    /// A safety function: a joint error of the state the controller is
    /// given beyond this (rad) starts a safe stop. `None`: off.
    pub max_joint_error_rad: Option<f64>,
}

/// A safe stop in progress: when it began, why, the last time a joint was
/// still moving, and whether every joint stayed within its limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Stopping {
    /// When the stop began (s, path time).
    pub t: f64,
    /// Why.
    pub reason: StopReason,
    /// The end of the last period in which a joint moved faster than
    /// `REST_SPEED` (s).
    pub moving_until: f64,
    /// Every joint stayed within its position limits since the stop began.
    pub within_limits: bool,
}

/// What [`Supervisor::inspect`] found in one reading.
#[derive(Debug, Clone, PartialEq)]
pub struct Inspection {
    /// Values of the reading were rejected (replaced by predictions).
    pub rejected: bool,
    /// A reason to stop the robot, if any.
    pub trigger: Option<StopReason>,
}

/// The supervisor stage: judges each reading (plausibility, the safety
/// limit on the joint error), the run (divergence), and when told, takes
/// the robot over from the controller with the safe-stop law.
///
/// Sized at construction ([`Supervisor::with_period`]); every other method
/// allocates nothing.
#[derive(Debug, Clone)]
pub struct Supervisor {
    settings: SupervisorSettings,
    n: usize,
    /// The control period (s).
    ts: f64,
    check: Option<Plausibility>,
    law: Option<SafeStop>,
    stop: Option<Stopping>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// The last [`FROZEN_SAMPLES`] + 1 inspected readings and
    /// [`FROZEN_SAMPLES`] commanded torques (oldest first), to replay a
    /// frozen joint from its last good reading.
    x_hist: Vec<f64>,
    tau_hist: Vec<f64>,
    /// The growth rule's history of `ε` (a ring of `2M` samples,
    /// [`Self::with_period`]) and how many samples were judged.
    errors: Vec<f64>,
    judged: usize,
    /// The largest error of the growth rule's look-back window.
    window: SlidingMax,
}

impl Supervisor {
    /// A supervisor for `robot` (its speed, position and torque limits) at
    /// the control period `ts` (s), which sizes the growth rule's history
    /// (`2M` samples, `M = round(`[`GROWTH_WINDOW_S`]`/ts)`; a `ts` that is
    /// not finite and positive gives `M = 1`). The one constructor that
    /// judges every [`DivergenceRule`] in full.
    /// Its plausibility check, stop law and time of rest use `ts` too: the
    /// period is given here, once.
    pub fn with_period(robot: &crate::robot::Robot, settings: SupervisorSettings, ts: f64) -> Self {
        let mut s = Self::build(robot, settings, ts);
        s.size_history(ts);
        s
    }

    fn build(robot: &crate::robot::Robot, settings: SupervisorSettings, ts: f64) -> Self {
        let n = robot.dof();
        let vmax: Vec<f64> = robot.joints().iter().map(|j| j.limits.velocity).collect();
        let tau_max: Vec<f64> = robot.joints().iter().map(|j| j.limits.effort).collect();
        let zero = vec![0.0; 2 * n];
        Self {
            settings,
            n,
            ts,
            check: settings
                .plausibility_check
                .then(|| Plausibility::new(&vmax, &zero, ts)),
            law: (settings.safe_stop || settings.max_joint_error_rad.is_some())
                .then(|| SafeStop::new(&tau_max, ts)),
            stop: None,
            lower: robot.lower_limits(),
            upper: robot.upper_limits(),
            x_hist: vec![0.0; (FROZEN_SAMPLES + 1) * 2 * n],
            tau_hist: vec![0.0; FROZEN_SAMPLES * n],
            errors: Vec::new(),
            judged: 0,
            window: SlidingMax::default(),
        }
    }

    /// The control period (s).
    pub fn period(&self) -> f64 {
        self.ts
    }

    fn size_history(&mut self, ts: f64) {
        let m = if ts.is_finite() && ts > 0.0 {
            ((GROWTH_WINDOW_S / ts).round() as usize).clamp(1, 1_000_000)
        } else {
            1
        };
        self.errors = vec![0.0; 2 * m];
        self.window = SlidingMax::with_capacity(2 * m);
    }

    /// What it was built with.
    pub fn settings(&self) -> &SupervisorSettings {
        &self.settings
    }

    /// Starts a run from the accepted reading `x0` (2n), no stop in
    /// progress.
    pub fn reset(&mut self, x0: &[f64]) {
        if let Some(c) = self.check.as_mut() {
            c.reset(x0);
        }
        for slot in self.x_hist.chunks_exact_mut(2 * self.n) {
            slot.copy_from_slice(x0);
        }
        self.tau_hist.fill(0.0);
        self.stop = None;
        self.judged = 0;
        self.window.clear();
    }

    /// Judges the reading `x` (2n, after the sensor) against the reference
    /// `w` (n): the plausibility check (not during a stop: the stop law
    /// judges the encoders itself), then the safety limit on the joint
    /// error. Rejected values of `x` are replaced by their predictions.
    pub fn inspect(&mut self, x: &mut [f64], w: &[f64]) -> Inspection {
        let n = self.n;
        let mut rejected = false;
        let mut trigger = None;
        let known = self.ts.is_finite();
        if let Some(c) = self.check.as_mut().filter(|_| self.stop.is_none() && known) {
            let before = c.rejections;
            trigger = c.check(x);
            rejected = c.rejections > before;
        }
        if let (None, None, Some(limit)) = (&self.stop, &trigger, self.settings.max_joint_error_rad)
        {
            if let Some(joint) = (0..n).find(|&i| (w[i] - x[i]).abs() > limit) {
                trigger = Some(StopReason::JointErrorLimit {
                    joint,
                    error_rad: w[joint] - x[joint],
                    limit_rad: limit,
                });
            }
        }
        self.x_hist.copy_within(2 * n.., 0);
        let last = self.x_hist.len() - 2 * n;
        self.x_hist[last..].copy_from_slice(x);
        Inspection { rejected, trigger }
    }

    /// The stop in progress, if any.
    pub fn stopping(&self) -> Option<&Stopping> {
        self.stop.as_ref()
    }

    /// Whether a stop can be made (the settings ask for the stop law, and
    /// the period is known).
    pub fn can_stop(&self) -> bool {
        self.law.is_some() && self.ts.is_finite()
    }

    /// Begins a safe stop at `t` for `reason` from the state `from` (2n);
    /// a frozen encoder's joint is dead-reckoned from its last good reading.
    /// Returns `false` (and does nothing) when a stop is already in
    /// progress or the settings have no stop law.
    pub fn begin_stop(
        &mut self,
        t: f64,
        reason: StopReason,
        from: &[f64],
        model: &mut dyn JointSpaceDynamics,
    ) -> bool {
        let n = self.n;
        let (None, Some(law), true) = (&self.stop, self.law.as_mut(), self.ts.is_finite()) else {
            return false;
        };
        let frozen = match reason {
            StopReason::FrozenEncoder { joint } => {
                Some((joint, &self.x_hist[..2 * n], &self.tau_hist[..]))
            }
            _ => None,
        };
        law.begin(from, frozen, model);
        self.stop = Some(Stopping {
            t,
            reason,
            moving_until: t,
            within_limits: true,
        });
        true
    }

    /// The stop law's torque (n) during a stop, from the raw reading `raw`
    /// and the state `x` the controller would be given ([`SafeStop::step`]).
    /// Call only while [`Self::stopping`].
    pub fn stop_torque(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        raw: &[f64],
        x: &[f64],
        tau: &mut [f64],
    ) -> Result<(), StepFailure> {
        match self.law.as_mut() {
            Some(law) => law.step(model, raw, x, tau),
            None => Err(StepFailure::Internal("stop torque without a stop law")),
        }
    }

    /// The stop law's position command `lead_s` ahead during a stop
    /// ([`SafeStop::command`]); `false` (nothing written) without a stop law.
    pub fn stop_command(&self, lead_s: f64, cmd: [&mut [f64]; 3]) -> bool {
        match self.law.as_ref() {
            Some(law) => {
                law.command(lead_s, cmd);
                true
            }
            None => false,
        }
    }

    /// The torque commanded at the current sample (n values).
    pub fn record_torque(&mut self, tau: &[f64]) {
        let n = self.n;
        self.tau_hist.copy_within(n.., 0);
        let last = self.tau_hist.len() - n;
        self.tau_hist[last..].copy_from_slice(tau);
    }

    /// Watches the robot (true `q`, `q̇`) after the period `[t, t + Ts)`
    /// during a stop: when it comes to rest, whether it stays in its limits.
    pub fn watch(&mut self, q: &[f64], qd: &[f64], t: f64) {
        if let Some(s) = self.stop.as_mut() {
            if qd.iter().any(|v| v.abs() >= REST_SPEED) {
                s.moving_until = t + self.ts;
            }
            if (0..self.n).any(|i| q[i] < self.lower[i] || q[i] > self.upper[i]) {
                s.within_limits = false;
            }
        }
    }

    /// Judges the true position `q` against the reference `w` after a
    /// sample by the settings' [`DivergenceRule`] and records the error for
    /// the growth rule: the joint with the largest error and its error
    /// `w − q` when the run diverges; `None` during a stop. Allocates
    /// nothing.
    pub fn judge(&mut self, w: &[f64], q: &[f64]) -> Option<(usize, f64)> {
        if self.stop.is_some() {
            return None;
        }
        if self.settings.divergence == DivergenceRule::Threshold {
            return self.divergence(w, q);
        }
        let n = self.n;
        let (mut joint, mut eps) = (0, 0.0_f64);
        for i in 0..n {
            let e = (w[i] - q[i]).abs();
            if e > eps || e.is_nan() {
                (joint, eps) = (i, e);
            }
        }
        self.slide();
        let grew = eps > self.settings.divergence_threshold_rad && self.grew(eps, q);
        let len = self.errors.len();
        if len > 0 {
            self.errors[self.judged % len] = eps;
        }
        self.judged += 1;
        grew.then(|| (joint, w[joint] - q[joint]))
    }

    /// The growth rule's look-back window at the current sample `J`
    /// (samples judged so far): `[J − 2m, J − m)` with `m = min(M, ⌊J/2⌋)`.
    fn look_back(&self) -> (usize, usize) {
        let m = (self.errors.len() / 2).min(self.judged / 2);
        (self.judged - 2 * m, self.judged - m)
    }

    /// Moves the sliding maximum to the current look-back window. Before
    /// `2M` samples the window starts at sample 0 or 1 by the parity of `J`:
    /// the deque covers the window from sample 1 on (both its ends then move
    /// only forward) and [`Self::grew`] adds sample 0 when the window holds it.
    fn slide(&mut self) {
        if self.errors.is_empty() {
            return;
        }
        let (from, to) = self.look_back();
        self.window.advance(&self.errors, from.max(1), to);
    }

    /// The growth rule's test of an error `eps` beyond the floor
    /// ([`DivergenceRule`]); the look-back's largest error is the sliding
    /// maximum's ([`Self::slide`]), O(1) per sample.
    fn grew(&self, eps: f64, q: &[f64]) -> bool {
        if eps > GROWTH_CEILING_RAD
            || (0..self.n).any(|i| q[i] < self.lower[i] || q[i] > self.upper[i])
        {
            return true;
        }
        let len = self.errors.len();
        let m = (len / 2).min(self.judged / 2);
        // The first half window of a run (0.25 s) is the settling of the
        // start (a payload sagging the arm): only the limits and the
        // ceiling judge it.
        if m == 0 || self.judged < len / 4 {
            return false;
        }
        eps >= GROWTH_FACTOR * self.past()
    }

    /// The largest error of the look-back window (0 when empty; NaN errors
    /// count for nothing, as `f64::max` ignores them) after [`Self::slide`].
    fn past(&self) -> f64 {
        let (from, to) = self.look_back();
        let past = self
            .window
            .max(&self.errors)
            .map_or(0.0, |v| 0.0_f64.max(v));
        match from == 0 && to > 0 {
            true => past.max(self.errors[0]),
            false => past,
        }
    }

    /// The look-back's largest error by a fold over the window (the
    /// definition [`Self::grew`]'s sliding maximum must match).
    #[cfg(test)]
    fn past_by_fold(&self) -> f64 {
        let len = self.errors.len();
        let (from, to) = self.look_back();
        (from..to).map(|j| self.errors[j % len]).fold(0.0, f64::max)
    }

    /// The first joint whose error `w − q` (reference, true position) is
    /// beyond the divergence threshold or not a number, with the error;
    /// `None` during a stop. The threshold rule alone ([`Self::judge`]
    /// applies the settings' rule; the loop's pre-roll at rest, where no
    /// offset is expected, this one under either rule).
    pub fn divergence(&self, w: &[f64], q: &[f64]) -> Option<(usize, f64)> {
        if self.stop.is_some() {
            return None;
        }
        let threshold = self.settings.divergence_threshold_rad;
        (0..self.n)
            .map(|i| (i, w[i] - q[i]))
            .find(|(_, e)| e.is_nan() || e.abs() > threshold)
    }
}

/// The maximum of a window `[from, to)` of a ring of values whose ends only
/// move forward: a monotone deque of indices (their values decreasing from
/// front to back; D. Lemire, "Streaming maximum-minimum filter using no more
/// than three comparisons per element", 2006), amortised O(1) per sample
/// instead of a fold over the window. NaN values are left out. Sized at
/// construction; allocates nothing after.
#[derive(Debug, Clone, Default)]
struct SlidingMax {
    /// The deque: a ring of indices into the values.
    idx: Vec<usize>,
    head: usize,
    len: usize,
    /// The next index to take in.
    next: usize,
}

impl SlidingMax {
    /// A deque for windows of at most `capacity` samples.
    fn with_capacity(capacity: usize) -> Self {
        Self {
            idx: vec![0; capacity.max(1)],
            ..Self::default()
        }
    }

    /// Empty, from index 0 on.
    fn clear(&mut self) {
        (self.head, self.len, self.next) = (0, 0, 0);
    }

    fn at(&self, k: usize) -> usize {
        self.idx[(self.head + k) % self.idx.len()]
    }

    /// Moves the window to `[from, to)` of `values` (a ring: index `j` is
    /// `values[j % len]`, valid for the last `len` indices). `from` and
    /// `to` never decrease from one call to the next.
    fn advance(&mut self, values: &[f64], from: usize, to: usize) {
        let ring = values.len();
        let cap = self.idx.len();
        while self.next < to {
            let j = self.next;
            self.next += 1;
            let v = values[j % ring];
            if j < from || v.is_nan() {
                continue;
            }
            // Values no larger than the new one can never be a maximum again.
            while self.len > 0 && values[self.at(self.len - 1) % ring] <= v {
                self.len -= 1;
            }
            if self.len == cap {
                // Not reached (the window is shorter than the capacity).
                self.head = (self.head + 1) % cap;
                self.len -= 1;
            }
            let slot = (self.head + self.len) % cap;
            self.idx[slot] = j;
            self.len += 1;
        }
        while self.len > 0 && self.at(0) < from {
            self.head = (self.head + 1) % cap;
            self.len -= 1;
        }
    }

    /// The window's largest value (`None`: empty, or NaN only).
    fn max(&self, values: &[f64]) -> Option<f64> {
        (self.len > 0).then(|| values[self.at(0) % values.len()])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::Robot;

    /// The sliding maximum equals the fold over the look-back window at
    /// every sample, for several periods, with NaN and repeated values,
    /// from the start of a run and after a reset.
    #[test]
    fn the_sliding_maximum_is_the_fold_over_the_window() {
        let robot = Robot::irb140();
        let settings = SupervisorSettings {
            divergence_threshold_rad: 1e9,
            divergence: DivergenceRule::Growth,
            plausibility_check: false,
            safe_stop: false,
            max_joint_error_rad: None,
        };
        let n = robot.dof();
        let mut seed = 12345_u64;
        let mut next = move || crate::linalg::random::uniform(&mut seed);
        for ts in [0.5, 0.25, 0.1, 0.03, 0.01] {
            let mut s = Supervisor::with_period(&robot, settings, ts);
            for run in 0..2 {
                s.reset(&vec![0.0; 2 * n]);
                let len = s.errors.len();
                for k in 0..5 * len + 7 {
                    let r = next();
                    // Errors of every kind: NaN, repeated, rising, falling.
                    let e = match k % 7 {
                        0 if r < 0.3 => f64::NAN,
                        1 => 0.1,
                        2 => 0.1,
                        _ => r * (1.0 + (k % 13) as f64) * 1e-2,
                    };
                    let w = vec![0.0; n];
                    let mut q = vec![0.0; n];
                    q[(k + run) % n] = e;
                    s.slide();
                    let (past, fold) = (s.past(), s.past_by_fold());
                    assert_eq!(past.to_bits(), fold.to_bits(), "ts {ts} run {run} k {k}");
                    // judge slides again: the window is where it was (idempotent).
                    let _ = s.judge(&w, &q);
                }
            }
        }
    }

    /// `with_period` sizes the growth rule: an error beyond the floor that
    /// quadruples against the look-back is a divergence, one that stays is
    /// an offset.
    #[test]
    fn the_period_given_at_construction_sizes_the_growth_rule() {
        let robot = Robot::irb140();
        let n = robot.dof();
        let settings = SupervisorSettings {
            divergence_threshold_rad: 0.01,
            divergence: DivergenceRule::Growth,
            plausibility_check: false,
            safe_stop: false,
            max_joint_error_rad: None,
        };
        let ts = 0.01;
        let m = (GROWTH_WINDOW_S / ts).round() as usize;
        let run = |s: &mut Supervisor| {
            s.reset(&vec![0.0; 2 * n]);
            let w = vec![0.0; n];
            let mut q = vec![0.0; n];
            // An offset of 0.02 rad for 2M samples, then 0.1 rad.
            for k in 0..2 * m {
                q[1] = 0.02;
                assert_eq!(s.judge(&w, &q), None, "offset at {k}");
            }
            q[1] = 0.1;
            s.judge(&w, &q)
        };
        let mut sized = Supervisor::with_period(&robot, settings, ts);
        assert_eq!(sized.errors.len(), 2 * m);
        assert_eq!(run(&mut sized), Some((1, -0.1)));
    }

    /// The threshold rule (the pre-roll's, and `judge`'s under
    /// `Threshold`): the first joint beyond the threshold or not a number.
    #[test]
    fn the_threshold_rule_takes_the_first_joint_beyond_it_or_not_a_number() {
        let robot = Robot::irb140();
        let n = robot.dof();
        let settings = SupervisorSettings {
            divergence_threshold_rad: 0.1,
            divergence: DivergenceRule::Threshold,
            plausibility_check: false,
            safe_stop: false,
            max_joint_error_rad: None,
        };
        let mut s = Supervisor::with_period(&robot, settings, 0.01);
        s.reset(&vec![0.0; 2 * n]);
        let w = vec![0.0; n];
        let mut q = vec![0.0; n];
        q[3] = 0.05;
        assert_eq!(s.divergence(&w, &q), None);
        q[4] = 0.2;
        assert_eq!(s.divergence(&w, &q), Some((4, -0.2)));
        q[2] = f64::NAN;
        let (joint, e) = s.divergence(&w, &q).unwrap();
        assert!(joint == 2 && e.is_nan());
    }
}
