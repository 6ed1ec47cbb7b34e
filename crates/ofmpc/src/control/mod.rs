//! Predictive controllers of Section III: the usual MPC (Eq. (43)) and the
//! two offset-free incremental algorithms (Eq. (32)/(37) and (34)/(39));
//! beside them the baselines a control engineer compares against
//! ([`baseline`]): joint PID with gravity compensation ([`pid`]), computed
//! torque ([`ctc`]), its adaptive variant ([`adaptive`]) and the
//! disturbance-observer MPC ([`dob_mpc`]), behind the same [`Algorithm`]
//! trait and [`ControllerBuilder`].
//!
//! Per sample every controller
//! 1. evaluates the robot model `H, C, g` at the measured state and forms
//!    `f0 = −H⁻¹C` ([`model`], Eq. (6)–(12)),
//! 2. discretizes `A = [[0, I], [0, f0]]`, `B = [[0], [I]]` by exact
//!    zero-order hold ([`zoh`], Eq. (13)),
//! 3. builds the prediction matrices ([`prediction`], Eq. (20)–(29)),
//! 4. solves the least-squares problem `min ‖𝒜 ΔU − b‖` (Eq. (40)–(42)),
//!    either as the stacked dense system by Householder QR ([`lsq`],
//!    [`Solver::DenseQr`]) or stage-wise by a square-root Riccati recursion
//!    whose cost is linear in `N` ([`Solver::Structured`]; by default the
//!    faster of the two for the controller and horizon, [`Solver::Auto`]:
//!    the structured solver from N = 16 (usual), 20 (first), 24 (second),
//!    [`structured_from_horizon`]),
//! 5. applies the first block and returns `τ_k = H u_k + g` (Eq. (15)).
//!
//! Build a controller with [`ControllerBuilder`]: it checks that the kind,
//! the tuning, the drives and the observer fit together ([`BuildError`])
//! and returns a [`Controller`] — one object for every kind
//! ([`ControllerKind::ALL`]: the paper's three, the adaptive variants, the
//! baselines) — that owns its model of the robot, its drives, its observer
//! and its output, and steps with one [`StepInput`] into one [`StepOutput`].
//!
//! All buffers are sized at construction; [`Controller::step`] allocates
//! nothing and never panics. It refuses bad input ([`StepError`]: the
//! controller is untouched); the numerical outcome of the sample is
//! [`StepOutput::status`] ([`StepStatus`]): on a numerical failure the
//! output holds the last torque and the controller's state (`x_{k−1}`,
//! `u_{k−1}`, `ē_{k−1}`) is as before the call.
//!
//! [`Algorithm`], the per-kind step behind [`Controller`], and
//! [`new_controller`] are the lower-level path it wraps, kept public only
//! until the tests and benches step through [`Controller`] (issue 34).

pub mod adaptive;
pub mod baseline;
pub mod builder;
pub mod constrained;
pub(crate) mod core;
pub mod ctc;
pub(crate) mod dense;
pub mod dob_mpc;
pub mod drive_model;
pub mod first;
mod kind;
pub mod lsq;
pub mod model;
pub mod observer;
pub mod pid;
pub mod prediction;
pub mod second;
pub mod settings;
pub(crate) mod simd;
pub(crate) mod structured;
pub(crate) mod tracking;
pub mod usual;
pub mod zoh;

use crate::dynamics::JointSpaceDynamics;

pub use adaptive::AdaptiveMpc;
pub use baseline::{triple_pole_gains, triple_pole_inertia_ratio_range, triple_pole_is_stable};
pub use builder::{
    check_torque_limits, model_robot, BuildError, Controller, ControllerBuilder, FrictionUse, Mpc,
    MpcParts, ObserverSettings, StepInput, StepOutput, DEFAULT_OBSERVER_POLE,
};
pub use constrained::{solve_box_qp, BoxQpWork, QpStatus};
pub use ctc::CtcController;
pub use dob_mpc::DobMpc;
pub use drive_model::{DriveModel, DriveQuantity};
pub use first::FirstMpc;
pub use kind::{ControllerKind, UnknownControllerKind};
pub use lsq::{LsqError, LsqInfo, LsqWorkspace};
pub use model::{LinearLikeModel, TermsError};
pub use observer::StateObserver;
pub use pid::PidController;
pub use prediction::Predictions;
pub use second::SecondMpc;
pub use settings::{
    bandwidths, structured_from_horizon, BaselineSettings, MpcSettings, SettingsError, Solver,
    Weight, STRUCTURED_FROM_HORIZON,
};
pub use usual::UsualMpc;
pub use zoh::{Zoh, ZohError};

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

/// Bad input to [`Controller::step`] or [`Controller::reset`]: the call did
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
    /// Stepped before the first [`Controller::reset`].
    #[error("the controller was stepped before it was reset at a measured state")]
    NotReset,
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
        }
    }
}

/// The numerical outcome of one [`Controller::step`], in
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
/// the built [`Controller`] reports it as [`StepStatus::HeldLastTorque`]).
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
    /// controller was given no drive model ([`Algorithm::set_drive_model`]):
    /// it would run unconstrained, or compensate nothing. Build it with
    /// [`ControllerBuilder`], which supplies the drives, or set them first.
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
    /// solver); call before a run. [`ControllerBuilder`] does it.
    fn set_drive_model(&mut self, drives: &DriveModel) -> Result<(), SettingsError> {
        let _ = drives;
        Err(SettingsError::DrivesUnsupported(self.kind().name()))
    }
    /// What the torque-limit QP did at the last step (`None` without limits).
    fn qp_status(&self) -> Option<QpStatus> {
        None
    }
    /// The outputs (joint positions) the controller's model predicted at its
    /// last successful step, `ŷ(k+i|k)` for `i = 1..N`, into `out` (N·n values,
    /// block `i − 1` is `ŷ_{k+i}`), from the very ZOH model and optimal
    /// sequence ([`Algorithm::increments`]) of that step
    /// ([`prediction::predicted_outputs`]). `false` (and `out` unspecified)
    /// for a controller without a prediction horizon (the baselines `pid`,
    /// `ctc`, `ctc-adaptive`) or an `out` not N·n long. Allocates nothing
    /// (mutable for its work buffer only: the controller's state is unchanged).
    fn predicted_outputs(&mut self, out: &mut [f64]) -> bool {
        let _ = out;
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
}

/// Builds the controller `kind` for `n` joints after
/// [`MpcSettings::validate_for_dof`], a baseline with the default bandwidths
/// ([`BaselineSettings::default`]): [`new_controller_with_baselines`] with
/// those.
pub fn new_controller(
    kind: ControllerKind,
    n: usize,
    settings: &MpcSettings,
) -> Result<Box<dyn Algorithm + Send>, SettingsError> {
    new_controller_with_baselines(kind, n, settings, &BaselineSettings::default())
}

/// Builds the controller `kind` for `n` joints: a predictive controller of
/// the paper from `settings`, a baseline ([`ControllerKind::BASELINES`])
/// from `settings` and its bandwidth of `baselines` (the predictive kinds
/// do not read `baselines`; a baseline checks only its own bandwidth).
pub fn new_controller_with_baselines(
    kind: ControllerKind,
    n: usize,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
) -> Result<Box<dyn Algorithm + Send>, SettingsError> {
    Ok(match kind {
        ControllerKind::Usual => Box::new(UsualMpc::new(n, settings)?),
        ControllerKind::First => Box::new(FirstMpc::new(n, settings)?),
        ControllerKind::Second => Box::new(SecondMpc::new(n, settings)?),
        ControllerKind::FirstAdaptive
        | ControllerKind::SecondAdaptive
        | ControllerKind::CtcAdaptive => Box::new(AdaptiveMpc::new(kind, n, settings, baselines)?),
        ControllerKind::Pid => Box::new(PidController::new(n, settings, baselines)?),
        ControllerKind::Ctc => Box::new(CtcController::new(n, settings, baselines)?),
        ControllerKind::DobMpc => Box::new(DobMpc::new(n, settings, baselines)?),
    })
}
