//! How a closed-loop run ended, and why a run could not start: typed, with
//! the offending values, so that callers (the CLI, bindings) word them.

use super::format::angle_text;
use super::plant::{PlantError, PlantSettingsError};
use super::settings_error::LoopSettingsError;
use super::supervisor::{DivergenceRule, StopReason, GROWTH_FACTOR, GROWTH_WINDOW_S};
use crate::control::{SettingsError, StepFailure};
use crate::robot::ModelError;
use serde::Serialize;
use std::fmt;

/// The largest number of values (samples × recorded columns) one run may
/// record: 100 million `f64`, 800 MB. A run that would need more is rejected
/// before anything is allocated ([`ExperimentError::TooManySamples`]).
pub const MAX_RECORD_VALUES: usize = 100_000_000;

/// The ways a run ends, as written in `metrics.json` (`"ok"`,
/// `"diverged"`, `"failed"`, `"stopped"`, `"failed_stop"`, `"hunting"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RunStatus {
    /// The run went through the path and the hold.
    Ok,
    /// The closed loop was unstable: a joint error passed the divergence
    /// threshold and the run was stopped. A result, not a failure.
    Diverged,
    /// The run could not go on: a controller step or the plant's integration
    /// failed. Its metrics cover what was recorded before.
    Failed,
    /// The loop brought the robot to a safe stop (divergence, a failed step
    /// or an implausible measurement, with the safe stop enabled): at rest
    /// by the end of the record, every joint within its limits.
    Stopped,
    /// The loop tried a safe stop, but the robot was not at rest by the end
    /// of the record or a joint left its position limits: not a stop (a
    /// real cell needs its brakes). A failure, like [`RunStatus::Failed`].
    #[serde(rename = "failed_stop")]
    FailedStop,
    /// The run went through the path and the hold, but the hold did not
    /// settle: on a plant with quantized encoders, a joint's measured error
    /// moved by more than 2 encoder counts peak-to-peak over the steady
    /// window (the last part of the hold: it hunts, oscillates or drifts).
    /// A warning, not a failure: the metrics are those of a completed run.
    /// Judged from the record after the run (never on an ideal plant).
    Hunting,
}

impl RunStatus {
    /// `"ok"`, `"diverged"`, `"failed"`, `"stopped"`, `"failed_stop"` or
    /// `"hunting"`.
    pub fn name(self) -> &'static str {
        match self {
            RunStatus::Ok => "ok",
            RunStatus::Diverged => "diverged",
            RunStatus::Failed => "failed",
            RunStatus::Stopped => "stopped",
            RunStatus::FailedStop => "failed_stop",
            RunStatus::Hunting => "hunting",
        }
    }

    /// The run failed (a failed step or integration, or a failed stop):
    /// the command reports it with a non-zero exit status.
    pub fn is_failure(self) -> bool {
        matches!(self, RunStatus::Failed | RunStatus::FailedStop)
    }
}

impl fmt::Display for RunStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Why a run failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RunFailure {
    /// The controller could not be initialized at the first measurement.
    #[error("the controller could not start from the first measurement: {0}")]
    Reset(StepFailure),
    /// A control step failed (model, discretization or solve).
    #[error("the controller step failed: {0}")]
    Controller(StepFailure),
    /// The plant's integration failed (its state stopped being finite).
    #[error("the plant's integration failed: {0}")]
    Plant(PlantError),
    /// A measured joint error is NaN: the state is no longer a number.
    #[error("the error of joint {} is not a number", joint + 1)]
    NonFiniteError {
        /// 0-based joint.
        joint: usize,
    },
    /// The robot's servo interface tripped its watchdog: `misses`
    /// consecutive interface cycles without a command
    /// ([`super::ServoSettings`]'s `watchdog_misses`); the robot stops.
    #[error("the robot's servo interface tripped its watchdog after {misses} consecutive missed cycles: the controller's commands came late")]
    ServoWatchdog {
        /// Consecutive missed cycles.
        misses: u32,
    },
    /// The caller asked the loop to stop ([`super::ClosedLoop::cancel_on`]): a user's
    /// Ctrl-C, not a fault of the run.
    #[error("interrupted")]
    Interrupted,
}

/// How one closed-loop run ended.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum RunOutcome {
    /// Through the path and the hold.
    Completed,
    /// Stopped at `t` because joint `joint` (0-based) had the error
    /// `error_rad`, beyond `threshold_rad`.
    Diverged {
        /// Time of the sample that passed the threshold (s).
        t: f64,
        /// 0-based joint.
        joint: usize,
        /// The joint error `w − q` there (rad).
        error_rad: f64,
        /// The divergence threshold (rad).
        threshold_rad: f64,
        /// The rule that judged it (with [`DivergenceRule::Growth`] the
        /// threshold is the floor beyond which the error grew).
        rule: DivergenceRule,
    },
    /// Stopped at `t` by a failure.
    Failed {
        /// Time of the sample that failed (s).
        t: f64,
        /// What failed.
        cause: RunFailure,
    },
    /// The loop stopped the robot safely from `t` on (braking, then hold).
    Stopped {
        /// Time the stop began (s).
        t: f64,
        /// Why.
        reason: StopReason,
        /// How long after `t` the robot came to rest (every true joint speed
        /// below the rest speed until the end of the record), if it did.
        at_rest_after_s: Option<f64>,
        /// The true joint positions stayed within the joint limits.
        within_limits: bool,
        /// The largest true joint speed at the end of the record (rad/s).
        final_speed: f64,
    },
}

/// A stop whose robot is still faster than this at the end of the record
/// (rad/s, on any joint) did not stop it ([`RunOutcome::is_failed_stop`]):
/// slower motion (a wrist hunting in friction at a few mrad/s while held)
/// is a stop that has not settled, not a robot running away.
pub const FAILED_STOP_SPEED: f64 = 0.05;

impl RunOutcome {
    /// `Ok`, `Diverged`, `Failed`, `Stopped`, or `FailedStop` for a stop
    /// whose robot was not at rest within its limits
    /// ([`Self::is_failed_stop`]).
    pub fn status(&self) -> RunStatus {
        match self {
            RunOutcome::Completed => RunStatus::Ok,
            RunOutcome::Diverged { .. } => RunStatus::Diverged,
            RunOutcome::Failed { .. } => RunStatus::Failed,
            RunOutcome::Stopped { .. } if self.is_failed_stop() => RunStatus::FailedStop,
            RunOutcome::Stopped { .. } => RunStatus::Stopped,
        }
    }

    /// A safe stop that is not one: a joint left its position limits after
    /// the stop began, or the robot was not at rest by the end of the record
    /// (a true joint speed above `crate::sim::REST_SPEED`) and still
    /// moved faster than `FAILED_STOP_SPEED` there.
    pub fn is_failed_stop(&self) -> bool {
        matches!(
            self,
            RunOutcome::Stopped { at_rest_after_s, within_limits, final_speed, .. }
                if !within_limits || (at_rest_after_s.is_none() && (*final_speed > FAILED_STOP_SPEED || final_speed.is_nan()))
        )
    }
    /// When the run was stopped early (s), `None` when it completed.
    pub fn stopped_at(&self) -> Option<f64> {
        match self {
            RunOutcome::Completed => None,
            RunOutcome::Diverged { t, .. }
            | RunOutcome::Failed { t, .. }
            | RunOutcome::Stopped { t, .. } => Some(*t),
        }
    }
    /// True when it completed.
    pub fn is_completed(&self) -> bool {
        matches!(self, RunOutcome::Completed)
    }
}

impl fmt::Display for RunOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunOutcome::Completed => f.write_str("completed the path and the hold"),
            RunOutcome::Diverged {
                t,
                joint,
                error_rad,
                threshold_rad,
                rule,
            } => {
                write!(
                    f,
                    "diverged: the error of joint {} reached {} rad at t = {t:.3} s, beyond the \
                     divergence threshold {threshold_rad} rad",
                    joint + 1,
                    angle_text(*error_rad)
                )?;
                match rule {
                    DivergenceRule::Threshold => Ok(()),
                    DivergenceRule::Growth => write!(
                        f,
                        " and growing (at least {GROWTH_FACTOR}× the error {GROWTH_WINDOW_S}–{} s before, \
                         a joint beyond its limits or half a turn)",
                        2.0 * GROWTH_WINDOW_S
                    ),
                }
            }
            RunOutcome::Failed { t, cause } => write!(f, "failed at t = {t:.3} s: {cause}"),
            RunOutcome::Stopped {
                t,
                reason,
                at_rest_after_s,
                within_limits,
                ..
            } => {
                if self.is_failed_stop() {
                    write!(f, "the safe stop from t = {t:.3} s failed: {reason}; ")?;
                } else {
                    write!(f, "stopped safely from t = {t:.3} s: {reason}; ")?;
                }
                match at_rest_after_s {
                    Some(d) => write!(f, "at rest {d:.3} s later")?,
                    None => f.write_str("not at rest by the end of the record")?,
                }
                if !within_limits {
                    f.write_str(", beyond a joint limit")?;
                }
                Ok(())
            }
        }
    }
}

/// Why an experiment cannot be run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExperimentError {
    /// The reference was built for another number of joints.
    #[error("the reference has {reference} joints but the robot has {robot}: build the reference for this robot")]
    ReferenceDof {
        /// Joints of the reference.
        reference: usize,
        /// Joints of the robot.
        robot: usize,
    },
    /// The controller's sample time differs from the reference's.
    #[error("the controller's sample time {controller} s differs from the reference's {reference} s: use one sample time")]
    SampleTime {
        /// The controller's (s).
        controller: f64,
        /// The reference's (s).
        reference: f64,
    },
    /// The controller's tuning does not fit.
    #[error(transparent)]
    Mpc(#[from] SettingsError),
    /// Hold, divergence threshold or steady window.
    #[error(transparent)]
    Loop(#[from] LoopSettingsError),
    /// The plant's settings, or its start.
    #[error(transparent)]
    Plant(#[from] PlantError),
    /// The payload is not a physical body, or the plant's start is invalid.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The controller's settings need data the experiment does not give (torque limits on a
    /// robot with no finite peak torque): refused as [`crate::control::ControllerBuilder`]
    /// refuses it, never run unconstrained.
    #[error(transparent)]
    Build(#[from] crate::control::BuildError),
    /// The run would record more values than `MAX_RECORD_VALUES`.
    #[error(
        "the run would record {samples} samples × {columns} values = {values} values, more than the limit of {limit}: \
         shorten the path or the hold, or use a longer sample time"
    )]
    TooManySamples {
        /// Samples of the path and the hold.
        samples: usize,
        /// Values recorded per sample.
        columns: usize,
        /// `samples × columns` (saturating).
        values: usize,
        /// `MAX_RECORD_VALUES`.
        limit: usize,
    },
    /// The caller interrupted the run ([`super::Experiment::run_cancellable`]) at path time
    /// `t` (s; negative in an adaptive controller's identification): no result.
    #[error("interrupted at t = {t} s")]
    Interrupted {
        /// The time of the sample at which the run stopped (s).
        t: f64,
    },
}

impl From<PlantSettingsError> for ExperimentError {
    fn from(e: PlantSettingsError) -> Self {
        ExperimentError::Plant(PlantError::Settings(e))
    }
}
