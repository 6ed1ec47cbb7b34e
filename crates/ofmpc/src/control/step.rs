//! The step types of the control layer: one sample's input and output, the
//! step's diagnostics, bad input ([`StepError`]), the numerical outcome
//! ([`StepStatus`]) and the internal algorithms' error ([`StepFailure`]).

use std::time::Duration;

use crate::control::model_errors::{TermsError, ZohError};
use crate::control::solvers::constrained::QpStatus;
use crate::control::solvers::lsq::LsqError;
use crate::control::telemetry::StepTelemetry;

/// Diagnostics of one successful control step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// Minimum of the cost, `J_min = c2ᵀ c2` (Eq. (42)).
    pub cost: f64,
    /// `max|R_ii| / min|R_ii|` of the QR factor, a lower bound of the
    /// condition number of `𝒜`.
    pub r_diag_ratio: f64,
    /// Doublings used by the ZOH discretization (grows with `‖f0‖·Ts`).
    pub zoh_squarings: u32,
}

/// Bad input to `Controller::step` or `Controller::reset`: the call did
/// nothing (the controller's state and last output are as before). The
/// numerical outcome of a step is not an error: it is
/// [`StepOutput::status`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StepError {
    /// A slice has the wrong length.
    #[error(
        "{what} has {got} values but {expected} are needed (x: 2n, w_k: n, preview: N·n, tau: n)"
    )]
    WrongLength {
        /// Which argument.
        what: &'static str,
        /// Needed length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// An input holds NaN or ±∞.
    #[error("{what}[{index}] is not finite: check the measurement and the reference")]
    NonFiniteInput {
        /// Which argument.
        what: &'static str,
        /// Index of the first bad value.
        index: usize,
    },
    /// Stepped before the first `Controller::reset`.
    #[error("the controller was stepped before it was reset at a measured state")]
    NotReset,
    /// [`Controller::reset`](crate::control::Controller::reset) passed its
    /// input checks but the algorithm could not start at `x0` (its model is
    /// unusable at that state, or the model refused the nominal payload):
    /// the reset did not complete.
    #[error("the controller could not be reset at this state: {0}")]
    ResetRefused(StepFailure),
}

impl From<StepError> for StepFailure {
    fn from(e: StepError) -> Self {
        match e {
            StepError::WrongLength {
                what,
                expected,
                got,
            } => StepFailure::WrongLength {
                what,
                expected,
                got,
            },
            StepError::NonFiniteInput { what, index } => {
                StepFailure::NonFiniteInput { what, index }
            }
            StepError::NotReset => StepFailure::Internal("stepped before reset"),
            StepError::ResetRefused(failure) => failure,
        }
    }
}

/// The numerical outcome of one `Controller::step`, in
/// [`StepOutput::status`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum StepStatus {
    /// Solved: the torque is the algorithm's optimum (with torque limits,
    /// the QP's optimum).
    Solved,
    /// The torque-limit QP stopped at its iteration cap (or a factorization
    /// inside it failed): the applied input is feasible but not optimal
    /// ([`QpStatus::fallback`]).
    QpIterationCap {
        /// Active-set iterations used.
        iterations: u32,
    },
    /// The step failed numerically (the model at this state, the
    /// discretization, a rank-deficient least-squares problem
    /// ([`LsqError::RankDeficient`]), a non-finite result, …): the fallback
    /// is to **hold the last torque** — [`StepOutput::tau`] keeps the previous
    /// step's torque (zeros before the first success), every other field of
    /// the output keeps its previous value, and the controller's state
    /// (`x_{k−1}`, `u_{k−1}`, `ē_{k−1}`) is as before the call. The observer,
    /// when it runs, has taken the measurement but not a torque. A loop
    /// should apply the held torque this sample and begin a safe stop (or
    /// end the run).
    HeldLastTorque(StepFailure),
}

impl StepStatus {
    /// The failure behind [`StepStatus::HeldLastTorque`], `None` when the
    /// step produced a new torque.
    pub fn failure(&self) -> Option<StepFailure> {
        match self {
            StepStatus::HeldLastTorque(f) => Some(*f),
            _ => None,
        }
    }
}

/// Why a control algorithm's step failed (the internal algorithms' error;
/// the built `Controller` reports it as [`StepStatus::HeldLastTorque`]).
/// The algorithm's state is as before the call.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StepFailure {
    /// A slice has the wrong length.
    #[error(
        "{what} has {got} values but {expected} are needed (x: 2n, w_k: n, preview: N·n, tau: n)"
    )]
    WrongLength {
        /// Which argument.
        what: &'static str,
        /// Needed length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// An input holds NaN or ±∞.
    #[error("{what}[{index}] is not finite: check the measurement and the reference")]
    NonFiniteInput {
        /// Which argument.
        what: &'static str,
        /// Index of the first bad value.
        index: usize,
    },
    /// The robot model is unusable at this state (dof, non-finite, H not SPD).
    #[error(transparent)]
    Model(#[from] TermsError),
    /// The discretization failed (`f0·Ts` too large or overflow).
    #[error(transparent)]
    Discretization(#[from] ZohError),
    /// The least-squares solve failed (rank loss, non-finite numbers).
    #[error(transparent)]
    Solve(#[from] LsqError),
    /// The computed input or torque is not finite.
    #[error("the computed {what}[{index}] is not finite: the problem is badly scaled or the model is wrong")]
    NonFiniteResult {
        /// `"u"` or `"tau"`.
        what: &'static str,
        /// Joint index.
        index: usize,
    },
    /// An adaptive controller was given a model that is not a rigid-body
    /// model, whose payload it cannot identify or update.
    #[error("an adaptive controller needs a rigid-body model of the robot to identify and update its payload")]
    NoRigidBodyModel,
    /// The settings ask for torque limits or friction compensation but the
    /// controller was given no drive model (`Algorithm::set_drive_model`):
    /// it would run unconstrained, or compensate nothing. Build it with
    /// `ControllerBuilder`, which supplies the drives, or set them first.
    #[error("torque limits or friction compensation are on but the controller has no drive model: give it the drives' limits and friction estimates before stepping")]
    NoDriveModel,
    /// The adaptive controller's payload estimate was refused by the model (not a physical
    /// body): the step is undone and the model keeps the payload it had.
    #[error("the identified payload is not a physical body: the controller's model keeps its previous payload")]
    PayloadRefused,
    /// An internal invariant failed (a bug: please report).
    #[error("internal error in the controller: {0} (please report this bug)")]
    Internal(&'static str),
}

/// One sample's measurement and reference, borrowed (no copy).
#[derive(Debug, Clone, Copy)]
pub struct StepInput<'a> {
    /// Measured state `x_k = [q_k; q̇_k]` (2n values; with an observer only
    /// the positions are used, possibly `D` samples old).
    pub x: &'a [f64],
    /// Current reference `w_k` (n values).
    pub w_k: &'a [f64],
    /// Preview `w_{k+1}, …, w_{k+N}` (N·n values, block `j−1` is `w_{k+j}`;
    /// past the end of a path repeat its last value).
    pub preview: &'a [f64],
}

/// What one successful `Controller::step` computed. Sized at build: the step
/// only overwrites it.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutput {
    /// The torque to apply, `τ_k = H u_k + g` (Eq. (15); plus the friction
    /// feed-forward with friction compensation), n values.
    pub tau: Box<[f64]>,
    /// Minimum of the cost, `J_min = c2ᵀ c2` (Eq. (42)).
    pub cost: f64,
    /// `max|R_ii| / min|R_ii|` of the least-squares factor.
    pub r_diag_ratio: f64,
    /// Doublings used by the ZOH discretization (Eq. (13)).
    pub zoh_squarings: u32,
    /// What the torque-limit QP did (`None` without torque limits).
    pub qp_status: Option<QpStatus>,
    /// The payload mass the model carries, identified online (kg; `None`
    /// for the kinds that do not identify it).
    pub payload_estimate: Option<f64>,
    /// Wall time of the step (observer, model, solve and torque).
    pub solve_time: Duration,
    /// The numerical outcome of the step: solved, QP at its iteration cap,
    /// or failed with the last torque held ([`StepStatus`]).
    pub status: StepStatus,
    /// With a position or velocity output
    /// ([`MpcSettings::output`](crate::control::MpcSettings::output)): the
    /// joint positions the controller's model predicted one lead time
    /// ahead ([`MpcSettings::output_lead_s`](crate::control::MpcSettings::output_lead_s);
    /// `control/command.rs`), n values (rad). Zeros with a torque output;
    /// held with the torque on a failed step.
    pub q_command: Box<[f64]>,
    /// The joint velocities predicted one lead time ahead (rad/s), as
    /// [`Self::q_command`].
    pub qd_command: Box<[f64]>,
    /// The joint accelerations predicted one lead time ahead (rad/s²), the
    /// feed-forward of the interface's own joint loop, as
    /// [`Self::q_command`].
    pub qdd_command: Box<[f64]>,
    /// With a position or velocity output and an adaptive kind that
    /// identifies its payload from the drives' applied torque
    /// (`Controller::set_applied_torque`): the torque feed-forward for an
    /// interface that adds one to its own joint loop, the identified
    /// payload's torque along the command, `ID_model − ID_nominal` at the
    /// lead point (`control/command.rs`), n values (N·m). Zeros otherwise.
    pub tau_command: Box<[f64]>,
    /// With [`MpcSettings::gains`](crate::control::MpcSettings::gains): the
    /// first-stage feedback gain `K = ∂τ_k/∂x_k` (n × 2n, row-major, N·m
    /// per rad and per rad/s) with the step's model (`H`, `g`, ZOH) held,
    /// so that between MPC samples a faster loop can apply
    /// `τ = tau_ff + K (x − x_lin)`; for the incremental algorithms
    /// (`u_k = u_{k−1} + Δu_k`) the state enters through `Δx_k` and `y_k`,
    /// and `u_{k−1}` is held. Empty when off; held with the torque on a
    /// failed step.
    pub gain: Box<[f64]>,
    /// The feed-forward of [`Self::gain`]'s law: the step's torque `τ_k`
    /// (n values; empty when off).
    pub tau_ff: Box<[f64]>,
    /// The linearization point of [`Self::gain`]'s law: the state `x_k`
    /// the step acted on (2n values; empty when off).
    pub x_lin: Box<[f64]>,
    /// Where the step's time went, what the QP did and which fallback the
    /// step took ([`StepTelemetry`]).
    pub telemetry: StepTelemetry,
}

impl StepOutput {
    /// The output of a controller with `n` joints, sized at build (the gain
    /// law's fields with `gains`), before any step.
    pub(crate) fn sized(n: usize, gains: bool) -> Self {
        let buf = |len: usize| vec![0.0; len].into_boxed_slice();
        Self {
            tau: buf(n),
            cost: 0.0,
            r_diag_ratio: 0.0,
            zoh_squarings: 0,
            qp_status: None,
            payload_estimate: None,
            solve_time: Duration::ZERO,
            status: StepStatus::Solved,
            q_command: buf(n),
            qd_command: buf(n),
            qdd_command: buf(n),
            tau_command: buf(n),
            gain: buf(if gains { 2 * n * n } else { 0 }),
            tau_ff: buf(if gains { n } else { 0 }),
            x_lin: buf(if gains { 2 * n } else { 0 }),
            telemetry: StepTelemetry::default(),
        }
    }
}
