//! Command modes: what the controller hands to the robot's interface.
//!
//! Most arms do not take joint torque from outside. A torque interface
//! (Franka's, KUKA's FRI torque overlay) takes [`OutputMode::Torque`]: the
//! controller's `τ_k`. Interfaces that close their own joint loop (UR's
//! `servoj`, ABB's EGM, KUKA's RSI) take a joint position and velocity
//! ([`OutputMode::PositionVelocity`]) or a velocity
//! ([`OutputMode::Velocity`]), and act on it some time later (their lag). For
//! them the controller outputs the state **its own model predicted** one
//! lead time `L` ahead (`[mpc] output_lead_s`, by default the interface's
//! lag and smoothing): the interface's drive then reaches at `t_k + L` the
//! point the controller planned for `t_k + L`, which compensates the lag
//! from the prediction the step already made (`ŷ(k+i|k)`, `i = 1..N`, of
//! [`Algorithm::predicted_outputs`](crate::control::Algorithm::predicted_outputs)):
//! no second model, no allocation.
//!
//! The lead point is read off the predicted positions `ŷ_0 = q_k` (the
//! state the step acted on), `ŷ_1, …, ŷ_N` by the quadratic through the
//! three samples nearest `s = L/Ts` (`j = clamp(round(s), 1, N − 1)`,
//! `u = s − j`):
//!
//! ```text
//! q_cmd   = ŷ_j + u (ŷ_{j+1} − ŷ_{j−1})/2 + u²/2 (ŷ_{j+1} − 2ŷ_j + ŷ_{j−1})
//! q̇_cmd   = [(ŷ_{j+1} − ŷ_{j−1})/2 + u (ŷ_{j+1} − 2ŷ_j + ŷ_{j−1})] / Ts
//! q̈_cmd   = (ŷ_{j+1} − 2ŷ_j + ŷ_{j−1}) / Ts²
//! ```
//!
//! so `L` may be any time from 0 to `(N − 1)·Ts` (refused beyond:
//! [`BuildError::OutputLead`](crate::control::BuildError::OutputLead)). The
//! acceleration is the feed-forward a drive's own loop adds; the torque
//! `τ_k` stays in the output for interfaces that take it as feed-forward.
//!
//! An interface that smooths its setpoint by a first-order filter of time
//! constant `T` (UR's `lookahead_time`: `ṡ = (c − s)/T`) delays a ramp by
//! `T` but also rounds every change of speed: a lead of `lag + T` leaves
//! the arm following a filtered copy of the plan (measured on ur-servoj:
//! 0.097 mm RMS where the torque interface gives 0.0047). With
//! `[mpc] output_smoothing_s = T` the command is the filter's inverse
//! applied to the plan, `c = y + T ẏ` on each channel,
//!
//! ```text
//! q_cmd + T q̇_cmd,   q̇_cmd + T q̈_cmd,   q̈_cmd + T q⃛_cmd,
//! q⃛_cmd = (ŷ_{j+2} − 3ŷ_{j+1} + 3ŷ_j − ŷ_{j−1}) / Ts³   (0 when j + 2 > N),
//! ```
//!
//! whose filtered value is the plan itself (exact for a cubic plan), and
//! the lead covers the lag alone (0.012 mm on the same run).

use crate::dynamics::{rnea, Workspace};
use crate::robot::{ModelError, Robot};
use serde::{Deserialize, Serialize};
use std::fmt;

/// What the controller's output drives (`[mpc] output`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum OutputMode {
    /// Joint torque `τ_k` (the paper's, the default).
    #[default]
    Torque,
    /// Joint position and velocity, one lead time ahead, with the
    /// acceleration and the torque as feed-forward.
    PositionVelocity,
    /// Joint velocity one lead time ahead, with the acceleration and the
    /// torque as feed-forward.
    Velocity,
}

impl OutputMode {
    /// Every mode, in the order of the documentation.
    pub const ALL: [OutputMode; 3] = [
        OutputMode::Torque,
        OutputMode::PositionVelocity,
        OutputMode::Velocity,
    ];

    /// `"torque"`, `"position_velocity"` or `"velocity"` (as in a scenario).
    pub fn name(self) -> &'static str {
        match self {
            OutputMode::Torque => "torque",
            OutputMode::PositionVelocity => "position_velocity",
            OutputMode::Velocity => "velocity",
        }
    }

    /// True for [`OutputMode::Torque`].
    pub fn is_torque(self) -> bool {
        self == OutputMode::Torque
    }

    /// Whether `self` is the default (for `skip_serializing_if`).
    pub(crate) fn is_default(&self) -> bool {
        self.is_torque()
    }
}

impl fmt::Display for OutputMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The largest lead time for a horizon of `horizon` samples of `ts` (s):
/// `(N − 1)·Ts` (the quadratic needs the sample after the lead point).
pub(crate) fn max_output_lead(horizon: usize, ts: f64) -> f64 {
    horizon.saturating_sub(1) as f64 * ts
}

/// The command one lead time ahead from the predicted positions: fills
/// `q`, `qd`, `qdd` (n each) from `now` (`ŷ_0`, n values) and `predicted`
/// (`ŷ_1..ŷ_N`, N·n values), `lead_s` ahead at the period `ts`,
/// pre-compensated for a first-order smoothing of time constant
/// `smoothing_s` (0: none; module docs). Allocation free; `N ≥ 2` (the
/// builder checks it through the lead's bound).
pub(crate) fn lead_point(
    now: &[f64],
    predicted: &[f64],
    lead_s: f64,
    smoothing_s: f64,
    ts: f64,
    cmd: [&mut [f64]; 3],
) {
    let n = now.len();
    let horizon = predicted.len() / n.max(1);
    let s = lead_s / ts;
    let j = (s.round() as usize).clamp(1, horizon.saturating_sub(1).max(1));
    let u = s - j as f64;
    let y = |i: usize, joint: usize| {
        if i == 0 {
            now[joint]
        } else {
            predicted
                .get((i - 1) * n + joint)
                .copied()
                .unwrap_or(now[joint])
        }
    };
    let [q, qd, qdd] = cmd;
    for i in 0..n {
        let (ym, y0, yp) = (y(j - 1, i), y(j, i), y(j + 1, i));
        let slope = 0.5 * (yp - ym);
        let curve = yp - 2.0 * y0 + ym;
        q[i] = y0 + u * slope + 0.5 * u * u * curve;
        qd[i] = (slope + u * curve) / ts;
        qdd[i] = curve / (ts * ts);
        if smoothing_s > 0.0 {
            let jerk = if j + 2 <= horizon {
                (y(j + 2, i) - 3.0 * yp + 3.0 * y0 - ym) / (ts * ts * ts)
            } else {
                0.0
            };
            q[i] += smoothing_s * qd[i];
            qd[i] += smoothing_s * qdd[i];
            qdd[i] += smoothing_s * jerk;
        }
    }
}

/// The payload, carried to a drive that closes its own joint loop on the
/// controller's nominal model (the payload the user declared), as a torque
/// feed-forward.
///
/// The drive computes `τ = ID_v(q, q̇, a) + τ_ff` (its inverse dynamics on
/// the vendor's model, `a` = the commanded acceleration plus its loop's
/// correction, and the feed-forward an interface that takes one adds). When
/// the controller's model carries an identified payload (an adaptive kind
/// through an interface that reports its applied torque) the arm needs
/// `τ* = ID_m(q, q̇, q̈)` along the plan, so the command's feed-forward is
///
/// ```text
/// τ_ff = ID_m(q, q̇, q̈) − ID_v(q, q̇, q̈)
/// ```
///
/// at the physical lead point (the plan's `q, q̇, q̈` one lead ahead, before
/// any smoothing pre-compensation): with it the drive's loop has no load
/// left to carry with its following error. Zero when the two models are
/// equal. (Carried in the commanded acceleration instead, `M_v⁻¹ τ_ff`, it
/// would also move the positions an interface extrapolates along the
/// command, `½ q̈ dt²`: a steady offset of 5e-5 rad on the IRB 140 at 2 kg
/// through the simulated ABB EGM.) Sized at construction; allocation-free.
#[derive(Debug, Clone)]
pub(crate) struct PayloadFeedForward {
    vendor: Robot,
    ws_vendor: Workspace,
    ws_model: Workspace,
    point: [Vec<f64>; 3],
}

impl PayloadFeedForward {
    /// For a drive whose model is `vendor` (the controller's nominal one).
    /// Allocates.
    pub(crate) fn new(vendor: &Robot) -> Self {
        let n = vendor.dof();
        Self {
            ws_vendor: Workspace::new(vendor),
            ws_model: Workspace::new(vendor),
            vendor: vendor.clone(),
            point: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
        }
    }

    /// The feed-forward for the controller's current `model` into `tau_ff`
    /// (n), at the lead point of `now`/`predicted` (as [`lead_point`] reads
    /// it, without smoothing).
    pub(crate) fn torque(
        &mut self,
        model: &Robot,
        now: &[f64],
        predicted: &[f64],
        lead_s: f64,
        ts: f64,
        tau_ff: &mut [f64],
    ) -> Result<(), ModelError> {
        let [q, qd, qdd] = &mut self.point;
        lead_point(now, predicted, lead_s, 0.0, ts, [q, qd, qdd]);
        let needed = rnea(model, &mut self.ws_model, q, qd, qdd)?;
        let vendor = rnea(&self.vendor, &mut self.ws_vendor, q, qd, qdd)?;
        for ((f, m), v) in tau_ff.iter_mut().zip(needed.iter()).zip(vendor.iter()) {
            *f = m - v;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a predicted parabola `y(t) = a + b t + c t²` the lead point is
    /// exact at any lead (on the grid and between), for position, velocity
    /// and acceleration.
    #[test]
    fn lead_point_is_exact_on_a_parabola() {
        let (ts, horizon) = (0.01, 10);
        let f = |t: f64| 0.3 + 1.5 * t - 4.0 * t * t;
        let now = [f(0.0)];
        let predicted: Vec<f64> = (1..=horizon).map(|i| f(i as f64 * ts)).collect();
        for lead in [0.0, 0.002, 0.0137, 0.04, 0.065, 0.09] {
            let (mut q, mut qd, mut qdd) = ([0.0], [0.0], [0.0]);
            lead_point(&now, &predicted, lead, 0.0, ts, [&mut q, &mut qd, &mut qdd]);
            assert!(
                (q[0] - f(lead)).abs() < 1e-12,
                "lead {lead}: {} vs {}",
                q[0],
                f(lead)
            );
            assert!((qd[0] - (1.5 - 8.0 * lead)).abs() < 1e-9, "lead {lead}");
            assert!((qdd[0] + 8.0).abs() < 1e-6, "lead {lead}");
        }
        assert!((max_output_lead(horizon, ts) - 0.09).abs() < 1e-15);
    }

    /// With a smoothing `T` the command is `c = y + T ẏ` on each channel of
    /// a cubic plan (exact); and a first-order filter of time constant `T`
    /// run on that command along the plan gives back the plan: the
    /// pre-compensation is the filter's inverse.
    #[test]
    fn the_smoothing_pre_compensation_is_the_filters_inverse() {
        let (ts, horizon, t_s) = (0.01, 10, 0.03);
        let f = |t: f64| 0.3 + 1.5 * t - 4.0 * t * t + 20.0 * t * t * t;
        let (df, ddf, dddf) = (
            |t: f64| 1.5 - 8.0 * t + 60.0 * t * t,
            |t: f64| -8.0 + 120.0 * t,
            |_: f64| 120.0,
        );
        let now = [f(0.0)];
        let predicted: Vec<f64> = (1..=horizon).map(|i| f(i as f64 * ts)).collect();
        for lead in [0.0, 0.0045, 0.01, 0.034, 0.06, 0.085] {
            let (mut q0, mut qd0, mut qdd0) = ([0.0], [0.0], [0.0]);
            lead_point(
                &now,
                &predicted,
                lead,
                0.0,
                ts,
                [&mut q0, &mut qd0, &mut qdd0],
            );
            let (mut q, mut qd, mut qdd) = ([0.0], [0.0], [0.0]);
            lead_point(&now, &predicted, lead, t_s, ts, [&mut q, &mut qd, &mut qdd]);
            // The third difference of a cubic's samples is its third
            // derivative, where the sample after next exists (j + 2 ≤ N).
            let j = ((lead / ts).round() as usize).clamp(1, horizon - 1);
            let jerk = if j + 2 <= horizon { dddf(lead) } else { 0.0 };
            assert!((q[0] - (q0[0] + t_s * qd0[0])).abs() < 1e-14, "lead {lead}");
            assert!(
                (qd[0] - (qd0[0] + t_s * qdd0[0])).abs() < 1e-12,
                "lead {lead}"
            );
            assert!(
                (qdd[0] - (qdd0[0] + t_s * jerk)).abs() < 1e-6,
                "lead {lead}: {}",
                qdd[0]
            );
            // Without the smoothing the channels are the plan's (the quadratic
            // through three samples of the cubic; exact at the middle one).
            if (lead / ts - j as f64).abs() < 1e-12 {
                assert!((q0[0] - f(lead)).abs() < 1e-12);
                assert!((qd0[0] - df(lead)).abs() < 120.0 * ts * ts / 6.0 + 1e-9);
                assert!((qdd0[0] - ddf(lead)).abs() < 1e-6);
            }
        }
        // The filter ṡ = (c − s)/T on c = y + T ẏ, from s(0) = y(0): s = y.
        let (h, mut s, mut worst) = (1e-5, f(0.0), 0.0f64);
        for k in 0..20_000 {
            let t = k as f64 * h;
            let c = |t: f64| f(t) + t_s * df(t);
            // RK4 of the filter.
            let k1 = (c(t) - s) / t_s;
            let k2 = (c(t + h / 2.0) - (s + h / 2.0 * k1)) / t_s;
            let k3 = (c(t + h / 2.0) - (s + h / 2.0 * k2)) / t_s;
            let k4 = (c(t + h) - (s + h * k3)) / t_s;
            s += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            worst = worst.max((s - f(t + h)).abs());
        }
        assert!(worst < 1e-12, "filtered command vs plan: {worst}");
    }

    #[test]
    fn names_round_trip() {
        for m in OutputMode::ALL {
            let toml = format!("\"{}\"", m.name());
            let back: OutputMode = serde_json::from_str(&toml).unwrap();
            assert_eq!(back, m);
        }
        assert_eq!(OutputMode::default(), OutputMode::Torque);
    }
}
