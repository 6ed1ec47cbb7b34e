//! The closed loop: measure, control, apply the torque over one period.

use super::actuator::Actuator;
use super::conditions::{RunConditions, SafetySettings};
use super::faults::{sample_at, LossSchedule, MeasurementFaults};
use super::horizon::HorizonRecorder;
use super::outcome::{RunFailure, RunOutcome, MAX_RECORD_VALUES};
use super::plant::{Plant, PlantError, PlantSettings, PlantSettingsError};
use super::recorder::{Record, Recorder, Sample};
use super::sensor::Sensor;
use super::servo::Servo;
use super::settings_error::LoopSettingsError;
use super::supervised::{SupervisedController, SupervisedError, SupervisedInput, SupervisedStatus};
use super::supervisor::{DivergenceRule, SupervisorSettings};
use super::telemetry::TelemetrySample;
use crate::control::{Controller, StepFailure};
use crate::motion::JointReference;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Settings of a closed-loop run.
///
/// Read from a scenario's `[simulation]`: `divergence` absent means
/// [`DivergenceRule::Threshold`] when `divergence_threshold_rad` is written,
/// else [`DivergenceRule::Growth`] (users who set the threshold keep its
/// meaning; everyone else gets the growth rule).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields, from = "LoopSettingsFile")]
pub struct LoopSettings {
    /// How long the last reference point is held after the path ends (s).
    pub hold_s: f64,
    /// The divergence threshold (rad): with [`DivergenceRule::Threshold`] a
    /// run whose joint error passes this on any joint is stopped as
    /// diverged; with [`DivergenceRule::Growth`] (the default) the error
    /// must also grow ([`DivergenceRule`]): the floor of the growth rule.
    pub divergence_threshold_rad: f64,
    /// How a divergence is recognised ([`DivergenceRule`]).
    pub divergence: DivergenceRule,
    /// The "steady" window at the end of the hold, for the metrics (s).
    pub steady_window_s: f64,
    /// Identification phase of the adaptive controllers (s, at most
    /// `MAX_IDENTIFICATION_S`): they hold the path's first point this long
    /// before the path starts, as industrial robots identify a newly attached
    /// load at rest. Not recorded (the record starts with the path at
    /// t = 0); ignored by the other controllers.
    pub identification_s: f64,
    /// Settling at rest of the controllers that do not identify the
    /// payload (s, at most `MAX_IDENTIFICATION_S`; 0, the default, none): as
    /// a real controller is engaged at rest before a path starts, they hold
    /// the path's first point this long first, under the payload they do
    /// not know. Not recorded, as the identification; its largest joint
    /// error is [`RunResult::pre_roll_peak_rad`].
    pub settle_s: f64,
    /// Check each measurement for plausibility (jumps, frozen encoders;
    /// `supervisor` module) and replace rejected values by predictions.
    pub plausibility_check: bool,
    /// On divergence, a failed controller step or an implausible
    /// measurement, bring the robot to a safe stop (brake, hold) and record
    /// `SAFE_STOP_RECORD_S` more seconds, instead of ending the run.
    pub safe_stop: bool,
}

/// [`LoopSettings`] as written in a file: the same keys, with
/// `divergence_threshold_rad` and `divergence` optional so that the rule
/// follows what the user wrote ([`LoopSettings`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct LoopSettingsFile {
    hold_s: f64,
    divergence_threshold_rad: Option<f64>,
    divergence: Option<DivergenceRule>,
    steady_window_s: f64,
    identification_s: f64,
    settle_s: f64,
    plausibility_check: bool,
    safe_stop: bool,
}

impl Default for LoopSettingsFile {
    fn default() -> Self {
        let d = LoopSettings::default();
        Self {
            hold_s: d.hold_s,
            divergence_threshold_rad: None,
            divergence: None,
            steady_window_s: d.steady_window_s,
            identification_s: d.identification_s,
            settle_s: d.settle_s,
            plausibility_check: d.plausibility_check,
            safe_stop: d.safe_stop,
        }
    }
}

impl From<LoopSettingsFile> for LoopSettings {
    fn from(f: LoopSettingsFile) -> Self {
        let d = LoopSettings::default();
        let divergence = f.divergence.unwrap_or(match f.divergence_threshold_rad {
            Some(_) => DivergenceRule::Threshold,
            None => DivergenceRule::Growth,
        });
        Self {
            hold_s: f.hold_s,
            divergence_threshold_rad: f
                .divergence_threshold_rad
                .unwrap_or(d.divergence_threshold_rad),
            divergence,
            steady_window_s: f.steady_window_s,
            identification_s: f.identification_s,
            settle_s: f.settle_s,
            plausibility_check: f.plausibility_check,
            safe_stop: f.safe_stop,
        }
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
            divergence: DivergenceRule::Growth,
            steady_window_s: 0.5,
            identification_s: 0.5,
            settle_s: 0.0,
            plausibility_check: false,
            safe_stop: false,
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
        if !(self.settle_s.is_finite() && (0.0..=MAX_IDENTIFICATION_S).contains(&self.settle_s)) {
            return Err(LoopSettingsError::SettleTime {
                value: self.settle_s,
                max: MAX_IDENTIFICATION_S,
            });
        }
        Ok(())
    }

    /// The [`super::Supervisor`]'s part of these settings, with the run's safety
    /// function ([`RunConditions::safety`]).
    pub fn supervisor(&self, safety: &SafetySettings) -> SupervisorSettings {
        SupervisorSettings {
            divergence_threshold_rad: self.divergence_threshold_rad,
            divergence: self.divergence,
            plausibility_check: self.plausibility_check,
            safe_stop: self.safe_stop,
            max_joint_error_rad: safety.max_joint_error_rad,
        }
    }

    /// Samples of the identification phase at the control period `ts`.
    pub fn identification_samples(&self, ts: f64) -> usize {
        (self.identification_s / ts).round() as usize
    }

    /// Samples of the settling at rest ([`Self::settle_s`]) at the control period `ts`.
    pub fn settle_samples(&self, ts: f64) -> usize {
        (self.settle_s / ts).round() as usize
    }

    /// Samples of the hold at the control period `ts`, saturating.
    pub fn hold_samples(&self, ts: f64) -> usize {
        (self.hold_s / ts).round() as usize
    }
}

/// Whether a run records the measurement the controller was given apart
/// from the true state: the plant's sensing is not ideal, or measurements
/// are lost ([`MeasurementFaults`]). The one rule for sizing, validating and
/// recording (`record_columns`'s `measured`).
pub fn records_measurement(plant: &PlantSettings, faults: &MeasurementFaults) -> bool {
    !(plant.measurement_is_ideal() && faults.is_empty())
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
    /// The largest joint error over the pre-roll at rest (rad, true state
    /// against the path's first point; 0 without a pre-roll): what the
    /// identification or the settling ([`LoopSettings::settle_s`]) carried
    /// before the record starts.
    pub pre_roll_peak_rad: f64,
}

/// Runs `controller` (built by [`crate::control::ControllerBuilder`], with
/// its own model of the robot and observer) against `plant` along
/// `reference`, then holds its last point for `settings.hold_s`.
///
/// The plant starts at rest wherever it was built (normally the reference's
/// first point). Row `k` of the record holds the state measured at `t_k` and
/// the torque applied over `[t_k, t_k + Ts)`. `progress(k, total)` is called
/// every 100 samples.
pub fn run_closed_loop(
    controller: Controller,
    plant: &mut Plant,
    reference: &JointReference,
    settings: &LoopSettings,
    progress: &mut dyn FnMut(usize, usize),
) -> RunResult {
    ClosedLoop::new(controller, plant, reference, settings).run(progress)
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

/// [`run_closed_loop`] with a pre-roll at rest and a payload picked up
/// mid-path: [`ClosedLoop`] with [`ClosedLoop::events`].
pub fn run_closed_loop_with(
    controller: Controller,
    plant: &mut Plant,
    reference: &JointReference,
    settings: &LoopSettings,
    events: &RunEvents,
    progress: &mut dyn FnMut(usize, usize),
) -> RunResult {
    ClosedLoop::new(controller, plant, reference, settings)
        .events(events)
        .run(progress)
}

/// The closed loop, composed of its stages: per sample
/// [`Sensor`] (the encoders on the plant's [`Plant::state`], lost samples)
/// → [`SupervisedController`] (repair, plausibility, safety limit, the
/// controller with its observer or the stop law during a safe stop, the
/// divergence judged on the true state) → [`Actuator`] (saturation, torque
/// drops, loading) → [`Plant`] (rigid body and payload) → [`Recorder`].
/// Each stage is a public type a user's own loop can use one by one; the
/// supervised controller is the one object such a loop steps, as this one
/// does (`examples/realtime_loop.rs`).
///
/// During the pre-roll (`RunEvents::pre_roll`) the reference and its
/// preview are the path's first point; a divergence or failure there is
/// reported at a negative time (`−pre_roll·Ts ≤ t < 0`). The record holds
/// the path and the hold; for a controller that identifies the payload it
/// also holds the mass estimate after each step. With an observer (the
/// controller's) the controller acts on the observer's estimate of the
/// current state instead of the (delayed, position-derived) measurement;
/// the record keeps the measurement.
///
/// Every buffer is sized by [`ClosedLoop::new`]; the samples allocate
/// nothing (the record is sized for the run).
pub struct ClosedLoop<'a> {
    /// The controller behind its guard.
    controller: SupervisedController,
    plant: &'a mut Plant,
    reference: &'a JointReference,
    settings: &'a LoopSettings,
    conditions: &'a RunConditions,
    events: RunEvents,
    sensor: Sensor,
    actuator: Actuator,
    /// The reading (2n), the true state (2n), the preview (N·n).
    x: Vec<f64>,
    x_true: Vec<f64>,
    preview: Vec<f64>,
    /// The sample of the pick-up and the payload, until it happened.
    pick_up: Option<(usize, crate::robot::Payload)>,
    /// The predicted horizons kept ([`RunConditions::horizons`]).
    horizon: Option<HorizonRecorder>,
    /// Set by another thread to end the run ([`ClosedLoop::cancel_on`]).
    cancel: Option<&'a AtomicBool>,
    /// The robot's servo interface (`[plant.servo]`), and whether this
    /// period's command is late for it.
    servo: Option<Servo>,
    late: bool,
    /// The interface reports the drives' applied torque to the controller
    /// (`reports_torque`), and a period has been driven since the start.
    reports_torque: bool,
    driven: bool,
    /// The largest joint error over the pre-roll ([`RunResult::pre_roll_peak_rad`]).
    pre_roll_peak: f64,
}

/// How a run ends early: the outcome, recorded up to there.
type Ended = RunOutcome;

impl<'a> ClosedLoop<'a> {
    /// The loop of `controller` (built by
    /// [`crate::control::ControllerBuilder`]; it has `reference`'s joints and
    /// period) against `plant` along `reference` and its hold, and no
    /// [`RunConditions`] (no pick-up
    /// time, safety limit, fault or recorded horizon): [`Self::with_conditions`]
    /// with [`RunConditions::NONE`]. Sizes every stage.
    pub fn new(
        controller: Controller,
        plant: &'a mut Plant,
        reference: &'a JointReference,
        settings: &'a LoopSettings,
    ) -> Self {
        const NONE: &RunConditions = &RunConditions::NONE;
        Self::with_conditions(controller, plant, reference, settings, NONE)
    }

    /// [`Self::new`] with the run's `conditions`: the safety limit (the
    /// [`super::Supervisor`]), the lost measurements (the [`Sensor`]'s
    /// [`LossSchedule`]) and the horizons to record. The pick-up time is an
    /// event of the run ([`Self::events`]). Sizes every stage.
    pub fn with_conditions(
        controller: Controller,
        plant: &'a mut Plant,
        reference: &'a JointReference,
        settings: &'a LoopSettings,
        conditions: &'a RunConditions,
    ) -> Self {
        let n = reference.dof();
        let ts = reference.ts();
        let horizon = controller.horizon();
        let predicted = conditions
            .horizons
            .and_then(|h| HorizonRecorder::new(controller.kind(), n, horizon, h.every, h.max));
        let lost = LossSchedule::new(&conditions.faults, ts);
        // The plant checked its settings when it was built.
        let sensor = Sensor::checked(plant.settings(), plant.robot().dof(), ts, lost);
        // The repair predicts with the torque of the reading's sample, and
        // between lost samples when samples are lost.
        let controller = SupervisedController::checked(
            controller,
            plant.robot(),
            settings.supervisor(&conditions.safety),
            ts,
            plant.settings().delay_samples,
            sensor.loses_samples(),
        );
        // The plant checked its settings when it was built.
        let actuator = plant.settings().actuator(plant.robot(), ts);
        let servo = servo_stage(&controller, plant, ts);
        let reports_torque = servo.is_some()
            && (plant.settings().servo.as_ref()).is_some_and(|s| s.reports_applied_torque());
        Self {
            controller,
            plant,
            reference,
            settings,
            conditions,
            events: RunEvents::default(),
            sensor,
            actuator,
            x: vec![0.0; 2 * n],
            x_true: vec![0.0; 2 * n],
            preview: vec![0.0; horizon * n],
            pick_up: None,
            horizon: predicted,
            cancel: None,
            servo,
            late: false,
            reports_torque,
            driven: false,
            pre_roll_peak: 0.0,
        }
    }

    /// Ends the run when `flag` becomes true (set by another thread, e.g. on a
    /// user's Ctrl-C): checked before each sample of the pre-roll, the path and
    /// the hold (one relaxed atomic load, outside the controller's `step`), the run
    /// then ends [`RunOutcome::Failed`] with [`RunFailure::Interrupted`].
    pub fn cancel_on(mut self, flag: &'a AtomicBool) -> Self {
        self.cancel = Some(flag);
        self
    }

    /// Whether the caller asked the run to end ([`Self::cancel_on`]).
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// With a pre-roll at rest and a payload picked up mid-path.
    pub fn events(mut self, events: &RunEvents) -> Self {
        self.events = *events;
        let ts = self.reference.ts();
        self.pick_up = events.pick_up.map(|(t, p)| (sample_at(t, ts), p));
        self
    }

    /// Whether the readings differ from the true state (a noisy, delayed or
    /// faulty sensor, lost samples): they are recorded too.
    fn measured(&self) -> bool {
        records_measurement(self.plant.settings(), &self.conditions.faults)
    }

    /// Runs the pre-roll, the path and the hold. `progress(k, total)` is
    /// called every 100 samples.
    pub fn run(mut self, progress: &mut dyn FnMut(usize, usize)) -> RunResult {
        let start = Instant::now();
        let n = self.reference.dof();
        let ts = self.reference.ts();
        let total = self
            .reference
            .len()
            .saturating_add(self.settings.hold_samples(ts));
        let measured = self.measured();
        let capacity = if total.saturating_mul(record_columns(n, measured)) <= MAX_RECORD_VALUES {
            total
        } else {
            // The caller did not check the bound ([`super::Experiment::run`]
            // does): grow as needed instead of reserving an absurd size.
            0
        };
        let estimates = self.controller.payload_estimate().is_some();
        let mut rec = Recorder::new(n, capacity, measured, estimates);
        let mut outcome = match self.start() {
            Ok(()) => self.follow(total, &mut rec, progress),
            Err(ended) => ended,
        };
        if let Some(s) = self.controller.stopping() {
            if outcome.is_completed() {
                let last = rec.record().t.last().copied().unwrap_or(s.t) + ts;
                let qd = &rec.record().qd;
                let final_speed = qd[qd.len().saturating_sub(n)..]
                    .iter()
                    .fold(0.0, |a: f64, v| a.max(v.abs()));
                outcome = RunOutcome::Stopped {
                    final_speed,
                    t: s.t,
                    reason: s.reason.clone(),
                    at_rest_after_s: (s.moving_until < last - 1e-9).then_some(s.moving_until - s.t),
                    within_limits: s.within_limits,
                };
            }
        }
        progress(total, total);
        let mut record = rec.into_record();
        record.horizons = self.horizon.map(HorizonRecorder::into_horizons);
        record.servo = self.servo.as_ref().map(Servo::report);
        RunResult {
            record,
            outcome,
            wall_s: start.elapsed().as_secs_f64(),
            pre_roll_peak_rad: self.pre_roll_peak,
        }
    }

    /// The first reading, every stage reset to it, and the pre-roll at rest
    /// on the path's first point.
    fn start(&mut self) -> Result<(), Ended> {
        let failed = |t: f64, cause: RunFailure| RunOutcome::Failed { t, cause };
        // The plant runs at the reference's period, and its faults (path
        // times) begin with the path, after the pre-roll.
        self.plant
            .set_period(self.reference.ts())
            .map_err(|e| failed(0.0, RunFailure::Plant(e)))?;
        self.plant.start_path_after(self.events.pre_roll);
        self.sensor
            .measure(&self.plant.state(), &mut self.x)
            .map_err(|e| failed(0.0, RunFailure::Plant(e)))?;
        self.controller
            .reset(&self.x)
            .map_err(|e| failed(0.0, RunFailure::Reset(step_failure(e))))?;
        self.start_servo().map_err(|e| failed(0.0, e))?;
        let pre_roll = self.events.pre_roll;
        for j in 0..pre_roll {
            let t = -((pre_roll - j) as f64) * self.reference.ts();
            if self.cancelled() {
                return Err(failed(t, RunFailure::Interrupted));
            }
            if self.pre_roll_sample(j, t)? {
                // A safe stop began: the path's samples brake and hold.
                break;
            }
        }
        if pre_roll > 0 {
            self.sensor
                .measure(&self.plant.state(), &mut self.x)
                .map_err(|e| failed(0.0, RunFailure::Plant(e)))?;
        }
        self.controller.reset_guard(&self.x);
        Ok(())
    }

    /// Sample `j` of the pre-roll (at time `t < 0`): hold the first point.
    /// `Ok(true)`: a failed step or a divergence began a safe stop (with
    /// the stop law: as on the path, the run then brakes and holds and ends
    /// "stopped"); without it they end the run.
    fn pre_roll_sample(&mut self, j: usize, t: f64) -> Result<bool, Ended> {
        let failed = |cause: RunFailure| RunOutcome::Failed { t, cause };
        let n = self.reference.dof();
        if j > 0 {
            self.sensor
                .measure(&self.plant.state(), &mut self.x)
                .map_err(|e| failed(RunFailure::Plant(e)))?;
        }
        let w0 = self.reference.q(0);
        for block in self.preview.chunks_mut(n.max(1)) {
            block.copy_from_slice(w0);
        }
        self.report_torque().map_err(failed)?;
        let out = self
            .controller
            .step_at_rest(t, &self.x, w0, &self.preview)
            .map_err(|e| failed(RunFailure::Controller(step_failure(e))))?;
        if out.status == SupervisedStatus::Stopping {
            return Ok(true);
        }
        self.actuate().map_err(|e| failed(RunFailure::Plant(e)))?;
        for (w, q) in w0.iter().zip(self.plant.q()) {
            self.pre_roll_peak = self.pre_roll_peak.max((w - q).abs());
        }
        // The one divergence rule ([`super::Supervisor::divergence`]): at
        // rest on the first point, the threshold alone under either rule (no
        // offset is expected there).
        match self.controller.judge_at_rest(t, w0, self.plant.q()) {
            None => Ok(false),
            Some((_, true)) => Ok(true),
            Some(((joint, error_rad), false)) => Err(RunOutcome::Diverged {
                t,
                joint,
                error_rad,
                threshold_rad: self.settings.divergence_threshold_rad,
                rule: DivergenceRule::Threshold,
            }),
        }
    }

    /// The path and the hold, from the reading [`Self::start`] left.
    fn follow(
        &mut self,
        total: usize,
        rec: &mut Recorder,
        progress: &mut dyn FnMut(usize, usize),
    ) -> RunOutcome {
        let ts = self.reference.ts();
        let stop_samples = (SAFE_STOP_RECORD_S / ts).round() as usize;
        // A stop that began in the pre-roll: the record holds its braking
        // and hold.
        let mut end = match self.controller.stopping() {
            Some(_) => stop_samples,
            None => total,
        };
        let mut k = 0;
        while k < end {
            if self.cancelled() {
                return RunOutcome::Failed {
                    t: k as f64 * ts,
                    cause: RunFailure::Interrupted,
                };
            }
            match self.sample(k, rec) {
                Ok(None) => {}
                Ok(Some(stop_began_at)) => end = stop_began_at + stop_samples,
                Err(ended) => return ended,
            }
            if k % 100 == 0 {
                progress(k.min(total), total);
            }
            k += 1;
        }
        RunOutcome::Completed
    }

    /// One sample `k` of the path or the hold. `Ok(Some(j))`: a safe stop
    /// began, counted from sample `j`; `Err`: the run ends.
    fn sample(&mut self, k: usize, rec: &mut Recorder) -> Result<Option<usize>, Ended> {
        let loop_start = Instant::now();
        let ts = self.reference.ts();
        let t = k as f64 * ts;
        let n = self.reference.dof();
        let failed = |cause: RunFailure| RunOutcome::Failed { t, cause };
        self.read(k).map_err(|e| failed(RunFailure::Plant(e)))?;
        rec.reading(&self.x);
        let w = self.reference.q(k);
        let flange = self.plant.flange_position();
        self.reference
            .preview(k, self.controller.horizon(), &mut self.preview);
        let t0 = Instant::now();
        let stopping_before = self.controller.stopping().is_some();
        self.report_torque().map_err(failed)?;
        // A missing or invalid reading: the controller runs on the model's
        // prediction; the divergence is judged on the true positions.
        let step = self.controller.step(&SupervisedInput {
            t,
            x: &self.x,
            w_k: w,
            preview: &self.preview,
            truth: Some(&self.x_true[..n]),
        });
        let status = step.map(|out| out.status);
        rec.fault(self.controller.repaired());
        if self.controller.controller_stepped() {
            if let Some(h) = &mut self.horizon {
                let controller = &mut self.controller;
                h.observe(k, |y| controller.predicted_outputs(y));
            }
        }
        rec.telemetry(&TelemetrySample::of(self.controller.step_output()));
        rec.loading(self.actuator.account(self.controller.torque()));
        let step_us = t0.elapsed().as_secs_f64() * 1e6;
        self.late = self.step_is_late(step_us);
        let status = status.map_err(|e| failed(RunFailure::Controller(step_failure(e))))?;
        self.actuate().map_err(|e| failed(RunFailure::Plant(e)))?;
        self.controller.watch(self.plant.q(), self.plant.qd(), t);
        rec.push(&Sample {
            t,
            q: &self.x_true[..n],
            qd: &self.x_true[n..],
            tau: self.plant.applied_torque(),
            w,
            flange_ref: self.reference.position(k),
            flange,
            step_us,
            payload_mass_est: self.controller.payload_estimate(),
        });
        self.servo_watchdog().map_err(failed)?;
        rec.loop_time(loop_start.elapsed().as_secs_f64() * 1e6);
        match status {
            SupervisedStatus::NonFiniteError { joint } => {
                Err(failed(RunFailure::NonFiniteError { joint }))
            }
            SupervisedStatus::Diverged => {
                let (joint, error_rad) = self.controller.divergence().unwrap_or((0, f64::NAN));
                Err(RunOutcome::Diverged {
                    t,
                    joint,
                    error_rad,
                    threshold_rad: self.settings.divergence_threshold_rad,
                    rule: self.settings.divergence,
                })
            }
            _ if stopping_before || self.controller.stopping().is_none() => Ok(None),
            _ if self.controller.stop_began_at_judgement() => Ok(Some(k + 1)),
            _ => Ok(Some(k)),
        }
    }

    /// The reading of sample `k` into `self.x` and the true state into
    /// `self.x_true`, after the payload is picked up when this is its
    /// sample.
    fn read(&mut self, k: usize) -> Result<(), PlantError> {
        let n = self.reference.dof();
        self.sensor
            .read(&self.plant.state(), k, k > 0, &mut self.x)?;
        if let Some((_, payload)) = self.pick_up.filter(|(at, _)| k >= *at) {
            self.pick_up = None;
            self.plant.set_payload(Some(payload))?;
        }
        self.x_true[..n].copy_from_slice(self.plant.q());
        self.x_true[n..].copy_from_slice(self.plant.qd());
        Ok(())
    }

    /// The controller's torque through the drives ([`Actuator::apply`])
    /// onto the plant over one period.
    fn actuate(&mut self) -> Result<(), PlantError> {
        if self.servo.is_some() {
            return self.actuate_servo();
        }
        let applied = self
            .actuator
            .apply(self.controller.torque(), self.plant.state().path_sample)?;
        self.plant.advance(applied)
    }
}

impl ClosedLoop<'_> {
    /// Checks the servo interface against the controller's output and
    /// starts it at the plant's state ([`Servo::start`]).
    fn start_servo(&mut self) -> Result<(), RunFailure> {
        let Some(servo) = self.servo.as_mut() else {
            return Ok(());
        };
        let output = self.controller.controller().settings().output;
        servo
            .check_output(output)
            .map_err(|e| RunFailure::Plant(PlantSettingsError::from(e).into()))?;
        servo
            .start(self.plant.q())
            .map_err(|e| RunFailure::Plant(e.into()))
    }

    /// Whether this sample's step, which took `step_us`, is late for the
    /// servo interface ([`Servo::is_late`]; never without one).
    fn step_is_late(&self, step_us: f64) -> bool {
        let path_sample = self.plant.state().path_sample;
        (self.servo.as_ref()).is_some_and(|s| s.is_late(path_sample, step_us * 1e-6))
    }

    /// The drives' torque applied over the last period
    /// ([`Plant::applied_torque`]) to the controller, when the interface
    /// reports it and a period was driven.
    fn report_torque(&mut self) -> Result<(), RunFailure> {
        if !(self.reports_torque && self.driven) {
            return Ok(());
        }
        self.controller
            .set_applied_torque(self.plant.applied_torque())
            .map_err(|_| {
                RunFailure::Controller(StepFailure::Internal(
                    "the plant's applied torque is not n finite values",
                ))
            })
    }

    /// The servo interface's watchdog: `Err` once it tripped.
    fn servo_watchdog(&self) -> Result<(), RunFailure> {
        match self.servo.as_ref().filter(|s| s.tripped()) {
            Some(servo) => Err(RunFailure::ServoWatchdog {
                misses: servo.report().max_consecutive_misses,
            }),
            None => Ok(()),
        }
    }

    /// The controller's command through the servo interface
    /// ([`Servo::receive`], late or not) and its drives, substep by substep
    /// ([`Servo::drive`]), through the drives' clamp ([`Actuator::apply`])
    /// onto the plant ([`Plant::advance_with`]).
    fn actuate_servo(&mut self) -> Result<(), PlantError> {
        let Some(servo) = self.servo.as_mut() else {
            return Ok(());
        };
        // The controller's command, or the stop law's during a stop.
        // A torque interface takes the controller's torque; one that closes
        // its own loop, the command's torque feed-forward (which it adds
        // with `torque_feedforward`).
        let (q, qd, qdd) = self.controller.command();
        let tau = if self.controller.controller().settings().output.is_torque() {
            self.controller.torque()
        } else {
            self.controller.command_torque()
        };
        servo.receive(tau, q, qd, qdd, self.late);
        self.late = false;
        let path_sample = self.plant.state().path_sample;
        let substep = self.plant.period() / self.plant.substeps() as f64;
        let actuator = &mut self.actuator;
        self.plant.advance_with(&mut |i, q, qd, tau| {
            servo.drive(i, q, qd, tau, substep)?;
            let applied = actuator.apply(tau, path_sample)?;
            tau.copy_from_slice(applied);
            Ok(())
        })?;
        self.driven = true;
        Ok(())
    }
}

/// The servo stage of the plant's `[plant.servo]` for `controller`'s model
/// at the period `ts`; `None` without one, or when its settings do not fit
/// (the plant checked them when it was built, and again at the loop's
/// period).
fn servo_stage(controller: &SupervisedController, plant: &Plant, ts: f64) -> Option<Servo> {
    let settings = plant.settings().servo.as_ref()?;
    let model = controller.controller().model().robot();
    Servo::new(settings, model, ts, plant.settings().substep).ok()
}

/// The step failure behind a supervised controller's error (the loop sizes
/// every input, so only a failed step is expected).
fn step_failure(e: SupervisedError) -> StepFailure {
    match e {
        SupervisedError::Step(f) => f,
        _ => StepFailure::Internal("the loop gave the controller an input of the wrong size"),
    }
}
