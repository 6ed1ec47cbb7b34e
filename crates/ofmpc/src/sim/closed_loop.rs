//! The closed loop: measure, control, apply the torque over one period.

use super::metrics::Record;
use super::plant::Plant;
use crate::control::Controller;
use crate::dynamics::JointSpaceDynamics;
use crate::motion::JointReference;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Settings of a closed-loop run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoopSettings {
    /// How long the last reference point is held after the path ends (s).
    pub hold_s: f64,
    /// A run whose joint error passes this (rad) on any joint is stopped as diverged.
    pub divergence_threshold_rad: f64,
    /// The "steady" window at the end of the hold, for the metrics (s).
    pub steady_window_s: f64,
}

impl Default for LoopSettings {
    fn default() -> Self {
        Self {
            hold_s: 2.0,
            divergence_threshold_rad: 0.2,
            steady_window_s: 0.5,
        }
    }
}

impl LoopSettings {
    /// Checks the values.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.hold_s.is_finite() && self.hold_s >= 0.0) {
            return Err(format!(
                "simulation.hold_s = {}: must be ≥ 0 s",
                self.hold_s
            ));
        }
        if !(self.divergence_threshold_rad.is_finite() && self.divergence_threshold_rad > 0.0) {
            return Err(format!(
                "simulation.divergence_threshold_rad = {}: must be > 0",
                self.divergence_threshold_rad
            ));
        }
        if !(self.steady_window_s.is_finite()
            && self.steady_window_s > 0.0
            && self.steady_window_s <= self.hold_s.max(1e-9))
        {
            return Err(format!(
                "simulation.steady_window_s = {}: must be > 0 and not longer than the hold ({} s)",
                self.steady_window_s, self.hold_s
            ));
        }
        Ok(())
    }
}

/// The outcome of one run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// What was recorded, up to the end or to the divergence.
    pub record: Record,
    /// Time at which the run was stopped as diverged.
    pub diverged_at: Option<f64>,
    /// Why it diverged: the joint error, or a failed controller step or plant step.
    pub reason: Option<String>,
    /// Wall time of the whole run (s).
    pub wall_s: f64,
}

/// Runs `controller` (with its own `model` of the robot) against `plant`
/// along `reference`, then holds its last point for `settings.hold_s`.
///
/// The plant starts at rest wherever it was built (normally the reference's
/// first point). Row `k` of the record holds the state measured at `t_k` and
/// the torque applied over `[t_k, t_k + Ts)`. `progress(k, total)` is called
/// every 100 samples.
pub fn run_closed_loop(
    controller: &mut dyn Controller,
    model: &mut dyn JointSpaceDynamics,
    plant: &mut Plant,
    reference: &JointReference,
    settings: &LoopSettings,
    progress: &mut dyn FnMut(usize, usize),
) -> RunResult {
    let start = Instant::now();
    let n = reference.dof();
    let ts = reference.ts();
    let horizon = controller.horizon();
    let total = reference.len() + (settings.hold_s / ts).round() as usize;
    let mut rec = Record::with_capacity(n, total);
    let mut x = vec![0.0; 2 * n];
    let mut tau = vec![0.0; n];
    let mut preview = vec![0.0; horizon * n];
    let mut diverged_at = None;
    let mut reason = None;
    plant.measure(&mut x);
    if let Err(e) = controller.reset(&x) {
        return RunResult {
            record: rec,
            diverged_at: Some(0.0),
            reason: Some(format!("reset failed: {e}")),
            wall_s: 0.0,
        };
    }
    for k in 0..total {
        let t = k as f64 * ts;
        if k > 0 {
            plant.measure(&mut x);
        }
        let flange = plant.flange_position();
        let w = reference.q(k);
        reference.preview(k, horizon, &mut preview);
        let t0 = Instant::now();
        let status = controller.step(model, &x, w, &preview, &mut tau);
        let us = t0.elapsed().as_secs_f64() * 1e6;
        if let Err(e) = status {
            diverged_at = Some(t);
            reason = Some(format!("controller step failed at t = {t:.3} s: {e}"));
            break;
        }
        if let Err(e) = plant.step(&tau, ts) {
            diverged_at = Some(t);
            reason = Some(format!("plant integration failed at t = {t:.3} s: {e}"));
            break;
        }
        rec.t.push(t);
        rec.q.extend_from_slice(&x[..n]);
        rec.qd.extend_from_slice(&x[n..]);
        rec.tau.extend_from_slice(plant.applied_torque());
        rec.q_ref.extend_from_slice(w);
        rec.flange_ref.push(reference.position(k));
        rec.step_us.push(us);
        rec.flange.push(flange);
        if let Some(i) = (0..n).find(|&i| {
            let e = rec.joint_error(k, i).abs();
            e.is_nan() || e > settings.divergence_threshold_rad
        }) {
            diverged_at = Some(t);
            reason = Some(format!(
                "joint {} error {:.4} rad passed the divergence threshold {} rad at t = {t:.3} s",
                i + 1,
                rec.joint_error(k, i),
                settings.divergence_threshold_rad
            ));
            break;
        }
        if k % 100 == 0 {
            progress(k, total);
        }
    }
    progress(total, total);
    RunResult {
        record: rec,
        diverged_at,
        reason,
        wall_s: start.elapsed().as_secs_f64(),
    }
}
