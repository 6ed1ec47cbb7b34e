//! What a predictive controller predicts over its horizon, recorded every few samples (the
//! report's 3-D replay draws it): the joint positions `ŷ_{k+1}, …, ŷ_{k+N}` its own model
//! predicts right after its step at sample `k`, from the state it was given and its optimal
//! sequence ([`Controller::increments`]).
//!
//! The model is the controller's (its [`JointSpaceDynamics`], with the payload an adaptive
//! variant identified), linearized at the state as the controllers do it (`f0 = −H⁻¹C`, Eq. (6)
//! and (12)) and discretized by zero-order hold (`Ad = [[I, Φ1], [0, e^M]]`,
//! `Bd = [[Φ2], [Φ1]]`, Eq. (13), [`Zoh`]):
//!
//! * the usual MPC and the disturbance-observer MPC (positional, Eq. (16) and (43)):
//!   `x_{j+1} = Ad x_j + Bd u_{k+j}` from `x_0 = x_k`, `ŷ = q` (the disturbance-observer MPC's
//!   sequence is `Ũ = U + d̂`, [`crate::control::dob_mpc`]);
//! * the incremental algorithms and their adaptive variants (Eq. (20)–(29)):
//!   `Δx_{j+1} = Ad Δx_j + Bd Δu_{k+j}` from `Δx_0 = x_k − x_{k−1}`,
//!   `ŷ_{k+j+1} = ŷ_{k+j} + Δq_{j+1}` from `ŷ_k = y_k` (`F_I y_k + F2 Δx_k + G2 ΔU`).
//!
//! The baselines without a horizon (`pid`, `ctc`, `ctc-adaptive`) predict nothing.
//!
//! Buffers are sized at construction: observing a step allocates nothing.

use crate::control::model::LinearLikeModel;
use crate::control::zoh::Zoh;
use crate::control::{Controller, ControllerKind};
use crate::dynamics::JointSpaceDynamics;

/// Which horizons a run records ([`super::RunConditions::horizons`]): the samples `0, every,
/// 2·every, …`, at most `max` of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HorizonSampling {
    /// Samples between two recorded horizons (≥ 1).
    pub every: usize,
    /// Most horizons recorded.
    pub max: usize,
}

/// The horizons recorded in a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PredictedHorizons {
    /// Joints `n`.
    pub n: usize,
    /// Horizon `N`.
    pub horizon: usize,
    /// The samples `k` (row of the record) at which a horizon was recorded.
    pub samples: Vec<usize>,
    /// Per recorded sample, `N·n` joint positions: block `j` is `ŷ_{k+j+1}` (rad or m).
    pub q: Vec<f64>,
}

impl PredictedHorizons {
    /// The predicted joint positions of recorded horizon `i`: `N` blocks of `n`.
    pub fn at(&self, i: usize) -> &[f64] {
        let len = self.n * self.horizon;
        &self.q[i * len..(i + 1) * len]
    }
}

/// How a controller's sequence maps to its predicted outputs.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Form {
    /// `u_{k+j}` with the state `x_k`.
    Positional,
    /// `Δu_{k+j}` with the state increment `x_k − x_{k−1}`.
    Incremental,
}

/// Records the predicted horizon of a controller at every `every`-th sample, at most
/// `capacity` of them.
#[derive(Debug, Clone)]
pub struct HorizonRecorder {
    form: Form,
    n: usize,
    ts: f64,
    every: usize,
    capacity: usize,
    model: LinearLikeModel,
    zoh: Zoh,
    /// The state the controller was given at its previous step (`x_{k−1}`).
    x_prev: Vec<f64>,
    /// Work: state (2n) and output (n) of the prediction.
    z: Vec<f64>,
    znext: Vec<f64>,
    y: Vec<f64>,
    out: PredictedHorizons,
}

impl HorizonRecorder {
    /// A recorder for controller `kind` (`n` joints, horizon `horizon`, period `ts`) keeping
    /// the horizon of every `every`-th sample (0 and each multiple), at most `capacity`;
    /// `None` for a controller without a prediction horizon.
    pub fn new(
        kind: ControllerKind,
        n: usize,
        horizon: usize,
        ts: f64,
        every: usize,
        capacity: usize,
    ) -> Option<Self> {
        let form = match kind {
            ControllerKind::Usual | ControllerKind::DobMpc => Form::Positional,
            ControllerKind::First
            | ControllerKind::Second
            | ControllerKind::FirstAdaptive
            | ControllerKind::SecondAdaptive => Form::Incremental,
            ControllerKind::Pid | ControllerKind::Ctc | ControllerKind::CtcAdaptive => return None,
        };
        Some(Self {
            form,
            n,
            ts,
            every: every.max(1),
            capacity,
            model: LinearLikeModel::new(n),
            zoh: Zoh::new(n),
            x_prev: vec![0.0; 2 * n],
            z: vec![0.0; 2 * n],
            znext: vec![0.0; 2 * n],
            y: vec![0.0; n],
            out: PredictedHorizons {
                n,
                horizon,
                samples: Vec::with_capacity(capacity),
                q: Vec::with_capacity(capacity * horizon * n),
            },
        })
    }

    /// The run starts at `x0` (the controller's `reset`).
    pub fn reset(&mut self, x0: &[f64]) {
        if x0.len() == self.x_prev.len() {
            self.x_prev.copy_from_slice(x0);
        }
    }

    /// After a successful step of `controller` on the state `x` (2n) with its `model`: at a
    /// recorded sample `k` (not during the pre-roll, `None`) its predicted horizon is kept.
    /// A horizon that cannot be computed (a model that fails, a sequence of the wrong
    /// length) is left out. Allocates nothing.
    pub fn observe(
        &mut self,
        k: Option<usize>,
        model: &mut dyn JointSpaceDynamics,
        x: &[f64],
        controller: &dyn Controller,
    ) {
        let n = self.n;
        if x.len() != 2 * n {
            return;
        }
        let wanted =
            k.is_some_and(|k| k % self.every == 0) && self.out.samples.len() < self.capacity;
        if let (Some(k), true) = (k, wanted) {
            if self.predict(model, x, controller.increments()) {
                self.out.samples.push(k);
            }
        }
        self.x_prev.copy_from_slice(x);
    }

    /// Appends the predicted outputs of one step to `out.q`; false when they cannot be
    /// computed.
    fn predict(&mut self, model: &mut dyn JointSpaceDynamics, x: &[f64], sequence: &[f64]) -> bool {
        let (n, nh) = (self.n, self.out.horizon);
        if sequence.len() != nh * n {
            return false;
        }
        if self.model.update(model, &x[..n], &x[n..]).is_err()
            || self.zoh.discretize(self.model.f0(), self.ts).is_err()
        {
            return false;
        }
        match self.form {
            Form::Positional => self.z.copy_from_slice(x),
            Form::Incremental => {
                for ((z, a), b) in self.z.iter_mut().zip(x).zip(&self.x_prev) {
                    *z = a - b;
                }
            }
        }
        self.y.copy_from_slice(&x[..n]);
        let (phi1, phi2, e) = (self.zoh.phi1(), self.zoh.phi2(), self.zoh.e());
        let start = self.out.q.len();
        for u in sequence.chunks_exact(n) {
            // q⁺ = q + Φ1 v + Φ2 u, v⁺ = e^M v + Φ1 u (Eq. (13)).
            for i in 0..n {
                let (mut dq, mut dv) = (0.0, 0.0);
                for j in 0..n {
                    dq += phi1[(i, j)] * self.z[n + j] + phi2[(i, j)] * u[j];
                    dv += e[(i, j)] * self.z[n + j] + phi1[(i, j)] * u[j];
                }
                self.znext[i] = self.z[i] + dq;
                self.znext[n + i] = dv;
            }
            std::mem::swap(&mut self.z, &mut self.znext);
            for i in 0..n {
                let yi = match self.form {
                    Form::Positional => self.z[i],
                    // y_{j+1} = y_j + Δq_{j+1}
                    Form::Incremental => self.y[i] + self.z[i],
                };
                self.y[i] = yi;
                self.out.q.push(yi);
            }
        }
        if self.out.q[start..].iter().all(|v| v.is_finite()) {
            true
        } else {
            self.out.q.truncate(start);
            false
        }
    }

    /// The horizons recorded.
    pub fn horizons(&self) -> &PredictedHorizons {
        &self.out
    }

    /// The horizons recorded.
    pub fn into_horizons(self) -> PredictedHorizons {
        self.out
    }
}
