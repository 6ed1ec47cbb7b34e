//! Stability of the closed loop near rest against an inertia mismatch.
//!
//! The plant is the controller's own robot model with its joint-space
//! inertia scaled by `1/α` (`α = H_model / H_plant`; gravity and Coriolis
//! terms as in the model): `q̈ = α H(q)⁻¹ (τ − C(q, q̇) q̇ − g(q))`, integrated by
//! RK4 under zero-order-hold torque. At rest at a pose `q₀`, `τ = g(q₀)` is an
//! equilibrium of plant and controller together. The one-sample map of the
//! closed loop, in the deviation of the augmented state
//!
//! * usual MPC: `z_k = x_k`,
//! * first algorithm: `z_k = [x_k; u_{k−1}]`,
//! * second algorithm: `z_k = [x_k; u_{k−1}; ē_{k−1}]`
//!
//! (`x = [q; q̇]`; the controllers' memory of Eq. (32) and (34) is
//! `x_{k−1}, u_{k−1}` and also `ē_{k−1}` for the second algorithm, but once the
//! loop has run one sample `x_k = Φ x_{k−1} + Γ u_{k−1}` with the plant's
//! invertible transition `Φ`, so `x_{k−1}` is a function of `z_k`: the
//! minimal state; regressing on the redundant one would leave directions the
//! loop never visits undetermined and give spurious eigenvalues), is
//! linearized by perturbation of the **actual controller step**
//! ([`crate::control::Algorithm::step`]) and the plant: short closed-loop
//! runs from small random deviations (a random `x_{−1}` through
//! [`crate::control::Algorithm::reset`], a random plant state, a random
//! first reference to excite `u` and `ē`) give pairs `(z_k, z_{k+1})` and the
//! matrix `M` with `z_{k+1} = M z_k` by least squares (exact for the linear
//! part: the deviations are 1e-7). The loop is stable near rest iff the
//! spectral radius `ρ(M) < 1`.
//!
//! With scalar weights the controller is isotropic in the input `u`, so a
//! matrix mismatch `H_plant⁻¹ H_model` acts mode by mode through its
//! eigenvalues: the loop stays stable while every generalized eigenvalue of
//! `(H_model, H_plant)` lies in the interval of scalar `α`
//! ([`inertia_ratio_range`], [`max_payload`]).
//!
//! Every function that builds the controller takes its tuning as the
//! controller does ([`crate::control::new_controller_with_baselines`]): the
//! [`MpcSettings`] and the [`BaselineSettings`], of which a baseline kind
//! reads its bandwidth and the predictive kinds nothing. The augmented state
//! above is that of the paper's controllers; a baseline's memory (its
//! integral, its observer's estimate) is not in it, and the analysis refuses
//! the baselines ([`StabilityError::Baseline`]).

use crate::control::{
    new_controller_with_baselines, Algorithm, BaselineSettings, ControllerKind, MpcSettings,
    SettingsError, StepFailure,
};
use crate::dynamics::{JointSpaceDynamics, RobotDynamics};
use crate::linalg::{random, rk4_second_order_step, RK4_WORK_PER_DOF};
use crate::robot::{ModelError, Payload, Robot};
use nalgebra::{DMatrix, DVector};

/// Options of the analysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityOptions {
    /// Smallest `α` searched (the lower end is reported as this when the
    /// loop is still stable there).
    pub alpha_min: f64,
    /// Largest `α` searched.
    pub alpha_max: f64,
    /// Width of the bisection's final bracket.
    pub tolerance: f64,
    /// Size of the state deviations (rad, rad/s).
    pub perturbation: f64,
    /// RK4 substeps per control period of the analysis plant.
    pub substeps: usize,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        Self {
            alpha_min: 0.01,
            alpha_max: 4.0,
            tolerance: 1e-3,
            perturbation: 1e-7,
            substeps: 10,
        }
    }
}

/// Why the analysis could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StabilityError {
    /// The tuning does not fit the robot.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// A controller step failed during the perturbation runs.
    #[error("a controller step failed at the pose: {0}")]
    Step(#[from] StepFailure),
    /// The pose or the payload is not valid for the robot.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The plant's state stopped being finite.
    #[error("the analysis plant's state stopped being finite at α = {alpha}")]
    NonFinite {
        /// The inertia ratio.
        alpha: f64,
    },
    /// The adaptive variants identify the payload: analyse their base algorithm.
    #[error("{kind} identifies the payload online: analyse the algorithm it runs ({base})", kind = .0, base = .0.base())]
    Adaptive(ControllerKind),
    /// A baseline's memory (its integral, its observer's estimate) is not in the augmented
    /// state of the analysis, which models the paper's predictive controllers: its spectral
    /// radius would be that of another loop.
    #[error("the stability analysis models the paper's predictive controllers; {0} is a baseline whose own state (integral, observer) it does not model: compare it in closed-loop simulation")]
    Baseline(ControllerKind),
    /// The loop is not stable even with an exact model (α = 1).
    #[error("the closed loop is not stable near rest even with an exact model (spectral radius {radius} at α = 1): change the tuning")]
    UnstableAtExactModel {
        /// `ρ(M)` at `α = 1`.
        radius: f64,
    },
    /// An option is out of range.
    #[error("the analysis option {what} is {value}: {requirement}")]
    Option {
        /// Which option.
        what: &'static str,
        /// Its value.
        value: f64,
        /// What it must satisfy.
        requirement: &'static str,
    },
}

impl StabilityOptions {
    fn validate(&self) -> Result<(), StabilityError> {
        let bad = |what, value, requirement| {
            Err(StabilityError::Option {
                what,
                value,
                requirement,
            })
        };
        if !(self.alpha_min > 0.0 && self.alpha_min < 1.0) {
            return bad("alpha_min", self.alpha_min, "it must be in (0, 1)");
        }
        if !(self.alpha_max > 1.0 && self.alpha_max.is_finite()) {
            return bad("alpha_max", self.alpha_max, "it must be finite and > 1");
        }
        if !(self.tolerance > 0.0 && self.tolerance < 0.5) {
            return bad("tolerance", self.tolerance, "it must be in (0, 0.5)");
        }
        if !(self.perturbation > 0.0 && self.perturbation < 1e-2) {
            return bad("perturbation", self.perturbation, "it must be in (0, 0.01)");
        }
        if self.substeps == 0 || self.substeps > 1000 {
            return bad(
                "substeps",
                self.substeps as f64,
                "it must be from 1 to 1000",
            );
        }
        Ok(())
    }
}

/// The analysis plant: the model with its inertia scaled by `1/α`.
struct ScaledPlant {
    model: RobotDynamics,
    alpha: f64,
    h: DMatrix<f64>,
    c: DMatrix<f64>,
    g: DVector<f64>,
}

impl ScaledPlant {
    fn accel(&mut self, q: &[f64], qd: &[f64], tau: &[f64]) -> Option<DVector<f64>> {
        self.model
            .terms(q, qd, &mut self.h, &mut self.c, &mut self.g);
        let rhs =
            DVector::from_column_slice(tau) - &self.c * DVector::from_column_slice(qd) - &self.g;
        let chol = self.h.clone().cholesky()?;
        Some(chol.solve(&rhs) * self.alpha)
    }

    /// Advances `x = [q; q̇]` by `ts` under constant `tau` (RK4 substeps, [`crate::linalg`]).
    fn step(&mut self, x: &mut [f64], tau: &[f64], ts: f64, substeps: usize) -> Option<()> {
        let n = tau.len();
        let h = ts / substeps as f64;
        let mut work = vec![0.0; RK4_WORK_PER_DOF * n];
        let (q, v) = x[..2 * n].split_at_mut(n);
        for _ in 0..substeps {
            rk4_second_order_step(q, v, h, &mut work, |q, v, a| {
                a.copy_from_slice(self.accel(q, v, tau).ok_or(())?.as_slice());
                Ok::<(), ()>(())
            })
            .ok()?;
        }
        x.iter().all(|v| v.is_finite()).then_some(())
    }
}

/// Blocks of the state for `kind` besides `x_k`: (u_{k−1}, ē_{k−1}).
fn memory(kind: ControllerKind) -> (bool, bool) {
    match kind {
        ControllerKind::Usual => (false, false),
        ControllerKind::First => (true, false),
        _ => (true, true),
    }
}

/// One stability question: the loop of controller `kind` with `settings` (and the baselines'
/// `baselines`) on the model `robot`, near rest at `q0`, analysed with `options`. Its methods
/// are the analyses of this module; [`inertia_ratio_range`] and [`max_payload`] translate their
/// inertia-ratio intervals into payloads.
#[derive(Debug, Clone, Copy)]
pub struct StabilityProblem<'a> {
    /// The controller's model (its payload, if any, is what the controller assumes).
    pub robot: &'a Robot,
    /// The controller (the paper's three; not adaptive, not a baseline).
    pub kind: ControllerKind,
    /// The controller's settings.
    pub settings: &'a MpcSettings,
    /// The baselines' settings (what building a controller takes).
    pub baselines: &'a BaselineSettings,
    /// The rest pose (one value per joint).
    pub q0: &'a [f64],
    /// Perturbation size, bisection bounds, plant substeps.
    pub options: &'a StabilityOptions,
}

impl StabilityProblem<'_> {
    /// The matrix `M` of the closed loop's one-sample map near rest at `q0`
    /// (see the module doc), for the plant with inertia ratio `alpha`.
    pub fn closed_loop_matrix(&self, alpha: f64) -> Result<DMatrix<f64>, StabilityError> {
        let p = self;
        closed_loop_matrix(
            p.robot,
            p.kind,
            p.settings,
            p.baselines,
            p.q0,
            alpha,
            p.options,
        )
    }

    /// `ρ(M)`: the largest eigenvalue modulus of [`StabilityProblem::closed_loop_matrix`].
    pub fn spectral_radius(&self, alpha: f64) -> Result<f64, StabilityError> {
        let p = self;
        spectral_radius(
            p.robot,
            p.kind,
            p.settings,
            p.baselines,
            p.q0,
            alpha,
            p.options,
        )
    }

    /// The loop linearized once (`LinearizedLoop`; the errors of
    /// [`StabilityProblem::closed_loop_matrix`]).
    pub fn linearized(&self) -> Result<LinearizedLoop, StabilityError> {
        let p = self;
        LinearizedLoop::new(p.robot, p.kind, p.settings, p.baselines, p.q0, p.options)
    }

    /// The interval `[lo, hi] ∋ 1` of `α` over which the loop near rest at `q0`
    /// is stable (`ρ < 1`), by bisection from `α = 1` towards
    /// [`StabilityOptions::alpha_min`] and [`StabilityOptions::alpha_max`] (a
    /// bound still stable there is reported as that end). Assumes one interval.
    /// `ρ(α)` is that of the loop linearized once (`LinearizedLoop`).
    pub fn alpha_interval(&self) -> Result<(f64, f64), StabilityError> {
        let p = self;
        alpha_interval(p.robot, p.kind, p.settings, p.baselines, p.q0, p.options)
    }

    /// [`StabilityProblem::alpha_interval`] with `ρ` of
    /// [`StabilityProblem::spectral_radius`] (the controller's perturbation runs
    /// repeated at every `α`): the slower reference the linearized loop is
    /// checked against.
    pub fn alpha_interval_by_perturbation(&self) -> Result<(f64, f64), StabilityError> {
        let p = self;
        alpha_interval_by_perturbation(p.robot, p.kind, p.settings, p.baselines, p.q0, p.options)
    }

    /// A closed-loop simulation near rest at `q0` with the plant's inertia
    /// scaled by `1/α` (the analysis plant), from a deviation of size
    /// `deviation` of the initial state: returns the largest joint deviation
    /// from `q0` over the last tenth of `steps` samples divided by the initial
    /// one. Below 1 (and shrinking with `steps`) when the loop is stable. The
    /// check of [`StabilityProblem::alpha_interval`] by simulation, independent
    /// of the linearization (`options` are not used: the simulation integrates
    /// 10 substeps per sample).
    pub fn simulated_growth(
        &self,
        alpha: f64,
        deviation: f64,
        steps: usize,
    ) -> Result<f64, StabilityError> {
        let p = self;
        simulated_growth(
            p.robot,
            p.kind,
            p.settings,
            p.baselines,
            p.q0,
            alpha,
            deviation,
            steps,
        )
    }
}

/// A small deterministic generator for the perturbations ([`crate::linalg::random`]).
struct Lcg(u64);
impl Lcg {
    /// Uniform in `[−1, 1)`.
    fn next(&mut self) -> f64 {
        random::symmetric(&mut self.0)
    }
}

/// The matrix `M` of the closed loop's one-sample map near rest at `q0`
/// (see the module doc), for the plant with inertia ratio `alpha`.
fn closed_loop_matrix(
    robot: &Robot,
    kind: ControllerKind,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
    q0: &[f64],
    alpha: f64,
    options: &StabilityOptions,
) -> Result<DMatrix<f64>, StabilityError> {
    check_input(robot, kind, q0, options)?;
    let n = robot.dof();
    let (with_u, with_ebar) = memory(kind);
    let dim = 2 * n + if with_u { n } else { 0 } + if with_ebar { n } else { 0 };
    let ts = settings.ts;
    let nh = settings.horizon;
    let mut model = RobotDynamics::new(robot.clone());
    let mut plant = ScaledPlant {
        model: RobotDynamics::new(robot.clone()),
        alpha,
        h: DMatrix::zeros(n, n),
        c: DMatrix::zeros(n, n),
        g: DVector::zeros(n),
    };
    let x0: Vec<f64> = [q0, &vec![0.0; n]].concat();
    let eps = options.perturbation;
    let mut rng = Lcg(0x5eed);
    // Pairs (z_k, z_{k+1}) as columns.
    let runs = dim + 4;
    let pairs_per_run = 3;
    let mut z_now = DMatrix::zeros(dim, runs * pairs_per_run);
    let mut z_next = DMatrix::zeros(dim, runs * pairs_per_run);
    let mut col = 0;
    let mut tau = vec![0.0; n];
    let preview0: Vec<f64> = q0.repeat(nh);
    for _ in 0..runs {
        let mut ctrl = new_controller_with_baselines(kind, n, settings, baselines)?;
        let x_minus: Vec<f64> = x0.iter().map(|v| v + eps * rng.next()).collect();
        ctrl.reset(&x_minus)?;
        let mut x: Vec<f64> = x0.iter().map(|v| v + eps * rng.next()).collect();
        let mut ebar = vec![0.0; n];
        // First step: a perturbed reference excites u and ē.
        let w: Vec<f64> = q0.iter().map(|v| v + eps * rng.next()).collect();
        let preview: Vec<f64> = preview0.iter().map(|v| v + eps * rng.next()).collect();
        ctrl.step(
            &mut model,
            &crate::control::StepInput {
                x: &x,
                w_k: &w,
                preview: &preview,
            },
            &mut tau,
        )?;
        for i in 0..n {
            ebar[i] += w[i] - x[i];
        }
        plant
            .step(&mut x, &tau, ts, options.substeps)
            .ok_or(StabilityError::NonFinite { alpha })?;
        let state = |x: &[f64], u: &[f64], ebar: &[f64]| {
            let mut z = Vec::with_capacity(dim);
            z.extend(x.iter().zip(&x0).map(|(a, b)| a - b));
            if with_u {
                z.extend_from_slice(u);
            }
            if with_ebar {
                z.extend_from_slice(ebar);
            }
            DVector::from_vec(z)
        };
        let mut z = state(&x, ctrl.input(), &ebar);
        for _ in 0..pairs_per_run {
            ctrl.step(
                &mut model,
                &crate::control::StepInput {
                    x: &x,
                    w_k: q0,
                    preview: &preview0,
                },
                &mut tau,
            )?;
            for i in 0..n {
                ebar[i] += q0[i] - x[i];
            }
            plant
                .step(&mut x, &tau, ts, options.substeps)
                .ok_or(StabilityError::NonFinite { alpha })?;
            let z1 = state(&x, ctrl.input(), &ebar);
            z_now.set_column(col, &z);
            z_next.set_column(col, &z1);
            col += 1;
            z = z1;
        }
    }
    // M Z = Z'  ⇔  Zᵀ Mᵀ = Z'ᵀ, least squares by SVD.
    let svd = z_now.transpose().svd(true, true);
    let mt = svd
        .solve(&z_next.transpose(), 1e-12 * eps)
        .map_err(|_| StabilityError::NonFinite { alpha })?;
    Ok(mt.transpose())
}

/// The checks both linearizations make of their input: valid options, a
/// non-adaptive controller (its model changes while it runs), a predictive
/// one (a baseline's memory is not modelled) and a finite `q0` of the robot's
/// size.
fn check_input(
    robot: &Robot,
    kind: ControllerKind,
    q0: &[f64],
    options: &StabilityOptions,
) -> Result<(), StabilityError> {
    options.validate()?;
    if kind.is_adaptive() {
        return Err(StabilityError::Adaptive(kind));
    }
    if kind.is_baseline() {
        return Err(StabilityError::Baseline(kind));
    }
    robot.check_vector("q0", q0)?;
    Ok(())
}

/// `ρ(M)`: the largest eigenvalue modulus of [`StabilityProblem::closed_loop_matrix`].
fn spectral_radius(
    robot: &Robot,
    kind: ControllerKind,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
    q0: &[f64],
    alpha: f64,
    options: &StabilityOptions,
) -> Result<f64, StabilityError> {
    let m = closed_loop_matrix(robot, kind, settings, baselines, q0, alpha, options)?;
    Ok(m.complex_eigenvalues()
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max))
}

/// Schur sweeps per matrix dimension before [`LinearizedLoop::spectral_radius`]
/// shifts the matrix (a converging iteration needs a few per eigenvalue).
const SCHUR_SWEEPS_PER_DIM: usize = 100;

/// The closed loop near rest at `q0`, linearized once and reused for every
/// inertia ratio `α`: [`StabilityProblem::closed_loop_matrix`] repeats the controller's
/// perturbation runs for each `α`, although only the plant depends on it.
///
/// * The controller's one-sample map is linear near rest in
///   `ξ_k = [δx_k; δx_{k−1}; u_{k−1}; ē_{k−1}]` (`ē` for the second
///   algorithm only; [`StabilityProblem::closed_loop_matrix`]'s module doc lists the memory):
///   `u_k = K ξ_k`, `δτ_k = T ξ_k`. `K`, `T` come from the **actual
///   controller step** ([`crate::control::Algorithm::step`]) by least
///   squares over steps from small random inputs (one controller, reset
///   between runs; exact for the linear part as in [`StabilityProblem::closed_loop_matrix`]).
/// * The plant `q̈ = α H⁻¹(τ − C q̇ − g)` linearized at the equilibrium
///   `(q₀, 0, τ₀ = g(q₀))`: `δq̈ = α (J_q δq + J_q̇ δq̇ + J_τ δτ)` (the bracket
///   vanishes at rest, so `∂H⁻¹` drops out; `J` by central differences of the
///   plant's acceleration at `α = 1`), discretized by the same RK4 substeps as
///   the analysis plant (RK4 of the linearization is the linearization of
///   RK4): `δx_{k+1} = Φ_α δx_k + Γ_α δτ_k`.
/// * The closed loop in `ξ`: `ξ_{k+1} = [Φ_α S_x + Γ_α T; S_x; K; S_ē − S_q] ξ_k`
///   with `S` selecting the blocks of `ξ` (reference `q₀`: `ē_k = ē_{k−1} − δq_k`).
///   `ξ` is redundant (`x_k = Φ x_{k−1} + Γ τ_{k−1}` on every trajectory of
///   the loop), but the defect `x_k − Φ x_{k−1} − Γ τ_{k−1}` is zero after
///   one sample whatever it was, so the extra eigenvalues are 0 and the
///   spectral radius is that of [`StabilityProblem::closed_loop_matrix`]'s `M`.
#[derive(Debug, Clone)]
pub struct LinearizedLoop {
    n: usize,
    with_ebar: bool,
    ts: f64,
    substeps: usize,
    /// `[K; T]`: `u_k` (rows `0..n`) and `δτ_k` (rows `n..2n`) from `ξ_k`.
    gains: DMatrix<f64>,
    /// `[J_q J_q̇ J_τ]` of the plant's acceleration at `α = 1` (n × 3n).
    jac: DMatrix<f64>,
    options: StabilityOptions,
    /// What [`StabilityProblem::spectral_radius`] needs where the linearization's eigenvalues
    /// do not converge.
    robot: Robot,
    kind: ControllerKind,
    settings: MpcSettings,
    baselines: BaselineSettings,
    q0: Vec<f64>,
}

impl LinearizedLoop {
    /// Linearizes the loop of `kind` with `settings` near rest at `q0` on the
    /// model `robot` (the errors of [`StabilityProblem::closed_loop_matrix`]).
    fn new(
        robot: &Robot,
        kind: ControllerKind,
        settings: &MpcSettings,
        baselines: &BaselineSettings,
        q0: &[f64],
        options: &StabilityOptions,
    ) -> Result<Self, StabilityError> {
        check_input(robot, kind, q0, options)?;
        let n = robot.dof();
        let (_, with_ebar) = memory(kind);
        let (gains, tau0) =
            controller_gains(robot, kind, settings, baselines, q0, options.perturbation)?;
        let jac = plant_jacobian(robot, q0, &tau0)?;
        Ok(Self {
            n,
            with_ebar,
            ts: settings.ts,
            substeps: options.substeps,
            gains,
            jac,
            options: *options,
            robot: robot.clone(),
            kind,
            settings: settings.clone(),
            baselines: baselines.clone(),
            q0: q0.to_vec(),
        })
    }

    /// Size of `ξ`.
    fn dim(&self) -> usize {
        5 * self.n + if self.with_ebar { self.n } else { 0 }
    }

    /// The plant's one-sample map `[Φ_α Γ_α]` (2n × 3n) of the linearization.
    fn plant_map(&self, alpha: f64) -> DMatrix<f64> {
        let n = self.n;
        let h = self.ts / self.substeps as f64;
        let jac = &self.jac * alpha;
        let mut out = DMatrix::zeros(2 * n, 3 * n);
        let mut work = vec![0.0; RK4_WORK_PER_DOF * n];
        for col in 0..3 * n {
            let mut q = vec![0.0; n];
            let mut v = vec![0.0; n];
            let mut tau = vec![0.0; n];
            match col {
                c if c < n => q[c] = 1.0,
                c if c < 2 * n => v[c - n] = 1.0,
                c => tau[c - 2 * n] = 1.0,
            }
            for _ in 0..self.substeps {
                let _ = rk4_second_order_step(&mut q, &mut v, h, &mut work, |q, v, a| {
                    for (i, ai) in a.iter_mut().enumerate() {
                        let r = jac.row(i);
                        *ai = (0..n)
                            .map(|j| r[j] * q[j] + r[n + j] * v[j] + r[2 * n + j] * tau[j])
                            .sum();
                    }
                    Ok::<(), ()>(())
                });
            }
            for i in 0..n {
                out[(i, col)] = q[i];
                out[(n + i, col)] = v[i];
            }
        }
        out
    }

    /// The closed loop's one-sample map in `ξ` for the inertia ratio `alpha`.
    pub fn matrix(&self, alpha: f64) -> DMatrix<f64> {
        let n = self.n;
        let m = self.dim();
        let pm = self.plant_map(alpha);
        let (phi, gamma) = (pm.columns(0, 2 * n), pm.columns(2 * n, n));
        let (k, t) = (self.gains.rows(0, n), self.gains.rows(n, n));
        let mut e = DMatrix::zeros(m, m);
        // δx_{k+1} = Φ δx_k + Γ T ξ.
        e.view_mut((0, 0), (2 * n, m)).copy_from(&(gamma * t));
        let mut top = e.view_mut((0, 0), (2 * n, 2 * n));
        top += phi;
        // δx_k moves down; u_k = K ξ.
        e.view_mut((2 * n, 0), (2 * n, 2 * n))
            .copy_from(&DMatrix::identity(2 * n, 2 * n));
        e.view_mut((4 * n, 0), (n, m)).copy_from(&k);
        if self.with_ebar {
            for i in 0..n {
                e[(5 * n + i, 5 * n + i)] = 1.0;
                e[(5 * n + i, i)] = -1.0;
            }
        }
        e
    }

    /// `ρ` of [`LinearizedLoop::matrix`]: the loop is stable near rest at
    /// `alpha` iff it is below 1. `None` when the eigenvalue iteration (Schur)
    /// does not converge, also on the shifted matrix.
    ///
    /// nalgebra's Schur iteration deflates a subdiagonal entry when it is below
    /// `ε (|t_ii| + |t_i+1,i+1|)`: relative to the diagonal, a test that
    /// eigenvalues at 0 (the redundant memory states of `ξ`, and the states a
    /// light arm barely moves) can stall forever (seen on the UR5). When the plain
    /// iteration does not converge within `SCHUR_SWEEPS_PER_DIM · dim` sweeps, the
    /// eigenvalues `μ` of `M + I` are computed instead (the same Schur vectors,
    /// every diagonal entry near 1) and `λ = μ − 1`.
    pub fn spectral_radius(&self, alpha: f64) -> Option<f64> {
        let m = self.matrix(alpha);
        let sweeps = SCHUR_SWEEPS_PER_DIM * m.nrows();
        let radius = |schur: nalgebra::linalg::Schur<f64, nalgebra::Dyn>, shift: f64| {
            (schur.complex_eigenvalues().iter())
                .map(|l| (l - shift).norm())
                .fold(0.0, f64::max)
        };
        if let Some(schur) = nalgebra::linalg::Schur::try_new(m.clone(), f64::EPSILON, sweeps) {
            return Some(radius(schur, 0.0));
        }
        let dim = m.nrows();
        let shifted = m + DMatrix::identity(dim, dim);
        nalgebra::linalg::Schur::try_new(shifted, f64::EPSILON, sweeps).map(|s| radius(s, 1.0))
    }

    /// The interval of `α` with `ρ < 1` ([`StabilityProblem::alpha_interval`]'s bisection);
    /// where the eigenvalues of the linearization do not converge, `ρ` of
    /// the perturbation runs at that `α` ([`StabilityProblem::spectral_radius`]).
    pub fn alpha_interval(&self) -> Result<(f64, f64), StabilityError> {
        bisect_interval(
            |a| match self.spectral_radius(a) {
                Some(r) => Ok(r),
                None => spectral_radius(
                    &self.robot,
                    self.kind,
                    &self.settings,
                    &self.baselines,
                    &self.q0,
                    a,
                    &self.options,
                ),
            },
            &self.options,
        )
    }
}

/// `[K; T]` of [`LinearizedLoop`] by least squares over steps of one
/// controller from random inputs of size `eps` about rest at `q0`, and the
/// torque at rest `τ₀` the controller returns there. Each run is stepped
/// twice, with the deviations `+eps·r` and `−eps·r`, and the least squares
/// uses half their differences (central differences: the second-order terms
/// of the controller's nonlinearity cancel, a bias `O(eps²)` instead of
/// `O(eps)`).
fn controller_gains(
    robot: &Robot,
    kind: ControllerKind,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
    q0: &[f64],
    eps: f64,
) -> Result<(DMatrix<f64>, Vec<f64>), StabilityError> {
    let n = robot.dof();
    let (_, with_ebar) = memory(kind);
    let m = 5 * n + if with_ebar { n } else { 0 };
    let mut pass = GainPass {
        model: RobotDynamics::new(robot.clone()),
        ctrl: new_controller_with_baselines(kind, n, settings, baselines)?,
        x0: [q0, &vec![0.0; n]].concat(),
        q0: q0.to_vec(),
        preview0: q0.repeat(settings.horizon),
        tau0: vec![0.0; n],
        with_ebar,
    };
    let (x0, p0) = (pass.x0.clone(), pass.preview0.clone());
    pass.ctrl.reset(&x0)?;
    pass.ctrl.step(
        &mut pass.model,
        &crate::control::StepInput {
            x: &x0,
            w_k: q0,
            preview: &p0,
        },
        &mut pass.tau0,
    )?;
    let mut rng = Lcg(0x5eed);
    let runs = 8;
    let per_run = (2 * m).div_ceil(runs);
    let rows = runs * per_run;
    let mut xi = DMatrix::zeros(rows, m);
    let mut out = DMatrix::zeros(rows, 2 * n);
    for run in 0..runs {
        let mut draw = |len: usize| (0..len).map(|_| rng.next()).collect::<Vec<f64>>();
        let draws = RunDraws {
            x_minus: draw(2 * n),
            x_first: draw(2 * n),
            w: draw(n),
            preview: draw(settings.horizon * n),
            xs: (0..per_run).map(|_| draw(2 * n)).collect(),
        };
        let plus = pass.run(&draws, eps)?;
        let minus = pass.run(&draws, -eps)?;
        for (k, ((xp, op), (xm, om))) in plus.iter().zip(&minus).enumerate() {
            let row = run * per_run + k;
            for j in 0..m {
                xi[(row, j)] = (xp[j] - xm[j]) / (2.0 * eps);
            }
            for j in 0..2 * n {
                out[(row, j)] = (op[j] - om[j]) / (2.0 * eps);
            }
        }
    }
    Ok((least_squares_gains(xi, &out)?.transpose(), pass.tau0))
}

/// `[K; T]ᵀ` from `Ξ [K; T]ᵀ = [U T]`, least squares by SVD; an error when it is not finite.
fn least_squares_gains(
    xi: DMatrix<f64>,
    out: &DMatrix<f64>,
) -> Result<DMatrix<f64>, StabilityError> {
    let gt = xi
        .svd(true, true)
        .solve(out, 1e-12)
        .map_err(|_| StabilityError::NonFinite { alpha: 1.0 })?;
    if !gt.iter().all(|v| v.is_finite()) {
        return Err(StabilityError::NonFinite { alpha: 1.0 });
    }
    Ok(gt)
}

/// The random draws of one run of [`controller_gains`] (in `[−1, 1)`, scaled
/// by `±eps`): `x_{−1}`, the first step's state, reference and preview (they
/// excite `u` and `ē`), then the states of the recorded steps.
struct RunDraws {
    x_minus: Vec<f64>,
    x_first: Vec<f64>,
    w: Vec<f64>,
    preview: Vec<f64>,
    xs: Vec<Vec<f64>>,
}

/// The controller of [`controller_gains`] with its model and rest point.
struct GainPass {
    model: RobotDynamics,
    ctrl: Box<dyn Algorithm + Send>,
    x0: Vec<f64>,
    q0: Vec<f64>,
    preview0: Vec<f64>,
    tau0: Vec<f64>,
    with_ebar: bool,
}

impl GainPass {
    /// Steps one run with the deviations `scale · draws` about rest: per
    /// recorded step, `ξ_k` and `[u_k; τ_k − τ₀]` (unscaled).
    #[allow(clippy::type_complexity)]
    fn run(&mut self, d: &RunDraws, scale: f64) -> Result<Vec<(Vec<f64>, Vec<f64>)>, StepFailure> {
        let n = self.q0.len();
        let about = |base: &[f64], r: &[f64]| -> Vec<f64> {
            base.iter().zip(r).map(|(b, r)| b + scale * r).collect()
        };
        let mut tau = vec![0.0; n];
        let mut x_prev = about(&self.x0, &d.x_minus);
        self.ctrl.reset(&x_prev)?;
        let x = about(&self.x0, &d.x_first);
        let w = about(&self.q0, &d.w);
        let preview = about(&self.preview0, &d.preview);
        self.ctrl.step(
            &mut self.model,
            &crate::control::StepInput {
                x: &x,
                w_k: &w,
                preview: &preview,
            },
            &mut tau,
        )?;
        let mut ebar: Vec<f64> = (0..n).map(|i| w[i] - x[i]).collect();
        x_prev.copy_from_slice(&x);
        let mut rows = Vec::with_capacity(d.xs.len());
        for r in &d.xs {
            let x = about(&self.x0, r);
            let xi: Vec<f64> = (x.iter().zip(&self.x0).map(|(a, b)| a - b))
                .chain(x_prev.iter().zip(&self.x0).map(|(a, b)| a - b))
                .chain(self.ctrl.input().iter().copied())
                .chain(
                    ebar.iter()
                        .copied()
                        .take(if self.with_ebar { n } else { 0 }),
                )
                .collect();
            self.ctrl.step(
                &mut self.model,
                &crate::control::StepInput {
                    x: &x,
                    w_k: &self.q0,
                    preview: &self.preview0,
                },
                &mut tau,
            )?;
            let out: Vec<f64> = (self.ctrl.input().iter().copied())
                .chain(tau.iter().zip(&self.tau0).map(|(t, t0)| t - t0))
                .collect();
            for i in 0..n {
                ebar[i] += self.q0[i] - x[i];
            }
            x_prev.copy_from_slice(&x);
            rows.push((xi, out));
        }
        Ok(rows)
    }
}

/// `[J_q J_q̇ J_τ]` (n × 3n): the Jacobian of the plant's acceleration
/// `H⁻¹(τ − C q̇ − g)` at `(q0, 0, tau0)`, by central differences (step
/// `1e-6` in `q`, `q̇`; the acceleration is affine in `τ`, step 1).
fn plant_jacobian(robot: &Robot, q0: &[f64], tau0: &[f64]) -> Result<DMatrix<f64>, StabilityError> {
    let n = robot.dof();
    let mut plant = ScaledPlant {
        model: RobotDynamics::new(robot.clone()),
        alpha: 1.0,
        h: DMatrix::zeros(n, n),
        c: DMatrix::zeros(n, n),
        g: DVector::zeros(n),
    };
    let mut jac = DMatrix::zeros(n, 3 * n);
    let base = [q0.to_vec(), vec![0.0; n], tau0.to_vec()];
    for col in 0..3 * n {
        let (block, i) = (col / n, col % n);
        let step = if block == 2 { 1.0 } else { 1e-6 };
        let mut acc = |sign: f64| {
            let mut args = base.clone();
            args[block][i] += sign * step;
            plant
                .accel(&args[0], &args[1], &args[2])
                .ok_or(StabilityError::NonFinite { alpha: 1.0 })
        };
        let d = (acc(1.0)? - acc(-1.0)?) / (2.0 * step);
        jac.set_column(col, &d);
    }
    Ok(jac)
}

/// The bisection of [`StabilityProblem::alpha_interval`] on the spectral radius `rho(α)`.
fn bisect_interval(
    mut rho: impl FnMut(f64) -> Result<f64, StabilityError>,
    options: &StabilityOptions,
) -> Result<(f64, f64), StabilityError> {
    let at_one = rho(1.0)?;
    if at_one >= 1.0 {
        return Err(StabilityError::UnstableAtExactModel { radius: at_one });
    }
    let mut edge = |stable: f64, far: f64| -> Result<f64, StabilityError> {
        if rho(far)? < 1.0 {
            return Ok(far);
        }
        let (mut s, mut u) = (stable, far);
        while (s - u).abs() > options.tolerance {
            let mid = 0.5 * (s + u);
            if rho(mid)? < 1.0 {
                s = mid;
            } else {
                u = mid;
            }
        }
        Ok(0.5 * (s + u))
    };
    let lo = edge(1.0, options.alpha_min)?;
    let hi = edge(1.0, options.alpha_max)?;
    Ok((lo, hi))
}

/// [`StabilityProblem::alpha_interval`] with the problem's parts.
fn alpha_interval(
    robot: &Robot,
    kind: ControllerKind,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
    q0: &[f64],
    options: &StabilityOptions,
) -> Result<(f64, f64), StabilityError> {
    LinearizedLoop::new(robot, kind, settings, baselines, q0, options)?.alpha_interval()
}

/// [`StabilityProblem::alpha_interval`] with `ρ` of [`StabilityProblem::spectral_radius`] (the controller's
/// perturbation runs repeated at every `α`): the slower reference the
/// linearized loop is checked against.
fn alpha_interval_by_perturbation(
    robot: &Robot,
    kind: ControllerKind,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
    q0: &[f64],
    options: &StabilityOptions,
) -> Result<(f64, f64), StabilityError> {
    bisect_interval(
        |a| spectral_radius(robot, kind, settings, baselines, q0, a, options),
        options,
    )
}

/// The range of the generalized eigenvalues of `(H_model, H_plant)` over the
/// poses (each `n` values): the inertia ratios `α` the loop meets when the
/// plant carries `payload` and the model `robot` does not (the model's own
/// payload, if any, is what it assumes).
pub fn inertia_ratio_range(
    robot: &Robot,
    payload: &Payload,
    poses: &[&[f64]],
) -> Result<(f64, f64), StabilityError> {
    let mut plant_robot = robot.clone();
    plant_robot.set_payload(Some(*payload))?;
    let n = robot.dof();
    let mut model = RobotDynamics::new(robot.clone());
    let mut plant = RobotDynamics::new(plant_robot);
    let (mut hm, mut hp) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    let (mut c, mut g) = (DMatrix::zeros(n, n), DVector::zeros(n));
    let zero = vec![0.0; n];
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for q in poses {
        robot.check_vector("q", q)?;
        model.terms(q, &zero, &mut hm, &mut c, &mut g);
        plant.terms(q, &zero, &mut hp, &mut c, &mut g);
        // eig(H_p⁻¹ H_m) = eig(L⁻¹ H_m L⁻ᵀ) with H_p = L Lᵀ.
        let Some(chol) = hp.clone().cholesky() else {
            return Err(StabilityError::NonFinite { alpha: f64::NAN });
        };
        let l = chol.l();
        let li = l
            .clone()
            .try_inverse()
            .ok_or(StabilityError::NonFinite { alpha: f64::NAN })?;
        let s = &li * &hm * li.transpose();
        let s = (&s + s.transpose()) * 0.5;
        for e in s.symmetric_eigenvalues().iter() {
            lo = lo.min(*e);
            hi = hi.max(*e);
        }
    }
    Ok((lo, hi))
}

/// The largest point payload at the flange centre, up to `mass_limit`, for
/// which the inertia ratios along `poses` stay inside `interval`
/// (bisection to 1 g). 0 when even a small payload leaves it.
pub fn max_payload(
    robot: &Robot,
    interval: (f64, f64),
    poses: &[&[f64]],
    mass_limit: f64,
) -> Result<f64, StabilityError> {
    let inside = |m: f64| -> Result<bool, StabilityError> {
        let (lo, hi) = inertia_ratio_range(robot, &Payload::point_mass(m), poses)?;
        Ok(lo >= interval.0 && hi <= interval.1)
    };
    if inside(mass_limit)? {
        return Ok(mass_limit);
    }
    let (mut ok, mut bad) = (0.0, mass_limit);
    if !inside(ok)? {
        return Ok(0.0);
    }
    while bad - ok > 1e-3 {
        let mid = 0.5 * (ok + bad);
        if inside(mid)? {
            ok = mid;
        } else {
            bad = mid;
        }
    }
    Ok(ok)
}

/// A closed-loop simulation near rest at `q0` with the plant's inertia
/// scaled by `1/α` (the analysis plant), from a deviation of size
/// `deviation` of the initial state: returns the largest joint deviation
/// from `q0` over the last tenth of `steps` samples divided by the initial
/// one. Below 1 (and shrinking with `steps`) when the loop is stable. The
/// check of [`StabilityProblem::alpha_interval`] by simulation, independent of the
/// linearization.
#[allow(clippy::too_many_arguments)]
fn simulated_growth(
    robot: &Robot,
    kind: ControllerKind,
    settings: &MpcSettings,
    baselines: &BaselineSettings,
    q0: &[f64],
    alpha: f64,
    deviation: f64,
    steps: usize,
) -> Result<f64, StabilityError> {
    robot.check_vector("q0", q0)?;
    let n = robot.dof();
    let mut model = RobotDynamics::new(robot.clone());
    let mut plant = ScaledPlant {
        model: RobotDynamics::new(robot.clone()),
        alpha,
        h: DMatrix::zeros(n, n),
        c: DMatrix::zeros(n, n),
        g: DVector::zeros(n),
    };
    let mut ctrl = new_controller_with_baselines(kind, n, settings, baselines)?;
    let mut x: Vec<f64> = [q0, &vec![0.0; n]].concat();
    ctrl.reset(&x)?;
    let mut rng = Lcg(7);
    for xi in x.iter_mut().take(n) {
        *xi += deviation * rng.next();
    }
    let initial = (0..n).map(|i| (x[i] - q0[i]).abs()).fold(0.0, f64::max);
    let preview = q0.repeat(settings.horizon);
    let mut tau = vec![0.0; n];
    let mut last = 0.0f64;
    for k in 0..steps {
        ctrl.step(
            &mut model,
            &crate::control::StepInput {
                x: &x,
                w_k: q0,
                preview: &preview,
            },
            &mut tau,
        )?;
        plant
            .step(&mut x, &tau, settings.ts, 10)
            .ok_or(StabilityError::NonFinite { alpha })?;
        let d = (0..n).map(|i| (x[i] - q0[i]).abs()).fold(0.0, f64::max);
        if d > 1.0 {
            return Ok(f64::INFINITY);
        }
        if k >= steps - steps / 10 {
            last = last.max(d);
        }
    }
    Ok(last / initial)
}
