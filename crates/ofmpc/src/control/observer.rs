//! A state observer for drives that measure position only, with a delay.
//!
//! Per joint it estimates position, velocity and an acceleration-level
//! disturbance `δ` (what the controller's model misses: an unknown payload,
//! friction) from the measured positions, driven by the model's acceleration
//! `a = f0 q̇ + H⁻¹(τ − g)` (Eq. (6)–(7)):
//!
//! ```text
//! predict:  q⁻ = q + q̇ Ts + ½ (a + δ) Ts²,  q̇⁻ = q̇ + (a + δ) Ts,  δ⁻ = δ
//! correct:  r = y − q⁻;  q = q⁻ + l1 r,  q̇ = q̇⁻ + l2 r,  δ = δ⁻ + l3 r
//! ```
//!
//! with `(l1, l2, l3)` placing the three poles of the error dynamics at `p`.
//! With a measurement `D` samples old it runs on the delayed time line and
//! then predicts `D` samples forward with the model, `δ` and the torques
//! commanded since, so that the payload does not bias the prediction.
//! Allocation-free after construction.

use crate::control::mpc::model::LinearLikeModel;
use crate::control::step::StepFailure;
use crate::dynamics::JointSpaceDynamics;

/// The observer of one controller (see the module docs).
#[derive(Debug, Clone)]
pub struct StateObserver {
    n: usize,
    ts: f64,
    delay: usize,
    gain: [f64; 3],
    q: Vec<f64>,
    v: Vec<f64>,
    dist: Vec<f64>,
    tau_hist: Vec<f64>,
    k: usize,
    model: LinearLikeModel,
    acc: Vec<f64>,
    tmp_q: Vec<f64>,
    tmp_v: Vec<f64>,
    out: Vec<f64>,
    /// Friction estimates per joint (Coulomb N·m, viscous N·m·s/rad); empty:
    /// none (the disturbance carries the friction).
    coulomb: Vec<f64>,
    viscous: Vec<f64>,
    /// With friction: the velocity scale `v_s` of the smoothed Coulomb law,
    /// integrated implicitly (creep); 0: the stick-aware clamp.
    creep_velocity: f64,
    /// With creep: the joints' friction solved together through the whole
    /// inertia matrix (Newton on the convex potential) instead of joint by joint
    /// through its diagonal ([`Self::set_creep_coupled`]).
    creep_coupled: bool,
    /// The free velocity `s` of the coupled solve (n values) and its
    /// workspace (`n² + 2n`).
    free_v: Vec<f64>,
    creep_work: Vec<f64>,
}

/// Characteristic polynomial `z³ + c2 z² + c1 z + c0` of a 3×3 row-major matrix.
fn charpoly(m: &[[f64; 3]; 3]) -> [f64; 3] {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let minors = m[0][0] * m[1][1] - m[0][1] * m[1][0] + m[0][0] * m[2][2] - m[0][2] * m[2][0]
        + m[1][1] * m[2][2]
        - m[1][2] * m[2][1];
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    [-tr, minors, -det]
}

/// Error-dynamics matrix `(I − L C) A` of the observer.
fn error_matrix(ts: f64, l: [f64; 3]) -> [[f64; 3]; 3] {
    let a = [[1.0, ts, 0.5 * ts * ts], [0.0, 1.0, ts], [0.0, 0.0, 1.0]];
    let ca = a[0];
    let mut m = a;
    for (r, row) in m.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v -= l[r] * ca[c];
        }
    }
    m
}

/// Gains placing the three observer poles at `p` (the characteristic
/// polynomial is affine in the gains: three evaluations and a 3×3 solve).
pub fn observer_gains(ts: f64, p: f64) -> [f64; 3] {
    let c0 = charpoly(&error_matrix(ts, [0.0; 3]));
    let mut jac = [[0.0; 3]; 3];
    for (j, e) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .into_iter()
        .enumerate()
    {
        let c = charpoly(&error_matrix(ts, e));
        for i in 0..3 {
            jac[i][j] = c[i] - c0[i];
        }
    }
    let target = [-3.0 * p, 3.0 * p * p, -p * p * p];
    let rhs = [target[0] - c0[0], target[1] - c0[1], target[2] - c0[2]];
    // Cramer's rule.
    let det3 = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(&jac);
    let mut l = [0.0; 3];
    for (j, lj) in l.iter_mut().enumerate() {
        let mut m = jac;
        for i in 0..3 {
            m[i][j] = rhs[i];
        }
        *lj = det3(&m) / d;
    }
    l
}

impl StateObserver {
    /// An observer for `n` joints, period `ts`, measurement delay `delay`
    /// samples (0: none; the estimate is then of the measured sample), poles
    /// at `pole` (in (0, 1); 0.5 is a good default at 10 ms).
    pub fn new(n: usize, ts: f64, delay: usize, pole: f64) -> Self {
        Self {
            n,
            ts,
            delay,
            gain: observer_gains(ts, pole),
            q: vec![0.0; n],
            v: vec![0.0; n],
            dist: vec![0.0; n],
            tau_hist: vec![0.0; (delay + 1) * n],
            k: 0,
            model: LinearLikeModel::new(n),
            acc: vec![0.0; n],
            tmp_q: vec![0.0; n],
            tmp_v: vec![0.0; n],
            out: vec![0.0; 2 * n],
            coulomb: Vec::new(),
            viscous: Vec::new(),
            creep_velocity: 0.0,
            creep_coupled: false,
            free_v: vec![0.0; n],
            creep_work: vec![0.0; n * n + 2 * n],
        }
    }

    /// Lets the observer's model carry the drives' friction estimates
    /// (Coulomb `coulomb[i]` N·m, viscous `viscous[i]` N·m·s/rad; n values
    /// each, else ignored) instead of leaving all of the friction to the
    /// disturbance estimate. The Coulomb part is stick-aware per joint: the
    /// friction torque that stops the joint within the step, bounded by
    /// `±F_c` (`F = clamp(H_ii v⁺/Ts, −F_c, F_c)`, `v⁺` the velocity the
    /// step reaches without it).
    pub fn set_friction(&mut self, coulomb: &[f64], viscous: &[f64]) {
        if coulomb.len() == self.n && viscous.len() == self.n {
            self.coulomb = coulomb.to_vec();
            self.viscous = viscous.to_vec();
        }
    }

    /// With the friction of [`Self::set_friction`]: the Coulomb part as the
    /// smoothed law `F_c tanh(q̇/v_s)` that creeps near rest, integrated
    /// implicitly over each sample (`crate::control::mpc::creep`), instead of
    /// the stick-aware clamp. `v_s ≤ 0` or not finite: the clamp.
    pub fn set_creep(&mut self, v_s: f64) {
        self.creep_velocity = if v_s.is_finite() && v_s > 0.0 {
            v_s
        } else {
            0.0
        };
    }

    /// With creep ([`Self::set_creep`]): solve the implicit friction step of
    /// all joints together, `H (x − s)/Ts + F(x) = 0` (the plant's friction
    /// acts through `H⁻¹`, and a heavy payload couples the joints whose axes
    /// are parallel), instead of each joint through `H_ii` alone.
    pub fn set_creep_coupled(&mut self, on: bool) {
        self.creep_coupled = on;
    }

    /// The gains `(l1, l2, l3)`.
    pub fn gains(&self) -> [f64; 3] {
        self.gain
    }

    /// The disturbance estimate `δ` (rad/s², per joint).
    pub fn disturbance(&self) -> &[f64] {
        &self.dist
    }

    /// Starts at rest at the measured positions of `x0` (2n values).
    pub fn reset(&mut self, x0: &[f64]) {
        let n = self.n;
        self.q.copy_from_slice(&x0[..n]);
        self.v.fill(0.0);
        self.dist.fill(0.0);
        self.tau_hist.fill(0.0);
        self.k = 0;
    }

    /// `acc = f0 v + H⁻¹(τ − g) + δ` at `(q, v)`.
    fn accel(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        from_tmp: bool,
        tau_slot: usize,
    ) -> Result<(), StepFailure> {
        let n = self.n;
        let (q, v) = if from_tmp {
            (&self.tmp_q, &self.tmp_v)
        } else {
            (&self.q, &self.v)
        };
        self.model.update(model, q, v)?;
        let tau = &self.tau_hist[tau_slot * n..(tau_slot + 1) * n];
        self.model.input_from_torque(tau, &mut self.acc)?;
        let f0 = self.model.f0().as_slice();
        for c in 0..n {
            let vc = v[c];
            for r in 0..n {
                self.acc[r] += f0[c * n + r] * vc;
            }
        }
        for (a, d) in self.acc.iter_mut().zip(&self.dist) {
            *a += d;
        }
        if !self.coulomb.is_empty() && self.creep_coupled && self.creep_velocity > 0.0 {
            self.coupled_creep(from_tmp);
        } else if !self.coulomb.is_empty() {
            let h = self.model.h();
            let ts = self.ts;
            let vs = self.creep_velocity;
            for i in 0..n {
                let hii = h[(i, i)];
                if vs > 0.0 && hii.is_finite() && hii > 0.0 {
                    let s = v[i] + self.acc[i] * ts;
                    let x = crate::control::mpc::creep::implicit_velocity(
                        hii,
                        ts,
                        s,
                        self.viscous[i],
                        self.coulomb[i],
                        vs,
                    );
                    self.acc[i] = (x - v[i]) / ts;
                } else if hii.is_finite() && hii > 0.0 {
                    let v_next = v[i] + self.acc[i] * ts;
                    let fc = self.coulomb[i];
                    let f = (hii * v_next / ts).clamp(-fc, fc) + self.viscous[i] * v[i];
                    self.acc[i] -= f / hii;
                }
            }
        }
        Ok(())
    }

    /// The coupled implicit friction step ([`Self::set_creep_coupled`]):
    /// from `acc` (without friction) at velocity `v` (the state or its
    /// forward copy), the end velocity `x` of `H (x − s)/Ts + F(x) = 0`,
    /// `s = v + acc·Ts` (`crate::control::mpc::creep::implicit_velocities`,
    /// Newton on the convex potential); `acc = (x − v)/Ts`. No allocation.
    fn coupled_creep(&mut self, from_tmp: bool) {
        let (n, ts, vs) = (self.n, self.ts, self.creep_velocity);
        let v = if from_tmp { &self.tmp_v } else { &self.v };
        let h = self.model.h();
        if (0..n).any(|i| !(h[(i, i)].is_finite() && h[(i, i)] > 0.0)) {
            return;
        }
        for i in 0..n {
            self.free_v[i] = v[i] + self.acc[i] * ts;
        }
        let x = &mut self.acc;
        crate::control::mpc::creep::implicit_velocities(
            h,
            ts,
            &self.free_v,
            (&self.viscous, &self.coulomb, vs),
            x,
            &mut self.creep_work,
        );
        for i in 0..n {
            x[i] = (x[i] - v[i]) / ts;
        }
    }

    /// One sample: `y` is the (delayed) measurement (2n values; only the
    /// positions are used). Returns the estimate of the current state
    /// `x_k = [q; q̇]`. Call [`Self::record_torque`] with the torque commanded
    /// at this sample afterwards. Allocation-free.
    pub fn update(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        y: &[f64],
    ) -> Result<&[f64], StepFailure> {
        let (n, ts, d) = (self.n, self.ts, self.delay);
        let slots = d + 1;
        if self.k > d {
            // Delayed time kd = k − D ≥ 1: predict from kd − 1, correct with y.
            let kd = self.k - d;
            self.accel(model, false, (kd - 1) % slots)?;
            let [l1, l2, l3] = self.gain;
            for i in 0..n {
                let a = self.acc[i];
                let qp = self.q[i] + self.v[i] * ts + 0.5 * a * ts * ts;
                let vp = self.v[i] + a * ts;
                let r = y[i] - qp;
                self.q[i] = qp + l1 * r;
                self.v[i] = vp + l2 * r;
                self.dist[i] += l3 * r;
            }
        }
        // Forward over the delay: from max(kd, 0) to k with the torques since.
        self.tmp_q.copy_from_slice(&self.q);
        self.tmp_v.copy_from_slice(&self.v);
        let from = self.k.saturating_sub(d);
        for j in from..self.k {
            self.accel(model, true, j % slots)?;
            for i in 0..n {
                let a = self.acc[i];
                self.tmp_q[i] += self.tmp_v[i] * ts + 0.5 * a * ts * ts;
                self.tmp_v[i] += a * ts;
            }
        }
        self.out[..n].copy_from_slice(&self.tmp_q);
        self.out[n..].copy_from_slice(&self.tmp_v);
        if let Some(i) = self.out.iter().position(|v| !v.is_finite()) {
            return Err(StepFailure::NonFiniteResult {
                what: "observer state",
                index: i % n,
            });
        }
        Ok(&self.out)
    }

    /// The model's payload changed at once (`dob-mpc`'s fit at rest) since
    /// the last [`Self::update`]: the disturbance `δ` takes over the change
    /// of the model's acceleration under the torque `tau` (n values),
    /// `δ += H⁻¹(τ − g) − H'⁻¹(τ − g')`, so that the prediction does not
    /// jump (the primed terms on the changed `model`, at the observer's
    /// state; the others as the last update evaluated them; nothing before
    /// the first prediction). Allocates nothing.
    pub fn carry_model_change(
        &mut self,
        model: &mut dyn JointSpaceDynamics,
        tau: &[f64],
    ) -> Result<(), StepFailure> {
        if self.k == 0 {
            // Nothing predicted yet: the next update starts on the new model.
            return Ok(());
        }
        self.model.input_from_torque(tau, &mut self.acc)?;
        for (d, a) in self.dist.iter_mut().zip(&self.acc) {
            *d += a;
        }
        self.model.update(model, &self.q, &self.v)?;
        self.model.input_from_torque(tau, &mut self.acc)?;
        for (d, a) in self.dist.iter_mut().zip(&self.acc) {
            *d -= a;
        }
        Ok(())
    }

    /// The torque commanded at the current sample (n values); advances the
    /// sample counter.
    pub fn record_torque(&mut self, tau: &[f64]) {
        let n = self.n;
        let slot = self.k % (self.delay + 1);
        self.tau_hist[slot * n..(slot + 1) * n].copy_from_slice(tau);
        self.k += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gains_place_the_three_poles() {
        for (ts, p) in [(0.01, 0.5), (0.001, 0.8), (0.01, 0.2)] {
            let l = observer_gains(ts, p);
            let m = error_matrix(ts, l);
            // (M − pI)³ = 0 for a triple pole at p (Cayley–Hamilton).
            let mut b = m;
            for (i, row) in b.iter_mut().enumerate() {
                row[i] -= p;
            }
            let mul = |x: &[[f64; 3]; 3], y: &[[f64; 3]; 3]| {
                let mut z = [[0.0; 3]; 3];
                for i in 0..3 {
                    for j in 0..3 {
                        z[i][j] = (0..3).map(|k| x[i][k] * y[k][j]).sum();
                    }
                }
                z
            };
            let cube = mul(&mul(&b, &b), &b);
            let c = charpoly(&m);
            assert!((c[0] + 3.0 * p).abs() < 1e-9 && (c[1] - 3.0 * p * p).abs() < 1e-9);
            assert!((c[2] + p * p * p).abs() < 1e-9, "{c:?}");
            // Scaled by the state units (rad, rad/s, rad/s²).
            for (i, row) in cube.iter().enumerate() {
                for (j, v) in row.iter().enumerate() {
                    let scale = ts.powi(j as i32 - i as i32);
                    assert!(v.abs() < 1e-9 * scale.max(1.0), "({i},{j}) = {v}");
                }
            }
        }
    }
}
