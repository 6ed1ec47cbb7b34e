//! Predictive controllers of Section III: the usual MPC (Eq. (43)) and the
//! two offset-free incremental algorithms (Eq. (32)/(37) and (34)/(39));
//! beside them the baselines a control engineer compares against
//! (`baselines/`): joint PID with gravity compensation, computed torque,
//! its adaptive variant and the disturbance-observer MPC, behind the same
//! [`ControllerBuilder`] and [`Controller`].
//!
//! Per sample every controller
//! 1. evaluates the robot model `H, C, g` at the measured state and forms
//!    `f0 = −H⁻¹C` (`mpc/model.rs`, Eq. (6)–(12)),
//! 2. discretizes `A = [[0, I], [0, f0]]`, `B = [[0], [I]]` by exact
//!    zero-order hold ([`Zoh`], Eq. (13)),
//! 3. builds the prediction matrices ([`Predictions`], Eq. (20)–(29)),
//! 4. solves the least-squares problem `min ‖𝒜 ΔU − b‖` (Eq. (40)–(42)),
//!    either as the stacked dense system by Householder QR ([`LsqWorkspace`],
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
//! Layout: the paper's controllers in `mpc/` (model, discretization,
//! prediction, the shared step skeleton, the three algorithms and their
//! torque-limit step), the numerical solvers in `solvers/` (least squares,
//! the structured recursion, the box QP), the baselines in `baselines/`
//! (built on the `mpc/` engine); above both the adaptive variants
//! (`adaptive.rs`: they wrap an MPC or the CTC baseline); beside them the
//! builder and its object (`builder.rs`), the step types (`step.rs`) and the
//! model's failure causes they name (`model_errors.rs`), the internal
//! per-kind trait (`algorithm.rs`) and its factory (`factory.rs`), the
//! settings, the kinds, the observer and the drive model. Each of them
//! imports only those before it in: solvers, settings, drive model, step,
//! algorithm, mpc, baselines, adaptive, builder. Every public item is
//! re-exported here, at one path.

mod adaptive;
mod algorithm;
mod baselines;
mod builder;
mod command;
pub(crate) mod dead_zone;
mod drive_model;
mod factory;
mod kind;
mod model_errors;
mod mpc;
mod observer;
mod settings;
mod solvers;
mod step;
mod telemetry;

#[doc(hidden)]
pub use adaptive::AdaptiveMpc;
#[doc(hidden)]
pub use algorithm::Algorithm;
#[doc(hidden)]
pub use baselines::baseline::triple_pole_inertia_ratio_range;
pub(crate) use builder::{check_torque_limits, DEFAULT_OBSERVER_POLE};
pub use builder::{
    model_robot, BuildError, Controller, ControllerBuilder, FrictionUse, ObserverSettings,
};
pub(crate) use command::max_output_lead;
pub use command::OutputMode;
pub use drive_model::DriveModel;
#[doc(hidden)]
pub use factory::{new_controller, new_controller_with_baselines};
pub use kind::{ControllerKind, UnknownControllerKind};
pub use model_errors::{TermsError, ZohError};
#[doc(hidden)]
pub use mpc::model::LinearLikeModel;
#[doc(hidden)]
pub use mpc::prediction::{fill_f_i, fill_f_ii, fill_w_s, predicted_outputs, Predictions};
#[doc(hidden)]
pub use mpc::zoh::Zoh;
#[doc(hidden)]
pub use observer::StateObserver;
pub use settings::{
    bandwidths, BaselineSettings, DriveQuantity, MpcSettings, SettingsError, Solver, Weight,
};
#[doc(hidden)]
pub use settings::{
    structured_from_horizon, DEFAULT_CTC_BANDWIDTH, MAX_HORIZON, STRUCTURED_FROM_HORIZON,
};
pub use solvers::constrained::QpStatus;
pub use solvers::lsq::LsqError;
#[doc(hidden)]
pub use solvers::lsq::{lsq_flops, LsqWorkspace};
pub use step::{StepError, StepFailure, StepInfo, StepInput, StepOutput, StepStatus};
pub use telemetry::{FallbackLevel, StepTelemetry};

/// The former name of [`Controller`], kept crate-private only until the
/// simulator's rename (issue 34, branch B2) is merged.
// TODO(merge): remove with sim's `Mpc` names.
pub(crate) type Mpc = Controller;
