//! Parts shared by the predictive controllers (the paper's three, their
//! adaptive variants and the disturbance-observer MPC's inner usual MPC):
//! buffers sized once, the per-sample
//! model pipeline (terms → `f0` → ZOH → predictions), the layout of the
//! least-squares system and the final `u`, `τ` update.
//!
//! With the structured solver ([`crate::control::Solver::Structured`]) the stacked
//! system is never formed: each controller writes its stage-wise model
//! (augmented state of [`stage_dims`], `A`, `B` from the ZOH blocks, `z_0`,
//! targets and affine terms) and [`crate::control::solvers::structured`] solves it; the
//! prediction matrices are then not needed either. The layout below is the
//! dense solver's.
//!
//! # Layout of `𝒜 ΔU = b`
//!
//! The paper stacks `𝒜 = [Q_YW G; Q_ΔY G1; Q_ΔU]` by cost term (Eq. (37),
//! (39)); the usual controller has `[Q_YW G1; Q_U]`. All `G` are block
//! lower-triangular. The rows and unknowns are permuted (which changes neither
//! the minimizer nor `J_min`) so that the matrix gets a block upper-triangular
//! profile that [`LsqWorkspace`] exploits:
//!
//! * unknown block `t' = 1..N` is `Δu_{k+N−t'}` (reversed order: `Δu_k`, the
//!   one applied, is the last block);
//! * row "level" `t = 1..N` holds, in this order, the `Q_YW` rows of block row
//!   `j = N+1−t` and the `Q_U` rows of unknown block `t` (usual controller).
//!
//! Block `(t, t')` is then `[Q_YW G[t'−t]; δ_{tt'} Q_U]` for `t ≤ t'` and zero
//! below: column block `t'` ends at row `2·n·t'`.
//!
//! The incremental algorithms' two tracking groups `[Q_YW S G1; Q_ΔY G1]`
//! (`S G1 = G2` or `G2 + G3`) are first halved by a constant orthogonal
//! transformation ([`crate::control::solvers::tracking`]) into `n` rows per block row,
//! `(L G1)[j, l] = Σ_{l ≤ j' ≤ j} L[j, j'] G1[j' − l]` (output by output),
//! which keeps the profile: level `t` holds those rows of block row
//! `j = N+1−t`, then the `Q_ΔU` rows of unknown block `t`. Same minimizer,
//! `J_min` and `R1` as the paper's system with half its rows.

use crate::control::drive_model::DriveModel;
use crate::control::kind::ControllerKind;
use crate::control::mpc::gains::GainWork;
use crate::control::mpc::model::LinearLikeModel;
use crate::control::mpc::prediction::{
    predicted_outputs, predicted_outputs_work, PredictionError, Predictions,
};
use crate::control::mpc::torque_limits::TorqueLimitQp;

use crate::control::mpc::zoh::Zoh;
use crate::control::settings::{MpcSettings, SettingsError, Solver};
use crate::control::solvers::constrained::QpStatus;
use crate::control::solvers::dense::gemm;
use crate::control::solvers::lsq::{LsqError, LsqInfo, LsqWorkspace};
use crate::control::solvers::structured::{StageError, StageLq};
use crate::control::solvers::tracking::{dense_entries, TrackingRows};
use crate::control::step::{StepError, StepFailure, StepInfo};
use crate::dynamics::JointSpaceDynamics;

/// What a controller's core gives [`Algorithm`](crate::control::Algorithm): the
/// accessors, `reset` and the drives, the same for every controller built on
/// it ([`Core`] for the predictive controllers, the baselines'
/// `JointLawCore`); [`impl_controller`] delegates to it.
pub(crate) trait ControllerCore {
    /// Number of joints `n`.
    fn dof(&self) -> usize;
    /// Prediction horizon `N`.
    fn horizon(&self) -> usize;
    /// The tuning.
    fn settings(&self) -> &MpcSettings;
    /// [`Algorithm::reset`](crate::control::Algorithm::reset).
    fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure>;
    /// The input `u` of the last successful step.
    fn input(&self) -> &[f64];
    /// The optimal sequence of the last successful step.
    fn increments(&self) -> &[f64];
    /// [`Algorithm::set_drive_model`](crate::control::Algorithm::set_drive_model).
    fn set_drive_model(&mut self, drives: &DriveModel) -> Result<(), SettingsError>;
    /// What the torque-limit QP did (`None`: no QP).
    fn qp_status(&self) -> Option<QpStatus> {
        None
    }
    /// Time the last step spent on the model (`None`: not timed).
    fn model_time(&self) -> Option<std::time::Duration> {
        None
    }
    /// [`crate::control::Algorithm::set_check_budget`] (no QP: nothing).
    fn set_check_budget(&mut self, _checks: Option<u32>) {}
    /// [`crate::control::Algorithm::set_step_clock`] (no QP: nothing).
    fn set_step_clock(&mut self, _start: std::time::Instant, _reserve_us: f64) {}
    /// [`crate::control::Algorithm::qp_end`] (no QP: `None`).
    fn qp_end(&self) -> Option<std::time::Instant> {
        None
    }
    /// [`Algorithm::predicted_outputs`](crate::control::Algorithm::predicted_outputs)
    /// (`false`: no prediction horizon).
    fn predicted_outputs(&mut self, out: &mut [f64]) -> bool {
        let _ = out;
        false
    }
    /// [`Algorithm::first_stage_gain`](crate::control::Algorithm::first_stage_gain)
    /// (`false`: no gain).
    fn first_stage_gain(&mut self, gain: &mut [f64]) -> bool {
        let _ = gain;
        false
    }
}

/// Implements [`Algorithm`](crate::control::Algorithm) for a controller struct with
/// a field `core` of the type `$core` (a [`ControllerCore`]): everything but
/// the step delegates to the core. The step is the core's own
/// (`core.step`, the joint laws) or the struct's method named last
/// (`run_step`, the predictive controllers), with the signature of
/// [`Algorithm::step`](crate::control::Algorithm::step):
///
/// ```text
/// impl_controller!(FirstMpc, ControllerKind::First, Core, run_step);
/// impl_controller!(PidController, ControllerKind::Pid, JointLawCore);
/// ```
macro_rules! impl_controller {
    ($ty:ty, $kind:expr, $core:ty) => {
        $crate::control::mpc::core::impl_controller!($ty, $kind, $core, core.step);
    };
    ($ty:ty, $kind:expr, $core:ty, $($step:ident).+) => {
        impl $crate::control::algorithm::Algorithm for $ty {
            fn kind(&self) -> $crate::control::kind::ControllerKind {
                $kind
            }

            fn dof(&self) -> usize {
                <$core as $crate::control::mpc::core::ControllerCore>::dof(&self.core)
            }

            fn horizon(&self) -> usize {
                <$core as $crate::control::mpc::core::ControllerCore>::horizon(&self.core)
            }

            fn settings(&self) -> &$crate::control::settings::MpcSettings {
                <$core as $crate::control::mpc::core::ControllerCore>::settings(&self.core)
            }

            fn reset(&mut self, x0: &[f64]) -> Result<(), $crate::control::step::StepFailure> {
                <$core as $crate::control::mpc::core::ControllerCore>::reset(&mut self.core, x0)
            }

            fn input(&self) -> &[f64] {
                <$core as $crate::control::mpc::core::ControllerCore>::input(&self.core)
            }

            fn increments(&self) -> &[f64] {
                <$core as $crate::control::mpc::core::ControllerCore>::increments(&self.core)
            }

            fn set_drive_model(
                &mut self,
                drives: &$crate::control::drive_model::DriveModel,
            ) -> Result<(), $crate::control::settings::SettingsError> {
                <$core as $crate::control::mpc::core::ControllerCore>::set_drive_model(
                    &mut self.core,
                    drives,
                )
            }

            fn qp_status(&self) -> Option<$crate::control::solvers::constrained::QpStatus> {
                <$core as $crate::control::mpc::core::ControllerCore>::qp_status(&self.core)
            }

            fn model_time(&self) -> Option<std::time::Duration> {
                <$core as $crate::control::mpc::core::ControllerCore>::model_time(&self.core)
            }

            fn set_check_budget(&mut self, checks: Option<u32>) {
                <$core as $crate::control::mpc::core::ControllerCore>::set_check_budget(
                    &mut self.core,
                    checks,
                )
            }

            fn set_step_clock(&mut self, start: std::time::Instant, reserve_us: f64) {
                <$core as $crate::control::mpc::core::ControllerCore>::set_step_clock(
                    &mut self.core,
                    start,
                    reserve_us,
                )
            }

            fn qp_end(&self) -> Option<std::time::Instant> {
                <$core as $crate::control::mpc::core::ControllerCore>::qp_end(&self.core)
            }

            fn predicted_outputs(&mut self, out: &mut [f64]) -> bool {
                <$core as $crate::control::mpc::core::ControllerCore>::predicted_outputs(
                    &mut self.core,
                    out,
                )
            }

            fn first_stage_gain(&mut self, gain: &mut [f64]) -> bool {
                <$core as $crate::control::mpc::core::ControllerCore>::first_stage_gain(
                    &mut self.core,
                    gain,
                )
            }

            fn step(
                &mut self,
                model: &mut dyn $crate::dynamics::JointSpaceDynamics,
                input: &$crate::control::step::StepInput<'_>,
                tau: &mut [f64],
            ) -> Result<$crate::control::step::StepInfo, $crate::control::step::StepFailure> {
                let (x, w_k, preview) = (input.x, input.w_k, input.preview);
                self.$($step).+(model, x, w_k, preview, tau)
            }
        }
    };
}
pub(crate) use impl_controller;

impl ControllerCore for Core {
    fn dof(&self) -> usize {
        Core::dof(self)
    }
    fn horizon(&self) -> usize {
        Core::horizon(self)
    }
    fn settings(&self) -> &MpcSettings {
        Core::settings(self)
    }
    fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure> {
        Core::reset(self, x0)
    }
    fn input(&self) -> &[f64] {
        Core::input(self)
    }
    fn increments(&self) -> &[f64] {
        Core::increments(self)
    }
    fn set_drive_model(&mut self, drives: &DriveModel) -> Result<(), SettingsError> {
        Core::set_drive_model(self, drives)
    }
    fn qp_status(&self) -> Option<QpStatus> {
        Core::qp_status(self)
    }
    fn model_time(&self) -> Option<std::time::Duration> {
        Some(Core::model_time(self))
    }
    fn set_check_budget(&mut self, checks: Option<u32>) {
        Core::set_check_budget(self, checks)
    }
    fn set_step_clock(&mut self, start: std::time::Instant, reserve_us: f64) {
        self.step_clock = Some((start, reserve_us));
    }
    fn qp_end(&self) -> Option<std::time::Instant> {
        self.qp_end
    }
    fn predicted_outputs(&mut self, out: &mut [f64]) -> bool {
        Core::predicted_outputs(self, out).is_ok()
    }
    fn first_stage_gain(&mut self, gain: &mut [f64]) -> bool {
        Core::first_stage_gain(self, gain)
    }
}

/// Largest accepted rows·cols of `𝒜` (64 Mi entries = 512 MiB).
const MAX_ENTRIES: usize = crate::control::settings::MAX_SYSTEM_ENTRIES;

/// The least-squares back-end of a controller, chosen once from
/// [`Solver::for_controller`]: every solver-specific buffer lives in its
/// variant, so a controller matches on one value instead of testing several
/// optional workspaces.
// One per controller, built once: the size difference costs nothing, a box
// would cost an indirection on every access of the stage-wise problem.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub(super) enum Backend {
    /// The stacked dense system by Householder QR ([`Solver::DenseQr`]).
    Dense(DenseBackend),
    /// The stage-wise square-root Riccati recursion ([`Solver::Structured`]).
    Structured(StructuredBackend),
}

/// Buffers of the dense solver (module docs: layout of `𝒜 ΔU = b`).
#[derive(Debug, Clone)]
pub(super) struct DenseBackend {
    /// The dense system `[𝒜 | b]`.
    pub(super) lsq: LsqWorkspace,
    /// The incremental algorithms' reduction of their two tracking row
    /// groups (`None` for the usual controller, which has one group).
    pub(super) tracking: Option<TrackingRows>,
    /// `Σ ‖d_i‖²` of the last [`Core::reduce_rhs`]: the part of `J_min`
    /// outside the reduced system.
    tracking_residual: f64,
}

/// Buffers of the structured solver.
#[derive(Debug, Clone)]
pub(super) struct StructuredBackend {
    /// The stage-wise problem.
    pub(super) stage: StageLq,
    /// With torque limits: the condensed problem of the constrained head of
    /// the horizon (`StageLq::condense_head`), formed and factored only on
    /// steps whose plan passes a limit (`head_ready`).
    head: Option<LsqWorkspace>,
    head_ready: bool,
}

impl Backend {
    /// The dense solver's buffers, or an internal error for the structured one.
    pub(super) fn dense_mut(&mut self) -> Result<&mut DenseBackend, StepFailure> {
        match self {
            Backend::Dense(d) => Ok(d),
            Backend::Structured(_) => {
                Err(StepFailure::Internal("dense solve without its workspace"))
            }
        }
    }

    /// The incremental algorithms' tracking rows (dense solver), or an
    /// internal error.
    pub(super) fn tracking_mut(&mut self) -> Result<&mut TrackingRows, StepFailure> {
        self.dense_mut()?
            .tracking
            .as_mut()
            .ok_or(StepFailure::Internal("dense solve without its workspace"))
    }

    /// The stage-wise problem when the structured solver is used.
    pub(super) fn stage_mut(&mut self) -> Option<&mut StageLq> {
        match self {
            Backend::Structured(s) => Some(&mut s.stage),
            Backend::Dense(_) => None,
        }
    }
}

/// The state and buffers shared by the predictive controllers (module docs).
#[derive(Debug, Clone)]
pub(crate) struct Core {
    pub(super) n: usize,
    pub(super) nh: usize,
    ts: f64,
    /// Rows of the paper's system per unknown: 3 (incremental, Eq. (37),
    /// (39)) or 2 (usual, Eq. (43)); the rank tests of both solvers use
    /// `groups·N·n` as the row count of their tolerance.
    groups: usize,
    pub(super) settings: MpcSettings,
    /// Diagonals of the square-root weights: Q_YW, Q_ΔY, Q_ΔU (or Q_U).
    pub(super) w_top: Vec<f64>,
    pub(super) w_mid: Vec<f64>,
    w_bot: Vec<f64>,
    model: LinearLikeModel,
    zoh: Zoh,
    /// `F1` and the `G1` generator; its `F2`, `F3` and the `G2`, `G3`
    /// generators are not maintained (the controllers form `F2 Δx`, `F3 Δx`
    /// from `F1 Δx` by running sums, and `G2`, `G3` enter through `G1`).
    pub(super) pred: Predictions,
    /// The least-squares solver and its buffers.
    pub(super) backend: Backend,
    /// The whole solution of the last step in natural order: block `j` is
    /// `Δu_{k+j}` (or `u_{k+j}` for the usual controller), `j = 0..N`.
    du: Vec<f64>,
    x_prev: Vec<f64>,
    u_prev: Vec<f64>,
    pub(super) ebar: Vec<f64>,
    pub(super) dx: Vec<f64>,
    u_new: Vec<f64>,
    pub(super) ebar_new: Vec<f64>,
    tau_new: Vec<f64>,
    /// N·n work vectors for F·Δx products.
    pub(super) v1: Vec<f64>,
    pub(super) v2: Vec<f64>,
    pub(super) v3: Vec<f64>,
    /// Incremental algorithm (`u_k = u_{k−1} + Δu_k`) or positional.
    incremental: bool,
    /// The drives as the controller models them ([`Core::set_drive_model`]).
    drives: Option<DriveModel>,
    /// Torque-limit QP, when `torque_limits` is on and a drive model is set.
    qp: Option<Box<TorqueLimitQp>>,
    /// Per-joint friction feed-forward `F̂(v_ref)` of the current sample.
    damping: Vec<f64>,
    /// Joints in the hold dead zone this sample ([`crate::control::dead_zone`]).
    hold: Vec<bool>,
    /// Half-width of the hold dead zone per joint (rad; 0: none).
    hold_band: Vec<f64>,
    /// Per joint: `Q_Δu`'s entry while the reference moves and the factor
    /// on it at rest (`hold_q_du_scale`); `None` when every factor is 1.
    hold_q_du: Option<(Vec<f64>, Vec<f64>)>,
    /// The measured output as the tracking rows see it: `y_k`, with `w_k` on
    /// the joints in the hold dead zone.
    pub(super) y_err: Vec<f64>,
    /// Work of [`Core::predicted_outputs`].
    predicted_work: Vec<f64>,
    /// With [`MpcSettings::gains`]: the first-stage gain's buffers
    /// ([`crate::control::mpc::gains`]).
    gains: Option<Box<GainWork>>,
    /// Time the last step spent in [`Core::prepare`].
    model_time: std::time::Duration,
    /// With a step budget: when the last step's torque-limit QP returned.
    qp_end: Option<std::time::Instant>,
    /// With a step budget: the longest time a step took after its QP (µs),
    /// kept back from the QP's deadline (when the caller gives no clock).
    tail_us: f64,
    /// The caller's clock for the next step's budget: its start and the
    /// time kept back for the work after the QP (µs);
    /// [`crate::control::Algorithm::set_step_clock`].
    step_clock: Option<(std::time::Instant, f64)>,
}

/// The per-algorithm part of one step of a paper controller: what it
/// targets, given to [`Core::step_with`], the step every paper controller
/// shares (model, prediction, least squares, torque, Eq. (6)–(15)).
pub(crate) trait StepTargets {
    /// Incremental algorithm (`u_k = u_{k−1} + Δu_k`, the reduced tracking
    /// system of Eq. (37)/(39)) rather than the positional one (Eq. (43)).
    const INCREMENTAL: bool;
    /// After [`Core::prepare`], before either solver: the algorithm's own
    /// quantities of this sample (the second's `ē_k`, Eq. (34)).
    fn begin(&mut self, _c: &mut Core, _x: &[f64], _w_k: &[f64], _preview: &[f64]) {}
    /// The stage-wise problem's initial state and targets.
    fn stage_targets(
        &mut self,
        c: &mut Core,
        x: &[f64],
        preview: &[f64],
    ) -> Result<(), StepFailure>;
    /// The stacked problem's right-hand side `b` (after its matrix is built).
    fn dense_rhs(&mut self, c: &mut Core, x: &[f64], preview: &[f64]) -> Result<(), StepFailure>;
    /// After a successful step: commit the algorithm's state.
    fn commit(&mut self, _c: &mut Core) {}
}

impl Core {
    /// One step of a paper controller, the skeleton the three share:
    /// [`Core::prepare`] (model, ZOH, predictions), the algorithm's
    /// [`StepTargets`], then either the stage-wise solve or the stacked
    /// least squares, then `τ_k = H u_k + g` ([`Core::finish`], Eq. (15)) and
    /// the algorithm's commit. Written only on success.
    pub(crate) fn step_with<T: StepTargets>(
        &mut self,
        targets: &mut T,
        model: &mut dyn JointSpaceDynamics,
        input: (&[f64], &[f64], &[f64]),
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        let (x, w_k, preview) = input;
        let start = std::time::Instant::now();
        // The caller's clock (its step's start and the time it keeps back
        // for its work after the QP), else this step's own and the longest
        // tail seen after the QP here (torque, checks, commit): the QP's
        // deadline keeps that back, so the step ends within the budget.
        let (origin, reserve_us) = self.step_clock.take().unwrap_or((start, self.tail_us));
        self.qp_end = None;
        if let Some(qp) = self.qp.as_mut() {
            let budget = self.settings.step_budget_us.map(|b| b - reserve_us);
            qp.arm(origin, budget);
        }
        self.prepare(model, x, w_k, preview, tau.len())?;
        self.model_time = start.elapsed();
        targets.begin(self, x, w_k, preview);
        let info = if self.backend.stage_mut().is_some() {
            targets.stage_targets(self, x, preview)?;
            self.fill_stage_model()?;
            self.solve_structured()?
        } else {
            if T::INCREMENTAL {
                self.build_reduced_matrix();
            } else {
                self.build_matrix();
            }
            targets.dense_rhs(self, x, preview)?;
            if T::INCREMENTAL {
                self.reduce_rhs()?;
            }
            self.solve()?
        };
        let out = self.finish(x, T::INCREMENTAL, info, tau)?;
        self.form_gain(model, x);
        targets.commit(self);
        if let Some(qp_end) = self.qp_end {
            self.tail_us = self.tail_us.max(qp_end.elapsed().as_secs_f64() * 1e6);
        }
        Ok(out)
    }
}

impl Core {
    /// Buffers for controller `kind` with `n` joints, after
    /// [`MpcSettings::validate_for_dof`]; the back-end from
    /// [`Solver::for_controller`].
    pub fn new(
        n: usize,
        settings: &MpcSettings,
        kind: ControllerKind,
    ) -> Result<Self, SettingsError> {
        settings.validate_for_dof(n)?;
        let incremental = kind != ControllerKind::Usual;
        let nh = settings.horizon;
        let groups = if incremental { 3 } else { 2 };
        let p = nh * n;
        let diag = |w: &crate::control::settings::Weight| {
            let mut v = vec![0.0; n];
            w.fill(&mut v);
            v
        };
        // The torque-limit QP (constrained.rs) works on the dense system, or on
        // the structured solver's condensed head (`head`).
        let backend = match settings.solver.for_controller(kind, nh) {
            Solver::DenseQr | Solver::Auto => Backend::Dense(DenseBackend {
                lsq: dense_workspace(n, nh, groups, incremental)?,
                tracking: match kind.base() {
                    ControllerKind::First | ControllerKind::Second => Some(TrackingRows::new(
                        &diag(&settings.q_yw),
                        &diag(&settings.q_dy),
                        nh,
                        kind.base() == ControllerKind::Second,
                    )),
                    // The usual controller (kind.base() is never adaptive).
                    _ => None,
                },
                tracking_residual: 0.0,
            }),
            Solver::Structured => {
                let mut b = structured_backend(n, settings, kind)?;
                if settings.gains {
                    b.stage.enable_gain();
                }
                Backend::Structured(b)
            }
        };
        let hold_scale: Vec<f64> = (0..n)
            .map(|i| settings.hold_q_du_scale.get(i).unwrap_or(1.0))
            .collect();
        let hold_q_du = (incremental && hold_scale.iter().any(|&f| f != 1.0))
            .then(|| (diag(&settings.q_du), hold_scale));
        Ok(Self {
            n,
            nh,
            ts: settings.ts,
            groups,
            settings: settings.clone(),
            w_top: diag(&settings.q_yw),
            w_mid: diag(&settings.q_dy),
            w_bot: if incremental {
                diag(&settings.q_du)
            } else {
                diag(&settings.q_u)
            },
            model: LinearLikeModel::new(n),
            zoh: Zoh::new(n),
            pred: Predictions::new(
                2 * n,
                n,
                n,
                if matches!(backend, Backend::Structured(_)) {
                    0
                } else {
                    nh
                },
            ),
            backend,
            du: vec![0.0; p],
            x_prev: vec![0.0; 2 * n],
            u_prev: vec![0.0; n],
            ebar: vec![0.0; n],
            dx: vec![0.0; 2 * n],
            u_new: vec![0.0; n],
            ebar_new: vec![0.0; n],
            tau_new: vec![0.0; n],
            v1: vec![0.0; p],
            v2: vec![0.0; p],
            v3: vec![0.0; p],
            incremental,
            drives: None,
            qp: None,
            damping: vec![0.0; n],
            hold: vec![false; n],
            y_err: vec![0.0; n],
            hold_band: crate::control::dead_zone::bands_rad(
                settings.encoder_counts,
                &settings.dead_zone_counts,
                n,
            ),
            hold_q_du,
            predicted_work: vec![0.0; predicted_outputs_work(n)],
            gains: settings.gains.then(|| Box::new(GainWork::new(n))),
            model_time: std::time::Duration::ZERO,
            qp_end: None,
            tail_us: 0.0,
            step_clock: None,
        })
    }

    /// Number of joints `n`.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Prediction horizon `N`.
    pub fn horizon(&self) -> usize {
        self.nh
    }

    /// The settings the controller was built with.
    pub fn settings(&self) -> &MpcSettings {
        &self.settings
    }

    /// `u_{k−1}`: the input of the last successful step.
    pub fn input(&self) -> &[f64] {
        &self.u_prev
    }

    /// The optimal sequence of the last successful step (natural order).
    pub fn increments(&self) -> &[f64] {
        &self.du
    }

    /// What the torque-limit QP did at the last step (`None` without limits).
    pub fn qp_status(&self) -> Option<QpStatus> {
        self.qp.as_ref().map(|q| q.status)
    }

    /// Time the last step spent on the model (terms, ZOH, predictions).
    pub fn model_time(&self) -> std::time::Duration {
        self.model_time
    }

    /// The torque-limit QP's budget in deadline checks (tests;
    /// `TorqueLimitQp::set_check_budget`); no effect without torque limits.
    pub fn set_check_budget(&mut self, checks: Option<u32>) {
        if let Some(qp) = self.qp.as_mut() {
            qp.set_check_budget(checks);
        }
    }

    /// The outputs the controller predicted at its last successful step,
    /// `ŷ(k+i|k)` for `i = 1..N`, into `out` (N·n values, block `i − 1` is
    /// `ŷ_{k+i}`): the step's own ZOH model (Eq. (13), at `x_k`) driven by its
    /// optimal sequence ([`Core::increments`]) from `x_k` (positional, Eq. (16))
    /// or from `Δx_k` and `y_k` (incremental, Eq. (20)–(29)),
    /// [`crate::control::mpc::prediction::predicted_outputs`]. Allocates nothing.
    pub fn predicted_outputs(&mut self, out: &mut [f64]) -> Result<(), PredictionError> {
        let n = self.n;
        let (z0, y_k) = if self.incremental {
            (&self.dx[..], Some(&self.x_prev[..n]))
        } else {
            (&self.x_prev[..], None)
        };
        predicted_outputs(&self.zoh, z0, y_k, &self.du, &mut self.predicted_work, out)
    }

    /// Gives the controller the drives' limits and friction estimates; with
    /// `torque_limits` on, sizes the QP workspace (this allocates; `step`
    /// then does not).
    pub fn set_drive_model(&mut self, drives: &DriveModel) -> Result<(), SettingsError> {
        drives.validate(self.n)?;
        self.qp = if self.settings.torque_limits {
            // The dense system, or the structured solver's condensed head of
            // nc stages (Core::new).
            let nc = self.settings.constraint_horizon.unwrap_or(self.nh);
            let blocks = match &self.backend {
                Backend::Dense(_) => self.nh,
                Backend::Structured(s) if s.head.is_some() => nc.clamp(1, self.nh),
                Backend::Structured(_) => {
                    return Err(SettingsError::DrivesUnsupported("structured solver"))
                }
            };
            Some(Box::new(TorqueLimitQp::new(
                self.n,
                blocks,
                nc,
                self.incremental,
                &drives.max_torque_nm,
            )))
        } else {
            None
        };
        self.drives = Some(drives.clone());
        Ok(())
    }

    /// True when the torque of joint `i` at this sample was held at its
    /// limit by the QP (for the anti-windup of the integrators).
    pub fn saturated(&self, i: usize) -> bool {
        self.qp
            .as_ref()
            .is_some_and(|q| q.status.active && q.saturated.get(i).copied().unwrap_or(false))
    }

    /// Commits `ē_k` (second algorithm) with anti-windup (conditional
    /// integration): the aggregated error of a joint whose torque the limits
    /// hold is not accumulated.
    pub fn commit_ebar(&mut self) {
        for i in 0..self.n {
            if !self.saturated(i) {
                self.ebar[i] = self.ebar_new[i];
            }
        }
    }

    /// `x_{−1} = x0`, `u_{−1} = 0`, `ē_{−1} = 0`.
    pub fn reset(&mut self, x0: &[f64]) -> Result<(), StepFailure> {
        check_len("x0", x0.len(), 2 * self.n)?;
        check_finite("x0", x0)?;
        self.x_prev.copy_from_slice(x0);
        self.u_prev.fill(0.0);
        self.ebar.fill(0.0);
        self.du.fill(0.0);
        Ok(())
    }

    /// Refuses to step without the drive model the settings need: torque
    /// limits without their QP would run unconstrained, friction
    /// compensation without estimates would compensate nothing.
    fn check_drives(&self) -> Result<(), StepFailure> {
        if (self.settings.torque_limits && self.qp.is_none())
            || (self.settings.friction_compensation && self.drives.is_none())
        {
            return Err(StepFailure::NoDriveModel);
        }
        Ok(())
    }

    /// The torque's first-stage feedback gain of the last successful step
    /// ([`crate::control::mpc::gains`]) into `gain` (n × 2n, row-major).
    /// `false` without it (other solver, torque limits,
    /// [`MpcSettings::gains`] off) or a `gain` not 2n² long. Allocates
    /// nothing.
    pub fn first_stage_gain(&self, gain: &mut [f64]) -> bool {
        match (&self.gains, &self.backend) {
            (Some(w), Backend::Structured(_))
                if self.qp.is_none() && gain.len() == w.gain().len() =>
            {
                gain.copy_from_slice(w.gain());
                true
            }
            _ => false,
        }
    }

    /// Forms the first-stage gain of this step (after [`Core::finish`]), at
    /// the state `x` the step acted on; nothing without it. The step has
    /// succeeded: model terms that are not finite next to `x` leave a NaN
    /// gain rather than fail it.
    fn form_gain(&mut self, model: &mut dyn JointSpaceDynamics, x: &[f64]) {
        let (Some(w), Backend::Structured(b)) = (self.gains.as_mut(), &self.backend) else {
            return;
        };
        let kz = b.stage.first_stage_gain();
        if !kz.is_empty()
            && w.form((kz, &self.hold), self.model.h(), &self.u_new, model, x)
                .is_err()
        {
            w.invalidate();
        }
    }

    /// Input checks, model terms, `f0`, ZOH, predictions and `Δx_k`.
    pub fn prepare(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        w_k: &[f64],
        preview: &[f64],
        tau_len: usize,
    ) -> Result<(), StepFailure> {
        let n = self.n;
        check_step_input(n, self.nh, x, w_k, preview, tau_len)?;
        self.check_drives()?;
        self.model.update(model, &x[..n], &x[n..])?;
        if self.settings.friction_compensation {
            if let Some(d) = &self.drives {
                // Friction feed-forward along the planned motion: the
                // estimate F(v) = F_v v + F_c tanh(v/v_s) at the reference's
                // velocity v = (w_{k+1} − w_k)/Ts, added to g so that
                // τ = H u + g + F(v) (Eq. (15)); bounded by F_c + F_v|v|.
                for (i, di) in self.damping.iter_mut().enumerate() {
                    let v = (preview[i] - w_k[i]) / self.ts;
                    *di = d.damping(i, v) * v;
                }
                self.model.add_bias_torque(&self.damping)?;
            }
        }
        // The hold dead zone (dead_zone.rs): the output error the tracking
        // rows see is zero on a resting joint within the encoder's
        // resolution, so nothing integrates it (the Δx rows still damp).
        crate::control::dead_zone::in_dead_zone_bands(
            &self.hold_band,
            w_k,
            &x[..n],
            preview,
            &mut self.hold,
        );
        for (((ye, h), w), y) in self.y_err.iter_mut().zip(&self.hold).zip(w_k).zip(x) {
            *ye = if *h { *w } else { *y };
        }
        self.hold_weights(x, w_k, preview);
        self.zoh.discretize(self.model.f0(), self.ts)?;
        if matches!(self.backend, Backend::Dense(_)) {
            self.pred
                .update_f1_and_g1_from_zoh(&self.zoh)
                .map_err(|_| StepFailure::Internal("prediction shapes"))?;
        }
        for ((d, a), b) in self.dx.iter_mut().zip(x).zip(&self.x_prev) {
            *d = a - b;
        }
        Ok(())
    }

    /// The usual (positional) algorithm's stiffer hold: `Q_u` × `scale[i]`
    /// (in `(0, 1]`) on the joints that hold on the friction's damper, as
    /// [`Core::hold_weights`] does with `Q_Δu` (`dob-mpc`'s inner MPC, its
    /// `dob_hold_gain_scale`). The dense solver only.
    pub(crate) fn set_hold_input_scale(&mut self, scale: Vec<f64>) -> Result<(), SettingsError> {
        if matches!(self.backend, Backend::Structured(_)) {
            return Err(SettingsError::HoldGainScaleStructured);
        }
        self.hold_q_du = Some((self.w_bot.clone(), scale));
        Ok(())
    }

    /// `Q_Δu` of this sample: the factor `hold_q_du_scale` on the joints with
    /// a compensated Coulomb friction (`friction_compensation`, `F_c > 0`)
    /// whose reference rests over the horizon and which creep
    /// ([`crate::control::dead_zone::creeps_at_rest`]: `|q̇| < CREEP_FACTOR · v_s`, where
    /// the friction is the stiff damper the factor is for; settings.rs says why). Beyond it — a joint broken
    /// away — the weight of the motion: the stiffer gain on the bare inertia
    /// would cycle through the delay.
    fn hold_weights(&mut self, x: &[f64], w_k: &[f64], preview: &[f64]) {
        let n = self.n;
        let Some((moving, scale)) = &self.hold_q_du else {
            return;
        };
        // The damper is the compensated friction's: none without it.
        let drives = self
            .drives
            .as_ref()
            .filter(|_| self.settings.friction_compensation);
        for (i, w) in self.w_bot.iter_mut().enumerate() {
            let creeps =
                crate::control::dead_zone::creeps_at_rest(drives, i, x[n + i], w_k, preview);
            *w = if creeps {
                moving[i] * scale[i]
            } else {
                moving[i]
            };
        }
        // The structured solver reads the weight from its stage rows.
        if let Some(st) = self.backend.stage_mut() {
            st.rd.copy_from_slice(&self.w_bot);
        }
    }

    /// Writes `𝒜` of the usual controller, `[Q_YW G1; Q_U]`, in the permuted
    /// layout (module docs).
    pub fn build_matrix(&mut self) {
        let (n, nh) = (self.n, self.nh);
        let p = nh * n;
        let top_gen = self.pred.g1_gen().as_slice();
        let Backend::Dense(DenseBackend { lsq, .. }) = &mut self.backend else {
            return;
        };
        let m = lsq.rows();
        let a = lsq.matrix_mut();
        // Column (t', jj) at level t holds the blocks of lag t' − t, so it is
        // the last t' levels of column (N, jj): write the last column block
        // (all N levels), then copy its tails into the other blocks.
        let gn = 2 * n;
        let (head, last) = a.split_at_mut((p - n) * m);
        for (jj, col) in last.chunks_exact_mut(m).enumerate() {
            let top_src = &top_gen[jj * p..jj * p + p];
            for (t, level) in col[..gn * nh].chunks_exact_mut(gn).enumerate() {
                let d = nh - 1 - t; // lag N − t
                let (top_rows, bot_rows) = level.split_at_mut(n);
                for ((r, s), w) in top_rows
                    .iter_mut()
                    .zip(&top_src[d * n..d * n + n])
                    .zip(&self.w_top)
                {
                    *r = w * s;
                }
                bot_rows.fill(0.0);
                if d == 0 {
                    bot_rows[jj] = self.w_bot[jj];
                }
            }
        }
        for tp in 1..nh {
            let len = gn * tp;
            let skip = gn * (nh - tp);
            for (jj, col) in head[(tp - 1) * n * m..tp * n * m]
                .chunks_exact_mut(m)
                .enumerate()
            {
                col[..len].copy_from_slice(&last[jj * m + skip..jj * m + skip + len]);
            }
        }
    }

    /// Writes `𝒜` of an incremental algorithm in the permuted layout with the
    /// reduced tracking rows (module docs): at level `t` (block row
    /// `j = N+1−t`) and unknown block `t'` (`Δu_{k+l−1}`, `l = N+1−t'`), row
    /// `i` holds `Σ_{l ≤ j' ≤ j} L_i[j, j'] G1[j' − l]_{i,·}`, then the `Q_ΔU`
    /// rows.
    pub fn build_reduced_matrix(&mut self) {
        if let Backend::Dense(DenseBackend {
            lsq,
            tracking: Some(tr),
            ..
        }) = &mut self.backend
        {
            let m = lsq.rows();
            tr.write_rows(
                self.pred.g1_gen().as_slice(),
                &self.w_bot,
                lsq.matrix_mut(),
                m,
            );
        }
    }

    /// Transforms the incremental algorithms' tracking right-hand side
    /// ([`TrackingRows::b`], filled by the controller) and writes the
    /// reduced `b` (module docs); keeps `Σ ‖d_i‖²` for `J_min`.
    pub fn reduce_rhs(&mut self) -> Result<(), StepFailure> {
        let n = self.n;
        let nh = self.nh;
        let Backend::Dense(DenseBackend {
            lsq,
            tracking: Some(tr),
            tracking_residual,
        }) = &mut self.backend
        else {
            return Err(StepFailure::Internal("dense solve without its workspace"));
        };
        *tracking_residual = tr.transform_rhs();
        let b = lsq.rhs_mut();
        for (tl, level) in b[..2 * n * nh].chunks_exact_mut(2 * n).enumerate() {
            let (rows, du) = level.split_at_mut(n);
            rows.copy_from_slice(tr.c(nh - 1 - tl));
            du.fill(0.0);
        }
        Ok(())
    }

    /// `out = F·v` for an N·n × 2n prediction matrix `F`.
    pub fn f_times(f: &[f64], v: &[f64], rows: usize, out: &mut [f64]) {
        gemm(rows, v.len(), 1, 1.0, f, v, 0.0, out);
    }

    /// Solves the dense least-squares system and copies its solution (stored
    /// in reversed block order) into `du`.
    pub fn solve(&mut self) -> Result<LsqInfo, StepFailure> {
        let n = self.n;
        let d = self.backend.dense_mut()?;
        let lsq = &mut d.lsq;
        let mut info = lsq.solve()?;
        info.residual_sq += d.tracking_residual;
        for (dst, src) in self
            .du
            .chunks_exact_mut(n)
            .zip(lsq.solution().chunks_exact(n).rev())
        {
            dst.copy_from_slice(src);
        }
        Ok(info)
    }

    /// Writes the per-sample part of the stage-wise model (the ZOH blocks of
    /// `A`, `B`) for controller `kind`; the caller fills `z_0`, targets and
    /// affine terms.
    pub fn fill_stage_model(&mut self) -> Result<(), StepFailure> {
        let n = self.n;
        let st = self.backend.stage_mut().ok_or(StepFailure::Internal(
            "structured solve without its workspace",
        ))?;
        let (phi1, phi2, e) = (
            self.zoh.phi1().as_slice(),
            self.zoh.phi2().as_slice(),
            self.zoh.e().as_slice(),
        );
        let nz = st.nz;
        let blocks = nz / n;
        // Every layout ends with the velocity block: Δq̇⁺ (or q̇⁺) = E · + Φ1 v,
        // and every other block row gets Φ1 from it and Φ2 from v.
        let last = blocks - 1;
        for r in 0..blocks {
            let (a_blk, b_blk) = if r == last { (e, phi1) } else { (phi1, phi2) };
            set_block(&mut st.a, nz, r * n, last * n, a_blk, n);
            set_block(&mut st.b, nz, r * n, 0, b_blk, n);
        }
        Ok(())
    }

    /// Solves the stage-wise problem (after [`Core::fill_stage_model`] and the
    /// caller's `z_0`, targets, affine terms) and copies its solution to `du`.
    pub fn solve_structured(&mut self) -> Result<LsqInfo, StepFailure> {
        let (n, nh, g) = (self.n, self.nh, self.groups);
        let Backend::Structured(StructuredBackend {
            stage: st,
            head,
            head_ready,
        }) = &mut self.backend
        else {
            return Err(StepFailure::Internal(
                "structured solve without its workspace",
            ));
        };
        let info = match st.solve() {
            Ok(info) => info,
            Err(StageError::NonFinite) => return Err(LsqError::NonFiniteResult.into()),
        };
        // The dense solver's rank test: |R_ii| > max(m, p)·ε·max|R_jj|, with
        // the columns numbered as in the dense system (Δu_{k+N−1} first).
        let tol = (g * nh * n) as f64 * f64::EPSILON * info.r_max;
        crate::control::solvers::lsq::rank_test(st.r_diagonal_dense_order(), tol)?;
        self.du.copy_from_slice(st.solution());
        // Torque limits: a plan that passes one in the constrained head gets
        // the head condensed and factored for the QP (finish).
        *head_ready = false;
        if let (Some(qp), Some(head)) = (self.qp.as_mut(), head.as_mut()) {
            if qp.violates(&self.model, &self.du, &self.u_prev) {
                let (a, b) = head.system_mut();
                st.condense_head(a, b);
                head.solve()?;
                *head_ready = true;
            }
        }
        Ok(LsqInfo {
            residual_sq: info.residual_sq,
            r_diag_ratio: info.r_diag_ratio,
        })
    }

    /// `u_k` from the solution, `τ_k = H u_k + g` (Eq. (15)); checks the
    /// result and commits `x_{k−1} ← x_k`, `u_{k−1} ← u_k`.
    pub fn finish(
        &mut self,
        x: &[f64],
        incremental: bool,
        info: LsqInfo,
        tau: &mut [f64],
    ) -> Result<StepInfo, StepFailure> {
        let n = self.n;
        let first = &self.du[..n];
        for ((u, prev), d) in self.u_new.iter_mut().zip(&self.u_prev).zip(first) {
            *u = if incremental { prev + d } else { *d };
        }
        // Torque limits over the horizon (constrained.rs): on the dense
        // system, or on the structured solver's condensed head when its plan
        // passed a limit; unchanged when the unconstrained solution respects
        // them.
        let source = match &self.backend {
            Backend::Structured(s) => s.head.as_ref().filter(|_| s.head_ready),
            Backend::Dense(d) => Some(&d.lsq),
        };
        if let Some(qp) = self.qp.as_mut() {
            match source {
                Some(lsq) => qp.enforce(&self.model, lsq, &self.u_prev, &mut self.u_new),
                None => qp.clear(),
            }
            if self.settings.step_budget_us.is_some() {
                self.qp_end = Some(std::time::Instant::now());
            }
        }
        self.model.torque(&self.u_new, &mut self.tau_new)?;
        if let Some(qp) = self.qp.as_ref().filter(|q| q.status.active) {
            // Rounding guard only: the QP keeps a relative margin of 1e-9.
            for (t, lim) in self.tau_new.iter_mut().zip(qp.limits()) {
                *t = t.clamp(-lim, *lim);
            }
        }
        check_result(&self.u_new, &self.tau_new)?;
        tau.copy_from_slice(&self.tau_new);
        self.x_prev.copy_from_slice(x);
        self.u_prev.copy_from_slice(&self.u_new);
        Ok(StepInfo {
            cost: info.residual_sq,
            r_diag_ratio: info.r_diag_ratio,
            zoh_squarings: self.zoh.squarings(),
        })
    }
}

/// The dense solver's system for `n` joints and horizon `nh`: `2·N·n` rows
/// (2 row groups per level; incremental: after the tracking rows'
/// reduction, module docs) with the block upper-triangular profile.
fn dense_workspace(
    n: usize,
    nh: usize,
    groups: usize,
    incremental: bool,
) -> Result<LsqWorkspace, SettingsError> {
    let p = nh * n;
    let m = 2 * p;
    let too_large = SettingsError::TooLarge {
        solver: Solver::DenseQr,
        rows: m,
        cols: p,
        limit: MAX_ENTRIES,
    };
    if !matches!(dense_entries(n, nh, incremental), Some(e) if e <= MAX_ENTRIES) {
        return Err(too_large);
    }
    let row_end: Vec<usize> = (0..p).map(|c| 2 * n * (c / n + 1)).collect();
    let mut lsq = LsqWorkspace::with_profile(m, p, row_end).map_err(|_| too_large)?;
    lsq.set_rank_rows(groups * p);
    Ok(lsq)
}

/// The structured solver's buffers for controller `kind`: the stage-wise
/// problem with its constant part and weights, and with torque limits the
/// condensed head of the first `constraint_horizon` stages.
fn structured_backend(
    n: usize,
    settings: &MpcSettings,
    kind: ControllerKind,
) -> Result<StructuredBackend, SettingsError> {
    let nh = settings.horizon;
    let p = nh * n;
    let incremental = kind != ControllerKind::Usual;
    let (nz, nq) = stage_dims(kind, n);
    // The largest buffers: the N stored stage rows [R_vv R_vz ρ]
    // (N·n × (n + nz + 1)) and the stacked stage matrix.
    let cols = n + nz + 1;
    let fits = |r: usize| matches!(r.checked_mul(cols), Some(e) if e <= MAX_ENTRIES);
    if !(fits(p) && fits(n + nq + nz)) {
        return Err(SettingsError::TooLarge {
            solver: Solver::Structured,
            rows: p,
            cols,
            limit: MAX_ENTRIES,
        });
    }
    let mut st = StageLq::new(n, nz, nq, nh);
    fill_stage_constants(kind, n, &mut st);
    // R = Q_Δu (Q_u), D = [Q_YW; Q_ΔY] (Q_YW) on the leading states.
    let bot = if incremental {
        &settings.q_du
    } else {
        &settings.q_u
    };
    bot.fill(&mut st.rd);
    settings.q_yw.fill(&mut st.qd[..n]);
    if incremental {
        settings.q_dy.fill(&mut st.qd[n..]);
    }
    let head = if settings.torque_limits {
        st.set_head(settings.constraint_horizon.unwrap_or(nh));
        let nc = settings.constraint_horizon.unwrap_or(nh).clamp(1, nh);
        let (m, p) = StageLq::head_dims(st.nu, st.nz, st.nq, nc);
        let too_large = SettingsError::TooLarge {
            solver: Solver::Structured,
            rows: m,
            cols: p,
            limit: MAX_ENTRIES,
        };
        if !matches!(m.checked_mul(p + 1), Some(e) if e <= MAX_ENTRIES) {
            return Err(too_large);
        }
        Some(LsqWorkspace::new(m, p).map_err(|_| too_large)?)
    } else {
        None
    };
    Ok(StructuredBackend {
        stage: st,
        head,
        head_ready: false,
    })
}

pub(crate) fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), StepError> {
    if got == expected {
        Ok(())
    } else {
        Err(StepError::WrongLength {
            what,
            expected,
            got,
        })
    }
}

/// A step's input for `n` joints and a horizon of `nh` samples: `x = [q; q̇]` (`2n`), the
/// reference `w_k` (`n`), its preview (`nh·n`), all finite, and room for `τ` (`n`); else
/// [`StepFailure::WrongLength`] or [`StepFailure::NonFiniteInput`] naming the argument. The one
/// check of every controller's `step`.
pub(crate) fn check_step_input(
    n: usize,
    nh: usize,
    x: &[f64],
    w_k: &[f64],
    preview: &[f64],
    tau_len: usize,
) -> Result<(), StepFailure> {
    check_len("x", x.len(), 2 * n)?;
    check_len("w_k", w_k.len(), n)?;
    check_len("preview", preview.len(), nh * n)?;
    check_len("tau", tau_len, n)?;
    check_finite("x", x)?;
    check_finite("w_k", w_k)?;
    Ok(check_finite("preview", preview)?)
}

/// A step's result, the input `u` and the torque `τ` (same length), must be finite: else
/// [`StepFailure::NonFiniteResult`] naming the first entry that is not (the step then changes
/// no state, so the caller may stop safely).
pub(crate) fn check_result(u: &[f64], tau: &[f64]) -> Result<(), StepFailure> {
    match u.iter().chain(tau).position(|v| !v.is_finite()) {
        Some(index) => Err(StepFailure::NonFiniteResult {
            what: if index < u.len() { "u" } else { "tau" },
            index: index % u.len(),
        }),
        None => Ok(()),
    }
}

pub(crate) fn check_finite(what: &'static str, v: &[f64]) -> Result<(), StepError> {
    match v.iter().position(|e| !e.is_finite()) {
        Some(index) => Err(StepError::NonFiniteInput { what, index }),
        None => Ok(()),
    }
}

/// `(nz, nq)` of the stage-wise problem of each controller: the augmented
/// state and how many of its leading entries the stage cost weights.
///
/// * usual, Eq. (43): `z = [q; q̇]`, cost `Q_yw (q − w)`;
/// * first, Eq. (37): `z = [y; Δq; Δq̇]`, cost `Q_yw (y − w)`, `Q_Δy Δq`;
/// * second, Eq. (39): `z = [s; Δq; y; Δq̇]` with
///   `s_j = Σ_{i≤j} (ŷ_{k+i} − w_{k+i}) − ē_k`, cost `Q_yw s`, `Q_Δy Δq`.
pub(crate) fn stage_dims(kind: ControllerKind, n: usize) -> (usize, usize) {
    // The adaptive variants run their base algorithm.
    match kind.base() {
        ControllerKind::Usual => (2 * n, n),
        ControllerKind::First => (3 * n, 2 * n),
        _ => (4 * n, 2 * n),
    }
}

/// The constant part of each controller's stage-wise model: the identity
/// blocks of `A` (position and integrator chains), and nothing else.
///
/// With `Δq⁺ = Δq + Φ1 Δq̇ + Φ2 v`, `Δq̇⁺ = E Δq̇ + Φ1 v` (Eq. (13)):
///
/// ```text
/// usual:  q⁺ = q + Φ1 q̇ + Φ2 u,             q̇⁺ = E q̇ + Φ1 u
/// first:  y⁺ = y + Δq + Φ1 Δq̇ + Φ2 v,       Δq⁺, Δq̇⁺ as above
/// second: s⁺ = s + y + Δq + Φ1 Δq̇ + Φ2 v − w_{k+j+1},
///         y⁺ = y + Δq + Φ1 Δq̇ + Φ2 v,       Δq⁺, Δq̇⁺ as above
/// ```
fn fill_stage_constants(kind: ControllerKind, n: usize, st: &mut StageLq) {
    let nz = st.nz;
    st.a.fill(0.0);
    st.b.fill(0.0);
    let mut eye = |r: usize, c: usize| {
        for i in 0..n {
            st.a[(c * n + i) * nz + r * n + i] = 1.0;
        }
    };
    match kind.base() {
        ControllerKind::Usual => eye(0, 0),
        ControllerKind::First => {
            // blocks: 0 y, 1 Δq, 2 Δq̇
            eye(0, 0);
            eye(0, 1);
            eye(1, 1);
        }
        _ => {
            // Second: blocks 0 s, 1 Δq, 2 y, 3 Δq̇
            eye(0, 0);
            eye(0, 1);
            eye(0, 2);
            eye(1, 1);
            eye(2, 1);
            eye(2, 2);
        }
    }
    // The second algorithm's c_j = [y_k − w_{k+j+1}; 0; 0; 0]; the others'
    // are zero.
    st.c_rows = if kind.base() == ControllerKind::Second {
        n
    } else {
        0
    };
}

/// Copies the n×n column-major `src` into `dst` (column-major, `ld` rows) at
/// `(r0, c0)`.
fn set_block(dst: &mut [f64], ld: usize, r0: usize, c0: usize, src: &[f64], n: usize) {
    for (j, col) in src.chunks_exact(n).enumerate() {
        let o = (c0 + j) * ld + r0;
        dst[o..o + n].copy_from_slice(col);
    }
}
