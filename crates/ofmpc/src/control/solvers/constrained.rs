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

use crate::control::solvers::dense::dot;
use crate::control::telemetry::FallbackLevel;
use crate::linalg::{cholesky_in_place, cholesky_solve_in_place_dot};
use std::time::Instant;

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
    pub(crate) z0: Vec<f64>,
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
