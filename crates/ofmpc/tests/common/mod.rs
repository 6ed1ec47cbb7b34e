//! Test models for the controller tests and benches (not part of the library).
#![allow(dead_code, clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector};
use ofmpc::dynamics::JointSpaceDynamics;

pub mod alloc_counter;
pub mod experiment;
pub mod gcode;
pub mod ik;
pub mod ik_model;
pub mod rng;
pub mod robots;

/// Deterministic pseudo-random numbers (`next()` in [-1, 1)): the tests' one LCG.
pub use rng::Lcg as Rng;

/// A linear plant: constant `H`, `C`, `g`.
#[derive(Clone, Debug)]
pub struct LinearModel {
    pub h: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub g: DVector<f64>,
}

impl LinearModel {
    /// A 2-joint example with coupling and damping.
    pub fn example2() -> Self {
        Self {
            h: DMatrix::from_row_slice(2, 2, &[2.0, 0.3, 0.3, 1.0]),
            c: DMatrix::from_row_slice(2, 2, &[0.5, 0.1, 0.0, 0.3]),
            g: DVector::from_row_slice(&[1.0, 0.5]),
        }
    }
}

impl JointSpaceDynamics for LinearModel {
    fn dof(&self) -> usize {
        self.h.nrows()
    }
    fn terms(
        &mut self,
        _q: &[f64],
        _qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    ) {
        h.copy_from(&self.h);
        c.copy_from(&self.c);
        g.copy_from(&self.g);
    }
}

/// An n-joint nonlinear model with a dense configuration-dependent inertia
/// `H(q) = H0 + Σ_k a_k cos(q_k) S_k`, its Christoffel Coriolis matrix and a
/// gravity-like `g_i = γ_i sin(q_i + 0.3)`. Allocation-free `terms`.
#[derive(Clone, Debug)]
pub struct CoupledModel {
    pub h0: DMatrix<f64>,
    pub a: Vec<f64>,
    pub s: Vec<DMatrix<f64>>,
    pub gamma: Vec<f64>,
    /// d_k = −a_k sin q_k of the current call (buffer, no allocation in terms).
    dk: Vec<f64>,
}

impl CoupledModel {
    pub fn new(n: usize, seed: u64) -> Self {
        let mut rng = Rng(seed);
        let m = rng.matrix(n, n) * 0.3;
        let h0 = &m * m.transpose()
            + DMatrix::from_diagonal(&DVector::from_fn(n, |i, _| 2.0 + 0.5 * i as f64));
        let s = (0..n)
            .map(|_| {
                let r = rng.matrix(n, n) * 0.2;
                (&r + r.transpose()) * 0.5
            })
            .collect();
        let a = (0..n).map(|k| 0.5 / (1.0 + k as f64)).collect();
        let gamma = (0..n)
            .map(|i| 5.0 * (1.0 + 0.3 * rng.next()) / (1.0 + i as f64))
            .collect();
        Self {
            h0,
            a,
            s,
            gamma,
            dk: vec![0.0; n],
        }
    }
}

impl JointSpaceDynamics for CoupledModel {
    fn dof(&self) -> usize {
        self.h0.nrows()
    }
    fn terms(
        &mut self,
        q: &[f64],
        qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    ) {
        let n = self.dof();
        h.copy_from(&self.h0);
        for k in 0..n {
            let w = self.a[k] * q[k].cos();
            for j in 0..n {
                for i in 0..n {
                    h[(i, j)] += w * self.s[k][(i, j)];
                }
            }
        }
        // C_ij = ½ Σ_k (∂H_ij/∂q_k + ∂H_ik/∂q_j − ∂H_jk/∂q_i) q̇_k, ∂H/∂q_k = d_k S_k.
        for k in 0..n {
            self.dk[k] = -self.a[k] * q[k].sin();
        }
        for j in 0..n {
            let dj = self.dk[j];
            for i in 0..n {
                let di = self.dk[i];
                let (sj, si) = (self.s[j].as_slice(), self.s[i].as_slice());
                let mut sum = 0.0;
                for k in 0..n {
                    // S symmetric, column-major: S_k[i,j] = [j*n+i], S_j[i,k] = [k*n+i], S_i[j,k] = [k*n+j].
                    let sk = self.s[k].as_slice();
                    sum += (self.dk[k] * sk[j * n + i] + dj * sj[k * n + i] - di * si[k * n + j])
                        * qd[k];
                }
                c[(i, j)] = 0.5 * sum;
            }
        }
        for i in 0..n {
            g[i] = self.gamma[i] * (q[i] + 0.3).sin();
        }
    }
}

/// Planar two-link arm with point-ish links (analytic H, C, g), gravity
/// along −y, joint angles from the x axis.
#[derive(Clone, Debug)]
pub struct TwoLinkArm {
    pub m1: f64,
    pub m2: f64,
    pub l1: f64,
    pub lc1: f64,
    pub lc2: f64,
    pub i1: f64,
    pub i2: f64,
    pub g0: f64,
}

impl TwoLinkArm {
    pub fn new() -> Self {
        Self {
            m1: 3.0,
            m2: 2.0,
            l1: 0.5,
            lc1: 0.25,
            lc2: 0.2,
            i1: 0.1,
            i2: 0.05,
            g0: 9.81,
        }
    }

    /// The same arm with a point payload `mp` at distance `r` on link 2.
    pub fn with_payload(&self, mp: f64, r: f64) -> Self {
        let m2 = self.m2 + mp;
        let lc2 = (self.m2 * self.lc2 + mp * r) / m2;
        // inertia about the new centre of mass (parallel axis theorem)
        let i2 = self.i2 + self.m2 * (self.lc2 - lc2).powi(2) + mp * (r - lc2).powi(2);
        Self {
            m2,
            lc2,
            i2,
            ..self.clone()
        }
    }
}

impl JointSpaceDynamics for TwoLinkArm {
    fn dof(&self) -> usize {
        2
    }
    fn terms(
        &mut self,
        q: &[f64],
        qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    ) {
        let (c2, s2) = (q[1].cos(), q[1].sin());
        let a = self.m1 * self.lc1.powi(2)
            + self.m2 * (self.l1.powi(2) + self.lc2.powi(2))
            + self.i1
            + self.i2;
        let b = self.m2 * self.l1 * self.lc2;
        let d = self.m2 * self.lc2.powi(2) + self.i2;
        h[(0, 0)] = a + 2.0 * b * c2;
        h[(0, 1)] = d + b * c2;
        h[(1, 0)] = d + b * c2;
        h[(1, 1)] = d;
        let hh = b * s2;
        c[(0, 0)] = -hh * qd[1];
        c[(0, 1)] = -hh * (qd[0] + qd[1]);
        c[(1, 0)] = hh * qd[0];
        c[(1, 1)] = 0.0;
        g[0] = (self.m1 * self.lc1 + self.m2 * self.l1) * self.g0 * q[0].cos()
            + self.m2 * self.lc2 * self.g0 * (q[0] + q[1]).cos();
        g[1] = self.m2 * self.lc2 * self.g0 * (q[0] + q[1]).cos();
    }
}

/// Exact ZOH of `q̈ = f0 q̇ + u` via the exponential of the augmented matrix
/// (independent of the library's series): returns `(Ad, Bd)`.
pub fn zoh_reference(f0: &DMatrix<f64>, ts: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = f0.nrows();
    let mut aug = DMatrix::<f64>::zeros(3 * n, 3 * n);
    for i in 0..n {
        aug[(i, n + i)] = 1.0;
        aug[(n + i, 2 * n + i)] = 1.0;
    }
    aug.view_mut((n, n), (n, n)).copy_from(f0);
    let ex = (aug * ts).exp();
    (
        ex.view((0, 0), (2 * n, 2 * n)).into_owned(),
        ex.view((0, 2 * n), (2 * n, n)).into_owned(),
    )
}

/// A plant simulated by RK4 with torques held over each sample, plus a
/// constant torque disturbance `d` (`H q̈ + C q̇ + g = τ + d`).
pub struct Plant<M: JointSpaceDynamics> {
    pub model: M,
    pub d: DVector<f64>,
    pub substeps: usize,
    h: DMatrix<f64>,
    c: DMatrix<f64>,
    g: DVector<f64>,
}

impl<M: JointSpaceDynamics> Plant<M> {
    pub fn new(model: M, d: DVector<f64>, substeps: usize) -> Self {
        let n = model.dof();
        Self {
            model,
            d,
            substeps,
            h: DMatrix::zeros(n, n),
            c: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
        }
    }

    fn accel(&mut self, x: &DVector<f64>, tau: &DVector<f64>) -> DVector<f64> {
        let n = self.model.dof();
        let q: Vec<f64> = x.rows(0, n).iter().copied().collect();
        let qd: Vec<f64> = x.rows(n, n).iter().copied().collect();
        self.model
            .terms(&q, &qd, &mut self.h, &mut self.c, &mut self.g);
        let rhs = tau + &self.d - &self.c * x.rows(n, n) - &self.g;
        let qdd = self.h.clone().cholesky().expect("plant H SPD").solve(&rhs);
        let mut dx = DVector::zeros(2 * n);
        dx.rows_mut(0, n).copy_from(&x.rows(n, n));
        dx.rows_mut(n, n).copy_from(&qdd);
        dx
    }

    /// Advances the state by `ts` with constant torque `tau`.
    pub fn advance(&mut self, x: &mut DVector<f64>, tau: &[f64], ts: f64) {
        let tau = DVector::from_column_slice(tau);
        let h = ts / self.substeps as f64;
        for _ in 0..self.substeps {
            let k1 = self.accel(x, &tau);
            let k2 = self.accel(&(&*x + &k1 * (h / 2.0)), &tau);
            let k3 = self.accel(&(&*x + &k2 * (h / 2.0)), &tau);
            let k4 = self.accel(&(&*x + &k3 * h), &tau);
            *x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
    }
}

/// Exact discretization of a linear plant with constant terms and a constant
/// torque disturbance: `x⁺ = Ad x + Bd H_p⁻¹(τ + d − g_p)`.
pub struct LinearPlant {
    pub ad: DMatrix<f64>,
    pub bd: DMatrix<f64>,
    pub h_inv: DMatrix<f64>,
    pub g: DVector<f64>,
    pub d: DVector<f64>,
}

impl LinearPlant {
    pub fn new(p: &LinearModel, d: DVector<f64>, ts: f64) -> Self {
        let h_inv = p.h.clone().try_inverse().unwrap();
        let f0 = -&h_inv * &p.c;
        let (ad, bd) = zoh_reference(&f0, ts);
        Self {
            ad,
            bd,
            h_inv,
            g: p.g.clone(),
            d,
        }
    }

    pub fn advance(&self, x: &mut DVector<f64>, tau: &[f64]) {
        let u = &self.h_inv * (DVector::from_column_slice(tau) + &self.d - &self.g);
        *x = &self.ad * &*x + &self.bd * u;
    }
}

/// Prediction matrices by the block formulas of docs/guide/paper-notes.md
/// ("Symbols") with explicit matrix powers of `(Ad, Bd)` and `C = [I, 0]`
/// (full G matrices).
pub struct Brute {
    pub f1: DMatrix<f64>,
    pub f2: DMatrix<f64>,
    pub f3: DMatrix<f64>,
    pub g1: DMatrix<f64>,
    pub g2: DMatrix<f64>,
    pub g3: DMatrix<f64>,
}

/// Block formulas of docs/guide/paper-notes.md ("Symbols") with explicit
/// matrix powers.
pub fn brute(ad: &DMatrix<f64>, bd: &DMatrix<f64>, n: usize, nh: usize) -> Brute {
    let nx = 2 * n;
    let mut c = DMatrix::<f64>::zeros(n, nx);
    c.view_mut((0, 0), (n, n)).fill_with_identity();
    let pow = |k: usize| (0..k).fold(DMatrix::<f64>::identity(nx, nx), |acc, _| &acc * ad);
    let ca = |k: usize| &c * pow(k);
    let cab = |k: usize| &c * pow(k) * bd;
    let mut r = Brute {
        f1: DMatrix::<f64>::zeros(nh * n, nx),
        f2: DMatrix::<f64>::zeros(nh * n, nx),
        f3: DMatrix::<f64>::zeros(nh * n, nx),
        g1: DMatrix::<f64>::zeros(nh * n, nh * n),
        g2: DMatrix::<f64>::zeros(nh * n, nh * n),
        g3: DMatrix::<f64>::zeros(nh * n, nh * n),
    };
    for j in 1..=nh {
        let o = (j - 1) * n;
        r.f1.view_mut((o, 0), (n, nx)).copy_from(&ca(j));
        let f2 = (1..=j).fold(DMatrix::<f64>::zeros(n, nx), |s, i| s + ca(i));
        r.f2.view_mut((o, 0), (n, nx)).copy_from(&f2);
        let f3 = (1..j).fold(DMatrix::<f64>::zeros(n, nx), |s, i| {
            s + ca(i) * ((j - i) as f64)
        });
        r.f3.view_mut((o, 0), (n, nx)).copy_from(&f3);
        for l in 1..=j {
            let ol = (l - 1) * n;
            r.g1.view_mut((o, ol), (n, n)).copy_from(&cab(j - l));
            let g2 = (l..=j).fold(DMatrix::<f64>::zeros(n, n), |s, m| s + cab(m - l));
            r.g2.view_mut((o, ol), (n, n)).copy_from(&g2);
            let g3 = (l..j).fold(DMatrix::<f64>::zeros(n, n), |s, m| {
                s + cab(m - l) * ((j - m) as f64)
            });
            r.g3.view_mut((o, ol), (n, n)).copy_from(&g3);
        }
    }
    r
}

/// The paper's path (Table I) for `robot` at Ts = 10 ms, through the
/// library's one planning entry point (`ofmpc::motion::plan`).
pub fn paper_reference(robot: &ofmpc::robot::Robot) -> ofmpc::motion::JointReference {
    ofmpc::motion::plan(
        ofmpc::gcode::PAPER_TABLE1,
        robot,
        &ofmpc::motion::PlanOptions::default(),
    )
    .unwrap()
    .reference
}
