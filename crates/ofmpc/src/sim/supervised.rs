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
//! other). A stop begins on an implausible reading, a joint error beyond the
//! safety limit, a failed step or a divergence, when the settings ask for
//! the safe stop; without it those end in the status (or, for a failed
//! step, the error) the caller acts on.

use super::repair::MeasurementGuard;
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
}

impl SupervisedController {
    /// `mpc` guarded for `robot` (its speed and torque limits) by the rules
    /// of `settings`, at the controller's period; `delay_samples`: how old
    /// the readings are (the repair's prediction uses the torque of that
    /// sample).
    pub fn new(
        mpc: Mpc,
        robot: &Robot,
        settings: SupervisorSettings,
        delay_samples: usize,
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
        Ok(Self {
            supervisor: Supervisor::with_period(robot, settings, ts),
            repair: MeasurementGuard::new(&vec![0.0; 2 * n], delay_samples, true, ts),
            x: vec![0.0; 2 * n],
            from: vec![0.0; 2 * n],
            output: SupervisedOutput {
                tau: vec![0.0; n],
                status: SupervisedStatus::Controlled,
            },
            mpc,
        })
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
        self.check_len(input.x.len(), 2 * n)?;
        self.check_len(input.w_k.len(), n)?;
        self.check_len(input.preview.len(), self.mpc.horizon() * n)?;
        self.x.copy_from_slice(input.x);
        let repaired = self.repair.check(self.mpc.parts_mut().model, &mut self.x);
        let inspection = self.supervisor.inspect(&mut self.x, input.w_k);
        if let Some(reason) = inspection.trigger {
            self.begin_stop(input.t, reason);
        }
        if let Err(e) = self.control(input) {
            if !self.begin_stop(input.t, StopReason::ControllerFailed(e)) {
                return Err(SupervisedError::Step(e));
            }
            self.control(input).map_err(SupervisedError::Step)?;
        }
        self.repair.record_torque(&self.output.tau);
        self.supervisor.record_torque(&self.output.tau);
        let diverged = self.supervisor.judge(input.w_k, &self.x[..n]);
        if let Some((joint, error_rad)) = diverged {
            self.begin_stop(input.t, StopReason::Diverged { joint, error_rad });
        }
        self.output.status = self.status(input.t, repaired || inspection.rejected, diverged);
        Ok(&self.output)
    }

    /// Why the stop in progress began (`None` without one).
    pub fn stop_reason(&self) -> Option<&StopReason> {
        self.supervisor.stopping().map(|s| &s.reason)
    }

    /// The controller's diagnostics of its last successful step.
    pub fn diagnostics(&self) -> &StepOutput {
        self.mpc.output()
    }

    /// The guarded controller.
    pub fn controller(&self) -> &Mpc {
        &self.mpc
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
            let out = self.mpc.step(&step)?;
            // A numerical failure holds the last torque (the output says so):
            // the guard treats it as a failed step.
            self.output.tau.copy_from_slice(&out.tau);
            return match out.status.failure() {
                Some(failure) => Err(failure),
                None => Ok(()),
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
        Ok(())
    }

    /// Begins a stop from the state the controller last acted on (the
    /// observer's estimate, when it runs); whether one began.
    fn begin_stop(&mut self, t: f64, reason: StopReason) -> bool {
        let from = self.mpc.state_estimate().unwrap_or(&self.x);
        self.from.copy_from_slice(from);
        let model = self.mpc.parts_mut().model;
        self.supervisor.begin_stop(t, reason, &self.from, model)
    }

    fn status(
        &mut self,
        t: f64,
        repaired: bool,
        diverged: Option<(usize, f64)>,
    ) -> SupervisedStatus {
        let n = self.output.tau.len();
        match self.supervisor.stopping() {
            Some(_) => {
                self.supervisor.watch(&self.x[..n], &self.x[n..], t);
                let moving = self.x[n..].iter().any(|v| v.abs() >= REST_SPEED);
                match moving {
                    true => SupervisedStatus::Stopping,
                    false => SupervisedStatus::Stopped,
                }
            }
            None if diverged.is_some() => SupervisedStatus::Diverged,
            None if repaired => SupervisedStatus::RepairedMeasurement,
            None => SupervisedStatus::Controlled,
        }
    }

    fn check_len(&self, got: usize, expected: usize) -> Result<(), SupervisedError> {
        match got == expected {
            true => Ok(()),
            false => Err(SupervisedError::InputLength { expected, got }),
        }
    }
}
