//! Online identification of the payload's inertial parameters.
//!
//! * `regressor`: the ten parameters `π` of a rigid payload, their physical
//!   consistency (pseudo-inertia) and the joint-space regressor
//!   `τ_payload = Y_q(q, q̇, q̈) π`;
//! * `rls`: recursive least squares with forgetting, projected onto the
//!   physically consistent set after each sample;
//! * [`PayloadEstimator`]: the two together on closed-loop data — measured
//!   `q`, `q̇` at two consecutive samples and the torque held in between.

pub(crate) mod regressor;
pub(crate) mod rls;

pub use regressor::PayloadParams;
#[doc(hidden)]
pub use regressor::{joint_regressor, params_of, payload_of, pseudo_inertia, NUM_PARAMS};
pub use rls::{PayloadRls, RlsSettings, RlsSettingsError};

use crate::dynamics::RobotDynamics;

/// Payload identification from sampled closed-loop data.
///
/// Over one control period the torque `τ_{k−1}` is held constant (zero-order
/// hold), so the mean acceleration over `[t_{k−1}, t_k]` is exactly
/// `(q̇_k − q̇_{k−1}) / Ts`: the estimator evaluates the dynamics at the
/// period's midpoint, `q_m = ½(q_{k−1} + q_k)`, `q̇_m = ½(q̇_{k−1} + q̇_k)`,
/// with that mean acceleration (a finite-difference filter of the velocity;
/// its error is second order in `Ts`). The measured payload torque is
/// `τ_{k−1} − τ^0(q_m, q̇_m, q̈_m)`, computed as `τ − τ̂ + Y π̂` with `τ̂` the
/// inverse dynamics of the model with its current payload estimate `π̂`.
#[derive(Debug, Clone)]
pub struct PayloadEstimator {
    rls: PayloadRls,
    rows: Vec<[f64; NUM_PARAMS]>,
    y: Vec<f64>,
    qm: Vec<f64>,
    qdm: Vec<f64>,
    qdd: Vec<f64>,
}

impl PayloadEstimator {
    /// For `n` joints, from the prior `π₀`.
    pub fn new(
        n: usize,
        settings: RlsSettings,
        prior: PayloadParams,
    ) -> Result<Self, RlsSettingsError> {
        Ok(Self {
            rls: PayloadRls::new(settings, prior)?,
            rows: vec![[0.0; NUM_PARAMS]; n],
            y: vec![0.0; n],
            qm: vec![0.0; n],
            qdm: vec![0.0; n],
            qdd: vec![0.0; n],
        })
    }

    /// The recursive least squares inside.
    pub fn rls(&self) -> &PayloadRls {
        &self.rls
    }

    /// Mutable access (reset, tests).
    pub fn rls_mut(&mut self) -> &mut PayloadRls {
        &mut self.rls
    }

    /// One period: states `x_prev = [q; q̇]` at `t_{k−1}`, `x` at `t_k`
    /// (2n values each), torque `tau_prev` held in between, period `ts`.
    /// `model` is the controller's model with its current payload estimate
    /// (its payload is read, not changed). Returns `false` (and learns
    /// nothing) on wrong lengths or non-finite data. Allocates nothing.
    pub fn update(
        &mut self,
        model: &mut RobotDynamics,
        x_prev: &[f64],
        x: &[f64],
        tau_prev: &[f64],
        ts: f64,
    ) -> bool {
        let n = self.y.len();
        if model.robot().dof() != n
            || x_prev.len() != 2 * n
            || x.len() != 2 * n
            || tau_prev.len() != n
            || !(ts > 0.0 && ts.is_finite())
            || !x_prev
                .iter()
                .chain(x)
                .chain(tau_prev)
                .all(|v| v.is_finite())
        {
            return false;
        }
        for i in 0..n {
            self.qm[i] = 0.5 * (x_prev[i] + x[i]);
            self.qdm[i] = 0.5 * (x_prev[n + i] + x[n + i]);
            self.qdd[i] = (x[n + i] - x_prev[n + i]) / ts;
        }
        self.learn(model, tau_prev, None)
    }

    /// One sample at a point of the motion: position `q`, velocity `qd`,
    /// acceleration `qdd` and the torque `tau` that produced them (n values
    /// each; the caller aligns them in time and removes what the rigid body
    /// does not carry, e.g. the friction estimate). Only the joints with
    /// `use_row[i]` contribute a row; with none, nothing is learnt (and
    /// nothing forgotten). Returns whether the estimate was updated.
    /// Allocates nothing.
    pub fn update_point(
        &mut self,
        model: &mut RobotDynamics,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        tau: &[f64],
        use_row: &[bool],
    ) -> bool {
        let n = self.y.len();
        if model.robot().dof() != n
            || [q.len(), qd.len(), qdd.len(), tau.len(), use_row.len()]
                .iter()
                .any(|&l| l != n)
            || !q
                .iter()
                .chain(qd)
                .chain(qdd)
                .chain(tau)
                .all(|v| v.is_finite())
            || !use_row.iter().any(|&u| u)
        {
            return false;
        }
        self.qm.copy_from_slice(q);
        self.qdm.copy_from_slice(qd);
        self.qdd.copy_from_slice(qdd);
        self.learn(model, tau, Some(use_row))
    }

    /// The regressor at `(qm, qdm, qdd)`, the payload torque of `tau`, the
    /// recursion (rows not in `use_row` left out).
    fn learn(&mut self, model: &mut RobotDynamics, tau: &[f64], use_row: Option<&[bool]>) -> bool {
        let n = self.y.len();
        let tau_prev = tau;
        let (robot, ws) = model.parts();
        joint_regressor(robot, ws, &self.qm, &self.qdm, &self.qdd, &mut self.rows);
        // The payload the model carries (normally π̂; whatever it is, τ̂ − Y π
        // removes it).
        let model_pi = robot
            .payload()
            .map(params_of)
            .unwrap_or_else(PayloadParams::zeros);
        for i in 0..n {
            let row = PayloadParams::from_column_slice(&self.rows[i]);
            self.y[i] = tau_prev[i] - ws.tau[i] + row.dot(&model_pi);
            if use_row.is_some_and(|u| !u[i]) {
                // A zero row carries no information: the scalar step leaves π and P.
                self.rows[i] = [0.0; NUM_PARAMS];
                self.y[i] = 0.0;
            }
        }
        self.rls.update(&self.rows, &self.y)
    }
}
