//! The closed loop: measure, control, apply the torque over one period.

use super::metrics::Record;
use super::outcome::{LoopSettingsError, RunFailure, RunOutcome, MAX_RECORD_VALUES};
use super::plant::Plant;
use super::supervisor::{
    MeasurementGuard, Plausibility, SafeStop, StopReason, FROZEN_SAMPLES, REST_SPEED,
};
use crate::control::{Controller, StateObserver, StepError};
use crate::dynamics::JointSpaceDynamics;
use crate::motion::JointReference;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Settings of a closed-loop run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoopSettings {
    /// How long the last reference point is held after the path ends (s).
    pub hold_s: f64,
    /// A run whose joint error passes this (rad) on any joint is stopped as diverged.
    pub divergence_threshold_rad: f64,
    /// The "steady" window at the end of the hold, for the metrics (s).
    pub steady_window_s: f64,
    /// Identification phase of the adaptive controllers (s, at most
    /// [`MAX_IDENTIFICATION_S`]): they hold the path's first point this long
    /// before the path starts, as industrial robots identify a newly attached
    /// load at rest. Not recorded (the record starts with the path at
    /// t = 0); ignored by the other controllers.
    pub identification_s: f64,
    /// When the plant picks up its payload (s, path time): it carries none
    /// before and the payload of the run from then on. `None`: from the
    /// start. The controllers are not told.
    #[serde(skip)]
    pub pick_up_at_s: Option<f64>,
    /// Check each measurement for plausibility (jumps, frozen encoders;
    /// `supervisor` module) and replace rejected values by predictions.
    pub plausibility_check: bool,
    /// On divergence, a failed controller step or an implausible
    /// measurement, bring the robot to a safe stop (brake, hold) and record
    /// [`SAFE_STOP_RECORD_S`] more seconds, instead of ending the run.
    pub safe_stop: bool,
    /// A safety function: when the error of a joint (of the state the
    /// controller is given) passes this (rad), the robot is brought to a
    /// safe stop as with [`Self::safe_stop`] and the run ends "stopped".
    /// `None`: off.
    #[serde(skip)]
    pub max_joint_error_rad: Option<f64>,
    /// Invalid and missing measurements (the controller runs on its own
    /// prediction over them).
    #[serde(skip)]
    pub measurement_faults: MeasurementFaults,
}

/// Faults of the measurement channel, at path times: at the sample at (or
/// first after) each `nan_at_s` the measurement is NaN; in each
/// `dropout_s = [from, to)` no measurement arrives (it reads as NaN). The
/// loop then hands the controller a model prediction
/// (the supervisor module) and counts the fault.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeasurementFaults {
    /// Times of single invalid (NaN) measurements (s).
    pub nan_at_s: Vec<f64>,
    /// Intervals without measurements, `[from, to)` (s).
    pub dropout_s: Vec<[f64; 2]>,
}

impl MeasurementFaults {
    /// No fault.
    pub fn is_empty(&self) -> bool {
        self.nan_at_s.is_empty() && self.dropout_s.is_empty()
    }

    /// Whether the measurement of the sample at `t` (period `ts`) is lost.
    pub fn lost_at(&self, t: f64, ts: f64) -> bool {
        let eps = 1e-9 * ts;
        self.nan_at_s
            .iter()
            .any(|&f| t >= f - eps && t < f + ts - eps)
            || self
                .dropout_s
                .iter()
                .any(|&[from, to]| t >= from - eps && t < to - eps)
    }

    fn validate(&self) -> Result<(), LoopSettingsError> {
        if let Some((index, &value)) = self
            .nan_at_s
            .iter()
            .enumerate()
            .find(|(_, t)| !(t.is_finite() && **t >= 0.0))
        {
            return Err(LoopSettingsError::FaultTime { index, value });
        }
        if let Some((index, &[from, to])) = self
            .dropout_s
            .iter()
            .enumerate()
            .find(|(_, [a, b])| !(a.is_finite() && b.is_finite() && *a >= 0.0 && a < b))
        {
            return Err(LoopSettingsError::DropoutInterval { index, from, to });
        }
        Ok(())
    }
}

/// Longest identification phase at rest (s).
pub const MAX_IDENTIFICATION_S: f64 = 1.0;

/// How long the loop records after a safe stop began (s).
pub const SAFE_STOP_RECORD_S: f64 = 1.0;

impl Default for LoopSettings {
    fn default() -> Self {
        Self {
            hold_s: 2.0,
            divergence_threshold_rad: 0.2,
            steady_window_s: 0.5,
            identification_s: 0.5,
            pick_up_at_s: None,
            plausibility_check: false,
            safe_stop: false,
            max_joint_error_rad: None,
            measurement_faults: MeasurementFaults::default(),
        }
    }
}

impl LoopSettings {
    /// Checks the values.
    pub fn validate(&self) -> Result<(), LoopSettingsError> {
        if !(self.hold_s.is_finite() && self.hold_s >= 0.0) {
            return Err(LoopSettingsError::HoldTime(self.hold_s));
        }
        if !(self.divergence_threshold_rad.is_finite() && self.divergence_threshold_rad > 0.0) {
            return Err(LoopSettingsError::DivergenceThreshold(
                self.divergence_threshold_rad,
            ));
        }
        if !(self.steady_window_s.is_finite()
            && self.steady_window_s > 0.0
            && self.steady_window_s <= self.hold_s.max(1e-9))
        {
            return Err(LoopSettingsError::SteadyWindow {
                value: self.steady_window_s,
                hold_s: self.hold_s,
            });
        }
        if !(self.identification_s.is_finite()
            && (0.0..=MAX_IDENTIFICATION_S).contains(&self.identification_s))
        {
            return Err(LoopSettingsError::IdentificationTime {
                value: self.identification_s,
                max: MAX_IDENTIFICATION_S,
            });
        }
        if let Some(t) = self.pick_up_at_s {
            if !(t.is_finite() && t >= 0.0) {
                return Err(LoopSettingsError::PickUpTime(t));
            }
        }
        if let Some(e) = self.max_joint_error_rad {
            if !(e.is_finite() && e > 0.0) {
                return Err(LoopSettingsError::MaxJointError(e));
            }
        }
        self.measurement_faults.validate()
    }

    /// Samples of the identification phase at the control period `ts`.
    pub fn identification_samples(&self, ts: f64) -> usize {
        (self.identification_s / ts).round() as usize
    }

    /// Samples of the hold at the control period `ts`, saturating.
    pub fn hold_samples(&self, ts: f64) -> usize {
        (self.hold_s / ts).round() as usize
    }
}

/// The state the controller acts on: the observer's estimate (updated from
/// the measurement `x` and copied into `x_est`) when there is an observer,
/// else the measurement itself.
fn observed<'a>(
    observer: Option<&mut StateObserver>,
    model: &mut dyn JointSpaceDynamics,
    x: &'a [f64],
    x_est: &'a mut [f64],
) -> Result<&'a [f64], StepError> {
    match observer {
        Some(o) => {
            x_est.copy_from_slice(o.update(model, x)?);
            Ok(x_est)
        }
        None => Ok(x),
    }
}

/// A safe stop in progress: when it began, why, the last time a joint was
/// still moving, and whether every joint stayed within its limits.
struct Stopping {
    t: f64,
    reason: StopReason,
    moving_until: f64,
    within_limits: bool,
}

/// Values recorded per sample for `n` joints: t, q, q̇, τ, w (4n), the
/// flange and its reference (6), the step time, and with `measured` the
/// measurement as the controller got it (2n).
pub fn record_columns(n: usize, measured: bool) -> usize {
    4 * n + 8 + if measured { 2 * n } else { 0 }
}

/// The outcome of one run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// What was recorded, up to the end or to the divergence.
    pub record: Record,
    /// How it ended.
    pub outcome: RunOutcome,
    /// Wall time of the whole run (s).
    pub wall_s: f64,
}

/// Runs `controller` (with its own `model` of the robot) against `plant`
/// along `reference`, then holds its last point for `settings.hold_s`.
///
/// The plant starts at rest wherever it was built (normally the reference's
/// first point). Row `k` of the record holds the state measured at `t_k` and
/// the torque applied over `[t_k, t_k + Ts)`. `progress(k, total)` is called
/// every 100 samples.
pub fn run_closed_loop(
    controller: &mut dyn Controller,
    model: &mut dyn JointSpaceDynamics,
    plant: &mut Plant,
    reference: &JointReference,
    settings: &LoopSettings,
    progress: &mut dyn FnMut(usize, usize),
) -> RunResult {
    run_closed_loop_with(
        controller,
        model,
        plant,
        reference,
        settings,
        &RunEvents::default(),
        None,
        progress,
    )
}

/// What happens in a run besides following the path.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunEvents {
    /// Samples at rest on the path's first point before the path starts
    /// (the adaptive controllers' identification phase), not recorded.
    pub pre_roll: usize,
    /// At this path time (s) the plant picks up this payload.
    pub pick_up: Option<(f64, crate::robot::Payload)>,
}

/// [`run_closed_loop`] with a pre-roll at rest, a payload picked up
/// mid-path, and an optional state observer between the sensors and the
/// controller.
///
/// During the pre-roll the reference and its preview are the path's first
/// point; a divergence or failure there is reported at a negative time
/// (`−pre_roll·Ts ≤ t < 0`). The record holds the path and the hold; for a
/// controller that identifies the payload it also holds the mass estimate
/// after each step. With an observer the controller gets the observer's
/// estimate of the current state instead of the (delayed, position-derived)
/// measurement; the record keeps the measurement.
#[allow(clippy::too_many_arguments)]
pub fn run_closed_loop_with(
    controller: &mut dyn Controller,
    model: &mut dyn JointSpaceDynamics,
    plant: &mut Plant,
    reference: &JointReference,
    settings: &LoopSettings,
    events: &RunEvents,
    mut observer: Option<&mut StateObserver>,
    progress: &mut dyn FnMut(usize, usize),
) -> RunResult {
    let start = Instant::now();
    let n = reference.dof();
    let ts = reference.ts();
    let horizon = controller.horizon();
    let total = reference.len().saturating_add(settings.hold_samples(ts));
    // What the controller gets differs from the true state: record it too.
    let measured =
        !(plant.settings().measurement_is_ideal() && settings.measurement_faults.is_empty());
    let capacity = if total.saturating_mul(record_columns(n, measured)) <= MAX_RECORD_VALUES {
        total
    } else {
        // The caller did not check the bound ([`super::Experiment::run`]
        // does): grow as needed instead of reserving an absurd size.
        0
    };
    let mut rec = Record::with_capacity(n, capacity);
    if controller.payload_estimate().is_some() {
        rec.payload_mass_est.reserve(capacity);
    }
    if measured {
        rec.q_meas.reserve(capacity * n);
        rec.qd_meas.reserve(capacity * n);
    }
    let mut picked = false;
    let mut x = vec![0.0; 2 * n];
    let mut tau = vec![0.0; n];
    let mut preview = vec![0.0; horizon * n];
    let mut outcome = RunOutcome::Completed;
    // A run that ends before the path starts.
    let early = |record: Record, t: f64, cause: RunFailure| RunResult {
        record,
        outcome: RunOutcome::Failed { t, cause },
        wall_s: start.elapsed().as_secs_f64(),
    };
    if let Err(e) = plant.measure(&mut x) {
        return early(rec, 0.0, RunFailure::Plant(e));
    }
    let mut x_est = x.clone();
    if let Some(o) = observer.as_deref_mut() {
        o.reset(&x);
    }
    if let Err(e) = controller.reset(&x) {
        return early(rec, 0.0, RunFailure::Reset(e));
    }
    // The identification phase at rest on the first point.
    let w0 = reference.q(0);
    for j in 0..events.pre_roll {
        let t = -((events.pre_roll - j) as f64) * ts;
        if j > 0 {
            if let Err(e) = plant.measure(&mut x) {
                return early(rec, t, RunFailure::Plant(e));
            }
        }
        for block in preview.chunks_mut(n.max(1)) {
            block.copy_from_slice(w0);
        }
        let stepped = observed(observer.as_deref_mut(), model, &x, &mut x_est)
            .and_then(|xs| controller.step(model, xs, w0, &preview, &mut tau));
        if let Err(e) = stepped {
            return early(rec, t, RunFailure::Controller(e));
        }
        if let Some(o) = observer.as_deref_mut() {
            o.record_torque(&tau);
        }
        if let Err(e) = plant.step(&tau, ts) {
            return early(rec, t, RunFailure::Plant(e));
        }
        if let Some(joint) = (0..n).find(|&i| {
            let e = w0[i] - plant.q()[i];
            e.is_nan() || e.abs() > settings.divergence_threshold_rad
        }) {
            return RunResult {
                record: rec,
                outcome: RunOutcome::Diverged {
                    t,
                    joint,
                    error_rad: w0[joint] - plant.q()[joint],
                    threshold_rad: settings.divergence_threshold_rad,
                },
                wall_s: start.elapsed().as_secs_f64(),
            };
        }
    }
    if events.pre_roll > 0 {
        if let Err(e) = plant.measure(&mut x) {
            return early(rec, 0.0, RunFailure::Plant(e));
        }
    }
    let robot = plant.robot();
    let vmax: Vec<f64> = robot.joints().iter().map(|j| j.limits.velocity).collect();
    let tau_max: Vec<f64> = robot.joints().iter().map(|j| j.limits.effort).collect();
    let lower = robot.lower_limits();
    let upper = robot.upper_limits();
    let mut check = settings
        .plausibility_check
        .then(|| Plausibility::new(&vmax, &x));
    let faults = &settings.measurement_faults;
    let mut guard = MeasurementGuard::new(&x, plant.settings().delay_samples, !faults.is_empty());
    let mut x_true = vec![0.0; 2 * n];
    // The stop law is sized here, before the loop: starting a stop allocates nothing.
    let mut law = (settings.safe_stop || settings.max_joint_error_rad.is_some())
        .then(|| SafeStop::new(&tau_max));
    let mut stop: Option<Stopping> = None;
    let stop_samples = (SAFE_STOP_RECORD_S / ts).round() as usize;
    // The last FROZEN_SAMPLES + 1 checked measurements and FROZEN_SAMPLES
    // torques (oldest first), to replay a frozen joint from its last good one.
    let hist = FROZEN_SAMPLES;
    let mut x_hist = vec![0.0; (hist + 1) * 2 * n];
    let mut tau_hist = vec![0.0; hist * n];
    for slot in x_hist.chunks_exact_mut(2 * n) {
        slot.copy_from_slice(&x);
    }
    let mut end = total;
    let mut k = 0;
    while k < end {
        let t = k as f64 * ts;
        if k > 0 {
            if let Err(e) = plant.measure(&mut x) {
                outcome = RunOutcome::Failed {
                    t,
                    cause: RunFailure::Plant(e),
                };
                break;
            }
        }
        if let Some((t_pick, payload)) = events.pick_up {
            // The payload is there from the first sample at or after t_pick.
            if !picked && t >= t_pick - 1e-9 * ts {
                picked = true;
                if let Err(e) = plant.set_payload(Some(payload)) {
                    outcome = RunOutcome::Failed {
                        t,
                        cause: RunFailure::Plant(e.into()),
                    };
                    break;
                }
            }
        }
        x_true[..n].copy_from_slice(plant.q());
        x_true[n..].copy_from_slice(plant.qd());
        if faults.lost_at(t, ts) {
            x.fill(f64::NAN);
        }
        if measured {
            rec.q_meas.extend_from_slice(&x[..n]);
            rec.qd_meas.extend_from_slice(&x[n..]);
        }
        // A missing or invalid measurement: the controller runs on the
        // model's prediction.
        let mut fault = guard.check(model, &mut x, ts);
        let mut trigger = None;
        // During a stop the stop law judges the encoders itself (frozen
        // joints are dead-reckoned until they change again).
        if let Some(c) = check.as_mut().filter(|_| stop.is_none()) {
            let before = c.rejections;
            trigger = c.check(&mut x, ts);
            fault |= c.rejections > before;
        }
        rec.faults += usize::from(fault);
        if let (None, None, Some(limit)) = (&stop, &trigger, settings.max_joint_error_rad) {
            let w = reference.q(k);
            if let Some(joint) = (0..n).find(|&i| (w[i] - x[i]).abs() > limit) {
                trigger = Some(StopReason::JointErrorLimit {
                    joint,
                    error_rad: w[joint] - x[joint],
                    limit_rad: limit,
                });
            }
        }
        x_hist.copy_within(2 * n.., 0);
        let last = x_hist.len() - 2 * n;
        x_hist[last..].copy_from_slice(&x);
        let flange = plant.flange_position();
        let w = reference.q(k);
        reference.preview(k, horizon, &mut preview);
        let t0 = Instant::now();
        if let (None, Some(reason), Some(law)) = (&stop, trigger, law.as_mut()) {
            let frozen = match reason {
                StopReason::FrozenEncoder { joint } => {
                    Some((joint, &x_hist[..2 * n], &tau_hist[..]))
                }
                _ => None,
            };
            // From the observer's estimate when there is one.
            let from = if observer.is_some() { &x_est } else { &x };
            law.begin(from, frozen, model, ts);
            stop = Some(Stopping {
                t,
                reason,
                moving_until: t,
                within_limits: true,
            });
            end = k + stop_samples;
        }
        let status =
            observed(observer.as_deref_mut(), model, &x, &mut x_est).and_then(|xs| {
                match (&stop, law.as_mut()) {
                    (Some(_), Some(law)) => law.step(model, &x, xs, ts, &mut tau).map(|_| ()),
                    _ => controller
                        .step(model, xs, w, &preview, &mut tau)
                        .map(|_| ()),
                }
            });
        if let (Some(o), Ok(())) = (observer.as_deref_mut(), &status) {
            o.record_torque(&tau);
        }
        guard.record_torque(&tau);
        let mut saturated = false;
        for (t, lim) in tau.iter().zip(&tau_max) {
            if lim.is_finite() && *lim > 0.0 {
                let r = t.abs() / lim;
                rec.max_torque_ratio = rec.max_torque_ratio.max(r);
                saturated |= r >= 1.0 - 1e-9;
            }
        }
        rec.saturated_samples += usize::from(saturated);
        let us = t0.elapsed().as_secs_f64() * 1e6;
        if let Err(e) = status {
            if let (None, Some(law)) = (&stop, law.as_mut()) {
                // Brake from here on (this sample holds the last torque).
                law.begin(&x, None, model, ts);
                stop = Some(Stopping {
                    t,
                    reason: StopReason::ControllerFailed(e),
                    moving_until: t,
                    within_limits: true,
                });
                end = k + stop_samples;
            } else {
                outcome = RunOutcome::Failed {
                    t,
                    cause: RunFailure::Controller(e),
                };
                break;
            }
        }
        tau_hist.copy_within(n.., 0);
        let last = tau_hist.len() - n;
        tau_hist[last..].copy_from_slice(&tau);
        if let Err(e) = plant.step(&tau, ts) {
            outcome = RunOutcome::Failed {
                t,
                cause: RunFailure::Plant(e),
            };
            break;
        }
        if let Some(s) = stop.as_mut() {
            if plant.qd().iter().any(|v| v.abs() >= REST_SPEED) {
                s.moving_until = t + ts;
            }
            let q = plant.q();
            if (0..n).any(|i| q[i] < lower[i] || q[i] > upper[i]) {
                s.within_limits = false;
            }
        }
        rec.t.push(t);
        rec.q.extend_from_slice(&x_true[..n]);
        rec.qd.extend_from_slice(&x_true[n..]);
        rec.tau.extend_from_slice(plant.applied_torque());
        rec.q_ref.extend_from_slice(w);
        rec.flange_ref.push(reference.position(k));
        rec.step_us.push(us);
        rec.flange.push(flange);
        if let Some(m) = controller.payload_estimate() {
            rec.payload_mass_est.push(m);
        }
        if let Some(joint) = (0..n).find(|&i| rec.joint_error(k, i).is_nan()) {
            outcome = RunOutcome::Failed {
                t,
                cause: RunFailure::NonFiniteError { joint },
            };
            break;
        }
        if stop.is_none() {
            if let Some(joint) =
                (0..n).find(|&i| rec.joint_error(k, i).abs() > settings.divergence_threshold_rad)
            {
                let error_rad = rec.joint_error(k, joint);
                if let Some(law) = law.as_mut() {
                    law.begin(&x, None, model, ts);
                    stop = Some(Stopping {
                        t,
                        reason: StopReason::Diverged { joint, error_rad },
                        moving_until: t,
                        within_limits: true,
                    });
                    end = k + 1 + stop_samples;
                } else {
                    outcome = RunOutcome::Diverged {
                        t,
                        joint,
                        error_rad,
                        threshold_rad: settings.divergence_threshold_rad,
                    };
                    break;
                }
            }
        }
        if k % 100 == 0 {
            progress(k.min(total), total);
        }
        k += 1;
    }
    if let Some(s) = stop {
        if outcome.is_completed() {
            let last = rec.t.last().copied().unwrap_or(s.t) + ts;
            outcome = RunOutcome::Stopped {
                t: s.t,
                reason: s.reason,
                at_rest_after_s: (s.moving_until < last - 1e-9).then_some(s.moving_until - s.t),
                within_limits: s.within_limits,
            };
        }
    }
    progress(total, total);
    RunResult {
        record: rec,
        outcome,
        wall_s: start.elapsed().as_secs_f64(),
    }
}
