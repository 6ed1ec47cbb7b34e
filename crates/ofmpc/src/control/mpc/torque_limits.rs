//! The torque-limit step of the predictive controllers: the limits `|τ_{k+j}| ≤ τmax` over
//! the horizon, turned into the box QP of `solvers/constrained.rs` (whose module docs derive
//! it) with the model's `H` and `g` (`τ = H u + g`, Eq. (15)).

use crate::control::mpc::model::LinearLikeModel;
use crate::control::solvers::constrained::{
    solve_box_qp_until, BoxQp, BoxQpWork, Deadline, QpStatus,
};
use crate::control::solvers::dense::dot;
use crate::control::solvers::lsq::LsqWorkspace;
use crate::control::telemetry::FallbackLevel;
use std::time::Instant;

/// Relative margin kept inside the limits so that rounding in `τ = H u + g`
/// never crosses them.
const MARGIN: f64 = 1e-9;

/// Most samples in a row a plan is shifted on (open loop) before a step
/// solves the QP past its budget: measured on the saturation example at
/// `Ts` = 10 ms, 9 shifts (`N − 1`) diverge.
const MAX_SHIFTS: usize = 1;

/// Deadline checks of a check budget kept back for the step's work after
/// the QP (the torque, the command, the telemetry), which the wall-clock
/// budget keeps back as its measured time: the QP gets the rest.
pub(crate) const TAIL_CHECKS: u32 = 1;

/// Preallocated workspace of the constrained step for `n` joints, horizon `N`,
/// and `m` rows of `𝒜`.
#[derive(Debug, Clone)]
pub(crate) struct TorqueLimitQp {
    n: usize,
    nh: usize,
    /// Constraint horizon: the torques `j < nc` are limited.
    nc: usize,
    incremental: bool,
    tau_max: Vec<f64>,
    /// `c1 − R1 e` (p).
    b: Vec<f64>,
    hinv: Vec<f64>,
    bz: Vec<f64>,
    hess: Vec<f64>,
    lin: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    z: Vec<f64>,
    state: Vec<i8>,
    work: BoxQpWork,
    u_seq: Vec<f64>,
    /// Per joint: the torque at sample `k` is at its limit.
    pub saturated: Vec<bool>,
    /// What the last step did.
    pub status: QpStatus,
    /// The step's deadline ([`Self::arm`] before each step).
    deadline: Deadline,
    /// A budget counted in deadline checks instead of µs, for tests
    /// ([`Self::arm`]).
    check_budget: Option<u32>,
    /// This step has a budget (armed with a deadline).
    budgeted: bool,
    /// This step's QP ran past its budget (no plan left to shift).
    overrun: bool,
    /// With a deadline: the torque plan `τ_{k+j}` of the last step that
    /// made one (natural order, block `j`), for the shifted-plan fallback.
    plan: Vec<f64>,
    /// Samples since `plan` was made (its block `plan_age` is the torque
    /// last returned); `None`: no plan yet.
    plan_age: Option<usize>,
}

impl TorqueLimitQp {
    /// Buffers for a controller with `n` joints and horizon `nh` whose first
    /// `nc` torques (`1 ≤ nc ≤ nh`) are limited.
    pub fn new(n: usize, nh: usize, nc: usize, incremental: bool, tau_max: &[f64]) -> Self {
        let p = n * nh;
        Self {
            n,
            nh,
            nc: nc.clamp(1, nh.max(1)),
            incremental,
            tau_max: tau_max.to_vec(),
            b: vec![0.0; p],
            hinv: vec![0.0; n * n],
            bz: vec![0.0; p * p],
            hess: vec![0.0; p * p],
            lin: vec![0.0; p],
            lo: vec![0.0; p],
            hi: vec![0.0; p],
            z: vec![0.0; p],
            state: vec![0; p],
            work: BoxQpWork::new(p),
            u_seq: vec![0.0; p],
            saturated: vec![false; n],
            status: QpStatus::default(),
            deadline: Deadline::Never,
            check_budget: None,
            budgeted: false,
            overrun: false,
            plan: vec![0.0; p],
            plan_age: None,
        }
    }

    /// Sets the deadline of a step that began at `start` with a budget of
    /// `budget_us` (`None`: none; the caller has already kept back the time
    /// of its work after the QP), or the check budget when one is set: of
    /// that, [`TAIL_CHECKS`] are kept back for the work after the QP.
    pub fn arm(&mut self, start: Instant, budget_us: Option<f64>) {
        self.deadline = match (self.check_budget, budget_us) {
            (Some(checks), _) => Deadline::Checks(checks.saturating_sub(TAIL_CHECKS)),
            // A budget beyond the clock's range is no deadline.
            (None, Some(b)) => std::time::Duration::try_from_secs_f64(b.max(0.0) * 1e-6)
                .ok()
                .and_then(|d| start.checked_add(d))
                .map_or(Deadline::Never, Deadline::At),
            (None, None) => Deadline::Never,
        };
        self.budgeted = self.deadline != Deadline::Never;
        self.overrun = false;
    }

    /// Counts the budget in deadline checks (`None`: in µs again): each
    /// check before a horizon block of the QP's build, a column of its
    /// Hessian or an iteration spends one; deterministic, for tests.
    pub fn set_check_budget(&mut self, checks: Option<u32>) {
        self.check_budget = checks;
    }

    /// Whether the step's deadline has passed (never without one).
    #[inline]
    fn spent(&mut self) -> bool {
        self.deadline.spent()
    }

    /// With a deadline, keeps the plan `τ_{k+j} = z_j + g` (the `z` of
    /// [`Self::plan_torques`] when `permuted` is false, of the QP's layout
    /// otherwise) for a later shifted-plan fallback.
    fn keep_plan(&mut self, g: &[f64], permuted: bool) {
        if !self.budgeted {
            return;
        }
        let (n, nh) = (self.n, self.nh);
        for j in 0..nh {
            for i in 0..n {
                let k = if permuted { self.col(j, i) } else { j * n + i };
                self.plan[j * n + i] = self.z[k] + g[i];
            }
        }
        self.plan_age = Some(0);
    }

    /// The budget fallback when the deadline passed before the QP's first
    /// iteration (its build unfinished) and a plan is left
    /// ([`Self::plan_left`]): the kept plan one sample on
    /// ([`FallbackLevel::ShiftedPlan`]), clamped into the limits, as `u_k`
    /// into `u_new` (without a plan, defensively, the unconstrained torque
    /// clamped: [`FallbackLevel::BestFeasible`]).
    /// Whether the kept plan has a block left to shift to.
    fn plan_left(&self) -> bool {
        self.plan_age
            .is_some_and(|a| a + 1 < self.nh && a < MAX_SHIFTS)
    }

    fn fall_back(&mut self, model: &LinearLikeModel, u_new: &mut [f64]) {
        let n = self.n;
        let g = model.g().as_slice();
        let age = self.plan_age.filter(|_| self.plan_left()).map(|a| a + 1);
        if age.is_some() {
            self.plan_age = age;
        }
        for i in 0..n {
            let lim = self.tau_max[i] * (1.0 - MARGIN);
            // Without a plan: z_0 = H u_k of the unconstrained solution.
            let tau = age.map_or(self.z[i] + g[i], |a| self.plan[a * n + i]);
            let tau = if lim.is_finite() {
                tau.clamp(-lim, lim)
            } else {
                tau
            };
            u_new[i] = tau - g[i];
            self.saturated[i] = lim.is_finite() && tau.abs() >= lim;
        }
        model.solve_h_in_place(u_new);
        self.status.fallback = true;
        self.status.budget_hit = true;
        self.status.fallback_level = match age {
            Some(_) => FallbackLevel::ShiftedPlan,
            None => FallbackLevel::BestFeasible,
        };
    }

    /// The limits `τmax` (n values).
    pub fn limits(&self) -> &[f64] {
        &self.tau_max
    }

    /// Column of `Δu_{k+j}` entry `i` in the permuted layout of `𝒜`
    /// (unknown block `t' = N − j`, see `core.rs`).
    #[inline]
    fn col(&self, j: usize, i: usize) -> usize {
        (self.nh - 1 - j) * self.n + i
    }

    /// Whether the plan `du` (natural order: block `j` is `Δu_{k+j}`, or
    /// `u_{k+j}`) passes a limit in its first `nc` torques. Allocation-free.
    pub fn violates(&mut self, model: &LinearLikeModel, du: &[f64], u_prev: &[f64]) -> bool {
        let n = self.n;
        self.plan_torques(model, u_prev, |j, i| du[j * n + i])
    }

    /// `u_{k+j}` and `z_j = H u_{k+j}` (`u_seq`, `z`) of a plan whose block
    /// `j`, entry `i` is `d(j, i)` (`Δu_{k+j}` or `u_{k+j}`), `j < nh`; true
    /// when a torque `z_j + g` of the first `nc` passes its limit.
    fn plan_torques(
        &mut self,
        model: &LinearLikeModel,
        u_prev: &[f64],
        d: impl Fn(usize, usize) -> f64,
    ) -> bool {
        let (n, nh) = (self.n, self.nh);
        for j in 0..nh {
            for i in 0..n {
                let dji = d(j, i);
                self.u_seq[j * n + i] = if !self.incremental {
                    dji
                } else if j == 0 {
                    u_prev[i] + dji
                } else {
                    self.u_seq[(j - 1) * n + i] + dji
                };
            }
        }
        let h = model.h().as_slice();
        let g = model.g().as_slice();
        let mut violated = false;
        for j in 0..nh {
            let u = &self.u_seq[j * n..(j + 1) * n];
            for i in 0..n {
                let mut z = 0.0;
                for l in 0..n {
                    z += h[l * n + i] * u[l];
                }
                self.z[j * n + i] = z;
                let lim = self.tau_max[i];
                if j < self.nc && lim.is_finite() && (z + g[i]).abs() > lim {
                    violated = true;
                }
            }
        }
        violated
    }

    /// Marks a step on which the QP did not run.
    pub fn clear(&mut self) {
        self.status = QpStatus::default();
        self.saturated.fill(false);
    }

    /// The QP of [`Self::enforce`] from `lsq`'s factor: `B = R1 T`,
    /// `b' = c1 − R1 e`, `P = BᵀB`, `c = Bᵀb'`. `false` (and the QP not
    /// built) when the step's deadline passes on the way (checked per
    /// horizon block and per column of `P`).
    fn build(&mut self, model: &LinearLikeModel, lsq: &LsqWorkspace, u_prev: &[f64]) -> bool {
        let (n, nh) = (self.n, self.nh);
        let p = n * nh;
        let m = p;
        // H⁻¹ column by column.
        self.hinv.fill(0.0);
        for c in 0..n {
            let col = &mut self.hinv[c * n..(c + 1) * n];
            col[c] = 1.0;
            model.solve_h_in_place(col);
        }
        // B = R1 T: column (j, c) = Σ_l (R[:, d_j,l] − R[:, d_{j+1},l]) H⁻¹[l, c]
        // (incremental); R[:, d_j,l] H⁻¹[l, c] (usual). Column d of R1 is
        // non-zero in rows 0..=d only.
        let col = |j: usize, i: usize| (nh - 1 - j) * n + i;
        for j in 0..nh {
            if self.spent() {
                return false;
            }
            for c in 0..n {
                let bc = col(j, c);
                let out = &mut self.bz[bc * m..bc * m + m];
                out.fill(0.0);
                for l in 0..n {
                    let w = self.hinv[c * n + l];
                    for (o, r) in out.iter_mut().zip(lsq.r_column(col(j, l))) {
                        *o += w * r;
                    }
                    if self.incremental && j + 1 < nh {
                        for (o, r) in out.iter_mut().zip(lsq.r_column(col(j + 1, l))) {
                            *o -= w * r;
                        }
                    }
                }
            }
        }
        // b' = c1 − R1 e, e = −u_{k−1} in the block of Δu_k (incremental).
        self.b.copy_from_slice(&lsq.transformed_rhs()[..p]);
        if self.incremental {
            for l in 0..n {
                let w = u_prev[l];
                for (bb, r) in self.b.iter_mut().zip(lsq.r_column(col(0, l))) {
                    *bb += w * r;
                }
            }
        }
        // P = BᵀB and c = Bᵀb'. Column block t' of R1 (and of B) is zero
        // below row n·t' (upper triangular).
        let end = |c: usize| n * (c / n + 1);
        for c1 in 0..p {
            if self.spent() {
                return false;
            }
            let b1 = &self.bz[c1 * m..c1 * m + end(c1)];
            for c2 in c1..p {
                let len = end(c1).min(end(c2));
                let b2 = &self.bz[c2 * m..c2 * m + len];
                let s = dot(&b1[..len], b2);
                self.hess[c2 * p + c1] = s;
                self.hess[c1 * p + c2] = s;
            }
            self.lin[c1] = dot(b1, &self.b);
        }
        true
    }

    /// Checks the unconstrained solution of the solved least-squares system
    /// `lsq` (layout of `𝒜`'s columns) against the limits over the horizon;
    /// when it violates one, solves the QP from `lsq`'s factor `R1`, `c1`
    /// and writes the constrained `u_k` into `u_new`. `u_prev` is `u_{k−1}`
    /// (incremental algorithms). Allocation-free.
    pub fn enforce(
        &mut self,
        model: &LinearLikeModel,
        lsq: &LsqWorkspace,
        u_prev: &[f64],
        u_new: &mut [f64],
    ) {
        let (n, nh) = (self.n, self.nh);
        let p = n * nh;
        let sol = lsq.solution();
        self.status = QpStatus::default();
        self.saturated.fill(false);
        // u_{k+j} and H u_{k+j} over the horizon from the unconstrained solution.
        let violated = self.plan_torques(model, u_prev, |j, i| sol[(nh - 1 - j) * n + i]);
        let g = model.g().as_slice();
        if !violated {
            self.keep_plan(g, false);
            return;
        }
        self.status.active = true;
        if !self.build(model, lsq, u_prev) {
            if self.plan_left() {
                self.fall_back(model, u_new);
                return;
            }
            // No plan left to shift: this step solves the QP past its
            // budget (a fresh plan for the next ones), counted as a hit.
            self.deadline = Deadline::Never;
            self.overrun = true;
            self.build(model, lsq, u_prev);
        }
        // The box and the warm start (the unconstrained z, clipped).
        for j in 0..nh {
            for i in 0..n {
                let lim = self.tau_max[i] * (1.0 - MARGIN);
                let k = self.col(j, i);
                let (lo, hi) = if lim.is_finite() && j < self.nc {
                    (-lim - g[i], lim - g[i])
                } else {
                    (f64::NEG_INFINITY, f64::INFINITY)
                };
                self.lo[k] = lo;
                self.hi[k] = hi;
                let zj = self.z[j * n + i];
                self.work.z0[k] = zj;
            }
        }
        self.z.copy_from_slice(&self.work.z0);
        let info = solve_box_qp_until(
            BoxQp {
                p,
                hess: &self.hess,
                lin: &self.lin,
                lo: &self.lo,
                hi: &self.hi,
            },
            &mut self.z,
            &mut self.state,
            &mut self.work,
            ((4 * p) as u32, &mut self.deadline),
        );
        self.status.iterations = info.0;
        self.status.fallback = !info.1;
        self.status.budget_hit = info.2 || self.overrun;
        self.status.active_constraints = self.state.iter().filter(|&&s| s != 0).count() as u32;
        if !info.1 {
            self.status.fallback_level = FallbackLevel::BestFeasible;
        }
        self.keep_plan(g, true);
        // u_k = H⁻¹ z_0.
        for i in 0..n {
            let k = self.col(0, i);
            u_new[i] = self.z[k];
            self.saturated[i] = self.state[k] != 0;
        }
        model.solve_h_in_place(u_new);
    }
}
