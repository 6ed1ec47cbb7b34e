//! Torque limits as constraints of the predictive controllers' optimization.
//!
//! Every controller minimizes `‖𝒜 ΔU − b‖²` (Eq. (37), (39), (43)). Over the
//! horizon the model gives the torque `τ_{k+j} = H u_{k+j} + g` (Eq. (15),
//! `H`, `g` frozen at `x_k` like the rest of the linear-like model), with
//! `u_{k+j} = u_{k−1} + Σ_{i≤j} Δu_{k+i}` for the incremental algorithms and
//! `u_{k+j}` itself for the usual one. The drive limits `|τ_{k+j,i}| ≤ τmax_i`
//! are therefore linear inequalities in `ΔU`. With the change of variables
//!
//! ```text
//! z_j = H u_{k+j}  (= τ_{k+j} − g),   j = 0..N−1,
//! ```
//!
//! which is one-to-one (`Δu_{k+j} = H⁻¹(z_j − z_{j−1})`, `z_{−1} = H u_{k−1}`),
//! they become a box, `−τmax − g ≤ z_j ≤ τmax − g`, and the problem a
//! box-constrained least-squares problem
//!
//! ```text
//! min ½ zᵀ P z − cᵀ z   s.t.  lo ≤ z ≤ hi,    P = (𝒜T)ᵀ(𝒜T), c = (𝒜T)ᵀ(b − 𝒜e),
//! ```
//!
//! with `ΔU = T z + e`. The unconstrained solve has already factored
//! `𝒜 = Q [R1; 0]`, `Qᵀb = [c1; c2]`, so `‖𝒜ΔU − b‖² = ‖R1 ΔU − c1‖² + ‖c2‖²`:
//! the QP is built from the `p × p` triangle `R1` and `c1` (`P = (R1T)ᵀ(R1T)`,
//! `c = (R1T)ᵀ(c1 − R1 e)`), not from the stacked `2p × p` system, and nothing is
//! copied before the solve. [`solve_box_qp`] solves it by a primal active-set
//! method on `P` (Cholesky of the free block per iteration): every iterate is
//! feasible, so when the bounded iteration count runs out the current iterate
//! still respects the limits (the fallback), only its cost is not minimal.
//! Warm start: the unconstrained optimum clipped to the box, with the clipped
//! entries as the first active set.
//!
//! When the unconstrained solution already satisfies the limits over the
//! whole horizon nothing is changed: the step is bit-identical to the
//! unconstrained controller.
//!
//! Why not a general conic solver (Clarabel): its setup allocates on every
//! new problem data, and the step must not allocate; the box structure in
//! `z` makes a dense active-set method of ~200 lines sufficient and
//! preallocated (`p = N·n = 60` unknowns for the IRB 140 at `N = 10`).

use crate::control::mpc::model::LinearLikeModel;
use crate::control::solvers::dense::dot;
use crate::control::solvers::lsq::LsqWorkspace;
use crate::control::telemetry::FallbackLevel;
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place_dot};
use std::time::Instant;

/// Relative margin kept inside the limits so that rounding in `τ = H u + g`
/// never crosses them.
const MARGIN: f64 = 1e-9;

/// Most samples in a row a plan is shifted on (open loop) before a step
/// solves the QP past its budget: measured on the saturation example at
/// `Ts` = 10 ms, 9 shifts (`N − 1`) diverge.
const MAX_SHIFTS: usize = 1;

/// What the constrained step did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct QpStatus {
    /// The unconstrained solution violated a limit and the QP was solved.
    pub active: bool,
    /// Active-set iterations used.
    pub iterations: u32,
    /// The iteration bound was reached (or a factorization failed): the
    /// returned input is feasible but not optimal.
    pub fallback: bool,
    /// Box constraints active at the returned answer.
    pub active_constraints: u32,
    /// The step budget ran out before the QP converged: the answer is its
    /// best feasible point so far (`fallback` is set too).
    pub budget_hit: bool,
    /// Which answer the QP returned: [`FallbackLevel::None`] (its optimum,
    /// or the unconstrained plan when it did not run),
    /// [`FallbackLevel::BestFeasible`] (stopped at its iteration cap or the
    /// deadline), [`FallbackLevel::ShiftedPlan`] (the deadline passed before
    /// its first iteration: the previous step's torque plan, one sample on,
    /// within the limits); never [`FallbackLevel::Hold`] (the controller's
    /// numerical failure).
    pub fallback_level: FallbackLevel,
}

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
    /// `budget_us` (`None`: none), or the check budget when one is set.
    pub fn arm(&mut self, start: Instant, budget_us: Option<f64>) {
        self.deadline = match (self.check_budget, budget_us) {
            (Some(checks), _) => Deadline::Checks(checks),
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

/// When a step's budget is spent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Deadline {
    /// No budget.
    #[default]
    Never,
    /// The clock passes this instant.
    At(Instant),
    /// After this many more checks (a deterministic budget for tests).
    Checks(u32),
}

impl Deadline {
    /// Whether the budget is spent; a check budget spends one check.
    #[inline]
    pub fn spent(&mut self) -> bool {
        match self {
            Deadline::Never => false,
            Deadline::At(d) => Instant::now() >= *d,
            Deadline::Checks(0) => true,
            Deadline::Checks(n) => {
                *n -= 1;
                false
            }
        }
    }
}

/// Preallocated work of [`solve_box_qp`] for up to `p` unknowns.
#[derive(Debug, Clone)]
pub struct BoxQpWork {
    free: Vec<usize>,
    k: Vec<f64>,
    l: Vec<f64>,
    rhs: Vec<f64>,
    grad: Vec<f64>,
    z0: Vec<f64>,
    /// `z` on the active set, zero on the free one (the reduced rhs).
    za: Vec<f64>,
}

impl BoxQpWork {
    /// Buffers for `p` unknowns.
    pub fn new(p: usize) -> Self {
        Self {
            free: vec![0; p],
            k: vec![0.0; p * p],
            l: vec![0.0; p * p],
            rhs: vec![0.0; p],
            grad: vec![0.0; p],
            z0: vec![0.0; p],
            za: vec![0.0; p],
        }
    }
}

/// Minimizes `½ zᵀ P z − cᵀ z` subject to `lo ≤ z ≤ hi` (`P` symmetric
/// positive definite, `p × p` column-major; `lo ≤ hi`, infinite bounds
/// allowed) by a primal active-set method.
///
/// `z` holds the starting point on entry (it is clipped to the box; the
/// clipped entries form the first active set) and the result on exit;
/// `state[i]` is `−1`/`+1` when `z_i` ends at its lower/upper bound, else 0.
/// Every iterate is feasible and none increases the cost, so when the
/// iteration bound `max_iter` is reached `z` is a feasible point no worse than
/// the clipped start. Returns (iterations, converged). Allocation-free.
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
pub fn solve_box_qp(
    p: usize,
    hess: &[f64],
    lin: &[f64],
    lo: &[f64],
    hi: &[f64],
    z: &mut [f64],
    state: &mut [i8],
    w: &mut BoxQpWork,
    max_iter: u32,
) -> (u32, bool) {
    let qp = BoxQp {
        p,
        hess,
        lin,
        lo,
        hi,
    };
    let (it, ok, _) = solve_box_qp_until(qp, z, state, w, (max_iter, &mut Deadline::Never));
    (it, ok)
}

/// The problem of [`solve_box_qp`]: `p` unknowns, `P`, `c` and the box.
#[derive(Debug, Clone, Copy)]
pub struct BoxQp<'a> {
    /// Number of unknowns.
    pub p: usize,
    /// `P`, `p × p` column-major.
    pub hess: &'a [f64],
    /// `c`.
    pub lin: &'a [f64],
    /// Lower bounds.
    pub lo: &'a [f64],
    /// Upper bounds.
    pub hi: &'a [f64],
}

/// [`solve_box_qp`] with a deadline: before each iteration, when the clock
/// has passed `limits.1` the solve stops with its current (feasible) point.
/// Returns (iterations, converged, deadline hit). `limits.0` bounds the
/// iterations (the worst case of the QP the controller runs: `4·N·n`).
pub fn solve_box_qp_until(
    qp: BoxQp<'_>,
    z: &mut [f64],
    state: &mut [i8],
    w: &mut BoxQpWork,
    limits: (u32, &mut Deadline),
) -> (u32, bool, bool) {
    let BoxQp {
        p,
        hess,
        lin,
        lo,
        hi,
    } = qp;
    let (max_iter, deadline) = limits;
    for i in 0..p {
        state[i] = 0;
        if z[i] <= lo[i] {
            z[i] = lo[i];
            state[i] = -1;
        } else if z[i] >= hi[i] {
            z[i] = hi[i];
            state[i] = 1;
        }
    }
    let scale = lin.iter().fold(0.0f64, |a, v| a.max(v.abs()))
        + (0..p).fold(0.0f64, |a, i| a.max(hess[i * p + i].abs()));
    let tol = 1e-11 * scale.max(f64::MIN_POSITIVE);
    // The free set (in the order of its factor) and the Cholesky factor of
    // P_FF (lower, column-major, leading dimension p): factored once, then
    // updated as variables leave (a row/column deleted: a rank-1 update of
    // the trailing block, O(n_F²)) or join (a row appended: one forward
    // substitution, O(n_F²)) instead of refactored (O(n_F³)) per iteration.
    let mut nf = 0;
    for i in 0..p {
        if state[i] == 0 {
            w.free[nf] = i;
            nf += 1;
        }
    }
    // The first iteration's factorization (O(n_F³)) is the costliest
    // unit of work: checked before it too.
    if deadline.spent() {
        return (0, false, true);
    }
    if !factor_free(p, hess, &w.free[..nf], &mut w.l) {
        return (1, false, false);
    }
    let mut it = 0u32;
    while it < max_iter {
        if deadline.spent() {
            return (it, false, true);
        }
        it += 1;
        // The reduced system P_FF z_F = c_F − P_FA z_A; P is symmetric, so
        // (P_FA z_A)_a is the contiguous column f_a of P against z_A (z with
        // the free entries zeroed).
        for ((za, zi), st) in w.za[..p].iter_mut().zip(z.iter()).zip(state.iter()) {
            *za = if *st != 0 { *zi } else { 0.0 };
        }
        for (a, &fa) in w.free[..nf].iter().enumerate() {
            w.rhs[a] = lin[fa] - dot(&hess[fa * p..fa * p + p], &w.za[..p]);
        }
        cholesky_solve_in_place_dot(nf, p, &w.l, &mut w.rhs[..nf]);
        let (alpha, block) = step_length(&w.free[..nf], &w.rhs[..nf], z, (lo, hi));
        for (a, &fa) in w.free[..nf].iter().enumerate() {
            z[fa] = if block.is_none() {
                w.rhs[a]
            } else {
                (z[fa] + alpha * (w.rhs[a] - z[fa])).clamp(lo[fa], hi[fa])
            };
        }
        if let Some((a, i, s)) = block {
            z[i] = if s < 0 { lo[i] } else { hi[i] };
            state[i] = s;
            delete_from_factor(nf, p, &mut w.l, a);
            w.free.copy_within(a + 1..nf, a);
            nf -= 1;
            continue;
        }
        let Some(i) = worst_multiplier((p, hess, lin), z, state, &mut w.grad, tol) else {
            return (it, true, false);
        };
        state[i] = 0;
        for (a, &fa) in w.free[..nf].iter().enumerate() {
            w.k[a] = hess[i * p + fa];
        }
        w.free[nf] = i;
        nf += 1;
        if !append_to_factor(nf - 1, p, &mut w.l, &mut w.k[..nf - 1], hess[i * p + i])
            && !factor_free(p, hess, &w.free[..nf], &mut w.l)
        {
            return (it, false, false);
        }
    }
    (it, false, false)
}

/// Largest step of [`solve_box_qp_until`] from `z` towards the free
/// subproblem's optimum `target` (entry `a` is that of `free[a]`) that stays
/// in the box: `α ≤ 1` and the bound that blocks it (position in `free`,
/// variable, `−1`/`+1` for lower/upper).
#[allow(clippy::type_complexity)]
fn step_length(
    free: &[usize],
    target: &[f64],
    z: &[f64],
    (lo, hi): (&[f64], &[f64]),
) -> (f64, Option<(usize, usize, i8)>) {
    let mut alpha = 1.0f64;
    let mut block: Option<(usize, usize, i8)> = None;
    for (a, &fa) in free.iter().enumerate() {
        let d = target[a] - z[fa];
        if d < 0.0 && target[a] < lo[fa] {
            let s = (lo[fa] - z[fa]) / d;
            if s < alpha {
                alpha = s.max(0.0);
                block = Some((a, fa, -1));
            }
        } else if d > 0.0 && target[a] > hi[fa] {
            let s = (hi[fa] - z[fa]) / d;
            if s < alpha {
                alpha = s.max(0.0);
                block = Some((a, fa, 1));
            }
        }
    }
    (alpha, block)
}

/// Optimal on the active set: the bound variable whose multiplier (gradient
/// sign) is the most wrong, beyond `tol` (`None`: optimal); the gradient of
/// the bound variables into `grad`.
fn worst_multiplier(
    (p, hess, lin): (usize, &[f64], &[f64]),
    z: &[f64],
    state: &[i8],
    grad: &mut [f64],
    tol: f64,
) -> Option<usize> {
    let mut worst = tol;
    let mut release = None;
    for i in 0..p {
        if state[i] == 0 {
            continue;
        }
        let gi = dot(&hess[i * p..i * p + p], &z[..p]) - lin[i];
        grad[i] = gi;
        // At the lower bound the cost must not decrease upwards (g ≥ 0),
        // at the upper bound not downwards (g ≤ 0).
        let v = if state[i] < 0 { -gi } else { gi };
        if v > worst {
            worst = v;
            release = Some(i);
        }
    }
    release
}

/// Cholesky factor of `P_FF` (rows and columns `free` of the p×p
/// column-major `hess`) into `l` (lower, leading dimension p); false when
/// `P_FF` is not (numerically) positive definite.
fn factor_free(p: usize, hess: &[f64], free: &[usize], l: &mut [f64]) -> bool {
    let nf = free.len();
    for (b, &fb) in free.iter().enumerate() {
        for (a, &fa) in free.iter().enumerate().skip(b) {
            l[b * p + a] = hess[fb * p + fa];
        }
    }
    cholesky_in_place(nf, p, l).is_ok()
}

/// Deletes row and column `k` of the n×n factor (`L Lᵀ = P_FF` without
/// that variable): the trailing block `L33` becomes the factor of
/// `L33 L33ᵀ + x xᵀ`, `x` the deleted column below the diagonal (a rank-1
/// update by rotations: stable), then the storage closes the gap.
fn delete_from_factor(n: usize, ld: usize, l: &mut [f64], k: usize) {
    // Rank-1 update of L33 (indices k+1..n) with x = L[k+1..n, k], held in
    // column k itself (rows k+1..n) as work.
    for j in k + 1..n {
        let (left, right) = l.split_at_mut(j * ld);
        let x = &mut left[k * ld..k * ld + n];
        let col = &mut right[..n];
        let (ljj, xj) = (col[j], x[j]);
        let r = ljj.hypot(xj);
        let (c, s) = (r / ljj, xj / ljj);
        col[j] = r;
        for (lij, xi) in col[j + 1..n].iter_mut().zip(&mut x[j + 1..n]) {
            *lij = (*lij + s * *xi) / c;
            *xi = c * *xi - s * *lij;
        }
    }
    // Close the gap: column c' takes old column c' (+1 from k on), row r'
    // old row r' (+1 from k on); every move goes up or left, so in place.
    for cn in 0..n - 1 {
        let co = if cn < k { cn } else { cn + 1 };
        for rn in cn..n - 1 {
            let ro = if rn < k { rn } else { rn + 1 };
            l[cn * ld + rn] = l[co * ld + ro];
        }
    }
}

/// Appends variable row/column `n` to the n×n factor: `y = L⁻¹ k` (`k` =
/// `P[F, i]` in factor order, overwritten by `y`), `d² = P_ii − yᵀy`.
/// False (factor unchanged in its first n columns) when `d²` is not safely
/// positive, for the caller to refactor.
fn append_to_factor(n: usize, ld: usize, l: &mut [f64], k: &mut [f64], pii: f64) -> bool {
    for j in 0..n {
        let yj = k[j] / l[j * ld + j];
        k[j] = yj;
        for (ki, li) in k[j + 1..n].iter_mut().zip(&l[j * ld + j + 1..j * ld + n]) {
            *ki -= li * yj;
        }
    }
    let d2 = pii - crate::control::solvers::dense::dot(&k[..n], &k[..n]);
    if !(d2 > 1e-12 * pii.abs() && d2.is_finite()) {
        return false;
    }
    for (j, y) in k[..n].iter().enumerate() {
        l[j * ld + n] = *y;
    }
    l[n * ld + n] = d2.sqrt();
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::linalg::random::symmetric as lcg;

    /// `MᵀM + eps·I` (p×p column-major) for a random `M` with entries in
    /// [−1, 1].
    fn random_spd(p: usize, eps: f64, s: &mut u64) -> Vec<f64> {
        let mm: Vec<f64> = (0..p * p).map(|_| lcg(s)).collect();
        let mut h = vec![0.0; p * p];
        for i in 0..p {
            for j in 0..p {
                h[j * p + i] = (0..p).map(|r| mm[i * p + r] * mm[j * p + r]).sum();
            }
            h[i * p + i] += eps;
        }
        h
    }

    fn cost(p: usize, h: &[f64], c: &[f64], z: &[f64]) -> f64 {
        let mut s = 0.0;
        for i in 0..p {
            for j in 0..p {
                s += 0.5 * z[i] * h[j * p + i] * z[j];
            }
            s -= c[i] * z[i];
        }
        s
    }

    /// Brute force: every assignment of {lower, free, upper} to the `p`
    /// unknowns, the equality-constrained optimum of each, the best feasible.
    fn brute(p: usize, h: &[f64], c: &[f64], lo: &[f64], hi: &[f64]) -> Vec<f64> {
        let mut best = (f64::INFINITY, vec![0.0; p]);
        let combos = 3usize.pow(p as u32);
        for code in 0..combos {
            let mut st = vec![0i8; p];
            let mut cc = code;
            for s in st.iter_mut() {
                *s = (cc % 3) as i8 - 1;
                cc /= 3;
            }
            let mut z = vec![0.0; p];
            for i in 0..p {
                if st[i] < 0 {
                    z[i] = lo[i];
                } else if st[i] > 0 {
                    z[i] = hi[i];
                }
            }
            let free: Vec<usize> = (0..p).filter(|&i| st[i] == 0).collect();
            let nf = free.len();
            if nf > 0 {
                let k = nalgebra::DMatrix::from_fn(nf, nf, |a, b| h[free[b] * p + free[a]]);
                let r = nalgebra::DVector::from_fn(nf, |a, _| {
                    c[free[a]]
                        - (0..p)
                            .filter(|&i| st[i] != 0)
                            .map(|i| h[i * p + free[a]] * z[i])
                            .sum::<f64>()
                });
                let sol = k.cholesky().unwrap().solve(&r);
                for (a, &f) in free.iter().enumerate() {
                    z[f] = sol[a];
                }
            }
            if (0..p).all(|i| z[i] >= lo[i] - 1e-12 && z[i] <= hi[i] + 1e-12) {
                let f = cost(p, h, c, &z);
                if f < best.0 {
                    best = (f, z);
                }
            }
        }
        best.1
    }

    #[test]
    fn box_qp_matches_brute_force_enumeration() {
        let mut s = 7u64;
        for trial in 0..200 {
            let p = 1 + trial % 6;
            // P = MᵀM + εI, condition up to ~1e4.
            let h = random_spd(p, 1e-3, &mut s);
            let c: Vec<f64> = (0..p).map(|_| 3.0 * lcg(&mut s)).collect();
            let lo: Vec<f64> = (0..p).map(|_| -0.5 - lcg(&mut s).abs()).collect();
            let hi: Vec<f64> = (0..p)
                .map(|i| {
                    if i == 0 && trial % 5 == 0 {
                        f64::INFINITY
                    } else {
                        0.2 + lcg(&mut s).abs()
                    }
                })
                .collect();
            let expect = brute(p, &h, &c, &lo, &hi);
            let mut z: Vec<f64> = (0..p).map(|_| 5.0 * lcg(&mut s)).collect();
            let mut st = vec![0i8; p];
            let mut w = BoxQpWork::new(p);
            let (_, ok) = solve_box_qp(p, &h, &c, &lo, &hi, &mut z, &mut st, &mut w, 100);
            assert!(ok, "trial {trial}: not converged");
            for i in 0..p {
                assert!(z[i] >= lo[i] && z[i] <= hi[i], "trial {trial}: infeasible");
            }
            let (f, fb) = (cost(p, &h, &c, &z), cost(p, &h, &c, &expect));
            assert!(
                f <= fb + 1e-9 * (1.0 + fb.abs()),
                "trial {trial}: active set {f} vs brute force {fb}"
            );
            for i in 0..p {
                assert!(
                    (z[i] - expect[i]).abs() < 1e-6 * (1.0 + expect[i].abs()),
                    "trial {trial}: z[{i}] {} vs {}",
                    z[i],
                    expect[i]
                );
            }
        }
    }

    /// The factor kept through a random sequence of deletions and
    /// appends equals the Cholesky factor of the current free set's `P_FF`
    /// computed from scratch (p = 40, condition ≈ 1e4).
    #[test]
    fn updated_factor_equals_the_refactored_one() {
        let mut s = 5u64;
        let p = 40;
        let h = random_spd(p, 1e-2, &mut s);
        let mut free: Vec<usize> = (0..p).filter(|i| i % 3 != 0).collect();
        let mut l = vec![0.0; p * p];
        assert!(factor_free(p, &h, &free, &mut l));
        let mut out: Vec<usize> = (0..p).filter(|i| i % 3 == 0).collect();
        for step in 0..60 {
            if step % 3 == 2 && !out.is_empty() {
                let i = out.remove((lcg(&mut s).abs() * out.len() as f64) as usize % out.len());
                let mut k: Vec<f64> = free.iter().map(|&f| h[i * p + f]).collect();
                assert!(append_to_factor(
                    free.len(),
                    p,
                    &mut l,
                    &mut k,
                    h[i * p + i]
                ));
                free.push(i);
            } else {
                let a = (lcg(&mut s).abs() * free.len() as f64) as usize % free.len();
                delete_from_factor(free.len(), p, &mut l, a);
                out.push(free.remove(a));
            }
            let mut fresh = vec![0.0; p * p];
            assert!(factor_free(p, &h, &free, &mut fresh));
            let nf = free.len();
            for c in 0..nf {
                for r in c..nf {
                    let (x, y) = (l[c * p + r], fresh[c * p + r]);
                    assert!(
                        (x - y).abs() <= 1e-9 * (1.0 + y.abs()),
                        "step {step} ({r}, {c}): {x} vs {y}"
                    );
                }
            }
        }
    }

    #[test]
    fn box_qp_out_of_iterations_is_feasible_and_no_worse_than_the_clipped_start() {
        let mut s = 11u64;
        let p = 6;
        let mut h = vec![0.0; p * p];
        for i in 0..p {
            for j in 0..p {
                h[j * p + i] = if i == j {
                    2.0
                } else {
                    0.9 + 0.05 * lcg(&mut s)
                };
            }
        }
        for i in 0..p {
            for j in 0..i {
                h[j * p + i] = h[i * p + j];
            }
        }
        let c: Vec<f64> = (0..p)
            .map(|i| if i % 2 == 0 { 9.0 } else { -9.0 })
            .collect();
        let lo = vec![-1.0; p];
        let hi = vec![1.0; p];
        let start: Vec<f64> = vec![0.0; p];
        let f0 = cost(p, &h, &c, &start);
        for max_iter in 1..4 {
            let mut z = start.clone();
            let mut st = vec![0i8; p];
            let mut w = BoxQpWork::new(p);
            solve_box_qp(p, &h, &c, &lo, &hi, &mut z, &mut st, &mut w, max_iter);
            assert!(z.iter().all(|v| (-1.0..=1.0).contains(v)));
            assert!(cost(p, &h, &c, &z) <= f0 + 1e-12);
        }
    }
}
