//! The per-kind step behind [`Controller`](crate::control::Controller): the
//! internal trait every algorithm implements.

use crate::control::drive_model::DriveModel;
use crate::control::kind::ControllerKind;
use crate::control::settings::{MpcSettings, SettingsError};
use crate::control::solvers::constrained::QpStatus;
use crate::control::step::{StepFailure, StepInfo, StepInput};
use crate::dynamics::JointSpaceDynamics;

/// A predictive controller: measured state and reference preview in, torque
/// out. Object safe: hold it as `Box<dyn Algorithm + Send>`.
pub trait Algorithm {
    /// Which algorithm this is.
    fn kind(&self) -> ControllerKind;
    /// Number of joints `n`.
    fn dof(&self) -> usize;
    /// Prediction horizon `N`.
    fn horizon(&self) -> usize;
    /// The settings it was built with.
    fn settings(&self) -> &MpcSettings;
    /// Starts a run at the measured state `x0 = [q; q̇]` (2n values):
    /// `x_{−1} = x0`, `u_{−1} = 0`, `ē_{−1} = 0`.
    fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure>;
    /// The input `u` of the last successful step (`u_{k−1}` of the next one),
    /// `n` values; zero after [`Algorithm::reset`].
    fn input(&self) -> &[f64];
    /// The whole optimal sequence of the last successful step, `N·n` values
    /// in natural order: block `j` is `Δu_{k+j}` (incremental algorithms) or
    /// `u_{k+j}` (usual controller), `j = 0..N`; only block 0 is applied.
    /// Zero before the first step.
    fn increments(&self) -> &[f64];
    /// Gives the controller the drives' torque limits and friction estimates
    /// (used when the settings' torque limits or friction compensation are
    /// on; without them such a controller refuses to step,
    /// [`StepFailure::NoDriveModel`]). Allocates (sizes the constrained
    /// solver); call before a run. `ControllerBuilder` does it.
    fn set_drive_model(&mut self, drives: &DriveModel) -> Result<(), SettingsError> {
        let _ = drives;
        Err(SettingsError::DrivesUnsupported(self.kind().name()))
    }
    /// What the torque-limit QP did at the last step (`None` without limits).
    fn qp_status(&self) -> Option<QpStatus> {
        None
    }
    /// Time the last step spent on the model (terms, ZOH, predictions);
    /// `None` for the controllers that do not time it.
    fn model_time(&self) -> Option<std::time::Duration> {
        None
    }
    /// Counts the step budget of the torque-limit QP in deadline checks
    /// instead of µs (`None`: µs again; no effect without torque limits):
    /// a deterministic budget for tests of the fallback levels.
    fn set_check_budget(&mut self, _checks: Option<u32>) {}
    /// The clock of the next step's budget: the instant the caller's step
    /// began (so the work before the algorithm's, input checks and the
    /// observer, counts) and the time (µs) kept back from the torque-limit
    /// QP's deadline for the work after it (the torque, the command, the
    /// telemetry). Without it the algorithm times its own step and keeps
    /// back the longest tail it saw itself. Consumed by the next step.
    fn set_step_clock(&mut self, _start: std::time::Instant, _reserve_us: f64) {}
    /// With a step budget: when the last step's torque-limit QP returned
    /// (its work after the QP began), `None` without a budget or when the
    /// last step did not reach it.
    fn qp_end(&self) -> Option<std::time::Instant> {
        None
    }
    /// The outputs (joint positions) the controller's model predicted at its
    /// last successful step, `ŷ(k+i|k)` for `i = 1..N`, into `out` (N·n values,
    /// block `i − 1` is `ŷ_{k+i}`), from the very ZOH model and optimal
    /// sequence ([`Algorithm::increments`]) of that step
    /// (`prediction::predicted_outputs`). `false` (and `out` unspecified)
    /// for a controller without a prediction horizon (the baselines `pid`,
    /// `ctc`, `ctc-adaptive`) or an `out` not N·n long. Allocates nothing
    /// (mutable for its work buffer only: the controller's state is unchanged).
    fn predicted_outputs(&mut self, out: &mut [f64]) -> bool {
        let _ = out;
        false
    }
    /// The first-stage feedback gain of the last successful step,
    /// `K = ∂τ_k/∂x_k` with the step's model held (n × 2n, row-major, into
    /// `gain`): `τ ≈ τ_k + K (x − x_k)` near the state `x_k` the step acted
    /// on, for a faster linear feedback between samples. `false` (and `gain`
    /// unspecified) for a controller without it (the baselines, the
    /// disturbance-observer MPC, the dense solver, torque limits, or
    /// [`MpcSettings::gains`](crate::control::MpcSettings::gains) off) or a
    /// `gain` not 2n² long. Allocates nothing.
    fn first_stage_gain(&mut self, gain: &mut [f64]) -> bool {
        let _ = gain;
        false
    }
    /// One control step at sample `k`.
    ///
    /// * `model`: the controller's robot model (its `dof()` must be `n`);
    /// * `input`: the measured state `x_k = [q_k; q̇_k]` (2n values), the
    ///   current reference `w_k` (n values; used by the second algorithm,
    ///   checked by all) and the preview `w_{k+1}, …, w_{k+N}` (N·n values,
    ///   block `j−1` is `w_{k+j}`; past the end of a path repeat its last
    ///   value), [`StepInput`];
    /// * `tau`: receives `τ_k = H u_k + g` (n values, Eq. (15)), written only
    ///   on success.
    ///
    /// Allocates nothing and never panics.
    fn step(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        input: &StepInput<'_>,
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure>;
    /// The payload mass its model carries, identified online (kg); `None`
    /// for the controllers that do not identify it.
    fn payload_estimate(&self) -> Option<f64> {
        None
    }
    /// The raw measurement of this sample (`[q; q̇]` as read, possibly `D`
    /// samples old), before [`Algorithm::step`]: for the controllers that
    /// identify from measured data rather than from the state they act on
    /// (the adaptive kinds on a real arm,
    /// `RealArmIdentification`).
    /// Default: ignored. Allocates nothing.
    fn measurement(&mut self, y: &[f64]) {
        let _ = y;
    }
    /// The torque the drives applied over the period that just ended
    /// (`[t_{k−1}, t_k]`, n values, N·m), as an interface that closes its own
    /// joint loop reports it, before [`Algorithm::step`] at `t_k`: for the
    /// controllers that identify from the applied torque (the adaptive kinds
    /// through a position or velocity output, whose own `τ_k` the arm never
    /// receives). Default: ignored. Allocates nothing.
    fn applied_torque(&mut self, tau: &[f64]) {
        let _ = tau;
    }
    /// Whether the last [`Algorithm::step`] changed its model's payload at
    /// once (`dob-mpc`'s fit at rest), so that the state observer carries
    /// its disturbance over to the new model
    /// ([`crate::control::StateObserver::carry_model_change`]); reading it
    /// clears it. Default: never.
    fn take_model_change(&mut self) -> bool {
        false
    }
}
