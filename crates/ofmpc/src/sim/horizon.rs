//! What a predictive controller predicts over its horizon, recorded every few samples (the
//! report's 3-D replay draws it): the joint positions `ŷ_{k+1}, …, ŷ_{k+N}` its own model
//! predicts right after its step at sample `k`, from the state it was given and its optimal
//! sequence ([`crate::control::Algorithm::increments`]).
//!
//! The controller hands them over itself ([`crate::control::Algorithm::predicted_outputs`]): the ZOH model
//! of its step (its [`crate::dynamics::JointSpaceDynamics`], with the payload an adaptive
//! variant identified, linearized at the state, `f0 = −H⁻¹C`, Eq. (6) and (12), discretized by
//! zero-order hold, `Ad = [[I, Φ1], [0, e^M]]`, `Bd = [[Φ2], [Φ1]]`, Eq. (13)), driven by its
//! sequence ([`crate::control::prediction::predicted_outputs`]):
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

use crate::control::ControllerKind;

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

/// Records the predicted horizon of a controller at every `every`-th sample, at most
/// `capacity` of them.
#[derive(Debug, Clone)]
pub struct HorizonRecorder {
    every: usize,
    capacity: usize,
    /// The predicted outputs of one step (N·n).
    y: Vec<f64>,
    out: PredictedHorizons,
}

impl HorizonRecorder {
    /// A recorder for controller `kind` (`n` joints, horizon `horizon`) keeping the horizon
    /// of every `every`-th sample (0 and each multiple), at most `capacity`; `None` for a
    /// controller without a prediction horizon.
    pub fn new(
        kind: ControllerKind,
        n: usize,
        horizon: usize,
        every: usize,
        capacity: usize,
    ) -> Option<Self> {
        if matches!(
            kind,
            ControllerKind::Pid | ControllerKind::Ctc | ControllerKind::CtcAdaptive
        ) {
            return None;
        }
        Some(Self {
            every: every.max(1),
            capacity,
            y: vec![0.0; horizon * n],
            out: PredictedHorizons {
                n,
                horizon,
                samples: Vec::with_capacity(capacity),
                q: Vec::with_capacity(capacity * horizon * n),
            },
        })
    }

    /// After a successful step of the controller at sample `k` of the path or the hold: at a
    /// recorded sample its predicted horizon, written by `predict` into the N·n values it is
    /// given (`false`: none, as [`super::SupervisedController::predicted_outputs`]), is kept.
    /// A horizon that cannot be had or is not finite is left out. Allocates nothing.
    pub fn observe(&mut self, k: usize, predict: impl FnOnce(&mut [f64]) -> bool) {
        let wanted = k.is_multiple_of(self.every) && self.out.samples.len() < self.capacity;
        if wanted && predict(&mut self.y) && self.y.iter().all(|v| v.is_finite()) {
            self.out.q.extend_from_slice(&self.y);
            self.out.samples.push(k);
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
