//! The measurement repair: a lost or invalid reading replaced by the
//! controller's model's prediction, so that everything after it sees finite
//! numbers ([`MeasurementGuard`]). The model's acceleration it predicts with
//! ([`model_accel`]) is also the safe stop's dead reckoning.

use crate::control::{LinearLikeModel, StepFailure};
use crate::dynamics::JointSpaceDynamics;

/// Stands in for a missing or invalid (non-finite) measurement: the state
/// the controller was last given, advanced one period through the
/// controller's model under the torque that produced the current
/// measurement (`delay` samples older with a delayed measurement), plus the
/// acceleration the model has been missing lately (a filtered disturbance,
/// learnt on the valid samples: an unknown payload biases the model). The
/// controller then runs on this prediction; every such sample counts as a
/// fault. Sized once ([`MeasurementGuard::new`]); allocation-free after.
#[derive(Debug, Clone)]
pub struct MeasurementGuard {
    n: usize,
    /// The control period (s).
    ts: f64,
    delay: usize,
    lin: LinearLikeModel,
    /// The last state handed on (2n).
    x_prev: Vec<f64>,
    /// Torques of the last `delay + 1` samples (ring) and how many were recorded.
    tau_hist: Vec<f64>,
    recorded: usize,
    a: Vec<f64>,
    /// Acceleration the model misses (filtered), rad/s².
    dist: Vec<f64>,
    /// Learn `dist` on every valid sample (one model evaluation per sample):
    /// only when measurements can be lost.
    track: bool,
    /// Samples whose measurement was replaced.
    pub faults: usize,
}

/// Gain of the disturbance filter of [`MeasurementGuard`] per sample.
const DISTURBANCE_GAIN: f64 = 0.3;

impl MeasurementGuard {
    /// A guard for a robot at rest at `x0` (2n: the prior for a first
    /// measurement that is already invalid), measurements `delay` samples
    /// old, one per control period `ts` (s); `track`: measurements can be
    /// lost (learn the disturbance).
    pub fn new(x0: &[f64], delay: usize, track: bool, ts: f64) -> Self {
        let n = x0.len() / 2;
        Self {
            n,
            ts,
            delay,
            lin: LinearLikeModel::new(n),
            x_prev: x0.to_vec(),
            tau_hist: vec![0.0; (delay + 1) * n],
            recorded: 0,
            a: vec![0.0; n],
            dist: vec![0.0; n],
            track,
            faults: 0,
        }
    }

    /// Starts over at rest at `x0` (2n), nothing recorded, no fault
    /// counted; allocates nothing.
    pub fn reset(&mut self, x0: &[f64]) {
        self.x_prev.copy_from_slice(x0);
        self.tau_hist.fill(0.0);
        self.recorded = 0;
        self.a.fill(0.0);
        self.dist.fill(0.0);
        self.faults = 0;
    }

    /// Replaces the non-finite entries of `x` (2n) by the prediction (both
    /// position and velocity of such a joint); returns whether it did.
    pub fn check(&mut self, model: &mut dyn JointSpaceDynamics, x: &mut [f64]) -> bool {
        let (n, ts) = (self.n, self.ts);
        let bad = |i: usize, x: &[f64]| !(x[i].is_finite() && x[n + i].is_finite());
        let invalid = (0..n).any(|i| bad(i, x));
        if !invalid && !self.track {
            self.x_prev.copy_from_slice(x);
            return false;
        }
        // The model's acceleration from the last state under the torque
        // applied at sample k − 1 − delay (none yet: no prediction).
        let slots = self.delay + 1;
        let predicted = self.recorded > self.delay && {
            let slot = (self.recorded - 1 - self.delay) % slots;
            let (q, v) = self.x_prev.split_at(n);
            let tau = &self.tau_hist[slot * n..(slot + 1) * n];
            model_accel(&mut self.lin, model, q, v, tau, &mut self.a).is_ok()
                && self.a.iter().all(|a| a.is_finite())
        };
        if !invalid {
            if predicted {
                for i in 0..n {
                    let seen = (x[n + i] - self.x_prev[n + i]) / ts;
                    let d = seen - self.a[i];
                    if d.is_finite() {
                        self.dist[i] += DISTURBANCE_GAIN * (d - self.dist[i]);
                    }
                }
            }
            self.x_prev.copy_from_slice(x);
            return false;
        }
        self.faults += 1;
        for i in 0..n {
            if bad(i, x) {
                let a = if predicted {
                    self.a[i] + self.dist[i]
                } else {
                    0.0
                };
                let (q, v) = (self.x_prev[i], self.x_prev[n + i]);
                x[i] = q + v * ts + 0.5 * a * ts * ts;
                x[n + i] = v + a * ts;
            }
        }
        self.x_prev.copy_from_slice(x);
        true
    }

    /// The torque commanded at the current sample (n values).
    pub fn record_torque(&mut self, tau: &[f64]) {
        let n = self.n;
        let slot = self.recorded % (self.delay + 1);
        self.tau_hist[slot * n..(slot + 1) * n].copy_from_slice(tau);
        self.recorded += 1;
    }
}

/// `a = f0 q̇ + H⁻¹(τ − g)` of the model at `(q, q̇)` (Eq. (6)–(7)).
pub(super) fn model_accel(
    lin: &mut LinearLikeModel,
    model: &mut dyn JointSpaceDynamics,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    a: &mut [f64],
) -> Result<(), StepFailure> {
    let n = q.len();
    lin.update(model, q, v)?;
    lin.input_from_torque(tau, a)?;
    let f0 = lin.f0().as_slice();
    for c in 0..n {
        for r in 0..n {
            a[r] += f0[c * n + r] * v[c];
        }
    }
    Ok(())
}
