//! The supervised controller: the built controller ([`Mpc`]) behind its
//! guard, one object with one `step`, for a real loop (and the C API to
//! come): it needs no plant.
//!
//! Per sample, from the raw reading: the measurement repair
//! ([`MeasurementGuard`]: a lost or non-finite value becomes the model's
//! prediction), the plausibility check and the safety limit
//! ([`Supervisor::inspect`]), the controller's step — or, once a stop began,
//! the safe-stop law on the observer's estimate — and the divergence rule
//! ([`Supervisor::judge`], on the measured positions: a real loop knows no
//! other; a simulation gives the true ones, [`SupervisedInput::truth`]). A
//! stop begins on an implausible reading, a joint error beyond the
//! safety limit, a failed step or a divergence, when the settings ask for
//! the safe stop; without it those end in the status (or, for a failed
//! step, the error) the caller acts on.
//!
//! A failed step holds the last torque for its sample and the stop law
//! brakes from the next one, from the reading; a stop on an implausible
//! reading or the safety limit starts from the state the controller last
//! acted on (the observer's estimate, when it runs). The simulator's
//! [`super::ClosedLoop`] steps its controller through this object
//! ([`SupervisedController::step_at_rest`] for the pre-roll,
//! [`SupervisedController::watch`] for the true state after each period).

use super::repair::MeasurementGuard;
use super::supervisor::Stopping;
use super::supervisor::{StopReason, Supervisor, SupervisorSettings, REST_SPEED};
use crate::control::{Mpc, StepFailure, StepInput, StepOutput};
use crate::robot::Robot;

/// One sample's raw reading and reference, borrowed.
#[derive(Debug, Clone, Copy)]
pub struct SupervisedInput<'a> {
    /// Time of the sample (s): stamps a stop.
    pub t: f64,
    /// The raw reading `[q; q̇]` (2n; NaN where a value was lost).
    pub x: &'a [f64],
    /// Current reference `w_k` (n).
    pub w_k: &'a [f64],
    /// Preview `w_{k+1}, …, w_{k+N}` (N·n).
    pub preview: &'a [f64],
    /// The true joint positions (n), known to a simulation only: when
    /// given, the divergence is judged on them instead of the measured
    /// positions, a non-finite error is reported
    /// ([`SupervisedStatus::NonFiniteError`]), and the robot is watched
    /// during a stop by the caller ([`SupervisedController::watch`]).
    pub truth: Option<&'a [f64]>,
}

/// What the supervised controller did at one sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SupervisedStatus {
    /// The controller's torque, on the reading as it came.
    Controlled,
    /// The controller's torque, on a reading whose lost, invalid or
    /// implausible values were replaced by predictions.
    RepairedMeasurement,
    /// A safe stop is in progress: the stop law's torque
    /// ([`SupervisedController::stop_reason`] says why).
    Stopping,
    /// The stop law holds the robot, which has come to rest.
    Stopped,
    /// The tracking error diverged and there is no stop law: the
    /// controller's torque is given, the caller must stop the robot.
    Diverged,
    /// The tracking error of this joint is not a number
    /// ([`SupervisedInput::truth`]): the caller must end the run.
    NonFiniteError {
        /// The first joint whose error is not a number.
        joint: usize,
    },
}

/// The output of [`SupervisedController::step`]; the controller's own
/// diagnostics of its last step are [`SupervisedController::diagnostics`].
#[derive(Debug, Clone, PartialEq)]
pub struct SupervisedOutput {
    /// The torque to command (n).
    pub tau: Vec<f64>,
    /// What produced it.
    pub status: SupervisedStatus,
}

/// Why a supervised controller cannot be built, or a step has no torque.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SupervisedError {
    /// The robot and the controller disagree on the number of joints.
    #[error("the robot has {robot} joints but the controller {controller}")]
    Dof {
        /// Joints of the robot.
        robot: usize,
        /// Joints of the controller.
        controller: usize,
    },
    /// A setting of the guard is out of its range.
    #[error("the divergence threshold is {0} rad: it must be a finite angle > 0")]
    DivergenceThreshold(f64),
    /// The input's lengths are not 2n, n and N·n.
    #[error("the input has {got} values where {expected} are expected")]
    InputLength {
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// The controller's step failed and there is no stop law to take over.
    #[error("the controller's step failed: {0}")]
    Step(StepFailure),
}

/// The controller behind its guard (module docs). Sized at construction;
/// [`Self::step`] allocates nothing.
pub struct SupervisedController {
    mpc: Mpc,
    supervisor: Supervisor,
    repair: MeasurementGuard,
    /// The reading after repair and inspection (2n).
    x: Vec<f64>,
    /// Where a stop starts from (2n).
    from: Vec<f64>,
    output: SupervisedOutput,
    /// The last step's reading was repaired or rejected.
    repaired: bool,
    /// The last step's torque is the controller's, from a successful step.
    stepped: bool,
    /// The last step called the controller's step (no stop in progress).
    called: bool,
    /// The last step's judgement began a stop (watched from the next sample).
    judged_stop: bool,
    /// The divergence the last step's judgement found.
    diverged: Option<(usize, f64)>,
    /// During a stop, with a position or velocity output: the stop law's
    /// position, velocity and acceleration command (3n,
    /// [`Self::command`]).
    stop_command: Vec<f64>,
    /// The stop's torque feed-forward: none (n zeros).
    no_torque: Vec<f64>,
}

impl SupervisedController {
    /// `mpc` guarded for `robot` (its speed and torque limits) by the rules
    /// of `settings`, at the controller's period; `delay_samples`: how old
    /// the readings are (the repair's prediction uses the torque of that
    /// sample); `track`: whether the repair also predicts between lost
    /// samples (`MeasurementGuard::new`).
    pub fn new(
        mpc: Mpc,
        robot: &Robot,
        settings: SupervisorSettings,
        delay_samples: usize,
        track: bool,
    ) -> Result<Self, SupervisedError> {
        let n = mpc.dof();
        if robot.dof() != n {
            return Err(SupervisedError::Dof {
                robot: robot.dof(),
                controller: n,
            });
        }
        let th = settings.divergence_threshold_rad;
        if !(th.is_finite() && th > 0.0) {
            return Err(SupervisedError::DivergenceThreshold(th));
        }
        let ts = mpc.settings().ts;
        Ok(Self::checked(
            mpc,
            robot,
            settings,
            ts,
            delay_samples,
            track,
        ))
    }

    /// [`Self::new`] at the period `ts` for a caller that checked the
    /// joints and the settings (the simulator's loop).
    pub(crate) fn checked(
        mpc: Mpc,
        robot: &Robot,
        settings: SupervisorSettings,
        ts: f64,
        delay_samples: usize,
        track: bool,
    ) -> Self {
        let n = mpc.dof();
        Self {
            supervisor: Supervisor::with_period(robot, settings, ts),
            repair: MeasurementGuard::new(&vec![0.0; 2 * n], delay_samples, track, ts),
            x: vec![0.0; 2 * n],
            from: vec![0.0; 2 * n],
            output: SupervisedOutput {
                tau: vec![0.0; n],
                status: SupervisedStatus::Controlled,
            },
            mpc,
            repaired: false,
            stepped: false,
            called: false,
            judged_stop: false,
            diverged: None,
            stop_command: vec![0.0; 3 * n],
            no_torque: vec![0.0; n],
        }
    }

    /// Starts a run at the reading `x0` (2n): the controller, the repair and
    /// the guard at rest there, no stop in progress.
    pub fn reset(&mut self, x0: &[f64]) -> Result<(), SupervisedError> {
        self.check_len(x0.len(), self.x.len())?;
        self.mpc
            .reset(x0)
            .map_err(|e| SupervisedError::Step(e.into()))?;
        self.repair.reset(x0);
        self.supervisor.reset(x0);
        self.output.tau.fill(0.0);
        self.output.status = SupervisedStatus::Controlled;
        Ok(())
    }

    /// One sample (module docs). `Err` only for an input of the wrong size
    /// or a failed step that no stop law can take over.
    pub fn step(&mut self, input: &SupervisedInput) -> Result<&SupervisedOutput, SupervisedError> {
        let n = self.output.tau.len();
        self.check_input(input)?;
        self.x.copy_from_slice(input.x);
        (self.stepped, self.called, self.judged_stop, self.diverged) = (false, false, false, None);
        let repaired = self.repair.check(self.mpc.parts_mut().model, &mut self.x);
        let inspection = self.supervisor.inspect(&mut self.x, input.w_k);
        self.repaired = repaired || inspection.rejected;
        if let Some(reason) = inspection.trigger {
            let from = self.mpc.state_estimate().unwrap_or(&self.x);
            self.from.copy_from_slice(from);
            self.begin_stop(input.t, reason);
        }
        let control = self.control(input);
        self.repair.record_torque(&self.output.tau);
        if let Err(e) = control {
            // Brake from the next sample (this one holds the last torque).
            self.from.copy_from_slice(&self.x);
            if !self.begin_stop(input.t, StopReason::ControllerFailed(e)) {
                return Err(SupervisedError::Step(e));
            }
        }
        self.supervisor.record_torque(&self.output.tau);
        let q = input.truth.unwrap_or(&self.x[..n]);
        if let Some(joint) = (0..n).find(|&i| (input.w_k[i] - q[i]).is_nan()) {
            self.output.status = SupervisedStatus::NonFiniteError { joint };
            return Ok(&self.output);
        }
        self.diverged = self.supervisor.judge(input.w_k, q);
        if let Some((joint, error_rad)) = self.diverged {
            self.from.copy_from_slice(&self.x);
            self.judged_stop = self.begin_stop(input.t, StopReason::Diverged { joint, error_rad });
        }
        self.output.status = self.status(input);
        Ok(&self.output)
    }

    /// One sample at rest before a run (the simulator's pre-roll, while an
    /// adaptive controller identifies its load): the controller's step on
    /// the reading `x` as it came (no repair, no inspection, no divergence
    /// judgement: [`Self::judge_at_rest`]). A failed step begins a stop from
    /// `x` ([`SupervisedStatus::Stopping`]) or, without a stop law, is the
    /// `Err`.
    pub fn step_at_rest(
        &mut self,
        t: f64,
        x: &[f64],
        w: &[f64],
        preview: &[f64],
    ) -> Result<&SupervisedOutput, SupervisedError> {
        let input = SupervisedInput {
            t,
            x,
            w_k: w,
            preview,
            truth: None,
        };
        self.check_input(&input)?;
        self.x.copy_from_slice(x);
        (self.stepped, self.called, self.judged_stop, self.diverged) = (false, false, false, None);
        self.repaired = false;
        self.output.status = SupervisedStatus::Controlled;
        if let Err(e) = self.control(&input) {
            self.from.copy_from_slice(&self.x);
            if !self.begin_stop(t, StopReason::ControllerFailed(e)) {
                return Err(SupervisedError::Step(e));
            }
            self.output.status = SupervisedStatus::Stopping;
        }
        Ok(&self.output)
    }

    /// Judges the position `q` at rest against `w` after a
    /// [`Self::step_at_rest`] by the threshold alone
    /// ([`Supervisor::divergence`]: no offset is expected at rest): the
    /// divergence found, and whether a stop began (from that sample's
    /// reading; never for an error that is not a number).
    pub fn judge_at_rest(&mut self, t: f64, w: &[f64], q: &[f64]) -> Option<((usize, f64), bool)> {
        let (joint, error_rad) = self.supervisor.divergence(w, q)?;
        self.from.copy_from_slice(&self.x);
        let began =
            !error_rad.is_nan() && self.begin_stop(t, StopReason::Diverged { joint, error_rad });
        Some(((joint, error_rad), began))
    }

    /// Starts the run proper at the reading `x0` after steps at rest: the
    /// repair and, unless a stop is under way, the guard; not the controller.
    pub fn reset_guard(&mut self, x0: &[f64]) {
        self.repair.reset(x0);
        if self.supervisor.stopping().is_none() {
            self.supervisor.reset(x0);
        }
    }

    /// Watches the robot (true `q`, `q̇`) after the period `[t, t + Ts)`
    /// during a stop, for a caller that gave [`SupervisedInput::truth`]
    /// ([`Supervisor::watch`]); a stop the judgement of this sample began
    /// is watched from the next sample on.
    pub fn watch(&mut self, q: &[f64], qd: &[f64], t: f64) {
        if !self.judged_stop {
            self.supervisor.watch(q, qd, t);
        }
    }

    /// The stop in progress (`None` without one).
    pub fn stopping(&self) -> Option<&Stopping> {
        self.supervisor.stopping()
    }

    /// Whether the last step's judgement began the stop in progress (it
    /// counts from the next sample).
    pub fn stop_began_at_judgement(&self) -> bool {
        self.judged_stop
    }

    /// The divergence (joint, error `w − q`) the last step found.
    pub fn divergence(&self) -> Option<(usize, f64)> {
        self.diverged
    }

    /// Whether the last step's reading was repaired or rejected.
    pub fn repaired(&self) -> bool {
        self.repaired
    }

    /// Whether the last step's torque came from a successful step of the
    /// controller (not the stop law, not a held torque).
    pub fn controller_stepped(&self) -> bool {
        self.stepped
    }

    /// The torque of the last step (n; also when the step was an `Err`).
    pub fn torque(&self) -> &[f64] {
        &self.output.tau
    }

    /// Prediction horizon `N` of the controller.
    pub fn horizon(&self) -> usize {
        self.mpc.horizon()
    }

    /// The payload mass the controller's model carries, identified online
    /// (kg; `None` for the kinds that do not identify it).
    pub fn payload_estimate(&mut self) -> Option<f64> {
        self.mpc.parts_mut().controller.payload_estimate()
    }

    /// The joint positions the controller predicted over its horizon at its
    /// last step into `y` (N·n; `false`: none,
    /// [`crate::control::Algorithm::predicted_outputs`]).
    pub fn predicted_outputs(&mut self, y: &mut [f64]) -> bool {
        self.mpc.parts_mut().controller.predicted_outputs(y)
    }

    /// Why the stop in progress began (`None` without one).
    pub fn stop_reason(&self) -> Option<&StopReason> {
        self.supervisor.stopping().map(|s| &s.reason)
    }

    /// The controller's diagnostics of its last successful step.
    pub fn diagnostics(&self) -> &StepOutput {
        self.mpc.output()
    }

    /// The controller's output of this sample, with its
    /// [`crate::control::StepTelemetry`], when the last step called the
    /// controller (`None` during a stop, whose torque is the stop law's).
    pub fn step_output(&self) -> Option<&StepOutput> {
        self.called.then(|| self.mpc.output())
    }

    /// The position, velocity and acceleration command of this sample for
    /// an interface that takes positions (n each; `[mpc] output`,
    /// `control/command.rs`): the controller's
    /// ([`StepOutput::q_command`] and the rest), or, during a stop, the
    /// stop law's braking trajectory one lead time ahead
    /// (`SafeStop::command`) — a position the drive's own loop
    /// brings to rest, where the controller's last command would leave it
    /// following a stale, moving target. With a torque output, the
    /// controller's (zeros).
    pub fn command(&self) -> (&[f64], &[f64], &[f64]) {
        let out = self.mpc.output();
        if self.stop_commanded() {
            let n = out.q_command.len();
            let (q, rest) = self.stop_command.split_at(n);
            let (qd, qdd) = rest.split_at(n);
            return (q, qd, qdd);
        }
        (&out.q_command, &out.qd_command, &out.qdd_command)
    }

    /// The torque feed-forward of this sample's command for an interface
    /// that adds one to its own joint loop (n): the controller's
    /// ([`StepOutput::tau_command`]: the identified payload's torque), or
    /// none during a stop (the drive's loop carries the load while it
    /// brakes).
    pub fn command_torque(&self) -> &[f64] {
        if self.stop_commanded() {
            return &self.no_torque;
        }
        &self.mpc.output().tau_command
    }

    /// Whether this sample's command is the stop law's: a stop under way
    /// whose law gave this sample's torque, with a position or velocity
    /// output.
    fn stop_commanded(&self) -> bool {
        !self.called
            && self.supervisor.stopping().is_some()
            && !self.mpc.settings().output.is_torque()
    }

    /// The guarded controller.
    pub fn controller(&self) -> &Mpc {
        &self.mpc
    }

    /// The torque the drives applied over the period that just ended, for
    /// the controller's identification through an interface that reports
    /// it ([`Mpc::set_applied_torque`]); call before [`Self::step`].
    pub fn set_applied_torque(&mut self, tau: &[f64]) -> Result<(), crate::control::StepError> {
        self.mpc.set_applied_torque(tau)
    }

    /// The torque of this sample into the output: the controller's, or the
    /// stop law's on the observer's estimate during a stop.
    fn control(&mut self, input: &SupervisedInput) -> Result<(), StepFailure> {
        if self.supervisor.stopping().is_none() {
            let step = StepInput {
                x: &self.x,
                w_k: input.w_k,
                preview: input.preview,
            };
            // Refused input and a numerical failure hold the last torque
            // (the output says so): the guard treats them as a failed step.
            self.called = true;
            let out = self.mpc.step(&step).map_err(StepFailure::from)?;
            self.output.tau.copy_from_slice(&out.tau);
            return match out.status.failure() {
                Some(failure) => Err(failure),
                None => {
                    self.stepped = true;
                    Ok(())
                }
            };
        }
        let parts = self.mpc.parts_mut();
        let model = parts.model;
        let tau = &mut self.output.tau;
        match parts.observer {
            Some(o) => {
                let xs = o.update(model, &self.x)?;
                self.supervisor.stop_torque(model, &self.x, xs, tau)?;
                o.record_torque(tau);
            }
            None => self.supervisor.stop_torque(model, &self.x, &self.x, tau)?,
        }
        let s = self.mpc.settings();
        if !s.output.is_torque() {
            // The stop's braking law is not pre-compensated for a
            // smoothing: its delay joins the lead.
            let lead = s.output_lead_s.unwrap_or(0.0) + s.output_smoothing_s.unwrap_or(0.0);
            let (q, rest) = self.stop_command.split_at_mut(self.x.len() / 2);
            let (qd, qdd) = rest.split_at_mut(q.len());
            self.supervisor.stop_command(lead, [q, qd, qdd]);
        }
        Ok(())
    }

    /// Begins a stop from `self.from`; whether one began.
    fn begin_stop(&mut self, t: f64, reason: StopReason) -> bool {
        let model = self.mpc.parts_mut().model;
        self.supervisor.begin_stop(t, reason, &self.from, model)
    }

    /// The status after a step: a stop's progress (watched on the measured
    /// state unless the caller watches the true one), a divergence without
    /// a stop law, a repaired reading, or the controller's torque.
    fn status(&mut self, input: &SupervisedInput) -> SupervisedStatus {
        let n = self.output.tau.len();
        match self.supervisor.stopping() {
            Some(_) => {
                if input.truth.is_none() {
                    self.supervisor.watch(&self.x[..n], &self.x[n..], input.t);
                }
                let moving = self.x[n..].iter().any(|v| v.abs() >= REST_SPEED);
                match moving {
                    true => SupervisedStatus::Stopping,
                    false => SupervisedStatus::Stopped,
                }
            }
            None if self.diverged.is_some() => SupervisedStatus::Diverged,
            None if self.repaired => SupervisedStatus::RepairedMeasurement,
            None => SupervisedStatus::Controlled,
        }
    }

    /// The lengths of `input`: 2n, n, N·n and n for the truth.
    fn check_input(&self, input: &SupervisedInput) -> Result<(), SupervisedError> {
        let n = self.output.tau.len();
        self.check_len(input.x.len(), 2 * n)?;
        self.check_len(input.w_k.len(), n)?;
        self.check_len(input.preview.len(), self.mpc.horizon() * n)?;
        match input.truth {
            Some(q) => self.check_len(q.len(), n),
            None => Ok(()),
        }
    }

    fn check_len(&self, got: usize, expected: usize) -> Result<(), SupervisedError> {
        match got == expected {
            true => Ok(()),
            false => Err(SupervisedError::InputLength { expected, got }),
        }
    }
}
